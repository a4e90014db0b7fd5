"""Slow-mode steps: where the piece of the cycle map changes every cycle.

On the FE-reduced block of 401 contact nodes the slip fronts are cascades of events a few
microradians apart that reorder every cycle, so plain cycling cannot be followed on one
piece; the state creeps along a few eigenvectors of the cycle's Jacobian M whose
eigenvalues are close to 1. :func:`~slipcycle.discrete.periodic.slow_mode_sum` sums their
part of the geometric series in closed form (the recursive projection method of Shroff &
Keller 1993) and leaves the eigenvalue 1 of the nodes' memory alone; each step ends where
the first node stops slipping, so that node keeps the slip plain cycling leaves it.
Independent references: the series summed term by term, its closed form for a rank-one
factor, and plain cycling of the 401-node block for 2200 cycles (measured once, 145 s;
its final state is ``data/fe_block_401_plain_limit.npy``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import assert_reproduced_by_one_more_cycle, assert_same_steady_state, slid_block
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from test_discrete_steady_jump import _random_case

from slipcycle.discrete import simulate, steady
from slipcycle.discrete.periodic import CycleJacobian, slow_mode_sum

DATA = Path(__file__).parent / "data"

#: plain cycling of the slid 401-node block (accelerate=False, 50 samples per cycle): D of
#: one more exact cycle from its state after 2200 cycles (145 s; the increments had reached
#: round-off, 3e-18 m), measured once
PLAIN_D_401 = 2.00886690660932e-08

#: D_j [J] of that cycle at the slipping nodes 378–400 (the stuck nodes' are below 2e-16 J)
PLAIN_DJ_401 = np.array([
    8.649481737671778e-12, 5.5309727268129295e-11, 3.991922060903854e-11,
    4.921906700393849e-11, 1.639450050586666e-11, 8.387389634200346e-12,
    1.1750862488462715e-13, 3.765788412493917e-12, 8.351909514395475e-12,
    4.1137700791588565e-11, 3.4502769796309915e-11, 1.0852194064604469e-10,
    6.886825045679633e-11, 1.7688089331841605e-10, 9.602324152023675e-11,
    2.1664166052787179e-10, 9.914416218009748e-11, 2.0134275897091175e-10,
    7.141279860545143e-11, 1.2405839063796093e-10, 9.462558006111229e-11,
    1.5694794911627015e-09, 1.699591345156871e-08])


def _jacobian(U: np.ndarray, A: np.ndarray) -> CycleJacobian:
    return CycleJacobian(np.arange(U.shape[1]), np.ascontiguousarray(U),
                         np.ascontiguousarray(A))


def _matrix(U: np.ndarray, A: np.ndarray) -> np.ndarray:
    """M = (I − u_E a_Eᵀ) ⋯ (I − u_1 a_1ᵀ), multiplied out."""
    M = np.eye(U.shape[1])
    for u, a in zip(U, A, strict=True):
        M = (np.eye(U.shape[1]) - np.outer(u, a)) @ M
    return M


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), m=st.integers(1, 12), extra=st.integers(2, 8))
def test_slow_mode_sum_is_the_tail_of_the_geometric_series_of_a_contracting_cycle(
        seed, m, extra):
    """Every eigenvalue below the cut: the sum is M r + M² r + … , summed term by term.
    Factors I − c u uᵀ (|u| = 1, 0 < c < 2) have norm 1, so M contracts once the u span
    the coordinates."""
    rng = np.random.default_rng(seed)
    events = m + extra
    U = rng.normal(size=(events, m))
    U /= np.linalg.norm(U, axis=1)[:, None]
    A = rng.uniform(0.2, 1.8, size=(events, 1)) * U
    M = _matrix(U, A)
    assume(np.max(np.abs(np.linalg.eigvals(M))) < 0.99)
    r = rng.normal(size=m)
    series, term = np.zeros(m), r.copy()
    for _ in range(5000):                 # 0.99⁵⁰⁰⁰ ≈ 1e-22
        term = M @ term
        series += term
    got = slow_mode_sum(_jacobian(U, A), r, krylov=m)
    np.testing.assert_allclose(got, series, rtol=0,
                               atol=1e-8 * max(1.0, float(np.abs(series).max())))


def test_slow_mode_sum_keeps_the_memory_of_a_rank_one_cycle():
    """M = I − u aᵀ: eigenvalue 1 on aᵀv = 0 (coordinates the cycle does not erase, the
    memory of stuck nodes) and λ = 1 − aᵀu on u. Only the part of r along u is summed,
    λ/(1 − λ) · (aᵀr / aᵀu) u; the memory part of r is not extrapolated."""
    u = np.array([0.3, -0.2, 0.1, 0.4])
    a = np.array([0.5, 0.1, -0.3, 0.6])
    lam = 1.0 - a @ u
    r = np.array([1.0, 2.0, -0.5, 0.25])
    expected = lam / (1 - lam) * (a @ r) / (a @ u) * u
    got = slow_mode_sum(_jacobian(u[None, :], a[None, :]), r)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)


def test_slow_mode_sum_leaves_a_mode_at_the_cut_and_a_vanishing_increment_alone():
    """λ ≥ 0.995 is not summed (next to the memory's 1, a piece's eigenvalue need not be
    the map's), and a zero increment gives a zero step."""
    u = np.array([1.0, 0.0])
    a = np.array([0.002, 0.0])                    # λ = 0.998
    got = slow_mode_sum(_jacobian(u[None, :], a[None, :]), np.array([1.0, 0.5]))
    np.testing.assert_array_equal(got, np.zeros(2))
    assert not slow_mode_sum(_jacobian(u[None, :], a[None, :]), np.zeros(2)).any()


@pytest.mark.slow
def test_fe_block_401_reaches_the_steady_state_of_2200_plain_cycles_to_1e6():
    """401 contact nodes, slide-first: the follower takes no step (its piece changes in
    the first followed cycle), plain cycling needs over a thousand cycles to bring D within
    1e-6 of its limit. The slow-mode steps, each shortened to the first node that stops,
    end in under 200 cycles at tolerance 1e-11 (measured 123; round-off, such as a
    friction coefficient changed by 1e-14, moves it between 114 and 135: the steps' noise
    is near that tolerance. D is small against the state's elastic energy, so D to 1e-6 needs
    the state to about 1e-11) on plain cycling's state after 2200 cycles to 1e-6 of the
    state (measured 6.0e-7: the slip of the 378 stuck nodes, their memory, is kept only
    that well), with D and every D_j within 1e-6 of D of plain cycling's (measured
    3.6e-7), its slipping nodes (the 23 at the trailing edge), and a state that one more
    exact cycle reproduces."""
    system, load, protocol = slid_block(200)
    fast = simulate(system, load, cycles=600, steps_per_cycle=50, protocol=protocol,
                    record=False, tol=1e-11, slow_modes=True)
    assert fast.steady_state == "cyclic_slip"
    assert fast.solver_stats["slow_mode_steps"] >= 1
    assert fast.cycles_run < 200
    plain_x = np.load(DATA / "fe_block_401_plain_limit.npy")
    x = fast.cycle_start_states[-1]
    assert np.abs(x - plain_x).max() <= 1e-6 * np.abs(plain_x).max()
    assert fast.dissipation_per_cycle == pytest.approx(PLAIN_D_401, rel=1e-6, abs=0)
    assert fast.slipping_nodes == list(range(378, 401))
    assert fast.permanently_stuck_nodes == list(range(378))
    expected = np.concatenate([np.zeros(378), PLAIN_DJ_401])
    np.testing.assert_allclose(fast.dissipation_per_node, expected, rtol=0,
                               atol=1e-6 * PLAIN_D_401)
    assert_reproduced_by_one_more_cycle(fast, system, load, 50, 1e-10)


@pytest.mark.parametrize("after", [1, 3, 7, 10])
def test_slow_mode_steps_keep_plain_cyclings_memory_whenever_they_start(monkeypatch, after):
    """41-node block (plain cycling to 1e-14: D = 3.1769966252792746e-07 J): some nodes
    stop early in the transient. Whenever the steps start, D lands within 1e-6 of plain
    cycling's (measured 1.2e-8 to 2.4e-8)."""
    system, load, protocol = slid_block(20)
    monkeypatch.setattr(steady, "SLOW_AFTER", after)
    run = simulate(system, load, cycles=200, steps_per_cycle=50, protocol=protocol,
                   record=False, tol=1e-11, slow_modes=True)
    assert run.steady_state == "cyclic_slip" and run.residual < 1e-11
    assert run.solver_stats["slow_mode_steps"] >= 1
    assert run.dissipation_per_cycle == pytest.approx(3.1769966252792746e-07, rel=1e-6,
                                                      abs=0)


def test_a_slow_mode_step_that_runs_past_a_stop_still_ends_on_a_periodic_state(
        monkeypatch):
    """Why every step ends where the first node stops: without that limit, the steps
    (starting here from a creep ratio of 0.5, earlier in the transient, where more nodes
    are still to stop) on the 41-node block still end on a periodic state (residual below
    the tolerance asked for), but which member of the set of periodic states (Barber 2012
    §3) they reach depends on the last bits of the path: D is 1.16e-5 off plain
    cycling's when this module runs alone and 9.3e-9 off in a process that loaded only
    this test (the same AMD EPYC), 1.5e-8 with OPENBLAS_CORETYPE=Haswell and 5.0e-7 with
    Prescott (residuals 2.0e-12 to 7.7e-12). Only what the algorithm guarantees is
    asserted: the class, the residual below its tolerance, and D within the spread of
    those periodic states (1e-4).
    """
    system, load, protocol = slid_block(20)
    monkeypatch.setattr(steady, "_before_a_stop", lambda *args: 1.0)
    monkeypatch.setattr(steady, "SLOW_CREEP", 0.5)
    tol = 1e-11
    run = simulate(system, load, cycles=200, steps_per_cycle=50, protocol=protocol,
                   record=False, tol=tol, slow_modes=True)
    assert run.steady_state == "cyclic_slip" and run.residual < tol
    rel = abs(run.dissipation_per_cycle - 3.1769966252792746e-07) / 3.1769966252792746e-07
    assert rel < 1e-4


def _random_slip(seed, system, load):
    """The random initial slip of ``test_discrete_steady_jump.py`` for the system of
    ``seed``."""
    rng = np.random.default_rng(seed + 1)
    return rng.normal(size=system.n_nodes) * 0.05 * float(
        np.abs(load(np.zeros(1))).max()) / float(np.max(np.diag(system.A)))


def test_slow_mode_steps_are_off_by_default():
    """By default the steps of the follower alone (they keep plain cycling's memory
    exactly, and get there in more cycles)."""
    system, load, protocol = slid_block(20)
    run = simulate(system, load, cycles=200, steps_per_cycle=50, protocol=protocol,
                   record=False, tol=1e-10)
    assert run.solver_stats["slow_mode_steps"] == 0
    assert run.solver_stats["periodic_steps"] >= 1
    assert run.dissipation_per_cycle == pytest.approx(3.1769966252792746e-07, rel=1e-6,
                                                      abs=0)


def test_slow_mode_steps_can_still_land_on_another_periodic_state_of_a_random_system(
        monkeypatch):
    """Why the steps stay off by default: they do not check the stuck nodes' friction
    limits on the way (the follower does), and can land on another member of the set of
    periodic states. On the random 4-node system of seed 67415 (with separation, from a
    random initial slip, the systems of ``test_discrete_steady_jump.py``), steps tried as
    soon as the follower has none end on a periodic state whose D is 7.3e-4 off plain
    cycling's (both at tolerance 1e-11): node 1 creeps at a ratio of 0.73 per cycle and
    stops for good after a few more cycles, and the steps carry it past that stop. The
    follower alone ends on plain cycling's."""
    system, load = _random_case(67415, 4, True)
    kw = dict(cycles=400, steps_per_cycle=40, tol=1e-11, record=False,
              initial_slip=_random_slip(67415, system, load))
    plain = simulate(system, load, accelerate=False, **kw)
    follower = simulate(system, load, accelerate=True, **kw)
    assert_same_steady_state(follower, plain)
    monkeypatch.setattr(steady, "SLOW_AFTER", 1)
    slow = simulate(system, load, accelerate=True, slow_modes=True, **kw)
    assert slow.steady_state == plain.steady_state == "cyclic_slip"
    assert slow.permanently_stuck_nodes == plain.permanently_stuck_nodes == [1]
    assert slow.solver_stats["slow_mode_steps"] >= 1
    rel = abs(slow.dissipation_per_cycle - plain.dissipation_per_cycle) / \
        plain.dissipation_per_cycle
    assert rel == pytest.approx(7.3e-4, rel=0.05)


def test_slow_mode_steps_wait_for_a_slow_creep(monkeypatch):
    """Why a step needs the last increment to keep at least SLOW_CREEP = 0.8 of the one
    before: a faster creep reaches the tolerance in a few more cycles anyway, and its
    extrapolation lands elsewhere. On the random 8-node system of seed 53914 (with
    separation; increments shrinking by 0.66 to 0.72 per cycle), steps allowed from a
    ratio of 0.5 on, as soon as the follower has none, end on a periodic state whose D is
    6.6e-3 off plain cycling's; with the default ratio no step is taken and the run ends
    on plain cycling's state."""
    system, load = _random_case(53914, 8, True)
    kw = dict(cycles=400, steps_per_cycle=40, tol=1e-11, record=False)
    plain = simulate(system, load, accelerate=False, **kw)
    monkeypatch.setattr(steady, "SLOW_AFTER", 1)
    waiting = simulate(system, load, accelerate=True, slow_modes=True, **kw)
    assert waiting.solver_stats["slow_mode_steps"] == 0
    assert_same_steady_state(waiting, plain)
    monkeypatch.setattr(steady, "SLOW_CREEP", 0.5)
    eager = simulate(system, load, accelerate=True, slow_modes=True, **kw)
    assert eager.steady_state == plain.steady_state == "cyclic_slip"
    assert eager.solver_stats["slow_mode_steps"] >= 1
    rel = abs(eager.dissipation_per_cycle - plain.dissipation_per_cycle) / \
        plain.dissipation_per_cycle
    assert rel == pytest.approx(6.6e-3, rel=0.05)


def test_a_slow_mode_step_that_carries_an_event_past_a_load_sample_lands_elsewhere(
        monkeypatch):
    """Why a step also ends where an event would leave its load segment: on the random
    12-node system of seed 59987 (with separation) the steps then end on plain cycling's
    steady state (D to 1e-6); allowed past the load samples, they end on a periodic state
    whose D is 1.0e-4 off (a node that slipped on through a sample stops there instead,
    with other slip: its memory). The steps start here from a creep ratio of 0.5 (from
    the default 0.8 they take none on this system); tolerance 1e-10 (at 1e-11 plain
    cycling does not converge: its state ends alternating between two states 7e-11
    apart)."""
    system, load = _random_case(59987, 12, True)
    kw = dict(cycles=400, steps_per_cycle=40, tol=1e-10, record=False)
    monkeypatch.setattr(steady, "SLOW_CREEP", 0.5)
    tight = simulate(system, load, accelerate=False, **dict(kw, tol=1e-11))
    x = tight.cycle_start_states
    d1, d0 = x[-1] - x[-2], x[-2] - x[-3]
    assert tight.steady_state == "not_converged"
    assert np.abs(d1 + d0).max() < 1e-3 * np.abs(d1).max()       # x alternates
    # alternating about 7e-11 apart here; the digit is round-off's, the decade is not
    assert 1e-11 < tight.residual < 1e-10
    plain = simulate(system, load, accelerate=False, **kw)
    slow = simulate(system, load, accelerate=True, slow_modes=True, **kw)
    assert slow.solver_stats["slow_mode_steps"] >= 1
    assert_same_steady_state(slow, plain)
    monkeypatch.setattr(steady, "SEGMENT_TOL", np.inf)      # no segment limit
    past = simulate(system, load, accelerate=True, slow_modes=True, **kw)
    assert past.steady_state == plain.steady_state == "cyclic_slip"
    rel = abs(past.dissipation_per_cycle - plain.dissipation_per_cycle) / \
        plain.dissipation_per_cycle
    assert rel == pytest.approx(1.04e-4, rel=0.05)
