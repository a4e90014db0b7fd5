"""Case file → :class:`HalfspaceModel` → results (``model = "halfspace"``, §6).

Keys of ``[halfspace]``:
  profile            sphere | cylinder | flat_punch | power_law | rough_exponential | tabulated
                     | topography
  radius             sphere/cylinder radius, punch radius (m)
  coefficient, exponent   power law z = c rⁿ (c in m^(1−n))
  gamma_sigma        γσ of the rough law dP/dU = P/(γσ) (m)
  table_U, table_P   tabulated P(U) pairs (m, N), convex, starting at P = 0; or
  table_file         CSV (header with columns U, P) or netCDF (variables U, P) of them
  topography_file    profile = "topography": a height map (any SurfaceTopography format)
                     pressed by a BEM into P(U) (:mod:`~slipcycle.halfspace.topography`),
                     with nominal_area (m²), fit ("table" | "exponential"), bem_grid,
                     bem_loads, fit_tolerance, short_cutoff, long_cutoff (m)
  reference_depth    cylinder: depth of the displacement reference point (m, default radius)
  E, nu              Young's moduli (Pa) and Poisson's ratios of both bodies, or
  contact_modulus    E* (Pa) directly
  compliance_ratio   λ_c (default 1 in 2-D, (2 − ν)/(2(1 − ν)) in 3-D)
  friction           f
Keys of ``[loading]``: P0, P1, P1_phase, Q0, Q1, phase with
  P = P0 + λP1 cos(θ − P1_phase), Q = Q0 + λQ1 cos(θ − phase) (lags; the convention is in
  :mod:`slipcycle.loading.periodic`, the Python twin :func:`~slipcycle.halfspace.contact_loads`);
  P1/Q1 may be lists over harmonics h = 1, 2, … with P1_phase/phase lists; U0, U1
  (approach control) instead of P0, P1; V0, V1 (displacement control) instead of Q0, Q1;
  lam (λ, default 1); or a table: theta, P (or U), Q (or V); ``[[loading.protocol]]``
  assembly states with P (or U) and Q (or V).
Keys of ``[run]``: cycles, steps_per_cycle, sliders, assembly_steps, snapshots, steady_tol.
"""

from __future__ import annotations

import numpy as np

from slipcycle.errors import InputError
from slipcycle.halfspace.elastic import ContactElasticity
from slipcycle.halfspace.loads import contact_loads
from slipcycle.halfspace.model import HalfspaceModel, LoadPathError, solve
from slipcycle.halfspace.outputs import HalfspaceResult
from slipcycle.halfspace.profiles import (
    Cylinder2D,
    FlatPunch,
    PowerLaw,
    RoughExponential,
    Tabulated,
    sphere,
)
from slipcycle.halfspace.topography import (
    TopographySource,
    read_source,
    read_table_file,
    topography_profile,
)
from slipcycle.io import Case, CaseError, RunOutputs, Section
from slipcycle.io.case import read_friction
from slipcycle.io.sizes import check_memory as check
from slipcycle.io.sizes import memory_limit
from slipcycle.loading import TabulatedLoad

__all__ = ["parse_case", "run_case", "solve_case", "solve_model"]

PROFILES = ("sphere", "cylinder", "flat_punch", "power_law", "rough_exponential", "tabulated",
            "topography")


def _elasticity(sec: Section, plane: bool) -> ContactElasticity:
    ratio = sec.float("compliance_ratio", None)
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


def _rough_compliance_ratio(sec: Section) -> float:
    """λ_c of a ``rough_exponential`` profile from E and ν (3-D).

    The same combination as every other profile (:meth:`ContactElasticity.from_materials`:
    E*/(4G*), Mindlin 1949). Without E it is (2 − ν)/(2(1 − ν)), which does not depend on
    the moduli when both ν are equal; dissimilar ν need E.
    """
    nu = sec.array("nu", None, shape=(2,), gt=-1.0, le=0.5)
    if nu is None:
        raise sec.error("compliance_ratio", "required for rough_exponential unless nu "
                        "(and E for dissimilar materials) is given")
    E = sec.array("E", None, shape=(2,), gt=0.0)
    if E is None:
        if nu[0] != nu[1]:
            raise sec.error("E", "required with dissimilar nu: λ_c = E*/(4G*) of two "
                            "materials depends on their moduli")
        E = np.ones(2)   # equal ν: E*/(4G*) = (2 − ν)/(2(1 − ν)) whatever the moduli
    return ContactElasticity.from_materials(tuple(E), tuple(nu), plane=False).compliance_ratio


def _profile(sec: Section):
    name = sec.string("profile", choices=PROFILES)
    if name in ("rough_exponential", "tabulated"):
        ratio = sec.float("compliance_ratio", None)
        if name == "rough_exponential":
            prof = RoughExponential(sec.float("gamma_sigma", gt=0.0))
            for key in ("E", "nu"):
                if ratio is not None and sec.has(key):
                    raise sec.error(key, "not used by a rough_exponential profile when "
                                    "compliance_ratio is given (E and nu only set λ_c)")
            if ratio is None:
                ratio = _rough_compliance_ratio(sec)
        else:
            if sec.has("table_file"):   # columns U [m], P [N] (CSV or netCDF)
                if sec.has("table_U") or sec.has("table_P"):
                    raise sec.error("table_file", "give either table_file or table_U and "
                                    "table_P, not both")
                ukey = pkey = "table_file"
                try:
                    U, P = read_table_file(sec.path("table_file"))
                except InputError as exc:
                    raise sec.error("table_file", exc.problem) from None
            else:
                ukey, pkey = "table_U", "table_P"
                U = sec.array("table_U", shape=(None,))
                P = sec.array("table_P", shape=(None,), ge=0.0)
            if np.any(P < 0):
                raise sec.error(pkey, "loads P must be >= 0")
            if U.size < 2 or U.size != P.size:
                raise sec.error(pkey, f"needs as many values as table_U (>= 2), got "
                                f"{P.size} and {U.size}")
            if np.any(np.diff(U) <= 0):
                raise sec.error(ukey, "must increase strictly")
            if P[0] != 0.0:
                raise sec.error(pkey, "must start at 0 (first touch)")
            slopes = np.diff(P) / np.diff(U)
            if np.any(slopes <= 0) or np.any(np.diff(slopes) < -1e-12 * slopes.max()):
                raise sec.error(pkey, "P(U) must increase with non-decreasing slope "
                                "(a convex normal law; otherwise no slider bed exists)")
            prof = Tabulated(U, P)
            if ratio is None:
                raise sec.error("compliance_ratio", "required for a tabulated profile")
        return prof, None, ratio
    plane = name == "cylinder"
    el = _elasticity(sec, plane)
    if name == "topography":   # BEM law of a measured surface, computed by parse_case
        return read_source(sec, el.contact_modulus), el, el.compliance_ratio
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


def _harmonic_keys(sec: Section, mean_key: str, amp_key: str, phase_key: str
                   ) -> tuple[float, np.ndarray, np.ndarray]:
    """(mean, amplitudes (H,), lags (H,)) of one load component, validated."""
    mean = sec.float(mean_key, 0.0)
    amp = np.atleast_1d(sec.array(amp_key, 0.0))
    if amp.ndim != 1:
        raise sec.error(amp_key, "must be a number or a list over harmonics")
    ph = np.atleast_1d(sec.array(phase_key, 0.0))
    if ph.ndim != 1 or ph.size not in (1, amp.size):
        raise sec.error(phase_key, f"needs 1 or {amp.size} values (one per harmonic)")
    return mean, amp, ph


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
        # the meaning of every key is that of contact_loads (lags; loading/periodic.py)
        P0, P1, P1_phase = _harmonic_keys(sec, f"{nk}0", f"{nk}1", f"{nk}1_phase")
        Q0, Q1, phase = _harmonic_keys(sec, f"{tk}0", f"{tk}1", "phase")
        normal, tangential = contact_loads(P0, P1, Q0, Q1, phase, P1_phase, lam)
    protocol = []
    for st in sec.tables("protocol", None):
        protocol.append([st.float(nk), st.float(tk, 0.0)])
        st.finish()
    return (normal, tangential, "force" if normal_force else "approach",
            "force" if tang_force else "displacement", np.array(protocol).reshape(-1, 2))


#: keys of [halfspace] that only some profiles read
PROFILE_KEYS = {
    "sphere": {"radius", "E", "nu", "contact_modulus", "compliance_ratio"},
    "cylinder": {"radius", "E", "nu", "contact_modulus", "compliance_ratio", "reference_depth"},
    "flat_punch": {"radius", "E", "nu", "contact_modulus", "compliance_ratio"},
    "power_law": {"coefficient", "exponent", "E", "nu", "contact_modulus", "compliance_ratio"},
    "rough_exponential": {"gamma_sigma", "compliance_ratio", "nu", "E"},
    "tabulated": {"table_U", "table_P", "table_file", "compliance_ratio"},
    "topography": {"topography_file", "nominal_area", "fit", "bem_grid", "bem_loads",
                   "fit_tolerance", "short_cutoff", "long_cutoff", "fill_undefined",
                   "topography_size", "E", "nu",
                   "contact_modulus", "compliance_ratio"},
}

_DEFAULT_SLIDERS = 2000
_DEFAULT_STEPS = 400


def parse_case(case: Case) -> HalfspaceModel:
    """Validate a ``halfspace`` case completely (raises CaseError) and build the model.

    The reader converts the TOML values; the values themselves are checked by
    :class:`HalfspaceModel` (and its load path by :meth:`HalfspaceModel.check_loads`),
    whose errors come out under the case-file key of the field (``_MODEL_KEYS``).
    """
    if "halfspace" not in case.data and "map" in case.data:
        raise CaseError("map", "this is a Ŵ map case: run it with `slipcycle map` (`slipcycle "
                        "run` needs a [halfspace] table)")
    sec = case.section("halfspace")
    profile, elasticity, ratio = _profile(sec)
    name = sec.data["profile"]
    for key in sorted(set(sec.data) - PROFILE_KEYS[name] - {"profile", "friction"}):
        users = sorted(p for p, keys in PROFILE_KEYS.items() if key in keys)
        if users:
            raise sec.error(key, f"not used by profile = {name!r} (only by "
                            f"{', '.join(users)})")
    friction = read_friction(sec)
    normal, tangential, ncontrol, tcontrol, protocol = _loading(case.section("loading"))
    run = case.section("run", required=False)
    steps = run.int("steps_per_cycle", _DEFAULT_STEPS)
    settings = dict(
        profile=profile, elasticity=elasticity, friction=friction, compliance_ratio=ratio,
        normal=normal, tangential=tangential, normal_control=ncontrol,
        tangential_control=tcontrol, protocol=protocol, steps_per_cycle=steps,
        # the model takes any number of cycles; a case file at most 10000
        max_cycles=run.int("cycles", 5, le=10000),
        n_sliders=run.int("sliders", _DEFAULT_SLIDERS),
        assembly_steps=run.int("assembly_steps", max(steps // 4, 10)),
        snapshots=run.values("snapshots", [0.0, np.pi / 2, np.pi, 1.5 * np.pi]),
        steady_tol=run.float("steady_tol", 1e-9),
        profile_name=name,
    )
    if isinstance(profile, TopographySource):   # the BEM runs once every key is valid
        for table in ("map", "roughness"):   # tables that other commands read
            if table in case.data:
                case.section(table).ignore()
        case.finish()
        law = topography_profile(sec, profile, normal, ncontrol, protocol, steps,
                                 settings["n_sliders"])
        settings.update(profile_name="", profile=law, surface=profile.describe(law))
    try:
        model = HalfspaceModel(**settings)
    except InputError as exc:
        raise CaseError(_MODEL_KEYS.get(exc.key, exc.key), exc.problem) from None
    if "map" in case.data:   # a run case may carry its Ŵ map (slipcycle map reads it)
        case.section("map").ignore()
    if "roughness" in case.data:   # ... and its roughness study (slipcycle roughness)
        case.section("roughness").ignore()
    case.finish()
    check_memory(model)
    try:
        model.check_loads()
    except LoadPathError as exc:
        raise CaseError(_load_path_key(model, exc), exc.problem) from None
    return model


#: the case-file key of each field of :class:`HalfspaceModel` (its checks are the model's)
_MODEL_KEYS = {
    "profile": "halfspace.profile", "elasticity": "halfspace", "friction": "halfspace.friction",
    "compliance_ratio": "halfspace.compliance_ratio", "normal": "loading",
    "tangential": "loading", "normal_control": "loading", "tangential_control": "loading",
    "protocol": "loading.protocol", "steps_per_cycle": "run.steps_per_cycle",
    "max_cycles": "run.cycles", "n_sliders": "run.sliders",
    "assembly_steps": "run.assembly_steps", "snapshots": "run.snapshots",
    "steady_tol": "run.steady_tol",
}


def _load_path_key(model: HalfspaceModel, exc: LoadPathError) -> str:
    """The case-file key to blame for a load path the model refuses
    (:meth:`HalfspaceModel.check_loads`).

    A harmonic normal load that never compresses the contact blames its mean (``P0``), one
    that becomes tensile its amplitude (``P1``); a tabulated one its table (``P``); an
    assembly state i its normal value (``loading.protocol[i].P``).
    """
    nk = "P" if model.normal_control == "force" else "U"
    if isinstance(model.normal, TabulatedLoad):
        normal = f"loading.{nk}"
    else:
        mean = float(np.ravel(getattr(model.normal, "mean", [1.0]))[0])
        # a mean that is not compressive itself is the key at fault, else the amplitude
        low_mean = exc.reason == "never_compressive" or (
            exc.reason in ("rough_unloaded", "tensile") and mean <= 0)
        normal = f"loading.{nk}0" if low_mean else f"loading.{nk}1"
    if exc.key.startswith("protocol["):
        return f"loading.{exc.key}.{nk}"
    # the key that sizes the profile: a power law's coefficient, else the radius
    size = "halfspace.coefficient" if model.profile_name == "power_law" else "halfspace.radius"
    return {"normal": normal, "profile.reference_depth": "halfspace.reference_depth",
            "profile": "halfspace.table_P", "profile.size": size}.get(exc.key, exc.key)


def memory_estimate(model: HalfspaceModel) -> float:
    """Bytes a run of ``model`` needs at its peak (order of magnitude).

    Per slider: the last cycle's forces and slips, recorded and stacked (32 B per step),
    the bed table (~1 kB) and, for axisymmetric profiles, the Abel operators on 200 radii
    (~16 kB). Per step of the history: ~100 B (U, V, P, Q, θ, cycle, stick load and their
    Dataset copies).
    """
    n, S = model.n_sliders + 1, model.steps_per_cycle
    per_slider = 32.0 * (S + 1) + 1e3 + (16e3 if model.profile.axisymmetric else 0.0)
    n_steps = model.assembly_steps * (model.protocol.shape[0] + 2) + model.max_cycles * S
    return n * per_slider + 100.0 * n_steps


def check_memory(model: HalfspaceModel, limit: float | None = None) -> None:
    """Refuse (CaseError naming the key that asks most) runs that would not fit in memory."""
    need = memory_estimate(model)
    if need <= (memory_limit() if limit is None else limit):
        return
    ratios = {
        "run.sliders": (model.n_sliders / _DEFAULT_SLIDERS, f"{model.n_sliders} sliders"),
        "run.steps_per_cycle": (model.steps_per_cycle / _DEFAULT_STEPS,
                                f"{model.steps_per_cycle} steps per cycle"),
        "run.assembly_steps": (model.assembly_steps / 100, f"{model.assembly_steps} "
                               "assembly steps"),
        "run.cycles": (model.max_cycles / 5, f"{model.max_cycles} cycles"),
    }
    key = max(ratios, key=lambda k: ratios[k][0])
    check(key, need, ratios[key][1], limit, advice=f"reduce {key.split('.')[1]}")


def solve_model(model: HalfspaceModel):
    """Solve a validated half-space model into its result object.

    Parameters
    ----------
    model : HalfspaceModel
        A model built in Python or by :func:`parse_case`.

    Returns
    -------
    HalfspaceResult
        The shared result vocabulary (:class:`~slipcycle.result.RunResult`) over the bed
        and history of :func:`~slipcycle.halfspace.model.solve`.
    """
    if not isinstance(model, HalfspaceModel):
        raise TypeError(f"expected a HalfspaceModel, got {type(model).__name__}")
    return HalfspaceResult.from_solution(model, *solve(model))


def solve_case(case: Case):
    """Validate a half-space case completely, then solve it.

    Parameters
    ----------
    case : Case
        A ``model = "halfspace"`` case.

    Returns
    -------
    HalfspaceResult

    Raises
    ------
    CaseError
        Naming the offending key, before any computation.
    """
    return solve_model(parse_case(case))


def run_case(case: Case) -> RunOutputs:
    """Validate, solve and package a half-space case (``solve_case(case).to_outputs()``)."""
    return solve_case(case).to_outputs()
