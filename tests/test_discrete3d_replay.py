"""The frozen subdivision of ``simulate3d`` (the step control's accepted sub-steps of a
cycle replayed once the slip pattern repeats, the result verified by an adaptive cycle):
replaying a recorded path reproduces it; replay on and off reach the same steady state
(class, dissipation in total and per node, slipping / stuck / separating nodes) on random
coupled systems and on an FE-like chain; and the FE-like case whose adaptive cycle map
ended on a period-4 orbit now converges to a steady state of the adaptive method."""

import numpy as np
import pytest
from test_discrete3d_steady_jump import (
    REF_TOL,
    TOL,
    _assert_same_steady_state,
    _fe_like,
    _random_coupled,
)

from slipcycle.discrete3d.evolution import Evolution3D
from slipcycle.discrete3d.steady import simulate3d
from slipcycle.loading.nodal import force_scale


def test_replaying_a_recorded_path_reproduces_it_with_fewer_solves():
    system, load = _fe_like(30)
    theta, vals = load.cycle_samples(30)
    F = force_scale(vals)
    n = system.n_nodes
    evo = Evolution3D(system, np.zeros(3 * n), np.zeros(3 * n), F, step_tol=1e-6)
    evo.follow(np.arange(2.0), np.array([np.zeros(3 * n), vals[0]]))
    evo.resync()
    x0 = evo.x.copy()
    adaptive = evo.follow(theta, vals)
    x_adaptive, solves_adaptive = evo.x.copy(), evo.solver.stats["solves"]
    assert adaptive.refinements > 0            # a subdivision worth replaying
    evo.x = x0.copy()
    evo.resync()
    evo.plan = adaptive.plan
    replayed = evo.follow(theta, vals)
    solves_replay = evo.solver.stats["solves"] - solves_adaptive
    assert replayed.replay_mismatches == 0
    assert replayed.steps == adaptive.steps
    # the same steps solved again: equal to the Newton tolerance
    assert np.max(np.abs(evo.x - x_adaptive)) <= 1e-9 * evo.disp_scale
    np.testing.assert_allclose(replayed.dissipation, adaptive.dissipation,
                               atol=1e-9 * F * evo.disp_scale)
    assert solves_replay < solves_adaptive


def _replay_pair(system, load, cycles, steps=40, step_tol=1e-6, tol=TOL, ref_tol=REF_TOL,
                 accelerate=True):
    kw = dict(steps_per_cycle=steps, step_tol=step_tol, record=False)
    on = simulate3d(system, load, cycles=cycles, tol=tol, replay=True,
                    accelerate=accelerate, **kw)
    off = simulate3d(system, load, cycles=cycles, tol=ref_tol, replay=False,
                     accelerate=False, **kw)
    return on, off


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_replay_on_and_off_reach_the_same_steady_state_on_random_coupled_systems(seed):
    # plain cycling with and without replay (with the extrapolation, seed 2 approaches
    # a shakedown whose dying slips the jump stops elsewhere: another member of the set)
    system, load = _random_coupled(seed, 8)
    on, off = _replay_pair(system, load, 200, accelerate=False)
    assert off.replayed_cycles == 0
    _assert_same_steady_state(on, off)


def test_replay_on_and_off_reach_the_same_steady_state_on_an_fe_like_chain():
    system, load = _fe_like(50)
    on, off = _replay_pair(system, load, 150, tol=1e-6, ref_tol=1e-9)
    assert on.replayed_cycles >= 1
    _assert_same_steady_state(on, off, tol=1e-6)
    assert on.steady_state == "cyclic_slip" and on.permanently_stuck_nodes


def test_period_four_orbit_case_converges_to_a_checked_fixed_point_of_its_subdivision():
    # N = 60, step_tol 1e-5, tol 1e-7: without the frozen subdivision the adaptive cycle
    # map's switching refinement decisions left the run on a period-4 orbit of the
    # dissipation, not converged in 50 cycles
    system, load = _fe_like(60)
    step_tol = 1e-5
    kw = dict(steps_per_cycle=40, step_tol=step_tol, record=False)
    res = simulate3d(system, load, cycles=50, tol=1e-7, replay=True, accelerate=True, **kw)
    assert res.steady_state == "cyclic_slip"
    assert res.replayed_cycles >= 1 and res.residual <= 1e-7
    # the verifying cycle replayed the subdivision with every sub-step's error estimate
    # checked; the adaptive method, which may take coarser steps, moves that start by
    # the step control's error level only and dissipates the same energy to that level
    n = system.n_nodes
    x = res.cycle_start_states[-2]       # the start of the verifying cycle
    check = simulate3d(system, load, cycles=1, tol=1e-7, replay=False, accelerate=False,
                       initial_slip=x[:2 * n], **kw)
    e_scale = res.force_scale * res.disp_scale
    assert check.residual <= 10 * step_tol
    assert abs(check.dissipation_per_cycle - res.dissipation_per_cycle) <= 10 * step_tol * e_scale
