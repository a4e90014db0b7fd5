"""The lane-batched Ŵ map against the per-point reference evaluation.

Points of the Ŵ map whose history has no lumping bound share the unlumped bed and approach
path of their P̂1, so ``w_hat_map`` drives them together, as lanes of one bed
(:func:`slipcycle.kernels.jenkins.drive_force_moving_limits`). Each lane does the
arithmetic of the one-point driver (:func:`slipcycle.halfspace.kernels.drive_with`), so a
lane gives the same bits alone, beside other lanes, and through the one-point path; the
map as a whole agrees with the reference algorithm (every step of every point on the full
bed, ``reference=True``) to round-off, gross-slip and zero-amplitude edges and the phases
0 and ±π included.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.halfspace.bed import rough_unit_bed
from slipcycle.halfspace.kernels import SLIP_TOL, STATUS_OK, drive_from
from slipcycle.halfspace.wmap import (
    _approach_path,
    _drive_lanes,
    _drive_point,
    _gross_slip_verdict,
    _lumping,
    _tangential_path,
    w_hat_map,
)
from slipcycle.kernels.jenkins import drive_force_moving_limits

#: Ŵ of a shakedown point is round-off around 0 (|Ŵ| < 1e-15 in the 50×50×36 map)
ROUND_OFF = 1e-14
STEPS, ASM, CYCLES, N = 200, 20, 2, 100


def _shared_bed(P1):
    """The unlumped bed of P̂1 and its approach path, as the map builds them."""
    _, fallback = _lumping(P1, 0.0, 0.0, STEPS)
    level, kn, _ = rough_unit_bed(fallback, (1.0 + P1) * (1 + 1e-9), N)
    return level, kn, _approach_path(P1, level, kn, STEPS, ASM, CYCLES)


def _lane_points(P1):
    """(Q̂1, φ) with no lumping bound that do not certainly reach gross slip: the lanes."""
    pts = [(q, ph) for q in (0.0, 0.2, 0.45, 0.6, 0.7) for ph in (-np.pi, -1.0, 0.0, 2.0,
                                                                   np.pi)
           if _gross_slip_verdict(P1, q, ph, STEPS, ASM) != 1
           and _lumping(P1, q, ph, STEPS)[0] <= 0.0]
    return pts


def test_coarse_map_equals_the_reference_per_point_evaluation():
    P1 = np.array([0.0, 0.3, 0.6, 0.9])
    Q1 = np.array([0.0, 0.01, 0.3, 0.45, 0.6, 0.95, 1.0])
    ph = np.array([-np.pi, -np.pi / 2, -0.3, 0.0, 1.0, np.pi / 2, np.pi, 2.5])
    fast = w_hat_map(P1, Q1, ph)
    ref = w_hat_map(P1, Q1, ph, reference=True)
    # the grid holds every kind of point: gross slip, lanes, lumped, zero amplitude
    lanes = [(p, q, f) for p in P1 for q in Q1 for f in ph
             if _gross_slip_verdict(p, q, f, STEPS, ASM) != 1
             and _lumping(p, q, f, STEPS)[0] <= 0.0]
    assert np.isnan(ref).any() and len(lanes) > 8
    assert (~np.isnan(ref) & (ref > 1e-6)).any()
    np.testing.assert_array_equal(np.isnan(fast), np.isnan(ref))
    ok = ~np.isnan(ref)
    assert np.all(np.abs(fast[ok] - ref[ok]) <= 1e-12 * np.abs(ref[ok]) + ROUND_OFF)
    # zero amplitude: no tangential load, no dissipation (exactly)
    assert np.all(fast[:, 0] == 0.0) and np.all(ref[:, 0] == 0.0)
    # phases 0 and π of P̂1 = 0 are the same loop (the phase only moves the start)
    np.testing.assert_allclose(fast[0, 1:5, 3], fast[0, 1:5, 6], rtol=1e-9, atol=ROUND_OFF)


def test_each_lane_gives_the_bits_of_the_one_point_driver():
    P1 = 0.4
    level, kn, U = _shared_bed(P1)
    pts = _lane_points(P1)
    assert len(pts) >= 10
    T = np.stack([_tangential_path(q, ph, STEPS, ASM, CYCLES) for q, ph in pts], axis=1)
    W, lowest = _drive_lanes(level, kn, U, np.ascontiguousarray(T), STEPS, ASM, CYCLES)
    for p in range(T.shape[1]):
        # alone as one lane, and through the one-point driver (drive_with)
        W1, low1 = _drive_lanes(level, kn, U, np.ascontiguousarray(T[:, p:p + 1]), STEPS, ASM,
                                CYCLES)
        W_point, low_point = _drive_point(level, kn, U, T[:, p].copy(), STEPS, ASM, CYCLES,
                                          False)
        assert W1[0] == W[p] == W_point or np.isnan(W1[0]) and np.isnan(W[p]) \
            and np.isnan(W_point)
        if not np.isnan(W[p]):
            assert low1[0] == lowest[p] == low_point


@settings(max_examples=40, deadline=None)
@given(n=st.integers(2, 40), lanes=st.integers(1, 9), steps=st.integers(5, 60),
       seed=st.integers(0, 2**31 - 1))
def test_lane_driver_is_drive_from_step_by_step(n, lanes, steps, seed):
    """Random beds (engaging during the path), approach and force paths, gross slip
    included: every lane has the displacements, forces, slip fronts and final state of
    ``drive_from`` driving it alone, to the bit, and stops at the same gross-slip step."""
    rng = np.random.default_rng(seed)
    level = np.sort(rng.uniform(0.0, 1.0, n))
    kn = rng.uniform(0.5, 2.0, n)
    kt = kn * rng.uniform(0.5, 1.0)
    U = 1.2 * np.abs(np.cumsum(rng.normal(0.0, 0.3, steps))) + 0.2
    U0 = float(level[0])
    T = rng.uniform(-1.0, 1.0, (steps, lanes)) * rng.uniform(0.05, 0.6) * (kn.sum())
    t = np.zeros((n, lanes))
    V, Q = np.zeros((steps, lanes)), np.zeros((steps, lanes))
    first = np.zeros((steps, lanes), np.int64)
    status = np.full(lanes, -1, np.int64)
    drive_force_moving_limits(t, level, kn, kt, 1.0 / kt, 0.7, U, np.ascontiguousarray(T), U0,
                              np.zeros(lanes), V, Q, first, status, SLIP_TOL)
    for p in range(lanes):
        tp = np.zeros(n)
        Vp, Qp, fp = np.zeros(steps), np.zeros(steps), np.zeros(steps, np.int64)
        st_p, _ = drive_from(tp, np.zeros(n), np.zeros(n), np.zeros(n), level, kn, kt, 0.7, U,
                             T[:, p].copy(), True, 0.0, U0, np.empty(0, np.int64),
                             np.empty((0, n)), np.empty((0, n)), Vp, Qp, fp)
        done = steps if st_p == STATUS_OK else st_p
        assert status[p] == (-1 if st_p == STATUS_OK else st_p)
        np.testing.assert_array_equal(V[:done, p], Vp[:done])
        np.testing.assert_array_equal(Q[:done, p], Qp[:done])
        np.testing.assert_array_equal(first[:done, p], fp[:done])
        if st_p == STATUS_OK:
            np.testing.assert_array_equal(t[:, p], tp)
