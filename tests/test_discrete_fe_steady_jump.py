"""The periodic-state step on FE-reduced blocks and FE-like random systems.

Independent references: plain cycling (``accelerate=False``) of the same history, the
dissipation of plain cycling of the 101-node block to a relative tolerance of 1e-13
(measured once, several hundred cycles), and one more exact cycle from the state the
accelerated run ends in (a periodic state must reproduce itself and its dissipation per
node).
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_reproduced_by_one_more_cycle, assert_same_steady_state, slid_block
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate

#: dissipation per cycle [J] of plain cycling of the slid 101-node block to 1e-13
#: (accelerate=False, 50 samples per cycle; measured once)
PLAIN_D_101 = 1.422803542687334e-07


def test_fe_block_101_step_reaches_the_dissipation_of_tightly_converged_plain_cycling():
    """101 contact nodes, slide-first: plain cycling needs 377 cycles to 1e-8 and still
    differs from its limit by 3e-4 in D. The accelerated run (tolerance 1e-10, 171 cycles:
    creeping nodes stop one after another, and each stop changes the piece of the cycle
    map, which the steps must not jump over) ends on plain cycling's limit (measured once:
    the state within 1.3e-9 of the plain run to 1e-13, 1523 cycles) and matches its D to
    1e-5 (measured 2.5e-6: nodes that graze their friction limit there slip back and forth
    by amounts of the state's own tolerance, so D resolves it about 10³ times more
    coarsely), with the stuck, slipping and separating nodes of plain cycling (nodes
    95–100 slip and open, the 95 others stay stuck)."""
    system, load, protocol = slid_block(50)
    fast = simulate(system, load, cycles=200, steps_per_cycle=50, protocol=protocol,
                    record=False, tol=1e-10)
    assert fast.steady_state == "cyclic_slip"
    assert fast.solver_stats["periodic_steps"] >= 1
    assert fast.cycles_run < 377 / 2
    assert fast.dissipation_per_cycle == pytest.approx(PLAIN_D_101, rel=1e-5, abs=0)
    assert fast.slipping_nodes == fast.separating_nodes == list(range(95, 101))
    assert fast.permanently_stuck_nodes == list(range(95))
    # one more exact cycle from the final state reproduces it and its D per node
    assert_reproduced_by_one_more_cycle(fast, system, load, 50, 1e-9)


def _fe_like_case(seed: int, n: int):
    """Banded, positive definite FE-like stiffness (decaying oscillating Toeplitz A, C and
    an odd coupling B, as for a punch on a strip), random harmonic loads with edge slip."""
    rng = np.random.default_rng(seed)
    i = np.arange(n)
    d = np.abs(i[:, None] - i[None, :])
    A = 2.0 * np.exp(-d / 2.0) * np.cos(0.7 * d) + np.eye(n)
    C = 1.3 * A
    B = rng.uniform(0.1, 0.4) * np.sign(i[:, None] - i[None, :]) * np.exp(-d / 3.0)
    system = FrictionalSystem(A, B, C, float(rng.uniform(0.2, 0.4)))
    x = np.linspace(-1.0, 1.0, n)
    load = DiscreteLoad.harmonic(np.ones(n), rng.uniform(0.0, 0.1) * x, 0.2 * np.ones(n),
                                 rng.uniform(0.1, 0.2) + rng.uniform(0.2, 0.5) * x ** 4,
                                 np.zeros(n), rng.uniform(0.0, 1.0) * x)
    return system, load


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 100_000), n=st.integers(16, 48))
def test_fe_like_random_systems_same_steady_state_with_and_without_the_step(seed, n):
    """N ≥ 16 (the step is on by default): class, stuck and slipping nodes, and D per node
    of plain cycling to 1e-11, whatever the number of steps taken."""
    system, load = _fe_like_case(seed, n)
    kw = dict(cycles=300, steps_per_cycle=40, tol=1e-11, record=False)
    plain = simulate(system, load, accelerate=False, **kw)
    fast = simulate(system, load, accelerate=True, **kw)
    assert plain.steady_state != "not_converged"
    assert_same_steady_state(fast, plain)
    assert fast.slipping_nodes == plain.slipping_nodes
