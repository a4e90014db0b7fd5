"""Exact travelling-wave (characteristic) solution for uniform, undamped rods.

In each uniform rod the torsion is d'Alembert's: φ_j = f_j(t − x/c_j) + g_j(t + x/c_j).
Write the angular velocities of the waves at the interface x = 0 as incoming (towards the
interface) and outgoing. With τ_j = L_j/c_j and the impedances Z_j = J_j √(ρ_j G_j):

* rod 2 (driven end φ2(L2) = Θ): incoming φ̇_2in(t) = Θ̇(t − τ2) − φ̇_2out(t − 2τ2);
* rod 1 (clamped end): incoming φ̇_1in(t) = −φ̇_1out(t − 2τ1);
* interface torque T = Z2 (φ̇_2in − φ̇_2out) = Z1 (φ̇_1out − φ̇_1in).

Eliminating the outgoing waves gives the exact interface equation

    δ̇ = 2 (φ̇_2in − φ̇_1in) − T / Z,      1/Z = 1/Z1 + 1/Z2,      T = T_interface(δ history),

a single first-order equation driven by the delayed incoming waves — no spatial
discretisation and no modal truncation. It is integrated by the trapezoidal rule with the
exact return map of the interface bed (the same :func:`~slipcycle.rods.kernels.bed_step` as
the other solvers, here with series compliance h/(2Z)); delayed values are interpolated
linearly. The only error is O(h²) in the time step, so this is the independent reference
for the modal solution of the frictional problem (ζ = 0, uniform rods, response from rest).

Reference: Graff, *Wave Motion in Elastic Solids* (1975), §1.1–1.3.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from slipcycle.rods.interfaces import Bed
from slipcycle.rods.kernels import bed_step
from slipcycle.rods.model import TwoRods

__all__ = ["characteristic_response"]


@njit(cache=True)
def _delayed(hist, s, lag):
    """Linear interpolation of hist at index s − lag (lag in steps, ≥ 1); 0 before t = 0."""
    x = s - lag
    if x < 0.0:
        return 0.0
    i = int(np.floor(x))
    w = x - i
    if i + 1 >= hist.size:
        return hist[i]
    return (1.0 - w) * hist[i] + w * hist[i + 1]


@njit(cache=True)
def _march(h, lag1, lag2, Z1, Z2, theta_d_delayed, N, t_el, kappa, cap_unit, rigid,
           d, T_out, delta_out):
    K = theta_d_delayed.size
    out1 = np.zeros(K)  # φ̇_1out at step s
    out2 = np.zeros(K)
    nb = t_el.size
    cap = np.empty(nb)
    wt = np.empty(nb + 1)
    wk = np.empty(nb + 1)
    wc = np.empty(nb + 1)
    Z = 1.0 / (1.0 / Z1 + 1.0 / Z2)
    C = 0.5 * h / Z
    T = 0.0
    delta = 0.0
    in1 = -_delayed(out1, 0.0, lag1)
    in2 = theta_d_delayed[0] - _delayed(out2, 0.0, lag2)
    vfree_old = 2.0 * (in2 - in1)
    out2[0] = in2 - T / Z2
    out1[0] = in1 + T / Z1
    T_out[0] = 0.0
    delta_out[0] = 0.0
    y = 0.0
    for s in range(1, K):
        in1 = -_delayed(out1, float(s), lag1)
        in2 = theta_d_delayed[s] - _delayed(out2, float(s), lag2)
        vfree = 2.0 * (in2 - in1)
        dpred = delta + 0.5 * h * (vfree_old + vfree) - C * T
        Nn = N[s] if N[s] > 0.0 else 0.0
        for i in range(nb):
            cap[i] = cap_unit[i] * Nn
        T, y = bed_step(t_el, kappa, cap, rigid, (dpred - delta) / C, C, y, wt, wk, wc, d)
        delta += y
        out2[s] = in2 - T / Z2
        out1[s] = in1 + T / Z1
        vfree_old = vfree
        T_out[s] = T
        delta_out[s] = delta


def characteristic_response(rods: TwoRods, bed: Bed, t: np.ndarray, theta_d, N) -> dict:
    """Response from rest of the undamped uniform rods to a drive Θ(t) (exact waves).

    Parameters
    ----------
    rods : TwoRods
    bed : Bed
        Interface law.
    t : (K,) array
        Uniform times from 0 (s); the step must be below the travel times τ_j/2.
    theta_d : callable
        Θ̇(t) (rad/s), evaluated at t − τ2 (taken as 0 for negative arguments).
    N : (K,) array or float
        Normal force (N).

    Returns
    -------
    dict
        ``T`` interface torque (N m), ``delta`` relative rotation (rad), ``dissipation`` (J).
    """
    r1, r2 = rods.rods
    h = float(t[1] - t[0])
    tau1, tau2 = r1.length / r1.c_torsion, r2.length / r2.c_torsion
    if h >= min(tau1, tau2):
        raise ValueError("time step must be shorter than the travel times of both rods")
    td = np.where(t - tau2 >= 0.0, theta_d(np.maximum(t - tau2, 0.0)), 0.0)
    Nv = np.broadcast_to(np.asarray(N, dtype=float), t.shape).copy()
    t_el = np.zeros(bed.size)
    d = np.zeros(bed.size)
    T_out = np.empty(t.size)
    delta_out = np.empty(t.size)
    _march(h, 2.0 * tau1 / h, 2.0 * tau2 / h, r1.impedance_torsion, r2.impedance_torsion,
           td, Nv, t_el, np.ascontiguousarray(bed.kappa, dtype=float),
           np.ascontiguousarray(bed.cap_unit, dtype=float), bed.rigid, d, T_out, delta_out)
    return {"T": T_out, "delta": delta_out, "dissipation": float(d.sum())}
