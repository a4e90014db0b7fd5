"""Exact harmonic response of the continuous rods (transfer matrices).

For harmonic motion e^{iΩt} a uniform rod segment of length ℓ maps the state
(φ, T) with T = G J φ′ from one end to the other by

    [φ(ℓ)]   [ cos kℓ          sin kℓ /(G J k) ] [φ(0)]
    [T(ℓ)] = [ −G J k sin kℓ   cos kℓ          ] [T(0)],      k = Ω / c,

(the same with E A, c_axial for the axial state (u, E A u′)). Chaining rod 1, the interface
(welded, or a linear torsional spring k: φ jumps by T/k) and rod 2 with φ(−L1) = 0 and
φ(L2) = Θ gives the interface torque per unit Θ exactly; its zeros in Θ (both outer
ends fixed) are the natural frequencies. Damping enters, where wanted, as a complex modulus
G(1 + 2iζ) (loss factor 2ζ, i.e. damping ratio ≈ ζ at every resonance); the exact
reference for the modal solution is the undamped one.

References: Graff, *Wave Motion in Elastic Solids* (1975), §1.4 and §2.2; Pestel & Leckie,
*Matrix Methods in Elastomechanics* (1963).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from slipcycle.rods.model import TwoRods

__all__ = ["transfer_matrix", "interface_torque_frf", "natural_frequencies", "omega1",
           "normal_force_frf", "normal_force_history", "POLE_RTOL"]

#: a frequency within this relative distance of an undamped natural frequency is a pole
POLE_RTOL = 1e-6


def transfer_matrix(stiffness: float, c: float, length: float, Omega: float,
                    zeta: float = 0.0) -> np.ndarray:
    """Field transfer matrix of a uniform segment, shape (2, 2), complex.

    Parameters
    ----------
    stiffness : float
        G J (N m²) for torsion or E A (N) for axial motion.
    c : float
        Wave speed (m/s).
    length : float
        Segment length (m).
    Omega : float
        Angular frequency (rad/s), ≥ 0.
    zeta : float
        Complex-modulus damping: stiffness·(1 + 2iζ).
    """
    s = stiffness * (1.0 + 2j * zeta)
    cc = c * np.sqrt(1.0 + 2j * zeta)
    k = Omega / cc
    kl = k * length
    if abs(kl) < 1e-8:
        return np.array([[1.0, length / s], [0.0, 1.0]], dtype=complex)
    return np.array([[np.cos(kl), np.sin(kl) / (s * k)],
                     [-s * k * np.sin(kl), np.cos(kl)]], dtype=complex)


def _torsion_chain(rods: TwoRods, Omega: float, k_int: float, zeta: float):
    r1, r2 = rods.rods
    M1 = transfer_matrix(r1.G * r1.J, r1.c_torsion, r1.length, Omega, zeta)
    M2 = transfer_matrix(r2.G * r2.J, r2.c_torsion, r2.length, Omega, zeta)
    s0 = np.array([0.0, 1.0], dtype=complex)  # φ(−L1) = 0, unit torque there
    s1 = M1 @ s0
    jump = 0.0 if not math.isfinite(k_int) else s1[1] / k_int
    s2 = np.array([s1[0] + jump, s1[1]])
    sL = M2 @ s2
    return s1, s2, sL


def interface_torque_frf(rods: TwoRods, Omega: float, k_int: float = math.inf,
                         zeta: float = 0.0) -> dict:
    """Exact interface response per unit driving rotation Θ̂ = 1.

    Parameters
    ----------
    rods : TwoRods
    Omega : float
        Excitation frequency (rad/s).
    k_int : float
        Linear interface torsional stiffness (N m/rad); inf for a welded interface.
    zeta : float
        Complex-modulus damping (0: undamped, the exact reference).

    Returns
    -------
    dict
        ``T`` interface torque (N m/rad), ``phi1``/``phi2`` the rotations of both faces at
        x = 0 and ``T_drive`` the torque at x = L2 (N m/rad), all complex.
    """
    s1, s2, sL = _torsion_chain(rods, Omega, k_int, zeta)
    scale = 1.0 / sL[0]
    return {"T": s1[1] * scale, "phi1": s1[0] * scale, "phi2": s2[0] * scale,
            "T_drive": sL[1] * scale}


def _det(rods: TwoRods, Omega: float, k_int: float) -> float:
    return float(np.real(_torsion_chain(rods, Omega, k_int, 0.0)[2][0]))


def natural_frequencies(rods: TwoRods, count: int = 1, k_int: float = math.inf) -> np.ndarray:
    """Lowest ``count`` torsional natural frequencies with both outer ends fixed (rad/s).

    Roots in Ω of φ(L2) for φ(−L1) = 0 and a unit torque there, chained through rod 1, the
    interface (a linear torsional spring ``k_int``, or welded) and rod 2 by the undamped
    field transfer matrices of the module docstring. They are located by a scan in steps
    of π/(400 τ), τ = L1/c1 + L2/c2 the torsional travel time through both rods, and refined
    by Brent's method to a relative tolerance of about 1e-14.

    Parameters
    ----------
    rods : TwoRods
        Lengths L_j (m), G_j J_j (N m²) and torsional wave speeds c_j (m/s) of both rods.
        ``rods.interface`` and ``rods.damping_ratio`` are not used (the interface is
        ``k_int``, the system undamped).
    count : int
        Number of frequencies, ≥ 1.
    k_int : float
        Linear interface torsional stiffness (N m/rad); inf for a welded interface.

    Returns
    -------
    (count,) ndarray
        The natural frequencies in ascending order (rad/s).

    References
    ----------
    Graff, K. F. (1975). Wave Motion in Elastic Solids, §1.4 and §2.2. Pestel, E. C. &
    Leckie, F. A. (1963). Matrix Methods in Elastomechanics, McGraw-Hill.
    """
    r1, r2 = rods.rods
    tau = r1.length / r1.c_torsion + r2.length / r2.c_torsion
    step = math.pi / tau / 400.0
    roots: list[float] = []
    lo = step * 1e-3
    f_lo = _det(rods, lo, k_int)
    while len(roots) < count:
        hi = lo + step
        f_hi = _det(rods, hi, k_int)
        if f_lo == 0.0:
            roots.append(lo)
        elif f_lo * f_hi < 0.0:
            roots.append(brentq(lambda w: _det(rods, w, k_int), lo, hi, xtol=1e-14 * hi,
                                rtol=1e-15))
        lo, f_lo = hi, f_hi
    return np.array(roots[:count])


def torque_free_frequencies(rods: TwoRods, max_omega: float) -> np.ndarray:
    """Frequencies ≤ ``max_omega`` of the modes that carry no torque through the interface.

    Rod 1 (clamped at −L1) and rod 2 (held by the drive at L2), each with its interface end
    free, vibrate at (j − 1/2) π c/L. Where a frequency of rod 1 equals one of rod 2 (to
    :data:`POLE_RTOL`), the two mode shapes scaled to the same interface rotation form a
    mode of the assembly with no relative rotation and no torque at the interface: no
    interface law — welded, elastic or frictional — does work on it. Undamped, the drive
    excites it without bound at that frequency: a pole of every interface law.

    Parameters
    ----------
    rods : TwoRods
        Lengths L_j (m) and torsional wave speeds c_j (m/s) of both rods.
    max_omega : float
        Upper end of the search (rad/s).

    Returns
    -------
    ndarray
        The frequencies in ascending order (rad/s); usually empty (equal travel times
        L1/c1 and L2/c2, or ratios of odd integers, make them exist).
    """
    def free_end(rod):
        step = math.pi * rod.c_torsion / rod.length
        n = int(max_omega * (1.0 + 2 * POLE_RTOL) / step + 0.5) + 1
        return (np.arange(1, n + 1) - 0.5) * step

    w1, w2 = free_end(rods.rods[0]), free_end(rods.rods[1])
    hit = np.any(np.abs(w1[:, None] / w2[None, :] - 1.0) <= POLE_RTOL, axis=1)
    return w1[hit & (w1 <= max_omega * (1.0 + POLE_RTOL))]


def omega1(rods: TwoRods) -> float:
    """ω1: lowest torsional natural frequency of the welded system, outer ends fixed (rad/s).

    The frequency scale of the two-rod problem (Ω/ω1 in case files and maps):
    ``natural_frequencies(rods.with_(interface="welded"), 1)[0]``.

    Parameters
    ----------
    rods : TwoRods
        Lengths L_j (m), G_j J_j (N m²) and torsional wave speeds c_j (m/s) of both rods;
        the interface law and damping are not used (welded, undamped).

    Returns
    -------
    float
        ω1 (rad/s).

    References
    ----------
    Graff, K. F. (1975). Wave Motion in Elastic Solids, §2.2. Pestel, E. C. & Leckie, F. A.
    (1963). Matrix Methods in Elastomechanics, McGraw-Hill.
    """
    return float(natural_frequencies(rods.with_(interface="welded"), 1)[0])


def normal_force_frf(rods: TwoRods, Omega: float, zeta: float | None = None) -> complex:
    """Interface normal force per unit axial force at x = L2 (closed contact, exact).

    The axial problem does not depend on the torsion, so while the contact stays closed
    (N ≥ 0) the steady normal force is exactly N = F0 + Re(H_N F̂_a e^{iΩt}).
    """
    zeta = rods.damping_ratio if zeta is None else zeta
    r1, r2 = rods.rods
    M1 = transfer_matrix(r1.E * r1.area, r1.c_axial, r1.length, Omega, zeta)
    M2 = transfer_matrix(r2.E * r2.area, r2.c_axial, r2.length, Omega, zeta)
    M = M2 @ M1
    # start (u = 0, tension s) at x = −L1; tension at L2 must equal −F (compression F)
    return complex(M1[1, 1] / M[1, 1])


def normal_force_history(rods: TwoRods, exc, t: np.ndarray) -> np.ndarray:
    """N(t) = F0 + Re(H_N(Ω) F_a e^{i(Ωt + ψ − π/2)}) for the closed contact (N), shape of t.

    Negative values mean the contact would open (separation); callers clip and flag them.
    """
    if exc.axial_amplitude == 0.0:
        return np.full(np.shape(t), exc.axial_force)
    H = normal_force_frf(rods, exc.frequency)
    # F_a sin(Ωt + ψ) = Re(−i F_a e^{i(Ωt+ψ)})
    return exc.axial_force + np.real(H * (-1j) * exc.axial_amplitude
                                     * np.exp(1j * (exc.frequency * t + exc.axial_phase)))

