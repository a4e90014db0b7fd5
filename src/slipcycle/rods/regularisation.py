"""Regularisation study: dissipation per cycle versus amplitude, per model.

The quasi-static loop of each interface model (distributed, jenkins, coulomb, fitted iwan) is
computed over drive amplitudes Θ_a from well inside stick to far into gross slip. Two
log–log slopes are reported per model:

``slope_microslip``
    d log D / d log T* over the points with D > 0 and T* < 0.95 T_g (T* the torque
    amplitude, T_g the gross-slip torque): the partial-slip law. Segalman's Iwan element
    gives ≈ 3 + χ at small amplitude; the rings, whose first slip threshold is finite
    (the rim at T_s = 3/4 T_g), give D ∝ (T* − T_s)² — a local slope that starts infinite
    and has no power law; Jenkins and Coulomb dissipate nothing below gross slip (None).
``slope_macroslip``
    d log D / d log Θ_a over the largest amplitudes (gross slip): → 1 for every model,
    since D ≈ 4 T_g Θ_a once the interface slides.
"""

from __future__ import annotations

import math

import numpy as np

from slipcycle.rods.interfaces import Bed, Iwan, SegalmanIwan, gross_slip_torque, interface_law
from slipcycle.rods.model import Excitation, TwoRods
from slipcycle.rods.quasistatic import quasi_static_loop

__all__ = ["regularisation_study", "REG_MODELS"]

REG_MODELS = ("distributed", "jenkins", "coulomb", "iwan")


def _slope(x, y):
    if x.size < 2:
        return None
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def regularisation_study(rods: TwoRods, exc: Excitation, rings: int = 100,
                         iwan: SegalmanIwan | None = None, points: int = 25,
                         steps_per_cycle: int = 400) -> dict:
    """Quasi-static dissipation per cycle versus amplitude for the four interface models.

    Amplitudes are Θ_a = s Θ_g with s ∈ [0.03, 30] (geometric, plus 8 points in the
    rings' microslip range 0.77–0.99) and Θ_g = T_g (C_r + 1/k_t J_a)
    the amplitude at which a stuck interface would carry the gross-slip torque T_g.
    Each point is a :func:`~slipcycle.rods.quasistatic.quasi_static_loop` at constant
    normal force F0 (the axial amplitude is set to 0). The slopes are least-squares
    log–log fits (module docstring): ``slope_microslip`` of D against T* over the points
    with D > 1e-9 max D and T* < 0.95 T_g, ``slope_macroslip`` of D against Θ_a over the
    five largest amplitudes.

    Parameters
    ----------
    rods : TwoRods
        Friction f, contact radius a (m), rods' compliance C_r (rad/(N m)) and a finite
        tangential interface stiffness k_t (N/m³; :func:`slipcycle.rods.case.parse_case`
        switches the study off without one); all four models are built from them,
        whatever ``rods.interface`` is.
    exc : Excitation
        Its mean axial force F0 (N) is the normal force; Θ_a is swept and F_a set to 0; Ω
        (rad/s) only sets the time axis.
    rings : int
        Rings of the ``distributed`` model (≥ 1).
    iwan : SegalmanIwan, optional
        The ``iwan`` model; None: fitted to the rings at F0 (:func:`slipcycle.rods.
        interfaces.fit_iwan`).
    points : int
        Geometric amplitudes s ∈ [0.03, 30]; with the 8 microslip points the study has
        n ≤ ``points`` + 8 distinct amplitudes.
    steps_per_cycle : int
        K, steps per period of each quasi-static loop.

    Returns
    -------
    dict
        ``amplitude`` : (n,) ndarray
            Drive amplitudes Θ_a (rad), ascending.
        ``gross_slip_torque`` : float
            T_g = (2/3) f F0 a (N m).
        ``theta_gross`` : float
            Θ_g (rad).
        ``iwan_params`` : dict
            ``F_S`` (N m), ``K_T`` (N m/rad), ``chi``, ``beta`` of the Iwan model used.
        ``distributed``, ``jenkins``, ``coulomb``, ``iwan`` : dict
            Per model: ``T_amp`` (n,) torque amplitudes max|T| (N m), ``dissipation`` (n,)
            per cycle (J, ≥ 0), ``slope_microslip`` and ``slope_macroslip`` (float, or None
            where fewer than two points qualify or some macroslip point does not dissipate).
        ``first_slip_torque`` : dict
            Per model, the torque at which its first element slips at F0 (N m).
        ``_beds`` : dict
            Per model, the :class:`~slipcycle.rods.interfaces.Bed` used (internal).

    References
    ----------
    Segalman, D. J. (2005). A four-parameter Iwan model for lap-type joints. J. Appl. Mech.
    72, 752–760 (D ∝ T*^(3+χ)). Iwan, W. D. (1966). J. Appl. Mech. 33, 893–900. Johnson,
    K. L. (1985). Contact Mechanics, §7.3 (the rings; slip inception at the rim).
    """
    N0 = exc.axial_force
    Tg = gross_slip_torque(rods.friction, N0, rods.contact_radius)
    k0 = rods.interface_stiffness * rods.contact_J
    theta_g = Tg * (rods.rods_compliance + 1.0 / k0)
    amps = theta_g * np.unique(np.concatenate([np.geomspace(0.03, 30.0, points),
                                               np.linspace(0.77, 0.99, 8)]))
    points = amps.size
    laws = {name: interface_law(name, rings=rings, iwan=iwan) for name in REG_MODELS}
    laws[Iwan.name] = iwan_law = laws[Iwan.name].fitted(rods, N0)  # fit once, report it
    beds: dict[str, Bed] = {name: law.bed(rods, N0) for name, law in laws.items()}
    iw = iwan_law.params
    out: dict = {"amplitude": amps, "gross_slip_torque": Tg,
                 "iwan_params": {"F_S": iw.F_S, "K_T": iw.K_T, "chi": iw.chi, "beta": iw.beta}}
    for name in REG_MODELS:
        T = np.empty(points)
        D = np.empty(points)
        for i, a in enumerate(amps):
            res = quasi_static_loop(rods, exc.with_(rotation_amplitude=float(a),
                                                    axial_amplitude=0.0), beds[name],
                                    steps_per_cycle)
            T[i], D[i] = res.T_max, max(res.dissipation, 0.0)
        floor = 1e-9 * max(float(D.max()), 1e-300)
        micro = (D > floor) & (T < 0.95 * Tg)
        macro = np.arange(points) >= points - 5
        out[name] = {"T_amp": T, "dissipation": D,
                     "slope_microslip": _slope(T[micro], D[micro]) if micro.sum() >= 2
                     else None,
                     "slope_macroslip": _slope(amps[macro], D[macro])
                     if np.all(D[macro] > 0) else None}
    out["theta_gross"] = theta_g
    out["first_slip_torque"] = {k: b.first_slip_torque(N0) for k, b in beds.items()}
    out["_beds"] = beds
    if not math.isfinite(theta_g):  # pragma: no cover - guarded by validation
        raise ValueError("interface_stiffness: must be finite for the regularisation study")
    return out
