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

The study of ``slipcycle limits`` (its ``[limits]`` table, summary, Dataset and figures)
is :mod:`slipcycle.studies.limits`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from slipcycle.rods.case import interface_bed
from slipcycle.rods.interfaces import Bed, Welded, gross_slip_torque, interface_law
from slipcycle.rods.modal import ModalBasis, Propagator, modal_basis, steady_state
from slipcycle.rods.model import Excitation, TwoRods
from slipcycle.rods.quasistatic import quasi_static_loop
from slipcycle.rods.welded import (
    POLE_RTOL,
    natural_frequencies,
    omega1,
    torque_free_frequencies,
)

__all__ = ["Study", "Point", "limit_frequency", "regime_map", "position_map",
           "gross_slip_amplitude", "make_study", "POLE_RTOL"]


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
        """Pole frequency ratios Ω/ω1 ≤ max_ratio: empty when damped; every natural
        frequency when welded; with a frictional interface the frequencies of the modes
        that carry no interface torque (:func:`torque_free_frequencies`)."""
        if self.rods.damping_ratio != 0.0:
            return np.zeros(0)
        key = ("poles", max_ratio)
        if key not in self._qs:
            if self.undamped_welded:
                n = int(max_ratio * 1.05) + 2
                w = natural_frequencies(self.rods.with_(interface=Welded.name), n)
            else:
                w = torque_free_frequencies(self.rods, max_ratio * self.omega1)
            w = w / self.omega1
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
