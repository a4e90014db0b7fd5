"""The CalculiX benchmark's own pieces (benchmarks/bench_calculix.py): the deck in the
repository is the one its generator writes, and the dissipation CalculiX's grip forces
give is the loop area (a Jenkins element: 4 c (δ_t − c/k); an elastic spring: none)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_calculix.py"
_spec = importlib.util.spec_from_file_location("bench_calculix", PATH)
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)


def test_the_deck_in_the_repository_is_the_generated_one():
    assert bench.DECK.read_text() == bench.block_deck()
    assert "TYPE=SURFACE TO SURFACE" in bench.DECK.read_text()


def _history(force_of):
    """Printed times and grip forces of the deck's steps: the normal step (4 prints),
    then 40 increments per cycle of the piecewise-linear sine amplitude."""
    s = np.linspace(0.0, bench.CYCLES, bench.CYCLES * bench.INCREMENTS + 1)[1:]
    tab = np.linspace(0.0, bench.CYCLES, 4 * bench.CYCLES * 8 + 1)
    d = bench.DELTA_T * np.interp(s, tab, np.sin(2 * np.pi * tab))
    t = np.concatenate([[0.25, 0.5, 0.75, 1.0], 1.0 + s])
    return t, np.concatenate([np.zeros(4), force_of(d)])


def test_cycle_dissipation_is_the_area_of_a_jenkins_loop():
    k, c = 2e9, 1000.0                              # N/m, N

    def jenkins(d):
        z, out, prev = 0.0, [], 0.0
        for di in d:
            z = float(np.clip(z + k * (di - prev), -c, c))
            out.append(z)
            prev = di
        return np.array(out)

    per_cycle = bench.cycle_dissipation(*_history(jenkins))
    exact = 4 * c * (bench.DELTA_T - c / k)
    # cycles 2, 3: the steady loop, to the trapezoids' error at 40 increments a cycle
    assert per_cycle[1:] == pytest.approx(exact, rel=0.01)
    assert per_cycle[0] < per_cycle[1]              # the first loading starts from zero
    elastic = bench.cycle_dissipation(*_history(lambda d: k * d))
    assert np.abs(elastic).max() <= 1e-12 * exact
