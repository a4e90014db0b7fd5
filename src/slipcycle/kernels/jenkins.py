"""The exact force-controlled step of a bed of Jenkins elements (Numba).

A bed is n elements in parallel; element i has stiffness κ_i, force t_i and a limit c_i.
Given a target total force Q, the displacement increment ΔV is the root of the monotone
piecewise-linear equation

    Σ_i clip(t_i + κ_i ΔV, −c_i, c_i) = Q.

It is solved exactly: Newton iterations on the active set (each lands on the root once the
stick set of the current piece is the final one), safeguarded by a bracket with Illinois
steps, and, should that ever stall, a bisection over the sorted breakpoints followed by the
exact linear solve on the final piece.

Used by the half-space slider bed (:mod:`slipcycle.halfspace.kernels`, after Jäger's
slider representation of Mindlin contacts) and by the rod interface beds
(:mod:`slipcycle.rods.kernels`); it belongs to neither, so neither model imports the other.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["solve_tangential_force"]

_MAX_NEWTON = 60


@njit(cache=True, inline="always")
def _clip(x, c):
    if x > c:
        return c
    if x < -c:
        return -c
    return x


@njit(cache=True)
def _force_and_slope(t, kt, cap, dv):
    q = 0.0
    s = 0.0
    for i in range(t.size):
        x = t[i] + kt[i] * dv
        c = cap[i]
        if x >= c:
            q += c
        elif x <= -c:
            q -= c
        else:
            q += x
            s += kt[i]
    return q, s


@njit(cache=True)
def _solve_exact_sorted(t, kt, cap, target, lo, hi):
    """Fallback: bisection over sorted breakpoints, then the exact solve on one piece."""
    n = t.size
    bp = np.empty(2 * n)
    m = 0
    for i in range(n):
        for sgn in (-1.0, 1.0):
            b = (sgn * cap[i] - t[i]) / kt[i]
            if lo < b < hi:
                bp[m] = b
                m += 1
    bp = np.sort(bp[:m])
    a, b = 0, m - 1
    left, right = lo, hi
    while a <= b:  # find the two consecutive breakpoints bracketing the root
        mid = (a + b) // 2
        q, _ = _force_and_slope(t, kt, cap, bp[mid])
        if q < target:
            left = bp[mid]
            a = mid + 1
        else:
            right = bp[mid]
            b = mid - 1
    # g is linear on [left, right]
    ql, _ = _force_and_slope(t, kt, cap, left)
    qr, _ = _force_and_slope(t, kt, cap, right)
    if qr == ql:
        return left
    return left + (target - ql) * (right - left) / (qr - ql)


@njit(cache=True)
def _newton(t, kt, cap, target, x, r, s, lo, hi, qmax):
    """Safeguarded Newton on the active set, from x with residual r and slope s."""
    tol = 1e-13 * (qmax + abs(target))
    g_lo = -qmax - target
    g_hi = qmax - target
    side = 0
    for it in range(_MAX_NEWTON):
        if abs(r) <= tol:
            return x, it
        if r < 0:
            lo, g_lo = x, r
            if side == -1:
                g_hi *= 0.5  # Illinois: keep regula falsi from stalling on one side
            side = -1
        else:
            hi, g_hi = x, r
            if side == 1:
                g_lo *= 0.5
            side = 1
        xn = x - r / s if s > 0 else np.nan
        if not (lo < xn < hi):
            xn = lo - g_lo * (hi - lo) / (g_hi - g_lo)
            if not (lo < xn < hi):
                xn = 0.5 * (lo + hi)
        x = xn
        q, s = _force_and_slope(t, kt, cap, x)
        r = q - target
    return _solve_exact_sorted(t, kt, cap, target, lo, hi), _MAX_NEWTON + 2


@njit(cache=True)
def _bracket(t, kt, cap):
    """Total capacity and the ΔV at which every slider is at −c (lo) or at +c (hi)."""
    qmax = 0.0
    lo = np.inf
    hi = -np.inf
    for i in range(t.size):
        qmax += cap[i]
        a = (-cap[i] - t[i]) / kt[i]
        b = (cap[i] - t[i]) / kt[i]
        lo = min(lo, a)
        hi = max(hi, b)
    return qmax, lo, hi


@njit(cache=True)
def solve_tangential_force(t, kt, cap, target, guess):
    """ΔV with Σ clip(t + κ ΔV, ±c) = target; assumes |target| < Σ c. Returns (ΔV, passes)."""
    qmax, lo, hi = _bracket(t, kt, cap)
    x = min(max(guess, lo), hi)
    q, s = _force_and_slope(t, kt, cap, x)
    dv, it = _newton(t, kt, cap, target, x, q - target, s, lo, hi, qmax)
    return dv, it + 2
