"""Limits of the quasi-static analysis: limit frequency and regime maps (seed 000).

For a drive amplitude Θ_a and frequency Ω the dynamic steady state (modal model) and the
quasi-static loop (massless rods, same interface) give the maximum interface torques
T_dyn, T_qs and the dissipation per cycle D_dyn, D_qs. The *limit frequency* is the largest
Ω/ω1 below which |T_dyn/T_qs − 1| ≤ ε on the whole frequency axis from its start (first
crossing, located by bisection in log Ω); the same is reported separately for the
dissipation. The maps evaluate both ratios over Ω/ω1 × amplitude and over Ω/ω1 × interface
position L1/(L1 + L2) (total length and everything else fixed; each geometry uses its own ω1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from slipcycle.rods.interfaces import Bed
from slipcycle.rods.modal import ModalBasis, Propagator, modal_basis, steady_state
from slipcycle.rods.model import Excitation, TwoRods
from slipcycle.rods.quasistatic import quasi_static_loop
from slipcycle.rods.welded import natural_frequencies, omega1

__all__ = ["Study", "limit_frequency", "regime_map", "position_map", "gross_slip_amplitude"]


@dataclass
class Study:
    """One system and the numerical settings shared by every point of a sweep."""

    rods: TwoRods
    exc: Excitation
    bed: Bed
    basis: ModalBasis
    steps_per_cycle: int = 400
    max_cycles: int = 150
    tol: float = 1e-5
    _props: dict = field(default_factory=dict)
    _qs: dict = field(default_factory=dict)

    @property
    def omega1(self) -> float:
        if "w1" not in self._qs:
            self._qs["w1"] = omega1(self.rods)
        return self._qs["w1"]

    def qs(self, amplitude: float):
        key = ("qs", amplitude)
        if key not in self._qs:
            self._qs[key] = quasi_static_loop(
                self.rods, self.exc.with_(rotation_amplitude=amplitude), self.bed,
                self.steps_per_cycle)
        return self._qs[key]

    def point(self, ratio: float, amplitude: float) -> tuple[float, float, bool]:
        """(T_dyn/T_qs, D_dyn/D_qs, converged) at Ω = ratio ω1 and Θ_a = amplitude."""
        W = ratio * self.omega1
        key = (W, self.steps_per_cycle)
        if key not in self._props:
            self._props = {key: Propagator.build(self.basis, W, self.steps_per_cycle,
                                                 self.bed.stiffness)}
        exc = self.exc.with_(rotation_amplitude=amplitude, frequency=W)
        dyn = steady_state(self.rods, exc, self.bed, self.basis, self.steps_per_cycle,
                           self.max_cycles, self.tol, propagator=self._props[key])
        qs = self.qs(amplitude)
        Dq = qs.dissipation
        d_ratio = dyn.dissipation / Dq if Dq > 1e-12 * qs.T_max * np.ptp(qs.delta) \
            and Dq > 0 else math.nan
        return dyn.T_max / qs.T_max, d_ratio, dyn.converged


def gross_slip_amplitude(rods: TwoRods, N: float) -> float:
    """Θ_g = T_g (C_r + 1/k0): the amplitude at which a stuck interface carries T_g (rad)."""
    k0 = rods.interface_torsional_stiffness
    Tg = 2.0 / 3.0 * rods.friction * N * rods.contact_radius
    return Tg * (rods.rods_compliance + (1.0 / k0 if math.isfinite(k0) else 0.0))


def _first_crossing(study: Study, ratios, values, tolerance, which, refine=6):
    err = np.abs(np.asarray(values) - 1.0)
    bad = np.flatnonzero(~(err <= tolerance))
    if bad.size == 0:
        return float(ratios[-1]), "above_range"
    i = int(bad[0])
    if i == 0:
        return float(ratios[0]), "below_range"
    lo, hi = math.log(ratios[i - 1]), math.log(ratios[i])
    for _ in range(refine):
        mid = 0.5 * (lo + hi)
        v = study.point(math.exp(mid), study.exc.rotation_amplitude)[which]
        if abs(v - 1.0) <= tolerance:
            lo = mid
        else:
            hi = mid
    return float(math.exp(0.5 * (lo + hi))), "found"


def limit_frequency(study: Study, tolerance: float = 0.05, ratios=None,
                    progress: bool = False) -> dict:
    """Limit frequency ratios for the torque and for the dissipation at the case amplitude.

    Returns
    -------
    dict
        ``ratios``, ``torque_ratio``, ``dissipation_ratio``, ``converged`` (arrays over the
        sweep), ``qs_limit_frequency_ratio`` and ``qs_limit_frequency_ratio_dissipation``
        (None when the quasi-static loop does not dissipate) with their ``*_status``:
        ``found``, ``below_range`` or ``above_range`` (the value is then a bound).
    """
    ratios = np.geomspace(0.01, 3.0, 40) if ratios is None else np.asarray(ratios)
    amp = study.exc.rotation_amplitude
    TR, DR, CV = [], [], []
    it = ratios
    if progress:
        from tqdm import tqdm

        it = tqdm(ratios, desc="frequency sweep", unit="pt")
    for r in it:
        a, b, c = study.point(float(r), amp)
        TR.append(a)
        DR.append(b)
        CV.append(c)
    TR, DR, CV = np.array(TR), np.array(DR), np.array(CV)
    lim_T, st_T = _first_crossing(study, ratios, TR, tolerance, 0)
    if np.all(np.isnan(DR)):
        lim_D, st_D = None, "no_dissipation"
    else:
        lim_D, st_D = _first_crossing(study, ratios, np.where(np.isnan(DR), 1.0, DR),
                                      tolerance, 1)
    return {"ratios": ratios, "torque_ratio": TR, "dissipation_ratio": DR, "converged": CV,
            "qs_limit_frequency_ratio": lim_T, "qs_limit_frequency_ratio_status": st_T,
            "qs_limit_frequency_ratio_dissipation": lim_D,
            "qs_limit_frequency_ratio_dissipation_status": st_D}


def regime_map(study: Study, ratios, amplitude_factors, progress: bool = True) -> dict:
    """T_dyn/T_qs and D_dyn/D_qs over Ω/ω1 × Θ_a/Θ_g, shape (len(ratios), len(factors))."""
    ratios = np.asarray(ratios, dtype=float)
    fac = np.asarray(amplitude_factors, dtype=float)
    theta_g = gross_slip_amplitude(study.rods, study.exc.axial_force)
    TR = np.empty((ratios.size, fac.size))
    DR = np.empty_like(TR)
    CV = np.empty(TR.shape, dtype=bool)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=TR.size, desc="regime map", unit="pt")
    for i, r in enumerate(ratios):
        for j, f in enumerate(fac):
            TR[i, j], DR[i, j], CV[i, j] = study.point(float(r), float(f * theta_g))
            if bar is not None:
                bar.update()
    if bar is not None:
        bar.close()
    nat = natural_frequencies(study.rods, 12, study.bed.stiffness) / study.omega1
    return {"ratios": ratios, "amplitude_factors": fac, "theta_gross": theta_g,
            "torque_ratio": TR, "dissipation_ratio": DR, "converged": CV,
            "resonances": nat[nat <= ratios.max()]}


def position_map(study: Study, fractions, ratios, amplitude: float | None = None,
                 modes: int | None = None, progress: bool = True) -> dict:
    """T_dyn/T_qs and D_dyn/D_qs over L1/(L1 + L2) × Ω/ω1 (shape (len(fractions), len(ratios)))."""
    from dataclasses import replace

    fr = np.asarray(fractions, dtype=float)
    ratios = np.asarray(ratios, dtype=float)
    total = study.rods.rod1.length + study.rods.rod2.length
    amp = study.exc.rotation_amplitude if amplitude is None else amplitude
    TR = np.empty((fr.size, ratios.size))
    DR = np.empty_like(TR)
    CV = np.empty(TR.shape, dtype=bool)
    W1 = np.empty(fr.size)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=TR.size, desc="position map", unit="pt")
    for i, x in enumerate(fr):
        rods = study.rods.with_(rod1=replace(study.rods.rod1, length=float(x * total)),
                                rod2=replace(study.rods.rod2, length=float((1 - x) * total)))
        sub = Study(rods, study.exc, study.bed, modal_basis(rods, modes or study.basis.modes,
                                                            study.basis.static_correction),
                    study.steps_per_cycle, study.max_cycles, study.tol)
        W1[i] = sub.omega1
        for j, r in enumerate(ratios):
            TR[i, j], DR[i, j], CV[i, j] = sub.point(float(r), amp)
            if bar is not None:
                bar.update()
    if bar is not None:
        bar.close()
    return {"fractions": fr, "ratios": ratios, "omega1": W1, "torque_ratio": TR,
            "dissipation_ratio": DR, "converged": CV}
