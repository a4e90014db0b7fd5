"""The exact force-controlled step of a bed of Jenkins elements (Numba).

A bed is n elements in parallel; element i has stiffness κ_i, force t_i and a limit c_i.
Given a target total force Q, the displacement increment ΔV is the root of the monotone
piecewise-linear equation

    Σ_i clip(t_i + κ_i ΔV, −c_i, c_i) = Q.

It is solved exactly: Newton iterations on the active set (each lands on the root once the
stick set of the current piece is the final one), safeguarded by a bracket with Illinois
steps, and, should that ever stall, a bisection over the sorted breakpoints followed by the
exact linear solve on the final piece.

Once ΔV is known, :func:`apply_increment` moves every element by it: the return map of a
Jenkins element with a (moving) limit c_i,

    t_i ← clip(t_i + κ_i ΔV, −c_i, c_i),   Δz_i = ΔV − Δt_i/κ_i,

booking the dissipation ½(t_old + t_new) Δz_i. Both steps serve the half-space slider bed
(:mod:`slipcycle.halfspace.kernels`, after Jäger's slider representation of Mindlin
contacts; also the Ŵ map, which drives the same bed) and the rod interfaces: rings, a single
Jenkins element and the Segalman–Iwan element discretised as a bed
(:mod:`slipcycle.rods.kernels`). The kernel belongs to neither model, so neither imports
the other.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["solve_tangential_force", "apply_increment", "drive_force_moving_limits"]

_MAX_NEWTON = 60
#: the root is accepted when |Σ clip − Q| ≤ _RTOL (Σ |clip| + |Q|): relative to the forces
#: being summed (their round-off), not to the bed's capacity Σ c_i, which a tiny load
#: (1e-12 of it) would leave unresolved
_RTOL = 1e-13


@njit(cache=True, inline="always")
def at_root(r, qa, target):
    """Whether the residual r = Σ clip − Q is the root's within round-off of the forces
    summed, qa = Σ |clip| (relative tolerance ``_RTOL``)."""
    return abs(r) <= _RTOL * (qa + abs(target))


@njit(cache=True, inline="always")
def _clip(x, c):
    if x > c:
        return c
    if x < -c:
        return -c
    return x


@njit(cache=True)
def _force_and_slope(t, kt, cap, dv):
    """Σ clip(t + κ ΔV, ±c), its slope, and Σ |clip(t + κ ΔV, ±c)| (the sum's scale)."""
    q = 0.0
    s = 0.0
    qa = 0.0
    for i in range(t.size):
        x = t[i] + kt[i] * dv
        c = cap[i]
        if x >= c:
            q += c
            qa += c
        elif x <= -c:
            q -= c
            qa += c
        else:
            q += x
            qa += abs(x)
            s += kt[i]
    return q, s, qa


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
        q, _, _ = _force_and_slope(t, kt, cap, bp[mid])
        if q < target:
            left = bp[mid]
            a = mid + 1
        else:
            right = bp[mid]
            b = mid - 1
    # g is linear on [left, right]
    ql, _, _ = _force_and_slope(t, kt, cap, left)
    qr, _, _ = _force_and_slope(t, kt, cap, right)
    if qr == ql:
        return left
    return left + (target - ql) * (right - left) / (qr - ql)


@njit(cache=True)
def _newton(t, kt, cap, target, x, r, s, lo, hi, qmax, qa):
    """Safeguarded Newton on the active set, from x with residual r, slope s and force
    scale qa = Σ |clip(t + κ x, ±c)|; qmax = Σ c bounds the residual on the bracket."""
    g_lo = -qmax - target
    g_hi = qmax - target
    side = 0
    for it in range(_MAX_NEWTON):
        if at_root(r, qa, target):
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
        q, s, qa = _force_and_slope(t, kt, cap, x)
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
    q, s, qa = _force_and_slope(t, kt, cap, x)
    dv, it = _newton(t, kt, cap, target, x, q - target, s, lo, hi, qmax, qa)
    return dv, it + 2


@njit(cache=True)
def apply_increment(t, k, k_step, cap, dv, d, z, slip, slip_tol):
    """Move every element of a bed by the common increment ΔV; updates the state in place.

    Element i takes the share ``k_step[i] / k[i]`` of ΔV (1 for an element in contact over
    the whole step; less for a slider of the half-space bed that touches during the step,
    which carries only the displacement after it touches), i.e. its trial force is
    t_i + k_step[i] ΔV, returned to [−c_i, c_i].

    Parameters
    ----------
    t : (n,) array
        Element forces (N, or N m for rotations), updated.
    k, k_step : (n,) arrays
        Element stiffnesses and the stiffnesses they show over this step (N/m or N m/rad).
    cap : (n,) array
        Limits c_i ≥ 0 at the end of the step.
    dv : float
        The common displacement (rotation) increment ΔV.
    d : (n,) array
        Dissipation per element (J), incremented by ½(t_old + t_new)(ΔV − Δt_i/k_i): booked
        against the common ΔV, so that Σ_i d_i is the trapezoidal ∮Q dV exactly.
    z, slip : (n,) arrays
        Accumulated slip of each element (m or rad) and its absolute value while the limit
        is positive (an element leaving contact releases its force; that is not slip).
    slip_tol : float
        An element counts as slipping when its trial force exceeds its limit by more than
        ``slip_tol`` times the limit (so an element brought back exactly to its limit, as on
        a proportional path, is not slipping because of rounding).

    Returns
    -------
    q : float
        The total force Σ t_i after the step.
    n_slip : int
        Number of slipping elements.
    first : int
        Index of the lowest slipping element (n if none).
    """
    n = t.size
    first = n
    q = 0.0
    n_slip = 0
    for i in range(n):
        told = t[i]
        x = told + k_step[i] * dv
        c = cap[i]
        if x > c or x < -c:
            tn = c if x > c else -c
            back = (tn - told) / k[i]
            dz = dv * k_step[i] / k[i] - back
            if c > 0.0 and abs(x) - c > slip_tol * c:
                n_slip += 1
                if i < first:
                    first = i
            d[i] += 0.5 * (told + tn) * (dv - back)
            z[i] += dz
            if c > 0.0:
                slip[i] += abs(dz)
        else:
            tn = x
            # a stuck element that was in contact over the whole step takes the whole ΔV
            # elastically: its exact slip and dissipation are 0 (the general formula gives
            # 0 up to round-off, at the price of a division per element and step)
            if k_step[i] != k[i]:
                d[i] += 0.5 * (told + tn) * (dv - (tn - told) / k[i])
        t[i] = tn
        q += tn
    return q, n_slip, first


@njit(cache=True)
def drive_force_moving_limits(t, level, kn, kt, inv_kt, friction, U_path, T_path, U0, V0,
                              V_out, Q_out, first_out, status, slip_tol):
    """Drive L copies ("lanes") of one Jenkins bed with moving limits, each along its own
    force-controlled path, over a common approach path; one sweep per step.

    Element i engages at the approach U = s_i (``level``), has limit c_i = f k_i (U − s_i)₊
    and stiffness κ_i; an element engaging inside a step (U linear within it) takes the
    share (U − s_i)/(U − U_old) of ΔV. This is Jäger's slider bed of a half-space contact
    (Jäger 1998; Ciavarella 1998), the bed that :func:`slipcycle.halfspace.kernels.drive_with`
    drives, and each lane does exactly its arithmetic: the return map ``_clip`` of the
    elements (the law of :func:`apply_increment`), the one-step root of
    Σ clip(t_i + κ_i ΔV, ±c_i) = Q when no breakpoint lies before it and otherwise the
    safeguarded Newton iteration of :func:`solve_tangential_force`, so every lane gives
    the same bits as ``drive_with`` on its own.

    What differs is the work: the limits and step stiffnesses, which depend only on the
    approach, are computed once for all lanes; the sweep that returns step k's elements
    also sets up step k + 1; and the lanes sit side by side in memory, so that the inner
    loop over lanes runs in SIMD registers. Dissipation, slip and base displacement are
    not booked (callers that need them use :func:`apply_increment`).

    Parameters
    ----------
    t : (n, L) array
        Element forces of every lane, updated in place.
    level, kn, kt, inv_kt : (n,) arrays
        Engagement approaches s_i, normal stiffnesses k_i, tangential stiffnesses κ_i and
        1/κ_i.
    friction : float
        f.
    U_path : (K,) array
        Approach at each step (common to the lanes).
    T_path : (K, L) array
        Total tangential force Q of each lane at each step.
    U0 : float
        Approach before the first step.
    V0 : (L,) array
        Tangential displacement of each lane before the first step.
    V_out, Q_out : (K, L) arrays
        Tangential displacement and total force Σ t_i after each step (written).
    first_out : (K, L) int array
        Index of the lowest element slipping in each step (n if none); an element slips
        when its trial force exceeds its limit by more than ``slip_tol`` times the limit.
    status : (L,) int array
        In: −1 for a lane to drive; a lane with any other value is not driven (ΔV = 0; its
        state and outputs are not meaningful). Out: a lane that reaches
        |Q| ≥ (1 − 1e-12) Σ c_i (gross slip) at step k gets k; its outputs up to step k − 1
        are those of ``drive_with``, later ones and its state are not meaningful.
    slip_tol : float
    """
    n, L = t.shape
    K = U_path.size
    cap = np.empty((2, n))
    ke = np.empty((2, n))
    V = V0.copy()
    dv = np.zeros(L)
    q0 = np.empty(L)
    qa0 = np.empty(L)
    s0 = np.empty(L)
    lo = np.empty(L)
    hi = np.empty(L)
    below = np.empty(L)
    above = np.empty(L)
    q = np.empty(L)
    first = np.empty(L, np.int64)
    U_old = U0
    U = U_path[0]
    for k in range(K + 1):
        # one sweep: return the elements of step k − 1 by dv, set up step k
        cur = k % 2
        prev = 1 - cur
        last = k == K
        qmax = 0.0
        q0[:] = 0.0
        qa0[:] = 0.0
        s0[:] = 0.0
        lo[:] = 0.0
        hi[:] = 0.0
        below[:] = -np.inf
        above[:] = np.inf
        q[:] = 0.0
        first[:] = n
        for i in range(n):
            if k > 0:
                cp = cap[prev, i]
                kp = ke[prev, i]
                for p in range(L):
                    x = t[i, p] + kp * dv[p]
                    ti = _clip(x, cp)
                    if cp > 0.0 and abs(x) - cp > slip_tol * cp and i < first[p]:
                        first[p] = i
                    t[i, p] = ti
                    q[p] += ti
            if last:
                continue
            gap = U - level[i]
            c = friction * kn[i] * gap if gap > 0.0 else 0.0
            cap[cur, i] = c
            qmax += c
            old_gap = U_old - level[i]
            if gap > 0.0 and old_gap < 0.0:
                kei = kt[i] * gap / (gap - old_gap)
                inv = 1.0 / kei
            else:
                kei = kt[i]
                inv = inv_kt[i]
            ke[cur, i] = kei
            for p in range(L):
                ti = t[i, p]
                if ti >= c:
                    q0[p] += c
                    qa0[p] += c
                elif ti <= -c:
                    q0[p] -= c
                    qa0[p] += c
                else:
                    q0[p] += ti
                    qa0[p] += abs(ti)
                    s0[p] += kei
                b_lo = (-c - ti) * inv
                b_hi = (c - ti) * inv
                lo[p] = min(lo[p], b_lo)
                hi[p] = max(hi[p], b_hi)
                if c > 0.0:  # an element out of contact carries nothing: no breakpoint
                    # reaching +c ahead, or leaving +c behind (0: at the limit now)
                    if b_hi > 0.0:
                        above[p] = min(above[p], b_hi)
                    else:
                        below[p] = max(below[p], b_hi)
                    if b_lo < 0.0:
                        below[p] = max(below[p], b_lo)
                    else:
                        above[p] = min(above[p], b_lo)
        live = 0
        for p in range(L):
            if k > 0:
                V[p] += dv[p]
                V_out[k - 1, p] = V[p]
                Q_out[k - 1, p] = q[p]
                first_out[k - 1, p] = first[p]
            dv[p] = 0.0
            if last or status[p] != -1:
                continue
            target = T_path[k, p]
            if target != 0.0 and abs(target) >= qmax * (1.0 - 1e-12):
                status[p] = k
                continue
            live += 1
            if qmax > 0.0:  # else nothing in contact and no load: nothing moves
                # the first Newton step, taken when it provably lands on the root (no
                # breakpoint between 0 and it); else the safeguarded iteration
                r0 = q0[p] - target
                d = 0.0 - r0 / s0[p] if s0[p] > 0.0 else np.nan
                if at_root(r0, qa0[p], target):
                    d = 0.0
                elif not (below[p] < d < above[p]):
                    d, _ = _newton(t[:, p], ke[cur], cap[cur], target, 0.0, r0, s0[p],
                                   lo[p], hi[p], qmax, qa0[p])
                dv[p] = d
        if live == 0:
            return  # every lane stopped
        U_old = U
        if k + 1 < K:
            U = U_path[k + 1]
