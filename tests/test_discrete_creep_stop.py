"""The steady-state test of a creeping system: where plain cycling's increments shrink
geometrically, by ρ per cycle, the state is still ρ/(1 − ρ) increments from its periodic
limit (Aitken's estimate), and :func:`~slipcycle.discrete.steady.simulate` is steady only
when that distance is below the tolerance too. FE-reduced blocks creep at ρ close to 1,
where the last increment alone says little about the distance to the limit."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import slid_block

from slipcycle.discrete import simulate, steady
from slipcycle.kernels.creep import creep_distance

#: D of plain cycling of the 41-node slid block to 1e-14 [J]
#: (``tests/test_discrete_slow_modes.py``)
D_41 = 3.1769966252792746e-07


def _starts(increments):
    """Start-of-cycle states of a 1-coordinate creep with the given increments."""
    return [np.array([v]) for v in np.concatenate([[1.0], 1.0 + np.cumsum(increments)])]


def test_creep_distance_is_the_rest_of_the_geometric_series():
    """Increments 1e-3·0.9^k: the rest after the last is 0.9/(1 − 0.9) = 9 times it."""
    inc = 1e-3 * 0.9 ** np.arange(5)
    starts = _starts(inc)
    got = creep_distance(starts, inc[-1], 1.0)
    assert got == pytest.approx(9 * inc[-1], rel=1e-9)
    exact_rest = 1e-3 * 0.9 ** 5 / (1 - 0.9)
    assert got == pytest.approx(exact_rest, rel=1e-9)


@pytest.mark.parametrize("case", ["fast", "growing", "round-off", "two starts"])
def test_creep_distance_is_the_last_increment_where_no_creep_shows(case):
    """A fast contraction (ρ ≤ 1/2, the rest is at most the last increment), increments
    that grow, increments at round-off, or too few cycles: the last increment itself."""
    inc = {"fast": 1e-3 * 0.3 ** np.arange(4), "growing": 1e-3 * 1.1 ** np.arange(4),
           "round-off": 1e-15 * 0.9 ** np.arange(4), "two starts": [1e-3]}[case]
    assert creep_distance(_starts(inc), inc[-1], 1.0) == inc[-1]


def test_plain_cycling_of_a_creeping_block_stops_near_its_limit():
    """41-node slid block, plain cycling at the default tolerance 1e-8 (the residual
    measured against the service cycle's displacement): it creeps at ρ = 0.95 per cycle.
    Steady after 336 cycles with D 3.7e-7 off the limit of plain cycling to 1e-14; the
    last increment alone (the test before) stopped it after 281 cycles with D 4.9e-6 off.
    (Measured against the whole load's displacement, 273 cycles and 7.6e-6, 214 and
    1.4e-4.)"""
    system, load, protocol = slid_block(20)
    kw = dict(cycles=600, steps_per_cycle=50, protocol=protocol, record=False,
              accelerate=False)
    run = simulate(system, load, **kw)
    inc = np.abs(np.diff(run.cycle_start_states, axis=0)).max(axis=1)
    rho = np.median(inc[-50:] / inc[-51:-1])
    assert rho == pytest.approx(0.95, abs=0.01)
    assert run.steady_state == "cyclic_slip" and run.cycles_run == 336
    assert abs(run.dissipation_per_cycle - D_41) / D_41 == pytest.approx(3.7e-7, rel=0.05)
    assert abs(run.dissipation_per_cycle - D_41) / D_41 < 1e-5


def test_the_last_increment_alone_stops_a_creeping_block_far_from_its_limit(monkeypatch):
    """The same run with the increment test alone: 281 cycles, D 4.9e-6 off."""
    monkeypatch.setattr(steady, "creep_distance", lambda starts, residual, xscale: residual)
    system, load, protocol = slid_block(20)
    run = simulate(system, load, cycles=600, steps_per_cycle=50, protocol=protocol,
                   record=False, accelerate=False)
    assert run.steady_state == "cyclic_slip" and run.cycles_run == 281
    assert abs(run.dissipation_per_cycle - D_41) / D_41 == pytest.approx(4.9e-6, rel=0.05)


def test_cycles_that_run_out_after_the_increment_test_still_give_the_class():
    """With 300 cycles allowed (the increment is below 1e-8 from cycle 281 on, the
    creep's distance only from 336): classified cyclic slip after the 300 cycles, as the
    increment test alone would say, not 'not converged'; closer to the limit than at 281."""
    system, load, protocol = slid_block(20)
    run = simulate(system, load, cycles=300, steps_per_cycle=50, protocol=protocol,
                   record=False, accelerate=False)
    assert run.steady_state == "cyclic_slip" and run.cycles_run == 300
    assert run.residual <= 1e-8
    assert abs(run.dissipation_per_cycle - D_41) / D_41 < 4.9e-6
