"""Dimensionless dissipation map Ŵ(P̂1, Q̂1, φ) of rough contacts (Barber 2012, §4.6).

For the rough law dP/dU = P/(γσ) the dissipation per cycle under
P = P0(1 + P̂1 cos θ), Q = f P0 Q̂1 cos(θ − φ) scales as W = λ_c γσ f² P0 Ŵ(P̂1, Q̂1, φ)
(Putignano et al.), so the map is computed once with P0 = γσ = f = λ_c = 1. Every grid
point runs the same slider bed through a normal preload, a tangential ramp to the start
of the cycle and two cycles (the second is steady for an uncoupled bed: frictional Melan
theorem; tests check it against a third). Each point gets its own bed, built by the same
compiled functions as ``slipcycle run`` (:func:`~slipcycle.halfspace.bed.rough_unit_bed`,
:func:`~slipcycle.halfspace.bed.lumping_load`): sliders that stay below every stick load of
the history are lumped, the rest equally spaced in load. Grid points run in parallel
threads (Numba ``prange``) without Python overhead per point.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from slipcycle.halfspace.bed import UNLUMPED_FRACTION, lumping_load, rough_unit_bed
from slipcycle.halfspace.kernels import drive_from

__all__ = ["w_hat_map", "w_hat_point"]


@njit(cache=True)
def _path(P1, Q1, phi, level, kn, steps, asm_steps, cycles):
    """Approach and tangential load at every step: preload, tangential ramp, cycles."""
    P_start = 1.0 + P1
    Q_start = Q1 * np.cos(-phi)
    K = np.cumsum(kn)
    M = np.cumsum(kn * level)
    P_knots = np.empty(level.size)
    P_knots[0] = 0.0
    for j in range(1, level.size):
        P_knots[j] = K[j - 1] * level[j] - M[j - 1]
    total = 2 * asm_steps + cycles * steps
    U = np.empty(total)
    T = np.empty(total)
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
    return U, T


@njit(cache=True)
def _run_point(P1, Q1, phi, P_lo, n_sliders, steps, asm_steps, cycles):
    """(Ŵ of the last cycle or nan at gross slip, lowest slipping slider index)."""
    P_max = (1.0 + abs(P1)) * (1 + 1e-9)    # the largest load, θ = 0
    level, kn, _ = rough_unit_bed(P_lo, P_max, n_sliders)
    kt = kn.copy()
    n = level.size
    U, T = _path(P1, Q1, phi, level, kn, steps, asm_steps, cycles)
    total = U.size
    t = np.zeros(n)
    z = np.zeros(n)
    d = np.zeros(n)
    slip = np.zeros(n)
    V_out = np.empty(total)
    Q_out = np.empty(total)
    first = np.empty(total, np.int64)
    idx = np.empty(0, np.int64)
    rec = np.empty((0, n))
    status, _ = drive_from(t, z, d, slip, level, kn, kt, 1.0, U, T, True, 0.0, level[0], idx,
                           rec, rec, V_out, Q_out, first)
    if status >= 0:
        return np.nan, 0
    s0 = total - steps - 1
    W = 0.0
    for k in range(s0 + 1, total):
        W += 0.5 * (Q_out[k] + Q_out[k - 1]) * (V_out[k] - V_out[k - 1])
    return W, first.min()


@njit(cache=True)
def _one_point(P1, Q1, phi, n_sliders, steps, asm_steps, cycles):
    """Ŵ of the last of ``cycles`` cycles; nan when |Q| reaches fP somewhere (gross slip).

    The bed is the one :meth:`HalfspaceModel.bed` builds for the same history: sliders
    below :func:`~slipcycle.halfspace.bed.lumping_load` are lumped, and the point is rerun
    on an unlumped bed should slip reach them.
    """
    # extremes of the loads the history visits: the start state and the cycle's samples
    # (the path is linear between them), as HalfspaceModel.lumping_load takes them
    P_min = P_max = 1.0 + P1
    Q_lo = Q_hi = Q1 * np.cos(-phi)
    for k in range(1, steps + 1):
        th = 2.0 * np.pi * k / steps
        P = 1.0 + P1 * np.cos(th)
        Q = Q1 * np.cos(th - phi)
        P_min, P_max = min(P_min, P), max(P_max, P)
        Q_lo, Q_hi = min(Q_lo, Q), max(Q_hi, Q)
    P_lo = lumping_load(P_min, P_max, Q_lo, Q_hi, 1.0)
    fallback = UNLUMPED_FRACTION * P_max
    W, first = _run_point(P1, Q1, phi, P_lo if P_lo > 0.0 else fallback, n_sliders, steps,
                          asm_steps, cycles)
    if P_lo > 0.0 and first <= 1 and not np.isnan(W):
        W, first = _run_point(P1, Q1, phi, fallback, n_sliders, steps, asm_steps, cycles)
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
