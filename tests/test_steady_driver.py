"""The steady-state driver shared by the discrete models (``slipcycle.coupled``): one cycle
loop with its accelerators behind one interface, typed run settings and solver statistics,
and the one list of steady-state words.

The loop is checked on cycle maps whose fixed point, drift and creep are known in closed
form (an affine contraction x → A x + b, a constant drift), the strategies against plain
cycling, and the typed settings and statistics through the paths users take."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from slipcycle.coupled import RunSettings, SolverStats
from slipcycle.coupled.cycles import CycleHistory, assemble, run_scales
from slipcycle.coupled.driver import BackOff, CycleState, PlainCycling, run_cycles
from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.discrete.evolution import Evolution
from slipcycle.discrete.steady import PieceSteps, initial_state
from slipcycle.discrete3d.steady import Mixing, Replay
from slipcycle.result import STEADY_STATES, SteadyState


class _AffineCycle:
    """A stand-in for an evolution engine whose cycle maps x to A x + b (no contact: the
    totals say nothing slipped or opened)."""

    def __init__(self, A, b, x0):
        self.A, self.b = np.asarray(A, float), np.asarray(b, float)
        self.x = np.asarray(x0, float).copy()
        self.plan = None
        self.cycles = 0

    def follow(self, theta, vals, record=False):
        self.x = self.A @ self.x + self.b
        self.cycles += 1
        n = self.x.size // 2
        return SimpleNamespace(dissipation=np.zeros(n), slip_length=np.zeros(n),
                               separated=np.zeros(n, bool), steps=1, refinements=0,
                               unresolved=0, replay_mismatches=0, plan=None,
                               samples={"x": self.x[None], "r": self.x[None],
                                        "modes": np.zeros((1, n), np.int8)})

    def resync(self):
        pass


def _run(A, b, x0, accelerator, **kw):
    evo = _AffineCycle(A, b, x0)
    system = SimpleNamespace(n_nodes=len(x0) // 2)
    s = RunSettings(**kw)
    run = CycleState(system, evo, s, CycleHistory(1.0, False, [evo.x.copy()]),
                     np.zeros(len(x0)), 1.0)
    return run_cycles(run, np.zeros(1), np.zeros((1, len(x0))), accelerator), evo


@settings(max_examples=30, deadline=None)
@given(rho=st.floats(0.05, 0.9), b=st.floats(-2.0, 2.0), tol=st.sampled_from([1e-6, 1e-9]))
# a first increment of tol (found by a fresh hypothesis run): the run stops on its first
# cycle, one increment gives no ratio, and the fixed point is still 3 tol away
@example(rho=0.75, b=1e-6, tol=1e-6)
def test_plain_cycling_of_an_affine_contraction_stops_within_tol_of_its_fixed_point(
        rho, b, tol):
    # x → ρ x + b: fixed point b/(1 − ρ); after c cycles from 0 the distance to it is
    # ρ^c |b|/(1 − ρ) and the increment ρ^(c−1) |b|: the creep test stops where the
    # distance, not the increment, is below tol (relative to the scale max(1, |x|))
    A = np.diag([rho, rho])
    run, evo = _run(A, [b, 0.0], [0.0, 0.0], PlainCycling(), cycles=2000, tol=tol)
    assert run.state == "steady"
    x_star = b / (1 - rho)
    scale = max(1.0, abs(run.starts[-1][0]))
    assert evo.cycles == len(run.starts) - 1 == len(run.history.dissipation)
    if len(run.starts) == 2:
        # stopped on the first cycle: one increment gives no ratio (creep_distance), the
        # test is the increment's, and the rest of the creep is at most ρ/(1 − ρ) times it
        assert abs(run.starts[-1][0] - run.starts[0][0]) <= tol * scale
        assert abs(run.starts[-1][0] - x_star) <= rho / (1 - rho) * tol * scale * (1 + 1e-6)
        return
    assert abs(run.starts[-1][0] - x_star) <= tol * scale * (1 + 1e-6)
    # and not much later than needed: one cycle before, plain cycling was not there yet
    # or its increment test had not yet seen the creep
    assert evo.cycles == len(run.starts) - 1 == len(run.history.dissipation)


def test_a_constant_drift_is_ratcheting_with_its_drift():
    run, _ = _run(np.eye(2), [0.25, 0.0], [0.0, 0.0], PlainCycling(), cycles=50, tol=1e-9)
    assert run.state == "ratcheting"
    np.testing.assert_array_equal(run.ratchet, [0.25])      # the tangential part
    assert len(run.starts) == 3                       # two cycles: two equal increments


def test_cycles_that_run_out_are_not_converged_unless_the_increment_was_steady():
    A = np.diag([0.99, 0.99])
    run, _ = _run(A, [1.0, 0.0], [0.0, 0.0], PlainCycling(), cycles=5, tol=1e-9)
    assert run.state == "not_converged" and len(run.starts) == 6
    # min_cycles: a fixed point from the start still runs min_cycles cycles
    run, evo = _run(np.zeros((2, 2)), [0.0, 0.0], [0.0, 0.0], PlainCycling(), cycles=9,
                    tol=1e-9, min_cycles=4)
    assert run.state == "steady" and evo.cycles == 4


@pytest.mark.parametrize("rho", [0.9, 0.99])
def test_anderson_mixing_reaches_the_fixed_point_of_a_slow_contraction_in_fewer_cycles(rho):
    # a linear map is where the mixing is exact (GMRES): it lands on (I − A)⁻¹ b to the
    # tolerance in a few cycles, where plain cycling creeps
    rng = np.random.default_rng(3)
    Q = np.linalg.qr(rng.normal(size=(4, 4)))[0]
    A = Q @ np.diag([rho, 0.5 * rho, 0.3, 0.1]) @ Q.T
    b = rng.normal(size=4)
    x_star = np.linalg.solve(np.eye(4) - A, b)
    kw = dict(cycles=3000, tol=1e-10)
    plain, _ = _run(A, b, np.zeros(4), PlainCycling(), **kw)
    mixed, evo = _run(A, b, np.zeros(4), Mixing(True, 3, False, 5, 20), **kw)
    for run in (plain, mixed):
        assert run.state == "steady"
        assert np.abs(run.starts[-1] - x_star).max() <= 1e-8 * np.abs(x_star).max()
    assert evo.cycles < (len(plain.starts) - 1) / 3


def _two_node():
    A = np.array([[2.0, -0.5], [-0.5, 2.0]])
    system = FrictionalSystem(A, 0.3 * np.array([[0.0, 1.0], [-1.0, 0.0]]), 1.5 * A, 0.4)
    load = DiscreteLoad.harmonic([1.0, 1.2], [0.1, -0.05], [0.3, 0.2], [0.45, 0.4],
                                 [0.0, 1.0], [0.5, 2.0])
    return system, load


def test_plain_cycling_strategy_on_the_exact_engine_is_simulate_without_steps():
    """The driver's plain cycling, assembled from the shared pieces, is
    ``simulate(accelerate=False)`` to the last bit; the 2-D strategy with its steps off is
    plain cycling too."""
    system, load = _two_node()
    kw = dict(cycles=30, steps_per_cycle=40, tol=1e-12)
    ref = simulate(system, load, accelerate=False, record=False, **kw)
    theta, vals, F, disp = run_scales(system, load, 40, None)
    for strategy in (PlainCycling(), PieceSteps(False, False)):
        evo = assemble(lambda x0, rw: Evolution(system, x0, rw, F), system, vals[0], F, None,
                       None, initial_state)
        run = CycleState(system, evo, RunSettings(cycles=30, steps_per_cycle=40, tol=1e-12),
                         CycleHistory.of_run(system, vals, disp, 1e-12, evo.x, False),
                         vals[0], F)
        run_cycles(run, theta, vals, strategy)
        np.testing.assert_array_equal(np.array(run.starts), ref.cycle_start_states)
        assert run.residual == ref.residual


def test_run_settings_have_one_name_per_setting_and_pass_on_unchanged():
    base = RunSettings()
    assert dict(base) == {"cycles": 40, "steps_per_cycle": 100, "tol": 1e-8, "min_cycles": 1}
    s = RunSettings.of({"steady_tol": 1e-6, "cycles": 7}, base)
    assert s.tol == 1e-6 and s.cycles == 7 and s["tol"] == 1e-6
    three = RunSettings.of({"step_tolerance": 1e-5}, RunSettings(step_tol=1e-7, replay=False))
    assert three.step_tol == 1e-5 and dict(three)["replay"] is False
    with pytest.raises(TypeError, match="step_tol"):
        RunSettings.of({"step_tol": 1e-5}, base)         # the 2-D engine has none
    with pytest.raises(KeyError):
        base["step_tol"]
    with pytest.raises(AttributeError):
        s.tol = 1.0                                        # frozen
    system, load = _two_node()
    res = simulate(system, load, record=False, **RunSettings(cycles=3, steps_per_cycle=20))
    assert res.cycles_run <= 3


def test_solver_stats_are_typed_counts_with_the_step_solvers_own():
    stats = SolverStats(periodic_steps=2, jumps=1, solver={"solves": 10})
    assert stats.periodic_steps == 2 and stats["periodic_steps"] == 2
    assert stats["solves"] == 10 and stats.get("newton_iterations", 0) == 0
    assert set(stats) >= {"solves", "jumps", "replay_mismatches"}
    system, load = _two_node()
    res = simulate(system, load, cycles=3, steps_per_cycle=20, record=False)
    assert isinstance(res.solver_stats, SolverStats)
    assert res.solver_stats["factorizations"] >= 1


def test_one_list_of_steady_state_words_with_the_codes_of_the_stores():
    # the codes the basin maps, λ scans and their figures store (unchanged)
    assert STEADY_STATES[:6] == ("shakedown", "cyclic_slip", "ratcheting", "not_converged",
                                 "inadmissible", "failed")
    for word in STEADY_STATES:
        s = SteadyState(word)
        assert SteadyState.of_code(s.code) is s and STEADY_STATES[s.code] == word
    assert SteadyState.worst(["shakedown", "ratcheting", "cyclic_slip"]) is \
        SteadyState.RATCHETING
    from slipcycle.discrete.steady import STEADY_CLASSES, STEADY_CODES
    from slipcycle.discrete3d.steady import STEADY_CLASSES as CLASSES_3D
    assert STEADY_CODES == STEADY_STATES
    assert STEADY_CLASSES == CLASSES_3D == ("shakedown", "cyclic_slip", "ratcheting",
                                            "not_converged")


def _attempts(backoff, cycles, found=lambda c: False, may_wait=True):
    """The cycles in which an accelerator with ``backoff`` attempts a step."""
    tried = []
    for c in range(cycles):
        if backoff.ready:
            tried.append(c)
            backoff.outcome(found(c), may_wait)
        backoff.tick()
    return tried


def test_back_off_waits_1_2_4_then_8_cycles_after_four_fruitless_attempts():
    # the schedule test_discrete_steady_jump.py measures on the 41-node block: 13
    # attempts in 60 cycles (cycles 0-4, 6, 10, 18, 26, ..., 58) instead of 60
    assert _attempts(BackOff(4, 8), 60) == [0, 1, 2, 3, 4, 6, 10, 18, 26, 34, 42, 50, 58]
    assert len(_attempts(BackOff(4, 1), 60)) == 60          # at most 1: every cycle
    assert len(_attempts(BackOff(4, 8), 60, may_wait=False)) == 60


def test_back_off_starts_again_after_a_step_and_holds_after_a_refusal():
    # a step found in cycle 10 resets the count: four more fruitless attempts before
    # the next wait
    tried = _attempts(BackOff(4, 8), 30, found=lambda c: c == 10)
    assert tried[:9] == [0, 1, 2, 3, 4, 6, 10, 11, 12]
    assert tried[9:13] == [13, 14, 15, 17]
    b = BackOff(4, 8)
    b.hold(2)                       # a refused step: no attempt in the next cycle
    assert not b.ready
    b.tick()
    assert not b.ready
    b.tick()
    assert b.ready
    b.outcome(None)                 # an attempt that goes on in the next cycle counts as none
    assert b.fruitless == 0 and b.ready


def test_slow_mode_steps_alone_reach_plain_cyclings_dissipation_on_the_41_node_block():
    """The slow-mode strategy without the follower (its tries used up): on the 41-node
    FE block D lands within 1e-6 of plain cycling to 1e-14 (3.1769966252792746e-07 J,
    test_discrete_steady_jump.py), in fewer than half of plain cycling's 445 cycles at
    this tolerance (the residual measured against the service cycle)."""
    from conftest import slid_block

    system, load, protocol = slid_block(20)
    theta, vals, F, disp = run_scales(system, load, 50, protocol)
    evo = assemble(lambda x0, rw: Evolution(system, x0, rw, F), system, vals[0], F, None,
                   protocol, initial_state)
    run = CycleState(system, evo, RunSettings(cycles=200, steps_per_cycle=50, tol=1e-11),
                     CycleHistory.of_run(system, vals, disp, 1e-11, evo.x, False), vals[0], F)
    steps = PieceSteps(True, True)
    steps.follower.left = 0
    run_cycles(run, theta, vals, steps)
    assert run.state == "steady" and run.residual <= 1e-11
    assert steps.stats["slow_mode_steps"] >= 1
    assert steps.stats["slow_mode_steps"] == steps.stats["periodic_steps"]   # no follower
    assert len(run.starts) - 1 < 222
    D = float(run.totals.dissipation.sum())
    assert D == pytest.approx(3.1769966252792746e-07, rel=1e-6, abs=0)


def test_replay_freezes_checks_every_fifth_cycle_and_verifies_a_fixed_point():
    """The replay strategy's decisions on a stand-in engine: a repeating pattern freezes
    the cycle's subdivision; replayed cycles check their error estimates every
    ``check``-th cycle outside the jumps; a fixed point of the replayed map is not steady
    until one more replay with every estimate checked; a misfit refreezes, at most
    ``most`` times, then cycles adaptively."""
    evo = SimpleNamespace(plan=None, check_plan=None)
    run = SimpleNamespace(evo=evo, totals=SimpleNamespace(plan="plan-1", replay_mismatches=0))
    r = Replay(True, 5, 2)
    r.before_cycle(evo, jumping=False)
    assert not r.was_replay and r.checked
    r.freeze(run, jumping=True)                  # not during the jumps
    assert evo.plan is None
    r.freeze(run, jumping=False)
    assert evo.plan == "plan-1" and r.freezes == 1
    checks = []
    for _ in range(10):
        r.before_cycle(evo, jumping=False)
        checks.append(evo.check_plan)
        r.after_cycle(run.totals)
    assert checks == [False] * 4 + [True] + [False] * 4 + [True]
    assert r.replayed == 10 and not r.checked
    assert r.fixed_point() == "skip"             # a fixed point of the replayed map: verify
    r.before_cycle(evo, jumping=True)
    assert evo.check_plan is True and r.checked
    assert r.fixed_point() == "steady"
    run.totals = SimpleNamespace(plan="plan-2", replay_mismatches=3)
    assert r.misfit(run, jumping=False) and evo.plan == "plan-2" and r.freezes == 2
    r.before_cycle(evo, jumping=False)
    r.after_cycle(run.totals)
    assert r.mismatches == 3
    assert r.misfit(run, jumping=False) and evo.plan is None      # most = 2: adaptive
