"""A long discrete run reports its progress: one call per cycle, through slipcycle.run."""

from __future__ import annotations

from conftest import case_text

import slipcycle


def test_discrete_run_reports_each_cycle_through_slipcycle_run():
    calls = []
    res = slipcycle.run(case_text("discrete_two_node"),
                        progress=lambda done, total: calls.append((done, total)))
    assert calls, "no progress reported"
    assert [d for d, _ in calls] == list(range(1, len(calls) + 1))
    assert all(total == calls[0][1] for _, total in calls)
    assert len(calls) == res.cycles_run
