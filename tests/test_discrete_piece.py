"""Plain cycling followed on one sequence of modes without running it.

On a piece of the cycle map every event moves by δt = −c/ġ and every state by M_s d, so
the next cycle's start, the lengths of every node's mode intervals and the smallest
margins of every inequality are affine in the start state
(:mod:`~slipcycle.discrete.periodic`). Independent reference: the next cycle, run exactly.
A step that skips the cycles in which plain cycling changes its sequence of modes (a
creeping slip that stops, a stuck node that touches its limit) lands on another member of
the set of steady states; the checks must refuse it.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from test_discrete_steady_jump import _random_case

from slipcycle.discrete import simulate
from slipcycle.discrete.periodic import (
    ModeIntervals,
    PieceConstraints,
    _apply_map_coefficients,
    cycle_jacobian,
    follow_piece,
    piece_constraints,
)
from slipcycle.discrete.steady import _assembled
from slipcycle.loading.nodal import force_scale


def _recorded_cycles(system, load, cycles, steps=40):
    """(start, end, jacobian, constraints, intervals, signature) of successive cycles."""
    theta, vals = load.cycle_samples(steps)
    F = force_scale(vals)
    evo = _assembled(system, vals[:1], F, None, None)   # assembly tolerances throughout
    out = []
    for _ in range(cycles):
        evo.jacobian_log, evo.margin_log = [], []
        evo.signature = hashlib.blake2b()
        x0 = evo.x.copy()
        evo.follow(theta, vals)
        evo.resync()
        jac = cycle_jacobian(evo.jacobian_log, system.K, system.friction)
        cons = piece_constraints(jac, evo.jacobian_log, evo.margin_log,
                                 evo.event_margin_log, system.K, system.friction,
                                 10 * evo.force_tol, 1e-12, evo.switch_log)
        out.append((x0, evo.x.copy(), jac, cons, ModeIntervals.from_log(evo.episode_log, 0.0),
                    evo.signature.digest()))
    return out, F


@pytest.mark.parametrize("seed, n", [(212, 4), (5, 5)])
def test_next_cycle_on_the_same_sequence_is_predicted_exactly(seed, n):
    """Where two successive cycles share their sequence of modes and events, the first
    one's record predicts the second's start (to 1e-9 of the increment, and 1e-13 of the
    state), the length of
    every mode interval (to 1e-11 rad), the smallest value of every inequality on every
    interval and at every event, and the value of the inequality on which a node switches
    at a load sample or at another node's event (seed 5: a node switches together with
    another node's event in every cycle), to 1e-9 of the force scale."""
    system, load = _random_case(seed, n, True)
    cycles, F = _recorded_cycles(system, load, 40)
    pairs = [(a, b) for a, b in zip(cycles, cycles[1:], strict=False) if a[5] == b[5]]
    assert pairs
    switches = 0
    for (x0, x1, jac, cons, iv, _), (y0, y1, _, cons2, iv2, _) in pairs:
        r = x1 - x0
        c = np.empty(jac.U.shape[0])
        e = _apply_map_coefficients(jac.U, jac.A, r[jac.S].copy(), c)
        actual = (y1 - y0)[jac.S]
        # round-off of the cycle itself: 1e-13 of the state
        assert np.abs(e - actual).max() <= 1e-9 * np.abs(r).max() + 1e-13 * np.abs(x1).max()
        shift = np.concatenate([jac.event_shift(c), [0.0]])
        predicted = iv.length + shift[iv.end] - shift[iv.start]
        np.testing.assert_allclose(predicted, iv2.length, rtol=0, atol=1e-11)
        change = cons.change(r[jac.S], c)
        low = cons.lowest + change
        finite = np.isfinite(cons2.lowest)
        np.testing.assert_array_equal(finite, np.isfinite(low))
        np.testing.assert_allclose(low[finite], cons2.lowest[finite], rtol=0, atol=1e-9 * F)
        at = cons.at_event + cons.event_rate * shift[:-1, None] + change[:-1]
        finite = np.isfinite(cons2.at_event)
        np.testing.assert_allclose(at[finite], cons2.at_event[finite], rtol=0, atol=1e-9 * F)
        assert cons.switch_value.size == cons2.switch_value.size
        for i, (k, ev) in enumerate(zip(cons.switch_interval, cons.switch_event,
                                        strict=True)):
            last = ev if ev >= 0 else k
            value = (cons.switch_value[i] + cons.switch_G[i] @ r[jac.S]
                     - cons.switch_GU[i, :last] @ c[:last])
            if ev >= 0:
                value += cons.switch_rate[i] * shift[ev]
            assert value == pytest.approx(cons2.switch_value[i], abs=1e-9 * F)
        switches += cons.switch_value.size
    assert switches > 0 or seed != 5


def test_mode_intervals_refuse_a_slip_that_would_shrink_below_nothing():
    """An interval from event 0 to a load sample (−1) of length 0.01 rad survives event 0
    moving 0.009 rad later and is refused when it moves 0.011 rad later; one between two
    events keeps its length when both move together."""
    iv = ModeIntervals(np.array([0, 1]), np.array([-1, 2]), np.array([0.01, 0.02]),
                       np.full(2, 1e-9))
    assert iv.hold(np.array([0.009, 0.0, 0.0]))
    assert not iv.hold(np.array([0.011, 0.0, 0.0]))
    assert iv.hold(np.array([0.0, 0.5, 0.5]))
    assert not iv.hold(np.array([0.0, 0.5, 0.47]))


@pytest.mark.parametrize("seed, n, sep, start", [(212, 4, True, "load")])
def test_step_keeps_the_memory_that_plain_cycling_selects(seed, n, sep, start):
    """Random system seed 212 (4 nodes, separation): plain cycling reaches D = 0.0551468 J
    in 107 cycles with node 0 creeping ever more slowly. A periodic step taken while node
    0's slip interval shrank towards a load sample (it stops there after finitely many
    cycles) froze node 0 short of that and landed on another steady state (D = 0.0550957 J,
    node 3 slipping 9.7e-5 m instead of 2.1e-4 m). Followed on its sequence of modes, the
    step is refused there, and the accelerated run agrees with plain cycling to 1e-9."""
    system, load = _random_case(seed, n, sep)
    kw = dict(cycles=400, steps_per_cycle=40, tol=1e-11, record=False)
    plain = simulate(system, load, accelerate=False, **kw)
    fast = simulate(system, load, accelerate=True, **kw)
    assert fast.cycles_run < plain.cycles_run / 4
    assert fast.dissipation_per_cycle == pytest.approx(plain.dissipation_per_cycle, rel=1e-9, abs=0)
    np.testing.assert_allclose(fast.slip_length, plain.slip_length, rtol=1e-6,
                               atol=1e-9 * plain.slip_length.max())
    assert fast.permanently_stuck_nodes == plain.permanently_stuck_nodes


def _one_event(hi: float):
    """One event moving node 0 of two (S = {0}): M = 1 − u a on S with u = 0.25 and a
    the gradient of f p + q of node 0; ġ = −1, the event at θ = 0.5 in [0, hi]."""
    K = np.array([[2.0, 0.3, 0.1, 0.0], [0.3, 2.0, 0.0, 0.1],
                  [0.1, 0.0, 2.0, 0.2], [0.0, 0.1, 0.2, 2.0]])
    log = [(0, 0, np.array([0]), np.array([0.25]), -1.0, 0.5, 0.0, hi)]
    jac = cycle_jacobian(log, K, np.array([0.5, 0.5]))
    none = PieceConstraints(np.zeros((2, 0)), np.zeros((1, 0)), np.zeros((1, 0)),
                            np.zeros((0, 1)), np.zeros((0, 1)), np.zeros(0))
    intervals = ModeIntervals(np.zeros(0, int), np.zeros(0, int), np.zeros(0), np.zeros(0))
    a = 0.5 * K[2, 0] + K[0, 0]
    return jac, none, intervals, a


def test_followed_path_sums_the_increments_of_plain_cycling():
    """On one piece the starts are x + r(1 + m + … + m^{k−1}) with m = 1 − u a: the
    follower arrives at r / (1 − m) (to the round-off bound), leaves every other
    coordinate alone, and counts the cycles it stands for."""
    jac, none, intervals, a = _one_event(hi=1.0)
    m = 1 - 0.25 * a
    run = follow_piece(jac, np.array([1e-3, 0.0, 0.0, 0.0]), none, intervals, 1e-15)
    assert run.reached
    assert list(jac.S) == [0]
    assert run.after[0] == pytest.approx(1e-3 / (1 - m), rel=1e-11, abs=0)
    assert run.cycles == int(np.ceil(np.log(1e-15 / 1e-3) / np.log(m)))


def test_follower_stops_before_the_cycle_whose_event_leaves_its_load_segment():
    """The event moves by δt = a d_k (ġ = −1); with 3 ms of room to the end of its load
    segment it stays in it from x + d_1 (d_1 = 1e-3, δt = 2.05e-3) but not from
    x + d_2 (d_2 = 1e-3 (1 + m), δt = 3.05e-3): one cycle is followed, and the step
    goes to x + d_1 with x + d_2 as the predicted next start."""
    jac, none, intervals, a = _one_event(hi=0.5 + 3e-3)
    m = 1 - 0.25 * a
    run = follow_piece(jac, np.array([1e-3, 0.0, 0.0, 0.0]), none, intervals, 1e-15)
    assert not run.reached
    assert run.cycles == 1
    assert run.start[0] == pytest.approx(1e-3, rel=1e-12, abs=0)
    assert run.after[0] == pytest.approx(1e-3 * (1 + m), rel=1e-12, abs=0)
