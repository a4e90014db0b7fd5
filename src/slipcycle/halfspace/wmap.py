"""Dimensionless dissipation map Ŵ(P̂1, Q̂1, φ) of rough contacts (seed 001 §4.6).

For the rough law dP/dU = P/(γσ) the dissipation per cycle under
P = P0(1 + P̂1 cos θ), Q = f P0 Q̂1 cos(θ − φ) scales as W = λ_c γσ f² P0 Ŵ(P̂1, Q̂1, φ)
(Putignano et al.), so the map is computed once with P0 = γσ = f = λ_c = 1. Every grid
point runs the same slider bed through a normal preload, a tangential ramp to the start
of the cycle and two cycles (the second is steady for an uncoupled bed: frictional Melan
theorem; tests check it against a third). Each point gets its own bed: sliders that stay
below every stick load of the history are lumped, the rest equally spaced in load. Grid
points run in parallel threads (Numba ``prange``) without Python overhead per point.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from slipcycle.halfspace.kernels import drive

__all__ = ["w_hat_map", "w_hat_point"]


@njit(cache=True)
def _rough_bed(P_lo, P_max, n):
    """Slider bed of P = exp(U) (γσ = 1) exact at n+1 equally spaced loads in [P_lo, P_max],
    with everything below P_lo lumped into one slider (same construction as make_bed)."""
    level = np.empty(n + 1)
    kn = np.empty(n + 1)
    level[0] = np.log(P_lo) - 1.0          # reproduces P and dP/dU at P_lo
    kn[0] = P_lo
    dP = (P_max - P_lo) / n
    for j in range(n):
        Pa = P_lo + j * dP
        Pb = Pa + dP
        kn[j + 1] = dP                      # ΔS with S = dP/dU = P
        level[j + 1] = (np.log(Pb) * Pb - np.log(Pa) * Pa - dP) / dP
    K = np.cumsum(kn)
    M = np.cumsum(kn * level)
    P_knots = np.empty(n + 1)
    P_knots[0] = 0.0
    for j in range(1, n + 1):
        P_knots[j] = K[j - 1] * level[j] - M[j - 1]
    return level, kn, K, M, P_knots


@njit(cache=True)
def _one_point(P1, Q1, phi, n_sliders, steps, asm_steps, cycles):
    """Ŵ of the last of ``cycles`` cycles; nan when |Q| reaches fP somewhere (gross slip)."""
    P_start = 1.0 + P1
    Q_start = Q1 * np.cos(-phi)
    # Sliders whose load level stays below every stick load P_S = P - |ΔQ|/f of the history
    # never slip; lumping them costs nothing and puts the resolution where slip happens.
    bound = min(1.0 - P1 - 2.0 * Q1, P_start - abs(Q_start))
    P_lo = 0.9 * bound if bound > 0.05 * (1.0 - P1) else 0.05 * (1.0 - P1)
    level, kn, K, M, P_knots = _rough_bed(P_lo, P_start * (1 + 1e-9), n_sliders)
    kt = kn.copy()
    n = level.size
    total = 2 * asm_steps + cycles * steps
    U = np.empty(total)
    T = np.empty(total)
    # loads: preload P(0) at Q = 0, ramp Q to Q(0), then the cycles
    for k in range(total):
        if k < asm_steps:
            P = P_start * (k + 1) / asm_steps
            Q = 0.0
        elif k < 2 * asm_steps:
            P = P_start
            Q = Q_start * (k - asm_steps + 1) / asm_steps
        else:
            th = 2.0 * np.pi * (k - 2 * asm_steps + 1) / steps
            P = 1.0 + P1 * np.cos(th)
            Q = Q1 * np.cos(th - phi)
        # exact inverse of the bed's piecewise-linear P(U)
        j = max(np.searchsorted(P_knots, P, side="right") - 1, 0)
        U[k] = (P + M[j]) / K[j]
        T[k] = Q
    t = np.zeros(n)
    z = np.zeros(n)
    d = np.zeros(n)
    V_out = np.empty(total)
    Q_out = np.empty(total)
    first = np.empty(total, np.int64)
    idx = np.empty(0, np.int64)
    rec = np.empty((0, n))
    status, _ = drive(t, z, d, level, kn, kt, 1.0, U, T, True, 0.0, idx, rec, rec,
                      V_out, Q_out, first)
    if status >= 0:
        return np.nan
    s0 = total - steps - 1
    W = 0.0
    for k in range(s0 + 1, total):
        W += 0.5 * (Q_out[k] + Q_out[k - 1]) * (V_out[k] - V_out[k - 1])
    return W


@njit(parallel=True, cache=True)
def _grid(P1s, Q1s, phis, n_sliders, steps, asm_steps, cycles):
    n1, n2, n3 = P1s.size, Q1s.size, phis.size
    out = np.empty(n1 * n2 * n3)
    for flat in prange(n1 * n2 * n3):
        i = flat // (n2 * n3)
        j = (flat // n3) % n2
        k = flat % n3
        out[flat] = _one_point(P1s[i], Q1s[j], phis[k], n_sliders, steps, asm_steps, cycles)
    return out.reshape((n1, n2, n3))


def w_hat_map(P1_hat, Q1_hat, phase, *, steps_per_cycle: int = 200, n_sliders: int = 100,
              cycles: int = 2, assembly_steps: int = 20) -> np.ndarray:
    """Ŵ on the grid P1_hat × Q1_hat × phase.

    Parameters
    ----------
    P1_hat, Q1_hat, phase : 1-D arrays
        P̂1 = P1/P0 in [0, 1), Q̂1 = Q1/(f P0) ≥ 0, φ in rad.
    steps_per_cycle, n_sliders, cycles, assembly_steps : int
        Discretisation (see module docstring; the convergence tests state the error).

    Returns
    -------
    (len(P1_hat), len(Q1_hat), len(phase)) array
        Ŵ; nan where the load path leaves the friction cone (gross slip).
    """
    P1 = np.atleast_1d(np.asarray(P1_hat, float))
    Q1 = np.atleast_1d(np.asarray(Q1_hat, float))
    ph = np.atleast_1d(np.asarray(phase, float))
    if np.any(P1 < 0) or np.any(P1 >= 1):
        raise ValueError("P1_hat must lie in [0, 1) (the contact must stay closed)")
    if np.any(Q1 < 0):
        raise ValueError("Q1_hat must be >= 0")
    return _grid(P1, Q1, ph, n_sliders, steps_per_cycle, assembly_steps, cycles)


def w_hat_point(P1_hat: float, Q1_hat: float, phase: float, **kw) -> float:
    """Ŵ at one point (see :func:`w_hat_map`)."""
    return float(w_hat_map([P1_hat], [Q1_hat], [phase], **kw)[0, 0, 0])
