"""One vocabulary: the run settings and result fields have the same names in every model.

Every case file bounds its cycling by ``run.cycles`` (the most cycles run) and tests the
steady state with ``run.steady_tol``; discrete cases still read the older name
``run.tolerance`` (same numbers), refuse both at once in one line, and every result object
answers the shared fields ``steady_state``, ``dissipation_per_cycle``, ``cycles_run``,
``residual``, ``converged`` and ``message``.
"""

from __future__ import annotations

import math

import pytest
from conftest import case_text

import slipcycle
from slipcycle.io.case import CaseError
from slipcycle.result import RunResult, SteadyState

SHARED_FIELDS = ("steady_state", "dissipation_per_cycle", "cycles_run", "residual",
                 "converged", "message")


@pytest.mark.parametrize("name", ["halfspace_sphere", "discrete_two_node"])
def test_every_model_reads_cycles_and_steady_tol(name):
    res = slipcycle.run(case_text(name, run={"cycles": 7, "steady_tol": 1e-7}))
    assert isinstance(res, RunResult)
    assert res.cycles_run <= 7


def test_discrete_steady_tol_and_its_older_name_give_the_same_numbers():
    new = slipcycle.run(case_text("discrete_two_node", run={"steady_tol": 1e-9}))
    old = slipcycle.run(case_text("discrete_two_node", run={"tolerance": 1e-9}))
    assert new.dissipation_per_cycle == old.dissipation_per_cycle
    assert new.cycles_run == old.cycles_run
    assert new.steady_state == old.steady_state


def test_discrete_refuses_both_names_of_the_tolerance_in_one_line():
    with pytest.raises(CaseError) as err:
        slipcycle.run(case_text("discrete_two_node",
                                run={"steady_tol": 1e-9, "tolerance": 1e-9}))
    assert err.value.key == "run.tolerance"
    assert "steady_tol" in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("name", ["halfspace_sphere", "discrete_two_node", "rods_spec"])
def test_every_result_answers_the_shared_fields(name):
    res = slipcycle.run(case_text(name) if name != "rods_spec"
                        else case_text(name, run={"cycles": 30, "steps_per_cycle": 64}))
    for field in SHARED_FIELDS:
        assert hasattr(res, field), field
    assert isinstance(res.steady_state, SteadyState)
    assert isinstance(res.converged, bool)
    assert isinstance(res.cycles_run, int) and res.cycles_run >= 1
    d = res.dissipation_per_cycle
    assert d is None or (math.isfinite(d) and d >= 0.0)
    summary = res.summary()
    assert summary["steady_state_class"] == res.steady_state.value
    assert "units" in summary
