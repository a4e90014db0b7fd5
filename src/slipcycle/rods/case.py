"""Case file → two-rod analysis → results (``model = "rods"``; docs/rods.md).

Keys of ``[rods]``: L, radius, E, nu, density (two values each: rod 1 clamped, rod 2
driven), friction, axial_force (F0, N; may also sit in [loading]), interface (welded |
distributed | coulomb | jenkins | iwan), interface_stiffness (k_t, N/m³), damping_ratio (ζ,
default 0.01), modes (per rod, default 50), rings (default 100), static_correction (default
true), iwan_chi / iwan_beta (optional: Segalman's χ ∈ (−1, 2] and β ≥ 0 instead of the fit;
the Iwan element's count of Jenkins elements is set by its accuracy target, see
:func:`slipcycle.rods.interfaces.segalman_density`).
Keys of ``[loading]``: rotation_amplitude (Θ_a, rad), frequency_ratio (Ω/ω1) or frequency
(Ω, rad/s), axial_amplitude (F_a, N, default 0), axial_phase (ψ, rad, default 0).
Keys of ``[run]``: steps_per_cycle (default 400), cycles (maximum, default 300), steady_tol
(default 1e-6), regularisation (bool, default true), regularisation_points (default 25).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from slipcycle.figure_task import figure_task
from slipcycle.io import Case, RunOutputs, Section
from slipcycle.io.case import read_friction
from slipcycle.io.sizes import MEMORY_LIMIT, check_memory, memory_limit
from slipcycle.result import STEADY_STATES, RunResult, classify
from slipcycle.rods.model import INTERFACES, Excitation, Rod, TwoRods

log = logging.getLogger("slipcycle")

__all__ = ["RodsCase", "RodsResult", "parse_case", "run_case", "solve_case", "solve_model",
           "analyse", "interface_bed", "RUN_UNITS", "RUN_FLAGS", "MEMORY_LIMIT"]



@dataclass
class RodsCase:
    """A validated two-rod case: system, excitation and solver settings.

    Built from a case file by :func:`parse_case` (every field checked there, the keys of
    docs/rods.md), or directly in Python (``examples/python_rods.py``); :func:`analyse`
    solves it. The fields are taken as given: ``frequency_ratio`` and ``omega1`` are
    reported, the solvers use ``exc.frequency``, so keep
    ``exc.frequency == frequency_ratio * omega1``.

    Parameters
    ----------
    rods : TwoRods
        The rods (lengths, radii, E, ν, ρ), friction f, interface law, tangential interface
        stiffness k_t (N/m³) and modal damping ratio ζ.
    exc : Excitation
        Drive rotation Θ_a sin Ωt (Θ_a rad, Ω rad/s) and axial force
        F0 + F_a sin(Ωt + ψ) (N, rad).
    frequency_ratio : float
        Ω/ω1 (dimensionless), reported in the summary.
    omega1 : float
        ω1, lowest torsional natural frequency of the welded system with both outer ends
        fixed (rad/s; :func:`slipcycle.rods.welded.omega1`), reported in the summary.
    modes : int
        Modes per rod of the modal model (≥ 0; :func:`slipcycle.rods.modal.modal_basis`).
    rings : int
        Rings of the ``distributed`` interface (≥ 1), also used by the rings model of the
        regularisation study.
    static_correction : bool
        Residual flexibility of the truncated modes (mode-acceleration correction).
    steps_per_cycle : int
        K, time steps per period of the dynamic and quasi-static runs.
    cycles : int
        Largest number of cycles of the dynamic run to reach the periodic steady state.
    steady_tol : float
        Relative cycle-to-cycle change at which the steady state is accepted.
    regularisation : bool
        Whether :func:`analyse` runs :func:`slipcycle.rods.regularisation.
        regularisation_study` (needs a finite k_t).
    regularisation_points : int
        Geometric amplitudes of that study (8 more are added in the rings' microslip range).
    iwan_chi : float, optional
        Segalman's exponent χ ∈ (−1, 2] of the ``iwan`` interface; None (with
        ``iwan_beta``): χ and β are fitted to the rings (:func:`slipcycle.rods.interfaces.
        fit_iwan`). Ignored by the other interfaces.
    iwan_beta : float, optional
        Segalman's β ≥ 0 (dimensionless), given together with ``iwan_chi``.

    References
    ----------
    Segalman, D. J. (2005). A four-parameter Iwan model for lap-type joints. J. Appl. Mech.
    72, 752–760 (χ, β).
    """

    rods: TwoRods
    exc: Excitation
    frequency_ratio: float
    omega1: float
    modes: int
    rings: int
    static_correction: bool
    steps_per_cycle: int
    cycles: int
    steady_tol: float
    regularisation: bool
    regularisation_points: int
    iwan_chi: float | None = None
    iwan_beta: float | None = None


def _either(sec: Section, other: Section, key: str, default, **bounds) -> tuple[float, Section]:
    """A key that may sit in either table; returns (value, the table it was read from)."""
    if sec.has(key) and other.has(key):
        raise sec.error(key, f"given in both [{sec.prefix}] and [{other.prefix}]; keep one")
    where = other if other.has(key) else sec
    return where.float(key, default, **bounds), where


def _run_bytes(modes: int, steps: int, rings: int) -> float:
    """Upper bound of one steady-state run's memory [bytes]: the periodic projection keeps
    dense (4m × 4m) monodromies of the 2m modes (the matrix, its K-th power, an LU and a few
    cached LUs), plus per-step histories and per-element states."""
    m4 = 4.0 * modes
    return 8.0 * (6.0 * m4 * m4 + 40.0 * steps + 8.0 * rings)


def parse_case(case: Case, *, finish: bool = True, limits: bool = False) -> RodsCase:
    """Validate a rods case completely (raises CaseError naming the key).

    ``limits=False`` (``slipcycle run``, sweeps) accepts a ``[limits]`` table unread;
    ``limits=True`` leaves it to :func:`slipcycle.studies.limits.parse_limits`.
    """
    from slipcycle.rods.welded import omega1

    sec = case.section("rods")
    load = case.section("loading")
    run = case.section("run", required=False)
    L = sec.array("L", shape=(2,), gt=0.0)
    r = sec.array("radius", shape=(2,), gt=0.0)
    E = sec.array("E", shape=(2,), gt=0.0)
    nu = sec.array("nu", shape=(2,), gt=-1.0, le=0.5)
    rho = sec.array("density", shape=(2,), gt=0.0)
    f = read_friction(sec, ge=0.0)
    iface = sec.string("interface", "distributed", choices=INTERFACES)
    kt = sec.float("interface_stiffness", None, gt=0.0)
    if kt is None and iface in ("distributed", "jenkins", "iwan"):
        raise sec.error("interface_stiffness", f"required for interface = {iface!r}")
    zeta = sec.float("damping_ratio", 0.01, ge=0.0, lt=1.0)
    modes = sec.int("modes", 50, ge=1, le=2000)
    rings = sec.int("rings", 100, ge=2, le=100000)
    static_corr = sec.bool("static_correction", True)
    chi = sec.float("iwan_chi", None, gt=-1.0, le=2.0)
    beta = sec.float("iwan_beta", None, ge=0.0)
    if (chi is None) != (beta is None):
        raise sec.error("iwan_beta" if beta is None else "iwan_chi",
                        "give both iwan_chi and iwan_beta, or neither (then they are fitted)")
    if chi is not None and iface != "iwan":
        raise sec.error("iwan_chi", f"only used with interface = 'iwan' (interface = "
                        f"{iface!r}); remove iwan_chi and iwan_beta")
    F0, f0_sec = _either(sec, load, "axial_force", None, ge=0.0)
    if F0 is None:
        raise sec.error("axial_force", "required key is missing (mean compressive force F0, N)")
    _check_frictional(iface, (sec, "friction", f), (f0_sec, "axial_force", F0))
    Fa = _either(sec, load, "axial_amplitude", 0.0, ge=0.0)[0]
    psi = _either(sec, load, "axial_phase", 0.0)[0]
    amp = load.float("rotation_amplitude", gt=0.0)
    has_r, has_w = load.has("frequency_ratio"), load.has("frequency")
    if has_r == has_w:
        raise load.error("frequency_ratio", "give exactly one of frequency_ratio (Ω/ω1) and "
                         "frequency (Ω, rad/s)")
    ratio = load.float("frequency_ratio", None, gt=0.0, le=1000.0)
    W = load.float("frequency", None, gt=0.0)
    K = run.int("steps_per_cycle", 400, ge=32, le=200000)
    cycles = run.int("cycles", 300, ge=1, le=100000)
    tol = run.float("steady_tol", 1e-6, gt=0.0, lt=1.0)
    reg = run.bool("regularisation", True)
    reg_pts = run.int("regularisation_points", 25, ge=8, le=400)
    if "limits" in case.data and not limits:  # read by `slipcycle limits` only
        case.section("limits").ignore()
    need = _run_bytes(modes, K, rings)
    if need > memory_limit():
        key = sec.key("modes") if 6.0 * (4.0 * modes) ** 2 * 8 > 0.5 * need else \
            run.key("steps_per_cycle")
        check_memory(key, need, f"{modes} modes per rod and {K} steps per cycle")
    if finish:
        case.finish()
    try:
        rods = TwoRods(Rod(L[0], r[0], E[0], nu[0], rho[0]), Rod(L[1], r[1], E[1], nu[1], rho[1]),
                       f, iface, kt if kt is not None else math.inf, zeta)
    except ValueError as exc:  # pragma: no cover - all checked above
        key, _, problem = str(exc).partition(": ")
        raise sec.error(key, problem) from None
    if reg and kt is None:
        reg = False  # no interface stiffness: the study needs the rings model
    w1 = omega1(rods)
    if ratio is None:
        ratio = W / w1
    else:
        W = ratio * w1
    exc = Excitation(amp, W, F0, Fa, psi)
    if zeta == 0.0 and not limits:  # `limits` marks poles instead
        _refuse_pole(rods, W, w1, load, "frequency_ratio" if has_r else "frequency")
    return RodsCase(rods, exc, ratio, w1, modes, rings, static_corr, K, cycles, tol, reg,
                    reg_pts, chi, beta)


def _check_frictional(iface: str, *keys) -> None:
    """A frictional interface needs f > 0 and F0 > 0 (each ``(section, key, value)``):
    otherwise its slip torque f N a is 0 and the rods are not coupled."""
    for sec, key, value in keys:
        if value <= 0.0 and iface != "welded":
            raise sec.error(key, f"must be > 0 for a frictional interface (interface = "
                            f"{iface!r}), got {value:g}")


def _refuse_pole(rods: TwoRods, W: float, w1: float, load: Section, key: str) -> None:
    """An undamped system driven at a pole has no steady state: for a welded interface at
    any natural frequency, for every other law where a mode carries no interface torque
    (:func:`~slipcycle.rods.welded.torque_free_frequencies`)."""
    from slipcycle.rods.welded import POLE_RTOL, natural_frequencies, torque_free_frequencies

    if rods.interface == "welded":
        poles = natural_frequencies(rods.with_(interface="welded"), int(W / w1 * 1.05) + 2)
        what = "a natural frequency of the welded, undamped system"
    else:
        poles = torque_free_frequencies(rods, W * (1.0 + 2 * POLE_RTOL))
        what = ("a natural frequency of both rods with the interface end free: the "
                "undamped mode carries no interface torque, so friction cannot bound it")
    hit = np.abs(W / poles - 1.0) <= POLE_RTOL
    if np.any(hit):
        r = float(poles[hit][0] / w1)
        raise load.error(key, f"Ω/ω1 = {W / w1:.9g} is {what} (pole at Ω/ω1 = {r:.9g}): "
                         "no steady state exists; give rods.damping_ratio > 0 or another "
                         "frequency")


def interface_bed(rc: RodsCase):
    """The interface law of a validated case: ``(Bed, SegalmanIwan or None)``.

    The one place that turns the case's interface keys into a bed, used by ``slipcycle
    run``, ``slipcycle limits`` and the Python API alike; an Iwan element uses the given
    ``iwan_chi``/``iwan_beta`` (else the fit to the rings) at the mean normal force F0.

    Parameters
    ----------
    rc : RodsCase
        The case; its ``rods.interface``, ``rings``, ``iwan_chi``, ``iwan_beta`` and the
        mean axial force ``exc.axial_force`` F0 (N) are used.

    Returns
    -------
    bed : Bed
        The interface as n Jenkins elements: stiffnesses ``kappa`` (n,) N m/rad and
        capacities per unit normal force ``cap_unit`` (n,) m (:func:`slipcycle.rods.
        interfaces.make_bed`; ``rings`` elements for ``distributed``, one for ``jenkins``,
        ``coulomb`` and ``welded``, the discretised element for ``iwan``).
    iwan : SegalmanIwan or None
        For ``iwan``: the element used, F_S = (2/3) f F0 a (N m), K_T = k_t J_a (N m/rad)
        with the given or fitted χ and β; None for every other interface.

    References
    ----------
    Segalman, D. J. (2005). A four-parameter Iwan model for lap-type joints. J. Appl. Mech.
    72, 752–760. Iwan, W. D. (1966). A distributed-element model for hysteresis and its
    steady-state dynamic response. J. Appl. Mech. 33, 893–900.
    """
    from slipcycle.rods.interfaces import SegalmanIwan, gross_slip_torque, iwan_bed, make_bed

    rods, N0 = rc.rods, rc.exc.axial_force
    if rods.interface != "iwan":
        return make_bed(rods, N0, rc.rings), None
    params = None
    if rc.iwan_chi is not None:
        params = SegalmanIwan(gross_slip_torque(rods.friction, N0, rods.contact_radius),
                              rods.interface_stiffness * rods.contact_J, rc.iwan_chi,
                              rc.iwan_beta)
    return iwan_bed(rods, N0, None, params)


def analyse(rc: RodsCase) -> dict:
    """Dynamic steady state, quasi-static loop, slip inception and regularisation study.

    Everything ``slipcycle run`` reports for a rods case (docs/rods.md): the periodic
    steady state of the modal model (:func:`slipcycle.rods.modal.steady_state`), the
    quasi-static loop of the massless rods (:func:`slipcycle.rods.quasistatic.
    quasi_static_loop`), both with the bed of :func:`interface_bed`, and the drive
    amplitudes at which the stuck interface starts to slip: the smallest Θ_a for which the
    stuck torque per unit Θ_a over the cycle (dynamic: the modal frequency response with
    the bed's stuck stiffness k0; quasi-static: sin Ωt/(C_r + 1/k0), C_r the rods'
    compliance) reaches the bed's first-slip torque at the normal force N(t) ≥ 0 (dynamic:
    the exact closed-contact axial response; quasi-static: F(t)).

    Parameters
    ----------
    rc : RodsCase
        The validated case (system, excitation, modes, rings, steps per cycle, cycle limit,
        tolerance, regularisation settings).

    Returns
    -------
    dict
        ``dyn`` : DynamicResult
            Last (steady) cycle of the dynamic run: t, Θ, T, δ, N histories of shape
            (K + 1,) (s, rad, N m, rad, N), friction dissipation, damping loss and input
            work per cycle (J), cycles run, ``converged``, residual.
        ``qs`` : DynamicResult
            The quasi-static loop, same fields.
        ``bed`` : Bed
            The interface bed (:func:`interface_bed`).
        ``basis`` : ModalBasis
            The modal model, ``rc.modes`` modes per rod.
        ``iwan`` : SegalmanIwan or None
            The Iwan element used (``iwan`` interface only).
        ``inception_dyn``, ``inception_qs`` : float
            Slip-inception drive amplitude Θ_a, dynamic and quasi-static (rad; inf if the
            interface never slips).
        ``natural`` : (5,) ndarray
            Lowest five torsional natural frequencies of the welded system with both outer
            ends fixed (rad/s).
        ``reg`` : RegularisationResult or None
            :func:`slipcycle.rods.regularisation.regularisation_study` (None when
            ``rc.regularisation`` is false).

    References
    ----------
    Nigam, N. C. & Jennings, P. C. (1969). Calculation of response spectra from
    strong-motion earthquake records. Bull. Seismol. Soc. Am. 59, 909–922 (the modal step).
    Graff, K. F. (1975). Wave Motion in Elastic Solids, §2.2 (torsional modes of rods).
    Johnson, K. L. (1985). Contact Mechanics, §7.3 (slip of a flat circular contact in
    torsion).
    """
    from slipcycle.rods.modal import modal_basis, modal_frf, steady_state
    from slipcycle.rods.quasistatic import (
        qs_normal_force,
        quasi_static_loop,
        slip_inception_amplitude,
    )
    from slipcycle.rods.regularisation import regularisation_study
    from slipcycle.rods.welded import natural_frequencies, normal_force_history

    rods, exc = rc.rods, rc.exc
    bed, iw = interface_bed(rc)
    basis = modal_basis(rods, rc.modes, rc.static_correction)
    dyn = steady_state(rods, exc, bed, basis, rc.steps_per_cycle, rc.cycles, rc.steady_tol)
    qs = quasi_static_loop(rods, exc, bed, rc.steps_per_cycle)
    # slip inception: stuck response per unit amplitude against the first-slip torque(t)
    K = rc.steps_per_cycle
    tt = np.arange(K) * exc.period / K
    Tdyn_unit = np.real(modal_frf(basis, exc.frequency, bed.stiffness) * (-1j)
                        * np.exp(1j * exc.frequency * tt))
    k0 = bed.stiffness
    C_qs = rods.rods_compliance + (1.0 / k0 if math.isfinite(k0) else 0.0)
    Tqs_unit = np.sin(exc.frequency * tt) / C_qs
    fs_unit = bed.first_slip_torque(1.0)
    N_dyn = np.maximum(normal_force_history(rods, exc, tt), 0.0)
    N_qs = np.maximum(qs_normal_force(exc, tt), 0.0)
    inc_dyn = slip_inception_amplitude(Tdyn_unit, fs_unit * N_dyn)
    inc_qs = slip_inception_amplitude(Tqs_unit, fs_unit * N_qs)
    nat = natural_frequencies(rods.with_(interface="welded"), 5)
    reg = None
    if rc.regularisation:
        reg = regularisation_study(rods, exc, rc.rings, iw, rc.regularisation_points,
                                   rc.steps_per_cycle)
    return {"dyn": dyn, "qs": qs, "bed": bed, "basis": basis, "iwan": iw,
            "inception_dyn": inc_dyn, "inception_qs": inc_qs, "natural": nat, "reg": reg}


_REG_UNITS = {f"regularisation.{m}.{k}": "1" for m in ("distributed", "jenkins", "coulomb",
                                                      "iwan")
              for k in ("slope_microslip", "slope_macroslip")}

#: unit of every numeric entry of the `slipcycle run` summary (nested entries dotted)
RUN_UNITS = {
    "omega1": "rad/s", "omega1_hz": "Hz", "natural_frequencies": "rad/s",
    "frequency": "rad/s", "frequency_ratio": "1", "rotation_amplitude": "rad",
    "T_dyn_max": "N m", "T_qs_max": "N m", "torque_ratio": "1",
    "dissipation_per_cycle": "J", "dissipation_per_cycle_qs": "J", "dissipation_ratio": "1",
    "damping_loss_per_cycle": "J", "input_work_per_cycle": "J", "energy_balance_error": "1",
    "slip_inception_amplitude_dyn": "rad", "slip_inception_amplitude_qs": "rad",
    "slip_inception_torque": "N m", "gross_slip_torque": "N m", "slipped": "1",
    "separation": "1", "min_normal_force": "N", "steady_state_reached": "1",
    "cycles_run": "1", "steady_residual": "1", "modes_per_rod": "1", "rings": "1",
    "iwan.F_S": "N m", "iwan.K_T": "N m/rad", "iwan.chi": "1", "iwan.beta": "1",
    "iwan.elements": "1", **_REG_UNITS,
    "regularisation.iwan_fit.F_S": "N m", "regularisation.iwan_fit.K_T": "N m/rad",
    "regularisation.iwan_fit.chi": "1", "regularisation.iwan_fit.beta": "1",
}

#: every word of the categorical entries of the `slipcycle run` summary
RUN_FLAGS = {"model": ("rods",), "interface": INTERFACES,
             "steady_state_class": STEADY_STATES}


def _none_if_inf(x: float):
    return None if not math.isfinite(x) else float(x)


def _energy_balance_error(dyn, amplitude: float) -> float:
    """(W_in − D − D_damp)/|W_in| over the steady cycle [1]; 0 when all three energies are
    within round-off of zero (a stuck, undamped cycle: 0/0, nothing to balance).

    Round-off of a cycle's work is relative to T_max Θa (J), the work scale of the cycle.
    """
    terms = (abs(dyn.input_work), abs(dyn.dissipation), abs(dyn.damping_loss))
    if max(terms) <= 1e-9 * dyn.T_max * amplitude:
        return 0.0
    return (dyn.input_work - dyn.dissipation - dyn.damping_loss) / max(terms[0], 1e-300)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class RodsResult(RunResult):
    """Result of a two-rod run: the shared vocabulary of :class:`~slipcycle.result.RunResult`
    over the validated case and the analyses of :func:`analyse`.

    ``steady_state``: ``shakedown`` (periodic state reached, the interface does not slip:
    detail ``stuck``), ``cyclic_slip`` (periodic state with slip every cycle: detail
    ``slipping``) or ``not_converged``. ``dissipation_per_cycle`` [J], ``cycles_run`` and
    ``residual`` are those of the dynamic steady state.

    Attributes
    ----------
    case : RodsCase
        The validated rods, excitation and run settings.
    analysis : dict
        The output of :func:`analyse` (``dyn``, ``qs``, ``bed``, ``iwan``,
        ``inception_dyn``, ``inception_qs``, ``natural``, ``reg``).
    """

    model: ClassVar[str] = "rods"

    case: RodsCase
    analysis: dict

    @classmethod
    def from_analysis(cls, rc: RodsCase, res: dict) -> RodsResult:
        """Wrap the output of :func:`analyse`.

        Parameters
        ----------
        rc : RodsCase
        res : dict

        Returns
        -------
        RodsResult
        """
        dyn = res["dyn"]
        state = classify(converged=bool(dyn.converged), slips=bool(dyn.slipped))
        detail = ("not_converged" if not dyn.converged
                  else "slipping" if dyn.slipped else "stuck")
        if dyn.converged:
            msg = (f"periodic steady state after {dyn.cycles} cycles; the interface "
                   + ("slips" if dyn.slipped else "sticks"))
        else:
            msg = (f"no periodic steady state within {dyn.cycles} cycles (residual "
                   f"{dyn.residual:.3g})")
            if rc.rods.damping_ratio == 0.0 and dyn.slipped:
                # nothing but slip removes energy: the free vibration that slip leaves in
                # the rods need not settle into a cycle (docs/rods.md, undamped resonance)
                msg += ("; undamped (rods.damping_ratio = 0): the vibration left by slip "
                        "does not decay, give rods.damping_ratio > 0")
                log.warning("rods: %s", msg)
        return cls(steady_state=state, steady_state_detail=detail,
                   dissipation_per_cycle=float(dyn.dissipation), cycles_run=int(dyn.cycles),
                   residual=float(dyn.residual), converged=bool(dyn.converged), message=msg,
                   case=rc, analysis=res)

    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word of the categorical summary entries (:data:`RUN_FLAGS`)."""
        return dict(RUN_FLAGS)

    def summary(self) -> dict:
        """The ``slipcycle run`` summary (keys in docs/rods.md), with ``units``."""
        rc, res = self.case, self.analysis
        rods, exc, dyn, qs = rc.rods, rc.exc, res["dyn"], res["qs"]
        N0 = exc.axial_force
        sep = bool(np.min(dyn.N) < 0.0)
        summary = {
            "model": "rods",
            "interface": rods.interface,
            "omega1": rc.omega1,
            "omega1_hz": rc.omega1 / (2 * math.pi),
            "natural_frequencies": res["natural"],
            "frequency": exc.frequency,
            "frequency_ratio": rc.frequency_ratio,
            "rotation_amplitude": exc.rotation_amplitude,
            "T_dyn_max": dyn.T_max,
            "T_qs_max": qs.T_max,
            # None where both torques underflow to 0 (a subnormal amplitude): 0/0
            "torque_ratio": dyn.T_max / qs.T_max if qs.T_max > 0 else None,
            "dissipation_per_cycle": dyn.dissipation,
            "dissipation_per_cycle_qs": qs.dissipation,
            "dissipation_ratio": (dyn.dissipation / qs.dissipation if qs.dissipation > 0 else None),
            "damping_loss_per_cycle": dyn.damping_loss,
            "input_work_per_cycle": dyn.input_work,
            "energy_balance_error": _energy_balance_error(dyn, exc.rotation_amplitude),
            "slip_inception_amplitude_dyn": _none_if_inf(res["inception_dyn"]),
            "slip_inception_amplitude_qs": _none_if_inf(res["inception_qs"]),
            "slip_inception_torque": _none_if_inf(res["bed"].first_slip_torque(N0)),
            "gross_slip_torque": _none_if_inf(res["bed"].capacity(N0)),
            "slipped": dyn.slipped,
            "separation": sep,
            "min_normal_force": float(np.min(dyn.N)),
            "steady_state_reached": dyn.converged,
            "steady_state_class": self.steady_state.value,
            "cycles_run": dyn.cycles,
            "steady_residual": dyn.residual,
            "modes_per_rod": rc.modes,
            "rings": rc.rings if rods.interface == "distributed" else None,
        }
        if res["iwan"] is not None:
            iw = res["iwan"]
            summary["iwan"] = {"F_S": iw.F_S, "K_T": iw.K_T, "chi": iw.chi, "beta": iw.beta,
                               "elements": res["bed"].size}
        reg = res["reg"]
        if reg is not None:
            summary["regularisation"] = reg.slopes()
            summary["regularisation"]["iwan_fit"] = reg.iwan_params
        summary["units"] = {k: v for k, v in RUN_UNITS.items()
                            if k.split(".")[0] in summary}
        # the shared entries (residual, converged, wall_time_s); steady_residual and
        # steady_state_reached are their aliases, kept for one release
        return self.with_shared(summary)

    def _build_dataset(self):
        """Dynamic and quasi-static loops over the last cycle (dimension ``time``), their
        dissipation per cycle and, with the regularisation study, its amplitude sweep
        (units on every variable)."""
        import xarray as xr

        dyn, qs, reg = self.analysis["dyn"], self.analysis["qs"], self.analysis["reg"]
        tatt = {"units": "s"}
        ds = xr.Dataset(
            {"theta": ("time", dyn.theta, {"units": "rad", "long_name": "drive rotation"}),
             "T_dyn": ("time", dyn.T, {"units": "N m", "long_name": "interface torque, dynamic"}),
             "delta_dyn": ("time", dyn.delta, {"units": "rad",
                                                "long_name": "interface relative rotation"}),
             "N": ("time", dyn.N, {"units": "N", "long_name": "normal force (closed contact)"}),
             "T_qs": ("time", qs.T, {"units": "N m",
                                     "long_name": "interface torque, quasi-static"}),
             "delta_qs": ("time", qs.delta, {"units": "rad"}),
             # the headline numbers of the summary, so that the file alone answers them
             "dissipation_per_cycle": ((), dyn.dissipation, {
                 "units": "J", "long_name": "interface dissipation per cycle, dynamic"}),
             "dissipation_per_cycle_qs": ((), qs.dissipation, {
                 "units": "J", "long_name": "interface dissipation per cycle, quasi-static"})},
            coords={"time": ("time", dyn.t, tatt)})
        if reg is not None:
            sweep = reg.to_dataset()  # the study's own Dataset: amplitude, reg_T_*, reg_D_*
            ds = ds.assign_coords(amplitude=sweep["amplitude"])
            for name in sweep.data_vars:
                ds[name] = sweep[name]
        return ds

    def figures(self, dataset=None) -> dict:
        """``hysteresis``, ``time_history`` and, with the study, ``regularisation``."""
        ds = self.to_dataset() if dataset is None else dataset
        reg = self.analysis["reg"]
        # plot functions named by string: picklable, so drawn by the CLI's workers
        figures = {"hysteresis": figure_task("slipcycle.plot.rods:hysteresis", ds),
                   "time_history": figure_task("slipcycle.plot.rods:time_history", ds)}
        if reg is not None:
            figures.update(reg.figures())
        return figures


def solve_model(rc: RodsCase) -> RodsResult:
    """Run the analyses of a validated rods case (:func:`analyse`).

    Parameters
    ----------
    rc : RodsCase

    Returns
    -------
    RodsResult
    """
    if not isinstance(rc, RodsCase):
        raise TypeError(f"expected a RodsCase, got {type(rc).__name__}")
    return RodsResult.from_analysis(rc, analyse(rc))


def solve_case(case: Case) -> RodsResult:
    """Validate a rods case completely (CaseError naming the key), then solve it.

    Parameters
    ----------
    case : Case
        A ``model = "rods"`` case.

    Returns
    -------
    RodsResult
    """
    return solve_model(parse_case(case))


def run_case(case: Case) -> RunOutputs:
    """Validate, solve and package a rods case (``solve_case(case).to_outputs()``)."""
    return solve_case(case).to_outputs()
