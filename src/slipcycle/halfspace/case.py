"""Case file → :class:`HalfspaceModel` → results (``model = "halfspace"``, SPEC §4, §6).

Keys of ``[halfspace]``:
  profile            sphere | cylinder | flat_punch | power_law | rough_exponential | tabulated
  radius             sphere/cylinder radius, punch radius (m)
  coefficient, exponent   power law z = c rⁿ (c in m^(1−n))
  gamma_sigma        γσ of the rough law dP/dU = P/(γσ) (m)
  table_U, table_P   tabulated P(U) pairs (m, N), convex, starting at P = 0
  reference_depth    cylinder: depth of the displacement reference point (m, default radius)
  E, nu              Young's moduli (Pa) and Poisson's ratios of both bodies, or
  contact_modulus    E* (Pa) directly
  compliance_ratio   λ_c (default 1 in 2-D, (2 − ν)/(2(1 − ν)) in 3-D)
  friction           f
Keys of ``[loading]``: P0, P1, Q0, Q1, phase (P = P0 + λP1 cos θ, Q = Q0 + λQ1 cos(θ − phase));
  P1/Q1 may be lists over harmonics h = 1, 2, … with P1_phase/phase lists; U0, U1
  (approach control) instead of P0, P1; V0, V1 (displacement control) instead of Q0, Q1;
  lam (λ, default 1); or a table: theta, P (or U), Q (or V); ``[[loading.protocol]]``
  assembly states with P (or U) and Q (or V).
Keys of ``[run]``: cycles, steps_per_cycle, sliders, assembly_steps, snapshots, steady_tol.
"""

from __future__ import annotations

import numpy as np

from slipcycle.halfspace.elastic import ContactElasticity
from slipcycle.halfspace.model import HalfspaceModel, solve
from slipcycle.halfspace.profiles import (
    Cylinder2D,
    FlatPunch,
    PowerLaw,
    RoughExponential,
    Tabulated,
    sphere,
)
from slipcycle.io import Case, CaseError, RunOutputs, Section
from slipcycle.loading import HarmonicLoad, TabulatedLoad

__all__ = ["parse_case", "run_case"]

PROFILES = ("sphere", "cylinder", "flat_punch", "power_law", "rough_exponential", "tabulated")


def _elasticity(sec: Section, plane: bool) -> ContactElasticity:
    ratio = sec.float("compliance_ratio", None, gt=0.0)
    if sec.has("contact_modulus"):
        if sec.has("E") or sec.has("nu"):
            raise sec.error("contact_modulus", "give either E and nu or contact_modulus, not both")
        e_star = sec.float("contact_modulus", gt=0.0)
        if ratio is None:
            raise sec.error("compliance_ratio", "required with contact_modulus "
                            "(1 for plane contacts, (2-ν)/(2(1-ν)) in 3-D)")
        return ContactElasticity(e_star, ratio)
    E = sec.array("E", shape=(2,), gt=0.0)
    nu = sec.array("nu", shape=(2,), gt=-1.0, le=0.5)
    return ContactElasticity.from_materials(tuple(E), tuple(nu), plane=plane,
                                            compliance_ratio=ratio)


def _profile(sec: Section):
    name = sec.string("profile", choices=PROFILES)
    if name in ("rough_exponential", "tabulated"):
        ratio = sec.float("compliance_ratio", None, gt=0.0)
        if name == "rough_exponential":
            prof = RoughExponential(sec.float("gamma_sigma", gt=0.0))
            if ratio is None:
                # λ_c from ν when given (3-D, eq. 9 of seed 001), else required
                nu = sec.array("nu", None, shape=(2,), gt=-1.0, le=0.5)
                if nu is None:
                    raise sec.error("compliance_ratio", "required for rough_exponential "
                                    "unless nu is given")
                sec.array("E", None, shape=(2,), gt=0.0)
                ratio = float(np.mean((2 - nu) / (2 * (1 - nu))))
        else:
            U = sec.array("table_U", shape=(None,))
            P = sec.array("table_P", shape=(None,), ge=0.0)
            if U.size < 2 or U.size != P.size:
                raise sec.error("table_P", f"needs as many values as table_U (>= 2), got "
                                f"{P.size} and {U.size}")
            if np.any(np.diff(U) <= 0):
                raise sec.error("table_U", "must increase strictly")
            if P[0] != 0.0:
                raise sec.error("table_P", "must start at 0 (first touch)")
            slopes = np.diff(P) / np.diff(U)
            if np.any(slopes <= 0) or np.any(np.diff(slopes) < -1e-12 * slopes.max()):
                raise sec.error("table_P", "P(U) must increase with non-decreasing slope "
                                "(a convex normal law; otherwise no slider bed exists)")
            prof = Tabulated(U, P)
            if ratio is None:
                raise sec.error("compliance_ratio", "required for a tabulated profile")
        return prof, None, ratio
    plane = name == "cylinder"
    el = _elasticity(sec, plane)
    if name == "sphere":
        prof = sphere(sec.float("radius", gt=0.0), el.contact_modulus)
    elif name == "cylinder":
        prof = Cylinder2D(sec.float("radius", gt=0.0), el.contact_modulus,
                          sec.float("reference_depth", None, gt=0.0))
    elif name == "flat_punch":
        prof = FlatPunch(sec.float("radius", gt=0.0), el.contact_modulus)
    else:
        prof = PowerLaw(sec.float("coefficient", gt=0.0), sec.float("exponent", gt=0.0),
                        el.contact_modulus)
    return prof, el, el.compliance_ratio


def _component(sec: Section, mean_key: str, amp_key: str, phase_key: str, lam: float,
               phase_sign: float) -> HarmonicLoad:
    mean = sec.float(mean_key, 0.0)
    amp = np.atleast_1d(sec.array(amp_key, 0.0))
    if amp.ndim != 1:
        raise sec.error(amp_key, "must be a number or a list over harmonics")
    ph = np.atleast_1d(sec.array(phase_key, 0.0))
    if ph.size not in (1, amp.size):
        raise sec.error(phase_key, f"needs 1 or {amp.size} values (one per harmonic)")
    ph = np.broadcast_to(ph, amp.shape)
    return HarmonicLoad(np.array([mean]), amp[:, None], phase_sign * ph[:, None], lam)


def _pick(sec: Section, force_keys: tuple[str, ...], disp_keys: tuple[str, ...],
          label: str) -> bool:
    """True for force control; refuses mixing force and displacement keys."""
    has_f = any(sec.has(k) for k in force_keys)
    has_d = any(sec.has(k) for k in disp_keys)
    if has_f and has_d:
        raise sec.error(disp_keys[0], f"{label}: give force keys ({', '.join(force_keys)}) or "
                        f"displacement keys ({', '.join(disp_keys)}), not both")
    return not has_d


def _loading(sec: Section):
    lam = sec.float("lam", 1.0, ge=0.0)
    normal_force = _pick(sec, ("P0", "P1", "P"), ("U0", "U1", "U"), "normal load")
    tang_force = _pick(sec, ("Q0", "Q1", "Q"), ("V0", "V1", "V"), "tangential load")
    nk, tk = ("P" if normal_force else "U"), ("Q" if tang_force else "V")
    if sec.has("theta"):
        theta = sec.array("theta", shape=(None,), ge=0.0, lt=2 * np.pi)
        if np.any(np.diff(theta) <= 0):
            raise sec.error("theta", "must increase strictly within [0, 2π)")
        vals = {k: sec.array(k, shape=(theta.size,)) for k in (nk, tk)}
        normal = TabulatedLoad(theta, vals[nk], None, 1.0)
        tangential = TabulatedLoad(theta, vals[tk], None, 1.0)
        if lam != 1.0:
            raise sec.error("lam", "applies to harmonic loads only")
    else:
        if not sec.has(f"{nk}0"):
            raise sec.error(f"{nk}0", "required key is missing (mean normal "
                            + ("load" if normal_force else "approach") + ")")
        normal = _component(sec, f"{nk}0", f"{nk}1", f"{nk}1_phase", lam, +1.0)
        # Q = Q0 + Q1 cos(θ − φ): the phase lag enters with a minus sign
        tangential = _component(sec, f"{tk}0", f"{tk}1", "phase", lam, -1.0)
    protocol = []
    for st in sec.tables("protocol", None):
        protocol.append([st.float(nk), st.float(tk, 0.0)])
        st.finish()
    return (normal, tangential, "force" if normal_force else "approach",
            "force" if tang_force else "displacement", np.array(protocol).reshape(-1, 2))


def parse_case(case: Case) -> HalfspaceModel:
    """Validate a ``halfspace`` case completely (raises CaseError) and build the model."""
    sec = case.section("halfspace")
    profile, elasticity, ratio = _profile(sec)
    friction = sec.float("friction", gt=0.0)
    normal, tangential, ncontrol, tcontrol, protocol = _loading(case.section("loading"))
    run = case.section("run", required=False)
    steps = run.int("steps_per_cycle", 400, ge=8)
    model = HalfspaceModel(
        profile=profile, elasticity=elasticity, friction=friction, compliance_ratio=ratio,
        normal=normal, tangential=tangential, normal_control=ncontrol,
        tangential_control=tcontrol, protocol=protocol, steps_per_cycle=steps,
        max_cycles=run.int("cycles", 5, ge=1, le=10000),
        n_sliders=run.int("sliders", 2000, ge=10, le=10_000_000),
        assembly_steps=run.int("assembly_steps", max(steps // 4, 10), ge=1),
        snapshots=np.atleast_1d(run.array("snapshots", [0.0, np.pi / 2, np.pi, 1.5 * np.pi],
                                          ge=0.0, le=2 * np.pi)),
        steady_tol=run.float("steady_tol", 1e-9, gt=0.0, lt=1.0),
        profile_name=sec.data["profile"],
    )
    case.finish()
    _check_physics(case, model)
    return model


def _check_physics(case: Case, model: HalfspaceModel) -> None:
    """Refuse loads the contact cannot carry (before any computation)."""
    lo, hi = model.normal_load_range()
    nk = "P" if model.normal_control == "force" else "U"
    if model.normal_control == "force":
        if hi <= 0:
            raise CaseError(f"loading.{nk}0", "the normal load never compresses the contact")
        if isinstance(model.profile, RoughExponential) and lo <= 0:
            raise CaseError(f"loading.{nk}1", f"a rough contact needs P > 0 throughout the "
                            f"cycle (minimum {lo:g} N)")
        if lo < 0:
            raise CaseError(f"loading.{nk}1", f"normal load becomes tensile (minimum {lo:g} N); "
                            "adhesion is not modelled")
        if isinstance(model.profile, Cylinder2D) and hi >= model.profile.max_load():
            raise CaseError("halfspace.reference_depth", "too shallow for the largest load: "
                            "the plane approach needs a < 2d/e")
    if isinstance(model.profile, Tabulated) and model.normal_control == "force" \
            and hi > model.profile.P[-1] * (1 + 1e-12):
        raise CaseError("halfspace.table_P", f"table ends at {model.profile.P[-1]:g} N but "
                        f"the loads reach {hi:g} N")


def run_case(case: Case) -> RunOutputs:
    """Validate, solve and package a half-space case."""
    from slipcycle.halfspace.outputs import package

    model = parse_case(case)
    bed, result = solve(model)
    return package(model, bed, result)
