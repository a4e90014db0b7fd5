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
threads (Numba ``prange``, in a scattered order so that both threads get their share of
the cheap gross-slip points) without Python overhead per point.

Points whose history admits no lumping bound (about two thirds of the work of a full map)
all run on the unlumped bed of their P̂1 along the same approach path; only the tangential
load differs. They are driven :data:`LANES` at a time as lanes of one bed
(:func:`slipcycle.kernels.jenkins.drive_force_moving_limits`): the limits and step
stiffnesses are computed once for all lanes and the lanes' sweeps run side by side. Each
lane does the arithmetic of the one-point driver
(:func:`slipcycle.halfspace.kernels.drive_with`), so the map is the same to the bit as
driving the points one by one. The cosines of the cycles are tabulated once per map.

Work that cannot change a value is not done (``reference=True`` does all of it, and tests
compare the two to round-off):

- a path whose samples certainly leave the friction cone (|Q| ≥ fP with a margin of 1e-9
  over the bed's round-off) is gross slip without driving the bed;
- the preload (Q = 0 on an unloaded bed) moves no slider and is not driven;
- the unlumped bed of each P̂1 and its approach path are built once, not per point;
- the second cycle stops at the first chunk end (every :data:`CHUNK` steps) where every
  slider force equals that of the first cycle at the same step to :data:`STATE_MATCH`:
  the bed's step depends only on its state and the loads, so from there the second cycle
  repeats the first (its dissipation is taken from it). In practice the two cycles meet
  after about half a cycle, at the first load extreme that wipes the memory of the ramp
  (Masing behaviour of the Jenkins bed).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from slipcycle.halfspace.bed import UNLUMPED_FRACTION, lumping_load, rough_unit_bed
from slipcycle.halfspace.kernels import SLIP_TOL, drive_from, drive_with
from slipcycle.kernels.jenkins import drive_force_moving_limits

__all__ = ["w_hat_map", "w_hat_point"]


@njit(cache=True)
def _cycle_cosines(phis, steps, cycles):
    """cos θ_j, shape (J,), and cos(θ_j − φ_k), shape (K, J), at the samples of the cycles
    θ_j = 2π j/steps, j = 1 .. J = cycles·steps: computed once per map and reused by every
    point, with the bits of the expressions the paths were written with."""
    J = cycles * steps
    cos_P = np.empty(J)
    cos_Q = np.empty((phis.size, J))
    for j in range(J):
        th = 2.0 * np.pi * (j + 1) / steps
        cos_P[j] = np.cos(th)
        for k in range(phis.size):
            cos_Q[k, j] = np.cos(th - phis[k])
    return cos_P, cos_Q


@njit(cache=True)
def _approach_path(P1, level, kn, steps, asm_steps, cycles):
    """Approach U at every step of preload, tangential ramp and cycles: the exact inverse of
    the bed's piecewise-linear P(U) at P = P0(1 + P̂1) k/n (preload), P0(1 + P̂1) (ramp) and
    P0(1 + P̂1 cos θ) (cycles), P0 = 1."""
    cos_P, _ = _cycle_cosines(np.zeros(0), steps, cycles)
    return _approach_from(P1, level, kn, cos_P, steps, asm_steps, cycles)


@njit(cache=True)
def _approach_from(P1, level, kn, cos_P, steps, asm_steps, cycles):
    """:func:`_approach_path` with the cosines of the cycles given (:func:`_cycle_cosines`)."""
    P_start = 1.0 + P1
    K = np.cumsum(kn)
    M = np.cumsum(kn * level)
    P_knots = np.empty(level.size)
    P_knots[0] = 0.0
    for j in range(1, level.size):
        P_knots[j] = K[j - 1] * level[j] - M[j - 1]
    total = 2 * asm_steps + cycles * steps
    U = np.empty(total)
    for k in range(total):
        if k < asm_steps:
            P = P_start * (k + 1) / asm_steps
        elif k < 2 * asm_steps:
            P = P_start
        else:
            P = 1.0 + P1 * cos_P[k - 2 * asm_steps]
        j = max(np.searchsorted(P_knots, P, side="right") - 1, 0)
        U[k] = (P + M[j]) / K[j]
    return U


@njit(cache=True)
def _tangential_path(Q1, phi, steps, asm_steps, cycles):
    """Tangential load Q at every step: 0 (preload), a ramp to Q̂1 cos φ, then Q̂1 cos(θ − φ)."""
    _, cos_Q = _cycle_cosines(np.array([phi]), steps, cycles)
    return _tangential_from(Q1, Q1 * np.cos(-phi), cos_Q[0], steps, asm_steps, cycles)


@njit(cache=True)
def _tangential_from(Q1, Q_start, cos_Q, steps, asm_steps, cycles):
    """:func:`_tangential_path` from Q_start = Q̂1 cos(−φ) and the cosines cos(θ_j − φ)."""
    total = 2 * asm_steps + cycles * steps
    T = np.empty(total)
    for k in range(total):
        if k < asm_steps:
            T[k] = 0.0
        elif k < 2 * asm_steps:
            T[k] = Q_start * (k - asm_steps + 1) / asm_steps
        else:
            T[k] = Q1 * cos_Q[k - 2 * asm_steps]
    return T


@njit(cache=True)
def _path(P1, Q1, phi, level, kn, steps, asm_steps, cycles):
    """Approach and tangential load at every step: preload, tangential ramp, cycles."""
    return (_approach_path(P1, level, kn, steps, asm_steps, cycles),
            _tangential_path(Q1, phi, steps, asm_steps, cycles))


@njit(cache=True)
def _gross_slip_verdict(P1, Q1, phi, steps, asm_steps):
    """1 if the sampled path certainly leaves the friction cone, 0 if it certainly stays
    inside, −1 when it grazes the cone too closely to tell without the bed.

    The bed is exact in P(U) at every sample, so its total limit there is f P up to
    round-off (relative 1e-14 at most, far below the 1e-9 margin); the driver reports gross
    slip at the first sample with |Q| ≥ (1 − 1e-12) f P (f = P0 = 1 here).
    """
    cos_P, cos_Q = _cycle_cosines(np.array([phi]), steps, 1)
    return _verdict_from(P1, Q1, Q1 * np.cos(-phi), cos_P, cos_Q[0], steps, asm_steps)


@njit(cache=True)
def _verdict_from(P1, Q1, Q_start, cos_P, cos_Q, steps, asm_steps):
    """:func:`_gross_slip_verdict` from Q_start = Q̂1 cos(−φ) and the cosines of the cycle."""
    verdict = 0
    for k in range(asm_steps + steps):
        if k < asm_steps:
            P = 1.0 + P1
            Q = Q_start * (k + 1) / asm_steps
        else:
            P = 1.0 + P1 * cos_P[k - asm_steps]
            Q = Q1 * cos_Q[k - asm_steps]
        edge = P * (1.0 - 1e-12)
        if abs(Q) >= edge * (1.0 + 1e-9):
            return 1
        if abs(Q) >= edge * (1.0 - 1e-9):
            verdict = -1
    return verdict


@njit(cache=True)
def _trapezoid(Q, V, s0, total):
    """∮Q dV over the steps s0+1 .. total−1 (trapezoidal), in the order the reference sums."""
    W = 0.0
    for k in range(s0 + 1, total):
        W += 0.5 * (Q[k] + Q[k - 1]) * (V[k] - V[k - 1])
    return W


#: steps per chunk of the second cycle between comparisons with the first
CHUNK = 8
_NO_RECORD = np.empty(0, np.int64)
#: two slider states agree when no force differs by more than this times the largest
STATE_MATCH = 1e-13


@njit(cache=True)
def _drive_chunk(t, z, d, slip, level, kn, kt, U, T, lo, hi, V_out, Q_out, first, work):
    """Drive the bed over the steps lo .. hi−1 (from the state after step lo − 1), only the
    sliders that touch somewhere in them; returns the driver's status.

    Levels ascend, so the sliders above the largest approach of the chunk form a suffix;
    they carry no force (t = 0, limit 0) and add exact zeros to every sum of the driver, so
    leaving them out changes no value (only their base slip z, which the map never reads).
    """
    U_top = U[lo - 1]
    for k in range(lo, hi):
        U_top = max(U_top, U[k])
    m = max(np.searchsorted(level, U_top, side="left"), 1)
    none = work[:0]
    status, _ = drive_with(t[:m], z[:m], d[:m], slip[:m], level[:m], kn[:m], kt[:m], 1.0,
                           U[lo:hi], T[lo:hi], True, V_out[lo - 1], U[lo - 1],
                           _NO_RECORD, none, none, V_out[lo:hi], Q_out[lo:hi],
                           first[lo:hi], work[0, :m], work[1, :m], work[2, :m])
    n = level.size
    for k in range(lo, hi):
        if first[k] >= m:
            first[k] = n          # no slip among the driven sliders: none at all
    return status


@njit(cache=True)
def _drive_chunk_lanes(t, level, kn, kt, inv_kt, U, T, lo, hi, V_out, Q_out, first, status):
    """:func:`_drive_chunk` for the lanes of one bed (the columns of ``T``)."""
    U_top = U[lo - 1]
    for k in range(lo, hi):
        U_top = max(U_top, U[k])
    m = max(np.searchsorted(level, U_top, side="left"), 1)
    drive_force_moving_limits(t[:m], level[:m], kn[:m], kt[:m], inv_kt[:m], 1.0, U[lo:hi],
                              T[lo:hi], U[lo - 1], V_out[lo - 1], V_out[lo:hi],
                              Q_out[lo:hi], first[lo:hi], status, SLIP_TOL)
    n = level.size
    for k in range(lo, hi):
        for p in range(first.shape[1]):
            if first[k, p] >= m:
                first[k, p] = n          # no slip among the driven sliders: none at all


#: a lane whose second cycle has met its first: no longer driven
_MET = -2


@njit(cache=True)
def _drive_lanes(level, kn, U, T, steps, asm_steps, cycles):
    """(Ŵ of the last cycle or nan at gross slip, lowest slipping slider index) of each
    column of ``T`` (K, L), all on the bed (``level``, ``kn``) along the approach ``U``.

    The preload is skipped (Q = 0 on an unloaded bed: no slider moves, an exact no-op),
    the path is driven in chunks of :data:`CHUNK` steps on the sliders in contact
    (:func:`_drive_chunk`), and the second cycle of a lane stops at the first chunk end
    where its slider forces equal those of its first cycle at the same step: from a common
    state the same loads give the same steps, so the rest of the second cycle is the rest
    of the first (forced-periodic Jenkins elements, Melan's theorem for the uncoupled
    bed). Each lane gives the bits it gives alone (L = 1).
    """
    kt = kn.copy()
    inv_kt = 1.0 / kt
    n = level.size
    total, L = T.shape
    t = np.zeros((n, L))
    V_out = np.zeros((total, L))
    Q_out = np.zeros((total, L))
    first = np.full((total, L), n, np.int64)
    status = np.full(L, -1, np.int64)
    a = asm_steps           # preload: a no-op (state stays zero, V = Q = 0, no slip)
    c1 = 2 * asm_steps      # first step of cycle 1
    c2 = c1 + steps         # first step of cycle 2
    _drive_chunk_lanes(t, level, kn, kt, inv_kt, U, T, a, c1, V_out, Q_out, first, status)
    n_chunks = (steps + CHUNK - 1) // CHUNK
    rec_t = np.empty((n_chunks, n, L))    # slider forces at the chunk ends of cycle 1
    for j in range(n_chunks):
        lo = c1 + j * CHUNK
        hi = min(lo + CHUNK, c2)
        _drive_chunk_lanes(t, level, kn, kt, inv_kt, U, T, lo, hi, V_out, Q_out, first, status)
        rec_t[j] = t
    stop = np.full(L, total)
    for j in range(n_chunks):
        if not np.any(status == -1):
            break
        lo = c2 + j * CHUNK
        hi = min(lo + CHUNK, total)
        _drive_chunk_lanes(t, level, kn, kt, inv_kt, U, T, lo, hi, V_out, Q_out, first, status)
        if hi >= total:
            break
        for p in range(L):
            if status[p] != -1:
                continue
            scale = 0.0
            gap = 0.0
            for i in range(n):
                scale = max(scale, abs(rec_t[j, i, p]))
                gap = max(gap, abs(t[i, p] - rec_t[j, i, p]))
            if gap <= STATE_MATCH * scale:
                stop[p] = hi
                status[p] = _MET
    W = np.empty(L)
    lowest = np.zeros(L, np.int64)
    for p in range(L):
        if status[p] >= 0:
            W[p] = np.nan
            continue
        # the rest of cycle 2 repeats cycle 1: its forces, and its displacements shifted
        # by the net displacement of cycle 1 (Q, ΔV and the lowest slipping slider per step)
        e = stop[p]
        shift = V_out[e - 1, p] - V_out[e - 1 - steps, p]
        for k in range(e, total):
            Q_out[k, p] = Q_out[k - steps, p]
            V_out[k, p] = V_out[k - steps, p] + shift
            first[k, p] = first[k - steps, p]
        W[p] = _trapezoid(Q_out[:, p], V_out[:, p], total - steps - 1, total)
        lowest[p] = first[:, p].min()
    return W, lowest


@njit(cache=True)
def _drive_point(level, kn, U, T, steps, asm_steps, cycles, reference):
    """(Ŵ of the last cycle or nan at gross slip, lowest slipping slider index).

    ``reference``: every step of the path on every slider, as the original algorithm.
    Otherwise the preload is skipped (Q = 0 on an unloaded bed: no slider moves, an exact
    no-op), the path is driven in chunks of :data:`CHUNK` steps on the sliders in contact
    (:func:`_drive_chunk`) and, with two cycles, the second one stops at the first chunk
    end where the slider forces equal those of the first cycle at the same step: from a
    common state the same loads give the same steps, so the rest of the second cycle is
    the rest of the first (forced-periodic Jenkins elements, Melan's theorem for the
    uncoupled bed).
    """
    kt = kn.copy()
    n = level.size
    total = U.size
    t = np.zeros(n)
    z = np.zeros(n)
    d = np.zeros(n)
    slip = np.zeros(n)
    V_out = np.zeros(total)
    Q_out = np.zeros(total)
    first = np.full(total, n, np.int64)
    if reference or cycles != 2:
        idx = np.empty(0, np.int64)
        none = np.empty((0, n))
        status, _ = drive_from(t, z, d, slip, level, kn, kt, 1.0, U, T, True, 0.0, level[0],
                               idx, none, none, V_out, Q_out, first)
        if status >= 0:
            return np.nan, 0
        return _trapezoid(Q_out, V_out, total - steps - 1, total), first.min()
    a = asm_steps           # preload: a no-op (state stays zero, V = Q = 0, no slip)
    c1 = 2 * asm_steps      # first step of cycle 1
    c2 = c1 + steps         # first step of cycle 2
    work = np.empty((3, n))  # the driver's limits, step stiffnesses and 1/κ
    work[2] = 1.0 / kt
    if _drive_chunk(t, z, d, slip, level, kn, kt, U, T, a, c1, V_out, Q_out, first,
                    work) >= 0:
        return np.nan, 0
    n_chunks = (steps + CHUNK - 1) // CHUNK
    rec_t = np.empty((n_chunks, n))       # slider forces at the chunk ends of cycle 1
    for j in range(n_chunks):
        lo = c1 + j * CHUNK
        hi = min(lo + CHUNK, c2)
        if _drive_chunk(t, z, d, slip, level, kn, kt, U, T, lo, hi, V_out, Q_out,
                        first, work) >= 0:
            return np.nan, 0
        rec_t[j] = t
    stop = total
    for j in range(n_chunks):
        lo = c2 + j * CHUNK
        hi = min(lo + CHUNK, total)
        if _drive_chunk(t, z, d, slip, level, kn, kt, U, T, lo, hi, V_out, Q_out,
                        first, work) >= 0:
            return np.nan, 0
        if hi >= total:
            break
        scale = 0.0
        gap = 0.0
        for i in range(n):
            scale = max(scale, abs(rec_t[j, i]))
            gap = max(gap, abs(t[i] - rec_t[j, i]))
        if gap <= STATE_MATCH * scale:
            stop = hi
            break
    # the rest of cycle 2 repeats cycle 1: its forces, and its displacements shifted by
    # the net displacement of cycle 1 (Q, ΔV and the lowest slipping slider per step)
    shift = V_out[stop - 1] - V_out[stop - 1 - steps]
    for k in range(stop, total):
        Q_out[k] = Q_out[k - steps]
        V_out[k] = V_out[k - steps] + shift
        first[k] = first[k - steps]
    return _trapezoid(Q_out, V_out, total - steps - 1, total), first.min()


@njit(cache=True)
def _run_point(P1, Q1, phi, P_lo, n_sliders, steps, asm_steps, cycles, reference):
    """(Ŵ of the last cycle or nan at gross slip, lowest slipping slider index)."""
    P_max = (1.0 + abs(P1)) * (1 + 1e-9)    # the largest load, θ = 0
    level, kn, _ = rough_unit_bed(P_lo, P_max, n_sliders)
    U, T = _path(P1, Q1, phi, level, kn, steps, asm_steps, cycles)
    return _drive_point(level, kn, U, T, steps, asm_steps, cycles, reference)


@njit(cache=True)
def _lumping(P1, Q1, phi, steps):
    """(history-derived lumping load, fallback load) of a point (see :func:`_one_point`)."""
    cos_P, cos_Q = _cycle_cosines(np.array([phi]), steps, 1)
    return _lumping_from(P1, Q1, Q1 * np.cos(-phi), cos_P, cos_Q[0], steps)


@njit(cache=True)
def _lumping_from(P1, Q1, Q_start, cos_P, cos_Q, steps):
    """:func:`_lumping` from Q_start = Q̂1 cos(−φ) and the cosines of the cycle."""
    # extremes of the loads the history visits: the start state and the cycle's samples
    # (the path is linear between them), as HalfspaceModel.lumping_load takes them
    P_min = P_max = 1.0 + P1
    Q_lo = Q_hi = Q_start
    for k in range(1, steps + 1):
        P = 1.0 + P1 * cos_P[k - 1]
        Q = Q1 * cos_Q[k - 1]
        P_min, P_max = min(P_min, P), max(P_max, P)
        Q_lo, Q_hi = min(Q_lo, Q), max(Q_hi, Q)
    return lumping_load(P_min, P_max, Q_lo, Q_hi, 1.0), UNLUMPED_FRACTION * P_max


@njit(cache=True)
def _one_point(P1, Q1, phi, n_sliders, steps, asm_steps, cycles, reference=True):
    """Ŵ of the last of ``cycles`` cycles; nan when |Q| reaches fP somewhere (gross slip).

    The bed is the one :meth:`HalfspaceModel.bed` builds for the same history: sliders
    below :func:`~slipcycle.halfspace.bed.lumping_load` are lumped, and the point is rerun
    on an unlumped bed should slip reach them.
    """
    P_lo, fallback = _lumping(P1, Q1, phi, steps)
    W, first = _run_point(P1, Q1, phi, P_lo if P_lo > 0.0 else fallback, n_sliders, steps,
                          asm_steps, cycles, reference)
    if P_lo > 0.0 and first <= 1 and not np.isnan(W):
        W, first = _run_point(P1, Q1, phi, fallback, n_sliders, steps, asm_steps, cycles,
                              reference)
    return W


@njit(cache=True)
def _fast_point(P1, Q1, Q_start, cos_P, cos_Q, n_sliders, steps, asm_steps, cycles,
                level_fb, kn_fb, U_fb):
    """:func:`_one_point` without the work that cannot change its value: a path that
    certainly reaches gross slip is not driven, the cosines of the cycles (``cos_P``,
    ``cos_Q`` of this φ, ``Q_start`` = Q̂1 cos(−φ)), the unlumped bed of this P̂1 and its
    approach path come precomputed (``level_fb``, ``kn_fb``, ``U_fb``), and the preload
    and the repeating end of the second cycle are not driven (:func:`_drive_point`)."""
    if _verdict_from(P1, Q1, Q_start, cos_P, cos_Q, steps, asm_steps) == 1:
        return np.nan
    P_lo, _ = _lumping_from(P1, Q1, Q_start, cos_P, cos_Q, steps)
    T = _tangential_from(Q1, Q_start, cos_Q, steps, asm_steps, cycles)
    if P_lo > 0.0:
        P_max = (1.0 + abs(P1)) * (1 + 1e-9)    # the largest load, θ = 0
        level, kn, _ = rough_unit_bed(P_lo, P_max, n_sliders)
        U = _approach_from(P1, level, kn, cos_P, steps, asm_steps, cycles)
        W, first = _drive_point(level, kn, U, T, steps, asm_steps, cycles, False)
        if first > 1 or np.isnan(W):
            return W
    W, _ = _drive_point(level_fb, kn_fb, U_fb, T, steps, asm_steps, cycles, False)
    return W


#: points driven together as lanes of one bed (a multiple of the SIMD width)
LANES = 16


@njit(cache=True)
def _lane_batches(shared, order, n1, per_P1):
    """Groups of :data:`LANES` flat indices of ``shared`` points with the same P̂1 index
    (``flat // per_P1``), each group in the scattered ``order``; −1 pads the last group of
    a P̂1. Returns a (batches, LANES) int array."""
    count = np.zeros(n1, np.int64)
    for flat in range(shared.size):
        if shared[flat]:
            count[flat // per_P1] += 1
    start = np.zeros(n1 + 1, np.int64)
    for i in range(n1):
        start[i + 1] = start[i] + (count[i] + LANES - 1) // LANES
    batches = np.full((start[n1], LANES), -1, np.int64)
    filled = np.zeros(n1, np.int64)
    for m in range(order.size):
        flat = order[m]
        if shared[flat]:
            i = flat // per_P1
            batches[start[i] + filled[i] // LANES, filled[i] % LANES] = flat
            filled[i] += 1
    return batches


@njit(parallel=True, cache=True)
def _grid(P1s, Q1s, phis, n_sliders, steps, asm_steps, cycles, order, reference):
    n1, n2, n3 = P1s.size, Q1s.size, phis.size
    out = np.empty(n1 * n2 * n3)
    if reference:
        for flat in prange(n1 * n2 * n3):
            i = flat // (n2 * n3)
            j = (flat // n3) % n2
            k = flat % n3
            out[flat] = _one_point(P1s[i], Q1s[j], phis[k], n_sliders, steps, asm_steps,
                                   cycles, True)
        return out.reshape((n1, n2, n3))
    cos_P, cos_Q = _cycle_cosines(phis, steps, cycles)
    # the unlumped bed of each P̂1 (the rough law's fallback) and its approach path
    total = 2 * asm_steps + cycles * steps
    level_fb = np.empty((n1, n_sliders + 1))
    kn_fb = np.empty((n1, n_sliders + 1))
    U_fb = np.empty((n1, total))
    for i in prange(n1):
        _, fallback = _lumping(P1s[i], 0.0, 0.0, steps)
        P_max = (1.0 + abs(P1s[i])) * (1 + 1e-9)
        level, kn, _ = rough_unit_bed(fallback, P_max, n_sliders)
        level_fb[i] = level
        kn_fb[i] = kn
        U_fb[i] = _approach_from(P1s[i], level, kn, cos_P, steps, asm_steps, cycles)
    n_pts = n1 * n2 * n3
    # the points with no lumping bound share the unlumped bed and approach path of their
    # P̂1: they run as lanes of one bed, LANES at a time (cycles = 2 only, as the lanes'
    # early stop); the others run one by one
    shared = np.zeros(n_pts, np.bool_)
    if cycles == 2:
        for m in prange(n_pts):
            i = m // (n2 * n3)
            j = (m // n3) % n2
            k = m % n3
            Q_start = Q1s[j] * np.cos(-phis[k])
            if _verdict_from(P1s[i], Q1s[j], Q_start, cos_P, cos_Q[k], steps,
                             asm_steps) == 1:
                continue
            P_lo, _ = _lumping_from(P1s[i], Q1s[j], Q_start, cos_P, cos_Q[k], steps)
            shared[m] = P_lo <= 0.0
    batches = _lane_batches(shared, np.arange(n_pts), n1, n2 * n3)
    nb = batches.shape[0]
    stride = 7919 if nb % 7919 else 7907    # a prime: visits every batch once
    for bb in prange(nb):
        b = (bb * stride) % nb              # P̂1 groups scattered over the threads
        i = batches[b, 0] // (n2 * n3)
        T = np.empty((total, LANES))
        for p in range(LANES):
            flat = batches[b, p] if batches[b, p] >= 0 else batches[b, 0]
            j = (flat // n3) % n2
            k = flat % n3
            T[:, p] = _tangential_from(Q1s[j], Q1s[j] * np.cos(-phis[k]), cos_Q[k], steps,
                                       asm_steps, cycles)
        W, _ = _drive_lanes(level_fb[i], kn_fb[i], U_fb[i], T, steps, asm_steps, cycles)
        for p in range(LANES):
            if batches[b, p] >= 0:
                out[batches[b, p]] = W[p]
    # the other points in a scattered order, so that every thread gets its share of the
    # cheap gross-slip points (they cluster at large P̂1 and Q̂1)
    for m in prange(n_pts):
        flat = order[m]
        if shared[flat]:
            continue
        i = flat // (n2 * n3)
        j = (flat // n3) % n2
        k = flat % n3
        out[flat] = _fast_point(P1s[i], Q1s[j], Q1s[j] * np.cos(-phis[k]), cos_P, cos_Q[k],
                                n_sliders, steps, asm_steps, cycles, level_fb[i], kn_fb[i],
                                U_fb[i])
    return out.reshape((n1, n2, n3))


def w_hat_map(P1_hat, Q1_hat, phase, *, steps_per_cycle: int = 200, n_sliders: int = 100,
              cycles: int = 2, assembly_steps: int = 20, reference: bool = False
              ) -> np.ndarray:
    """Ŵ on the grid P1_hat × Q1_hat × phase.

    Parameters
    ----------
    P1_hat, Q1_hat, phase : 1-D arrays
        P̂1 = P1/P0 in [0, 1), Q̂1 = Q1/(f P0) ≥ 0, φ in rad.
    steps_per_cycle, n_sliders, cycles, assembly_steps : int
        Discretisation (see module docstring; the convergence tests state the error).
    reference : bool
        Drive every step of every point (the original algorithm; the default skips only
        work that cannot change a value, see module docstring, and agrees with it to
        round-off).

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
    order = np.random.default_rng(0).permutation(P1.size * Q1.size * ph.size)
    return _grid(P1, Q1, ph, int(n_sliders), int(steps_per_cycle), int(assembly_steps),
                 int(cycles), order, bool(reference))


def w_hat_point(P1_hat: float, Q1_hat: float, phase: float, **kw) -> float:
    """Ŵ at one point (see :func:`w_hat_map`)."""
    return float(w_hat_map([P1_hat], [Q1_hat], [phase], **kw)[0, 0, 0])
