"""Limits of the quasi-static analysis: limit frequency and regime maps.

For a drive amplitude Θ_a and frequency Ω the dynamic steady state (modal model) and the
quasi-static loop (massless rods, same interface) give the maximum interface torques
T_dyn, T_qs and the dissipation per cycle D_dyn, D_qs. The *limit frequency* is the largest
Ω/ω1 below which |T_dyn/T_qs − 1| ≤ ε on the whole frequency axis from its start (first
crossing, located by bisection in log Ω); the same is reported separately for the
dissipation. The maps evaluate both ratios over Ω/ω1 × amplitude and over Ω/ω1 × interface
position L1/(L1 + L2) (total length and everything else fixed; each geometry uses its own ω1).

Every point is computed exactly as ``slipcycle run`` computes its one point (same interface
bed from :func:`slipcycle.rods.case.interface_bed`, same steps, cycle limit and tolerance),
so a number read off the limit curve equals the one ``slipcycle run`` reports at that
frequency. Each point's steady state is :func:`slipcycle.rods.modal.steady_state`: cycling
from the stuck linear steady state with a periodic projection (per frequency, one
:class:`~slipcycle.rods.modal.Propagator` serves every amplitude: step coefficients and the
Fourier form of the scheme's periodic response), and, where cycling would still need many
cycles, semismooth Newton on the periodic problem (:mod:`slipcycle.rods.periodic`), whose
solution one ordinary cycle must verify. A point that reaches no verified periodic state
within the cycle limit is flagged ``converged = False``.

Undamped resonance. With ζ = 0 and a welded interface the system is linear and lossless:
at a natural frequency of the welded system (both outer ends fixed) the steady response is
unbounded — a pole. Such points are not computed; they are flagged (``pole``), their ratios
are NaN (masked in figures, never passed to the bisection) and the pole frequencies are
listed in the summary. A frictional interface can slip and dissipate, so it is solved at
every frequency; a point that does not reach a periodic state is flagged ``converged =
False``. Natural frequencies by transfer matrices: Graff, *Wave Motion in Elastic
Solids* (1975), §2.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from slipcycle.io.results import RunOutputs
from slipcycle.io.sizes import check_memory
from slipcycle.result import StudyResult
from slipcycle.rods.case import interface_bed, parse_case
from slipcycle.rods.interfaces import Bed, Welded, gross_slip_torque, interface_law
from slipcycle.rods.modal import ModalBasis, Propagator, modal_basis, steady_state
from slipcycle.rods.model import Excitation, TwoRods
from slipcycle.rods.quasistatic import quasi_static_loop
from slipcycle.rods.welded import POLE_RTOL, natural_frequencies, omega1

__all__ = ["Study", "Point", "limit_frequency", "regime_map", "position_map",
           "gross_slip_amplitude", "LimitsCase", "parse_limits", "run_limits", "limits_study",
           "LimitsResult", "make_study",
           "POLE_RTOL", "LIMITS_UNITS", "LIMITS_FLAGS"]


#: bytes per map point kept until the figures are written (arrays, Dataset, figure mesh)
_MAP_POINT_BYTES = 400.0


@dataclass(frozen=True)
class Point:
    """One (Ω, Θ_a) point: dynamic and quasi-static maxima and losses.

    Attributes
    ----------
    T_dyn, T_qs : float
        Maximum interface torque, dynamic (over the last cycle run, also when it did not
        converge) and quasi-static (N m); NaN at a pole or when non-finite.
    D_dyn, D_qs : float
        Friction dissipation per cycle, dynamic and quasi-static (J); likewise.
    converged : bool
        Periodic steady state reached (False at a pole).
    pole : bool
        Ω is an undamped natural frequency of the welded system (no steady state).
    """

    T_dyn: float
    T_qs: float
    D_dyn: float
    D_qs: float
    converged: bool
    pole: bool = False

    @property
    def torque_ratio(self) -> float:
        return self.T_dyn / self.T_qs if self.T_qs > 0 else math.nan

    @property
    def dissipation_ratio(self) -> float:
        """D_dyn/D_qs; NaN when the quasi-static loop does not dissipate."""
        return self.D_dyn / self.D_qs if self.D_qs > 0 else math.nan


@dataclass
class Study:
    """One system and the numerical settings shared by every point of a sweep.

    Caches what the points share (ω1, pole frequencies, the quasi-static loop per
    amplitude, the modal propagator of the last frequency); :meth:`solve` gives one point.

    Parameters
    ----------
    rods : TwoRods
        The two rods and their interface.
    exc : Excitation
        Drive: rotation amplitude Θa [rad], frequency Ω [rad/s] (set per point) and
        axial force N [N].
    bed : Bed
        Interface bed of Jenkins elements (:func:`slipcycle.rods.case.interface_bed`).
    basis : ModalBasis
        Modal basis of the rods (:func:`~slipcycle.rods.modal.modal_basis`).
    steps_per_cycle : int
        Time steps per load cycle.
    max_cycles : int
        Cycles allowed to reach the periodic steady state.
    tol : float
        Relative steadiness tolerance of the dynamic steady state [1].
    """

    rods: TwoRods
    exc: Excitation
    bed: Bed
    basis: ModalBasis
    steps_per_cycle: int = 400
    max_cycles: int = 300
    tol: float = 1e-6
    _props: dict = field(default_factory=dict)
    _qs: dict = field(default_factory=dict)

    @property
    def omega1(self) -> float:
        if "w1" not in self._qs:
            self._qs["w1"] = omega1(self.rods)
        return self._qs["w1"]

    @property
    def undamped_welded(self) -> bool:
        return self.rods.damping_ratio == 0.0 and not self.bed.is_frictional

    def poles(self, max_ratio: float) -> np.ndarray:
        """Pole frequency ratios Ω/ω1 ≤ max_ratio (empty unless welded and undamped)."""
        if not self.undamped_welded:
            return np.zeros(0)
        key = ("poles", max_ratio)
        if key not in self._qs:
            n = int(max_ratio * 1.05) + 2
            w = natural_frequencies(self.rods.with_(interface=Welded.name), n) / self.omega1
            self._qs[key] = w[w <= max_ratio * (1 + POLE_RTOL)]
        return self._qs[key]

    def is_pole(self, ratio: float) -> bool:
        p = self.poles(ratio * (1 + 2 * POLE_RTOL))
        return bool(np.any(np.abs(ratio / p - 1.0) <= POLE_RTOL)) if p.size else False

    def qs(self, amplitude: float):
        key = ("qs", amplitude)
        if key not in self._qs:
            self._qs[key] = quasi_static_loop(
                self.rods, self.exc.with_(rotation_amplitude=amplitude), self.bed,
                self.steps_per_cycle)
        return self._qs[key]

    def solve(self, ratio: float, amplitude: float) -> Point:
        """The point at Ω = ratio ω1 and Θ_a = amplitude."""
        if self.is_pole(ratio):
            return Point(math.nan, math.nan, math.nan, math.nan, False, True)
        W = ratio * self.omega1
        key = (W, self.steps_per_cycle)
        if key not in self._props:
            self._props = {key: Propagator.build(self.basis, W, self.steps_per_cycle,
                                                 self.bed.stiffness)}
        exc = self.exc.with_(rotation_amplitude=amplitude, frequency=W)
        dyn = steady_state(self.rods, exc, self.bed, self.basis, self.steps_per_cycle,
                           self.max_cycles, self.tol, propagator=self._props[key])
        qs = self.qs(amplitude)
        finite = math.isfinite(dyn.T_max) and math.isfinite(dyn.dissipation)
        Dq = qs.dissipation
        if not Dq > 1e-12 * qs.T_max * float(np.ptp(qs.delta)):
            Dq = 0.0  # no loss in the quasi-static loop: the ratio is undefined
        # the last cycle's values are kept (as `slipcycle run` reports them) with the flag
        return Point(dyn.T_max if finite else math.nan, qs.T_max,
                     dyn.dissipation if finite else math.nan, Dq, dyn.converged and finite)

    def point(self, ratio: float, amplitude: float) -> tuple[float, float, bool]:
        """(T_dyn/T_qs, D_dyn/D_qs, converged) at Ω = ratio ω1 and Θ_a = amplitude."""
        p = self.solve(ratio, amplitude)
        return p.torque_ratio, p.dissipation_ratio, p.converged


def gross_slip_amplitude(rods: TwoRods, N: float) -> float:
    """Θ_g = T_g (C_r + 1/k0): the amplitude at which a stuck interface carries T_g (rad)."""
    k0 = interface_law(rods.interface).stiffness(rods)
    Tg = gross_slip_torque(rods.friction, N, rods.contact_radius)
    return Tg * (rods.rods_compliance + (1.0 / k0 if math.isfinite(k0) else 0.0))


def _inside(p: Point, which: int, tolerance: float) -> bool | None:
    """Whether a point's ratio is within ε of 1; None when unknown (no steady state).

    A pole is outside (unbounded response). For the dissipation, a point whose quasi-static
    loop does not dissipate is inside if the dynamic one does not either, outside if it does
    (dynamic slip that the quasi-static analysis misses).
    """
    if p.pole:
        return False
    if not p.converged:
        return None
    if which == 0:
        return abs(p.torque_ratio - 1.0) <= tolerance
    if p.D_qs > 0:
        return abs(p.dissipation_ratio - 1.0) <= tolerance
    return p.D_dyn <= 0.0  # steady_state already zeroes the round-off of a stuck cycle


def _first_crossing(study: Study, ratios, points, tolerance, which, refine=6):
    """First Ω/ω1 where the ratio leaves 1 ± ε, refined by bisection in log Ω.

    Status ``found``; ``below_range`` (already outside at the first ratio);
    ``above_range`` (inside on the whole axis: the value is a lower bound);
    ``not_converged`` (a point without a steady state comes first: the value, the last
    ratio known to be inside, is a lower bound).
    """
    states = [_inside(p, which, tolerance) for p in points]
    first = next((i for i, s in enumerate(states) if s is not True), None)
    if first is None:
        return float(ratios[-1]), "above_range"
    if first == 0:
        return float(ratios[0]), "below_range" if states[0] is False else "not_converged"
    if states[first] is None:
        return float(ratios[first - 1]), "not_converged"
    lo, hi = math.log(ratios[first - 1]), math.log(ratios[first])
    amp = study.exc.rotation_amplitude
    for _ in range(refine):
        mid = 0.5 * (lo + hi)
        if _inside(study.solve(math.exp(mid), amp), which, tolerance):
            lo = mid
        else:  # outside or unknown: the limit is not above mid
            hi = mid
    return float(math.exp(0.5 * (lo + hi))), "found"


def limit_frequency(study: Study, tolerance: float = 0.05, ratios=None,
                    progress: bool = False) -> dict:
    """Limit frequency ratios for the torque and for the dissipation at the case amplitude.

    The limit is the first Ω/ω1 of the sweep where |T_dyn/T_qs − 1| > ε (resp. the
    dissipation ratio), refined by bisection in log Ω.

    Parameters
    ----------
    study : Study
        The system and settings (:func:`make_study`); its excitation amplitude is used.
    tolerance : float
        Relative tolerance ε on the ratios [1].
    ratios : array_like, shape (F,), optional
        Increasing frequency ratios Ω/ω1 [1] (default 40 geometric values 0.01…3).
    progress : bool
        Show a progress bar.

    Returns
    -------
    dict
        Arrays over the sweep (``ratios``,): ``torque_ratio``, ``dissipation_ratio``,
        ``T_dyn``, ``T_qs`` (N m), ``D_dyn``, ``D_qs`` (J), ``converged``, ``pole``;
        ``poles`` (pole ratios in range); ``qs_limit_frequency_ratio`` and
        ``qs_limit_frequency_ratio_dissipation`` (None when the quasi-static loop does not
        dissipate) with their ``*_status``: ``found``, ``below_range`` or ``above_range``
        (the value is then a bound), ``not_converged`` (a point without a steady state
        comes first; the value is a lower bound) or, for the dissipation, ``no_dissipation``.
    """
    ratios = np.geomspace(0.01, 3.0, 40) if ratios is None else np.asarray(ratios, float)
    amp = study.exc.rotation_amplitude
    it = ratios
    if progress:
        from tqdm import tqdm

        it = tqdm(ratios, desc="frequency sweep", unit="pt")
    pts = [study.solve(float(r), amp) for r in it]
    arr = {k: np.array([getattr(p, k) for p in pts]) for k in
           ("T_dyn", "T_qs", "D_dyn", "D_qs", "converged", "pole")}
    TR = np.array([p.torque_ratio for p in pts])
    DR = np.array([p.dissipation_ratio for p in pts])
    lim_T, st_T = _first_crossing(study, ratios, pts, tolerance, 0)
    if not np.any(arr["D_qs"] > 0):
        lim_D, st_D = None, "no_dissipation"
    else:
        lim_D, st_D = _first_crossing(study, ratios, pts, tolerance, 1)
    return {"ratios": ratios, "torque_ratio": TR, "dissipation_ratio": DR, **arr,
            "converged": arr["converged"].astype(bool), "pole": arr["pole"].astype(bool),
            "poles": study.poles(float(ratios.max())),
            "qs_limit_frequency_ratio": lim_T, "qs_limit_frequency_ratio_status": st_T,
            "qs_limit_frequency_ratio_dissipation": lim_D,
            "qs_limit_frequency_ratio_dissipation_status": st_D}


def _bar(total, desc, progress):
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="pt")


def regime_map(study: Study, ratios, amplitude_factors, progress: bool = True) -> dict:
    """T_dyn/T_qs and D_dyn/D_qs over Ω/ω1 × Θa/Θg, shape (len(ratios), len(factors)).

    Θg (:func:`gross_slip_amplitude`) is the amplitude at which a stuck interface would
    carry the gross-slip torque.

    Parameters
    ----------
    study : Study
        The system and settings (:func:`make_study`).
    ratios : array_like, shape (F,)
        Frequency ratios Ω/ω1 [1].
    amplitude_factors : array_like, shape (A,)
        Amplitude ratios Θa/Θg [1].
    progress : bool
        Show a progress bar.

    Returns
    -------
    dict
        ``ratios`` (F,), ``amplitude_factors`` (A,), ``theta_gross`` Θg [rad],
        ``torque_ratio`` and ``dissipation_ratio`` (F, A) [1] (NaN at poles and where the
        quasi-static loop does not dissipate), ``converged`` (F, A) bool (False at points
        without a periodic steady state and at poles), ``pole`` (F, A) bool,
        ``resonances``: the stuck system's natural frequency ratios in range [1].
    """
    ratios = np.asarray(ratios, dtype=float)
    fac = np.asarray(amplitude_factors, dtype=float)
    theta_g = gross_slip_amplitude(study.rods, study.exc.axial_force)
    TR = np.empty((ratios.size, fac.size))
    DR = np.empty_like(TR)
    CV = np.empty(TR.shape, dtype=bool)
    PL = np.empty(TR.shape, dtype=bool)
    bar = _bar(TR.size, "regime map", progress)
    for i, r in enumerate(ratios):
        for j, f in enumerate(fac):
            p = study.solve(float(r), float(f * theta_g))
            TR[i, j], DR[i, j], CV[i, j], PL[i, j] = (p.torque_ratio, p.dissipation_ratio,
                                                      p.converged, p.pole)
            if bar is not None:
                bar.update()
    if bar is not None:
        bar.close()
    nat = natural_frequencies(study.rods, 12, study.bed.stiffness) / study.omega1
    return {"ratios": ratios, "amplitude_factors": fac, "theta_gross": theta_g,
            "torque_ratio": TR, "dissipation_ratio": DR, "converged": CV, "pole": PL,
            "resonances": nat[nat <= ratios.max()]}


def position_map(study: Study, fractions, ratios, amplitude: float | None = None,
                 modes: int | None = None, progress: bool = True) -> dict:
    """T_dyn/T_qs and D_dyn/D_qs over L1/(L1 + L2) × Ω/ω1.

    The total length and everything else are fixed; each geometry uses its own ω1.

    Parameters
    ----------
    study : Study
        The system and settings (:func:`make_study`).
    fractions : array_like, shape (P,)
        Interface positions L1/(L1 + L2) [1], in (0, 1).
    ratios : array_like, shape (F,)
        Frequency ratios Ω/ω1 [1], ω1 of each geometry.
    amplitude : float, optional
        Drive amplitude Θa [rad] (default the study's).
    modes : int, optional
        Modes of each geometry's basis (default the study's).
    progress : bool
        Show a progress bar.

    Returns
    -------
    dict
        ``fractions`` (P,), ``ratios`` (F,), ``omega1`` (P,) [rad/s], ``torque_ratio`` and
        ``dissipation_ratio`` (P, F) [1], ``converged`` and ``pole`` (P, F) bool.
    """
    from dataclasses import replace

    fr = np.asarray(fractions, dtype=float)
    ratios = np.asarray(ratios, dtype=float)
    total = study.rods.rod1.length + study.rods.rod2.length
    amp = study.exc.rotation_amplitude if amplitude is None else amplitude
    TR = np.empty((fr.size, ratios.size))
    DR = np.empty_like(TR)
    CV = np.empty(TR.shape, dtype=bool)
    PL = np.empty(TR.shape, dtype=bool)
    W1 = np.empty(fr.size)
    bar = _bar(TR.size, "position map", progress)
    for i, x in enumerate(fr):
        rods = study.rods.with_(rod1=replace(study.rods.rod1, length=float(x * total)),
                                rod2=replace(study.rods.rod2, length=float((1 - x) * total)))
        sub = Study(rods, study.exc, study.bed, modal_basis(rods, modes or study.basis.modes,
                                                            study.basis.static_correction),
                    study.steps_per_cycle, study.max_cycles, study.tol)
        W1[i] = sub.omega1
        for j, r in enumerate(ratios):
            p = sub.solve(float(r), amp)
            TR[i, j], DR[i, j], CV[i, j], PL[i, j] = (p.torque_ratio, p.dissipation_ratio,
                                                      p.converged, p.pole)
            if bar is not None:
                bar.update()
    if bar is not None:
        bar.close()
    return {"fractions": fr, "ratios": ratios, "omega1": W1, "torque_ratio": TR,
            "dissipation_ratio": DR, "converged": CV, "pole": PL}


# ---------------------------------------------------------------------------------------
# `slipcycle limits`: the [limits] table, the analysis and its outputs
# ---------------------------------------------------------------------------------------
@dataclass
class LimitsCase:
    """A validated limits case: the rods case and the axes of the sweeps."""

    rc: object  # slipcycle.rods.case.RodsCase
    tolerance: float
    ratios: np.ndarray
    amplitude_ratios: np.ndarray
    positions: np.ndarray
    position_frequencies: int


def _axis(sec, key, default, **bounds):
    """A grid axis; values given as a list are sorted."""
    vals = sec.grid(key, default, max_num=10000, **bounds)
    return vals if isinstance(sec.data.get(key, default), dict) else np.sort(vals)


def parse_limits(case, tolerance: float, maps: bool = True) -> LimitsCase:
    """Validate a limits case completely: ``[limits]`` with the same :class:`Section` rules
    as every table (unknown keys with a suggestion, types, bounds, sizes refused with their
    estimated memory), then the rods case (:func:`slipcycle.rods.case.parse_case`).

    ``[limits]`` keys: ``frequency_ratio`` (Ω/ω1 axis, list or ``{start, stop, num}``
    geometric; default 0.01…3 × 40), ``amplitude_ratio`` (Θa/Θg, geometric; 0.3…3 × 20),
    ``position`` (L1/(L1 + L2), linear; 0.1…0.9 × 9), ``position_frequencies`` (20).
    """
    from slipcycle.io import CaseError

    if not (0.0 < tolerance < 1.0):
        raise CaseError("--tolerance", f"must be in (0, 1), got {tolerance:g}")
    load = case.data.get("loading")
    if isinstance(load, dict) and "frequency_ratio" not in load and "frequency" not in load:
        load["frequency_ratio"] = 1.0  # the sweep sets the frequency
    sec = case.section("limits", required=False)
    ratios = _axis(sec, "frequency_ratio", {"start": 0.01, "stop": 3.0, "num": 40},
                   gt=0.0, le=1e3, geometric=True)
    amps = _axis(sec, "amplitude_ratio", {"start": 0.3, "stop": 3.0, "num": 20},
                 gt=0.0, le=1e4, geometric=True)
    pos = _axis(sec, "position", {"start": 0.1, "stop": 0.9, "num": 9}, gt=0.0, le=0.999)
    npf = sec.int("position_frequencies", 20, ge=2, le=10000)
    if maps:
        for key, size in (("amplitude_ratio", ratios.size * amps.size),
                          ("position", pos.size * npf)):
            check_memory(sec.key(key), size * _MAP_POINT_BYTES, f"a map of {size:.3g} points")
    rc = parse_case(case, limits=True)
    return LimitsCase(rc, tolerance, ratios, amps, pos, npf)


#: unit of every numeric entry of the limits summary
LIMITS_UNITS = {
    "tolerance": "1", "omega1": "rad/s", "rotation_amplitude": "rad",
    "qs_limit_frequency_ratio": "1", "qs_limit_frequency": "rad/s",
    "qs_limit_frequency_ratio_dissipation": "1", "poles_frequency_ratio": "1",
    "sweep_points_not_converged": "1", "sweep_points_at_pole": "1",
    "wall_time_sweep_s": "s", "map_shape": "1", "map_points_not_converged": "1",
    "position_map_points_not_converged": "1", "wall_time_map_s": "s",
    "wall_time_position_map_s": "s", "theta_gross": "rad",
    "resonances_frequency_ratio": "1", "position_omega1": "rad/s",
    "iwan.F_S": "N m", "iwan.K_T": "N m/rad", "iwan.chi": "1", "iwan.beta": "1",
    "iwan.elements": "1",
}

#: every word of the categorical entries of the limits summary
LIMITS_FLAGS = {
    "model": ("rods",),
    "analysis": ("limits",),
    "interface": ("welded", "distributed", "coulomb", "jenkins", "iwan"),
    "qs_limit_frequency_ratio_status": ("found", "below_range", "above_range",
                                        "not_converged"),
    "qs_limit_frequency_ratio_dissipation_status": ("found", "below_range", "above_range",
                                                    "not_converged", "no_dissipation"),
}


def make_study(rc) -> tuple[Study, object]:
    """The :class:`Study` of a validated rods case, with ``slipcycle run``'s bed and settings.

    Parameters
    ----------
    rc : RodsCase
        A validated rods case (:func:`slipcycle.rods.case.parse_case`).

    Returns
    -------
    study : Study
        The rods, excitation, interface bed (:func:`slipcycle.rods.case.interface_bed`),
        modal basis and the case's steps per cycle, cycle limit and steadiness tolerance.
    iwan : SegalmanIwan or None
        The Iwan parameters used (F_S [N m], K_T [N m/rad], χ, β); None for other
        interfaces.
    """

    bed, iw = interface_bed(rc)
    basis = modal_basis(rc.rods, rc.modes, rc.static_correction)
    return Study(rc.rods, rc.exc, bed, basis, rc.steps_per_cycle, rc.cycles,
                 rc.steady_tol), iw


def run_limits(lc: LimitsCase, maps: bool = True, progress: bool = False) -> RunOutputs:
    """What ``slipcycle limits`` writes: ``limits_study(lc, maps, progress).to_outputs()``.

    Parameters
    ----------
    lc, maps, progress
        See :func:`limits_study`.

    Returns
    -------
    RunOutputs
    """
    return limits_study(lc, maps=maps, progress=progress).to_outputs()


def limits_study(lc: LimitsCase, maps: bool = True, progress: bool = False) -> LimitsResult:
    """Limit frequency of the quasi-static analysis (and the regime maps) of a limits case.

    Parameters
    ----------
    lc : LimitsCase
        A validated limits case (:func:`parse_limits`).
    maps : bool
        Also compute the regime map (Ω/ω1 × Θa/Θg) and the position map
        (L1/(L1 + L2) × Ω/ω1).
    progress : bool
        Show progress bars.

    Returns
    -------
    LimitsResult
        Its ``to_outputs()`` is what ``slipcycle limits`` writes.
    """
    import time

    study, iw = make_study(lc.rc)
    t0 = time.perf_counter()
    lim = limit_frequency(study, lc.tolerance, lc.ratios, progress=progress)
    t1 = time.perf_counter()
    m = pm = None
    t2 = t3 = t1
    if maps:
        m = regime_map(study, lc.ratios, lc.amplitude_ratios, progress=progress)
        t2 = time.perf_counter()
        pr = np.geomspace(lc.ratios.min(), lc.ratios.max(), lc.position_frequencies)
        pm = position_map(study, lc.positions, pr, progress=progress)
        t3 = time.perf_counter()
    return LimitsResult(
        wall_time_s=t3 - t0, tolerance=lc.tolerance, interface=lc.rc.rods.interface,
        omega1=study.omega1, rotation_amplitude=lc.rc.exc.rotation_amplitude, sweep=lim,
        iwan=None if iw is None else {"F_S": iw.F_S, "K_T": iw.K_T, "chi": iw.chi,
                                      "beta": iw.beta, "elements": study.bed.size},
        wall_time_sweep_s=t1 - t0, regime=m, positions=pm, wall_time_map_s=t2 - t1,
        wall_time_position_map_s=t3 - t2)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class LimitsResult(StudyResult):
    """Limit frequency of the quasi-static analysis and regime maps (``slipcycle limits``).

    Attributes
    ----------
    wall_time_s : float
        Wall time of the sweep and the maps [s].
    tolerance : float
        Relative tolerance ε on T_dyn/T_qs and D_dyn/D_qs [1].
    interface : str
        Interface law of the case.
    omega1 : float
        First natural frequency ω1 of the stuck system [rad/s].
    rotation_amplitude : float
        Drive amplitude Θa of the case [rad].
    sweep : dict
        :func:`limit_frequency` at the case amplitude (arrays over Ω/ω1, the limits and
        their status).
    iwan : dict or None
        Iwan parameters used (F_S [N m], K_T [N m/rad], chi, beta, elements).
    wall_time_sweep_s : float
        Wall time of the frequency sweep [s].
    regime, positions : dict or None
        :func:`regime_map` and :func:`position_map` (None without maps).
    wall_time_map_s, wall_time_position_map_s : float
        Wall times of the two maps [s] (0 without maps).
    """

    model: ClassVar[str] = "rods"
    analysis: ClassVar[str] = "limits"
    FLAGS: ClassVar[dict] = LIMITS_FLAGS

    tolerance: float
    interface: str
    omega1: float
    rotation_amplitude: float
    sweep: dict
    iwan: dict | None
    wall_time_sweep_s: float
    regime: dict | None = None
    positions: dict | None = None
    wall_time_map_s: float = 0.0
    wall_time_position_map_s: float = 0.0

    @property
    def qs_limit_frequency_ratio(self) -> float:
        """Ω/ω1 below which |T_dyn/T_qs − 1| ≤ ε (see its ``_status``) [1]."""
        return self.sweep["qs_limit_frequency_ratio"]

    def headline(self) -> list[tuple]:
        """ω1, the two limit frequency ratios with their status, and the wall time."""
        lim = self.sweep
        return [("omega1", self.omega1, "rad/s"),
                ("qs_limit_frequency_ratio", lim["qs_limit_frequency_ratio"], "1"),
                ("status", lim["qs_limit_frequency_ratio_status"], ""),
                ("qs_limit_frequency_ratio_dissipation",
                 lim["qs_limit_frequency_ratio_dissipation"], "1"),
                ("status_dissipation", lim["qs_limit_frequency_ratio_dissipation_status"], ""),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """``summary.json`` of ``slipcycle limits`` (units: :data:`LIMITS_UNITS`).

        Returns
        -------
        dict
            ``omega1`` [rad/s], ``qs_limit_frequency_ratio`` and its status,
            ``qs_limit_frequency`` [rad/s], the same for the dissipation, poles, points
            not converged, wall times [s], ``iwan``, with maps their shapes, points not
            converged, ``theta_gross`` [rad], resonances and ``position_omega1`` [rad/s];
            ``units``.
        """
        lim = self.sweep
        summary = {
            "model": "rods",
            "analysis": "limits",
            "tolerance": self.tolerance,
            "interface": self.interface,
            "omega1": self.omega1,
            "rotation_amplitude": self.rotation_amplitude,
            "qs_limit_frequency_ratio": lim["qs_limit_frequency_ratio"],
            "qs_limit_frequency_ratio_status": lim["qs_limit_frequency_ratio_status"],
            "qs_limit_frequency": lim["qs_limit_frequency_ratio"] * self.omega1,
            "qs_limit_frequency_ratio_dissipation":
                lim["qs_limit_frequency_ratio_dissipation"],
            "qs_limit_frequency_ratio_dissipation_status":
                lim["qs_limit_frequency_ratio_dissipation_status"],
            "poles_frequency_ratio": lim["poles"],
            "dissipation_per_cycle": None,
            "sweep_points_not_converged": int(np.sum(~lim["converged"] & ~lim["pole"])),
            "sweep_points_at_pole": int(np.sum(lim["pole"])),
            "wall_time_sweep_s": self.wall_time_sweep_s,
        }
        if self.iwan is not None:
            summary["iwan"] = dict(self.iwan)
        m, pm = self.regime, self.positions
        if m is not None:
            summary.update({
                "map_shape": list(m["torque_ratio"].shape),
                "map_points_not_converged": int(np.sum(~m["converged"])),
                "position_map_points_not_converged": int(np.sum(~pm["converged"])),
                "wall_time_map_s": self.wall_time_map_s,
                "wall_time_position_map_s": self.wall_time_position_map_s,
                "theta_gross": m["theta_gross"],
                "resonances_frequency_ratio": m["resonances"],
                "position_omega1": pm["omega1"],
            })
        summary["units"] = {k: v for k, v in LIMITS_UNITS.items()
                            if k.split(".")[0] in summary}
        return summary

    def to_dataset(self):
        """Ratios, maximum torques [N m], dissipation [J], ``converged`` and ``pole`` over
        Ω/ω1; with maps, the ratios and ``converged`` over (map_frequency_ratio,
        amplitude_ratio) and (position, position_frequency_ratio).

        The only place the Dataset of a limits study is built.

        Returns
        -------
        xarray.Dataset
        """
        import xarray as xr

        lim, one, fdim = self.sweep, {"units": "1"}, "frequency_ratio"
        ds = xr.Dataset(
            {"torque_ratio": (fdim, lim["torque_ratio"], one),
             "dissipation_ratio": (fdim, lim["dissipation_ratio"], one),
             "T_dyn_max": (fdim, lim["T_dyn"], {"units": "N m"}),
             "T_qs_max": (fdim, lim["T_qs"], {"units": "N m"}),
             "dissipation_per_cycle": (fdim, lim["D_dyn"], {"units": "J"}),
             "dissipation_per_cycle_qs": (fdim, lim["D_qs"], {"units": "J"}),
             "converged": (fdim, lim["converged"], one),
             "pole": (fdim, lim["pole"], one)},
            coords={fdim: (fdim, lim["ratios"], one)})
        m, pm = self.regime, self.positions
        if m is None:
            return ds
        ds = ds.assign_coords(
            map_frequency_ratio=("map_frequency_ratio", m["ratios"], one),
            amplitude_ratio=("amplitude_ratio", m["amplitude_factors"], one),
            position=("position", pm["fractions"], one),
            position_frequency_ratio=("position_frequency_ratio", pm["ratios"], one))
        dims = ("map_frequency_ratio", "amplitude_ratio")
        ds["map_torque_ratio"] = (dims, m["torque_ratio"], one)
        ds["map_dissipation_ratio"] = (dims, m["dissipation_ratio"], one)
        ds["map_converged"] = (dims, m["converged"], one)
        pd = ("position", "position_frequency_ratio")
        ds["position_torque_ratio"] = (pd, pm["torque_ratio"], one)
        ds["position_dissipation_ratio"] = (pd, pm["dissipation_ratio"], one)
        ds["position_converged"] = (pd, pm["converged"], one)
        return ds

    def figures(self, dataset=None) -> dict:
        """``limit_frequency`` and, with maps, ``regime_map`` and ``position_map``.

        Returns
        -------
        dict of str to callable
        """
        from slipcycle.plot import rods as plots

        tol = self.tolerance
        figures = {"limit_frequency": lambda: plots.limit_curve(self.sweep, tol)}
        if self.regime is not None:
            figures["regime_map"] = lambda: plots.regime_map(self.regime, tol)
            figures["position_map"] = lambda: plots.position_map(self.positions, tol)
        return figures
