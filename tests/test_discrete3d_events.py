"""Contact events inside a load step of the 3-D engine: a node that closes or opens (or
starts to slip while another stops) inside a step takes its state from that instant.

References: the exact event-driven 2-D solver (``slipcycle.discrete``, piecewise-linear
paths solved event by event) for loads along t1 only, where the cone reduces to
|q| ≤ f p; and, on the cone, the observed order of backward Euler with fixed steps.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from random_systems import along_t1, random_coupled_2d

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.discrete3d.evolution import Evolution3D
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import SEPARATED, STICK, FrictionalSystem3D, embed_2d
from slipcycle.discrete3d.steady import simulate3d
from slipcycle.errors import InadmissibleInitialState

#: the 3-D engine's local step tolerance of the 2-D comparisons: the global error of D is
#: not bounded by the local one (at 1e-8 the 20-sample run of system 925988 is 4.9e-6 off,
#: at 1e-10 5.7e-10: see the convergence test below)
STEP_TOL = 1e-10


def _pair(seed, steps, slip0, step_tol=STEP_TOL, **kw):
    """The 2-D solver and the 3-D engine on the same system, loads along t1 only."""
    A, B, C, f, (p0, q0, p1, q1, pph, qph) = random_coupled_2d(seed)
    r2 = simulate(FrictionalSystem(A, B, C, f), DiscreteLoad.harmonic(p0, q0, p1, q1, pph, qph),
                  cycles=60, steps_per_cycle=steps, tol=1e-11, initial_slip=slip0)
    load3 = Load3D.harmonic(p0, along_t1(q0), p1, along_t1(q1), pph, np.repeat(qph, 2))
    r3 = simulate3d(embed_2d(A, B, C, f), load3, cycles=60, steps_per_cycle=steps, tol=1e-11,
                    step_tol=step_tol, initial_slip=None if slip0 is None else along_t1(slip0),
                    **kw)
    return r2, r3


def _worst_d_error(r2, r3):
    d2 = r2.dissipation_per_cycle
    return max(abs(r3.dissipation_per_cycle - d2),
               float(np.max(np.abs(r3.dissipation_per_node - r2.dissipation_per_node)))) / d2


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.filter_too_much])
@given(seed=st.integers(0, 2 ** 31 - 1), steps=st.sampled_from([20, 37, 100, 199]),
       slip0=st.one_of(st.none(), st.lists(st.floats(-0.05, 0.05), min_size=2, max_size=2)))
def test_separating_and_reclosing_nodes_reproduce_the_exact_2d_solver(seed, steps, slip0):
    """With loads along t1 only and a node that opens and closes again every cycle, the
    dissipation per cycle and every node's D_j agree with the exact 2-D solver to 1e-6
    of D (before the events were located: off by 1e-5 … 1.5e-3, not converging with
    the samples per cycle)."""
    try:
        r2, r3 = _pair(seed, steps, None if slip0 is None else np.array(slip0))
    except InadmissibleInitialState:
        assume(False)
    assume(r2.steady_converged and r2.separating_nodes and r2.dissipation_per_cycle > 1e-3)
    assert r3.steady_state == r2.steady_state
    assert r3.separating_nodes == r2.separating_nodes
    assert _worst_d_error(r2, r3) <= 1e-6


def test_the_2d_limit_converges_with_the_step_tolerance_where_events_are_coarsely_sampled():
    """The 3-D engine's error of D and every D_j against the exact 2-D solver falls with its
    local step tolerance, at 20 samples per cycle on a system with a separating node (the
    example hypothesis found 4.9e-6 off at step_tol 1e-8): a tolerance 100 times smaller
    gives an error at least 10 times smaller, down to below 1e-6."""
    errors = [_worst_d_error(*_pair(925988, 20, None, step_tol=tol))
              for tol in (1e-8, 1e-10, 1e-12)]
    assert errors[1] <= 1e-6
    assert errors[1] < errors[0] / 10 and errors[2] < errors[1] / 10


def test_without_event_location_the_closing_node_keeps_the_slip_of_the_step_start(
        monkeypatch):
    """The check above can fail: the same comparison with the event location switched
    off misses the 2-D dissipation by more than 1e-5 of D (random system 21: node 1
    opens and closes again every cycle)."""
    r2, r3 = _pair(21, 100, None)
    assert r2.separating_nodes == [0, 1]
    assert _worst_d_error(r2, r3) <= 1e-6
    monkeypatch.setattr(Evolution3D, "locate_events", False)
    _, off = _pair(21, 100, None)
    assert _worst_d_error(r2, off) > 1e-5


#: t2 load amplitude relative to t1 in the cone case
EPS = 0.05


def _cone_case():
    """Random system 21 of the 2-D comparison with a t2 load EPS × the t1 load, a quarter
    period behind: the slip directions turn (a genuine cone problem); node 1 opens,
    closes and sticks every cycle."""
    A, B, C, f, (p0, q0, p1, q1, pph, qph) = random_coupled_2d(21)
    q1v = np.column_stack([q1, EPS * q1]).ravel()
    ph = np.column_stack([qph, qph - np.pi / 2]).ravel()
    return embed_2d(A, B, C, f), Load3D.harmonic(p0, along_t1(q0), p1, q1v, pph, ph)


def _one_cycle(system, load, x0, steps, **kw):
    theta, vals = load.cycle_samples(steps)
    F = float(np.max(np.abs(vals)))
    evo = Evolution3D(system, x0, vals[0], F, **kw)
    evo.step_log = []
    totals = evo.follow(theta, vals)
    return float(np.sum(totals.dissipation)), evo


def _orders(system, load, x0, d_ref, ms=(4, 8, 16, 32)):
    err = [abs(_one_cycle(system, load, x0, 25, adaptive=False, substeps=m)[0] - d_ref)
           for m in ms]
    return np.log2(np.array(err[:-1]) / np.array(err[1:])), err


def test_error_of_d_with_a_closing_and_sticking_node_is_first_order_in_the_step(monkeypatch):
    """On the cone, with a node that closes and sticks inside a step, backward Euler with
    m fixed steps per load interval (25 samples per cycle) converges at first order:
    the orders of the error of D over one cycle between m = 4, 8, 16, 32 measure 1.35,
    1.11, 1.12 (against step doubling at ``step_tol`` 1e-9, whose own error is below
    2 % of the smallest one). Asserted: every order ≥ 0.9 — first order is what a
    backward-Euler step guarantees once every event is located (its local error O(h²)
    in smooth slip), above it the pre-asymptotic range. Without the event location the
    closing node keeps the slip of its step's start, an O(h) error whose size moves
    irregularly with the event's place in the step: orders 0.25, 1.16, 0.33 here (the
    assertion fails, checked below)."""
    system, load = _cone_case()
    start = simulate3d(system, load, cycles=60, steps_per_cycle=25, tol=1e-9,
                       step_tol=1e-8, accelerate=False)
    x0 = start.cycle_start_states[-1]
    d_ref, evo = _one_cycle(system, load, x0, 25, step_tol=1e-9)
    # a node closes and sticks inside a step (the case this order is about)
    modes = [m for _, _, m, _ in evo.step_log]
    assert any(np.any((a == SEPARATED) & (b == STICK))
               for a, b in zip(modes[:-1], modes[1:], strict=True))
    orders, err = _orders(system, load, x0, d_ref)
    assert np.all(orders >= 0.9), orders
    assert err[-1] <= 1e-4 * d_ref
    monkeypatch.setattr(Evolution3D, "locate_events", False)
    assert np.min(_orders(system, load, x0, d_ref)[0]) < 0.9


@pytest.mark.parametrize("closing", [True, False], ids=["closes", "opens"])
def test_a_located_event_ends_its_step_at_the_instant_of_the_crossing(closing):
    """One node (uncoupled, no friction load): its gap is affine in the load, so the
    closing (opening) instant is known in closed form; the engine's step ends there
    within the event tolerance, and the node's slip is that of the instant."""
    system = FrictionalSystem3D(np.eye(2), np.zeros((1, 2)), [[1.0]], 0.5)
    n = 1
    p_start, p_end = (-0.3, 0.7) if closing else (0.7, -0.3)
    # normal load affine from p_start to p_end, tangential load q = 0.1 + 0.2 s
    vals = np.array([[0.1, 0.0, p_start], [0.3, 0.0, p_end]])
    x0 = np.zeros(3 * n)
    if closing:
        x0 = np.array([-0.1, 0.0, 0.3])             # open: v = −q^w, w = −p^w
    evo = Evolution3D(system, x0, vals[0], 1.0, step_tol=1e-10)
    evo.step_log = []
    totals = evo.follow(np.arange(2.0), vals)
    s_star = p_start / (p_start - p_end)            # p^w = 0
    assert totals.events >= 1
    ends = [x for x, _, _, _ in evo.step_log]
    # the step at the event: the slip is −q^w(s*) (free while open) at the instant
    v_star = -(0.1 + 0.2 * s_star)
    assert min(abs(x[0] - v_star) for x in ends) <= 1e-9
    if closing:
        assert evo.x[0] == pytest.approx(v_star, abs=1e-9)   # sticks from s* on
