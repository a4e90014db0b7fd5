"""The protocol runs of a lap-joint study side by side in worker processes.

Each protocol run is a function of its joint, protocol and settings only, so running the
runs in worker processes (``workers`` > 1, ``slipcycle run --workers``, by default every
core on the command line) must give the numbers of one process: the same dissipation,
classes, bolt forces and cycle states, in the order of the protocols. An error of a run
reaches the caller as itself, and the run settings made in Python are checked as the
case files' are.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from test_lap_joint_study import FAST, synthetic_joint

import slipcycle
from slipcycle.api import takes_workers
from slipcycle.cli.main import main
from slipcycle.coupled.settings import RunSettings
from slipcycle.discrete3d.evolution import IncrementalSolverError
from slipcycle.errors import CaseError, InadmissibleInitialState, InputError, ModelError
from slipcycle.examples import example_path
from slipcycle.joints.lap_joint_study import (
    STANDARD_PROTOCOLS,
    StudySettings,
    joint_system,
    lap_joint_study,
    protocol_runs,
    standard_protocol,
)

PROTOCOLS = [standard_protocol(n, 3) for n in STANDARD_PROTOCOLS]
SETTINGS = StudySettings(preload=1e4, service_amplitude=1500.0, friction=0.3,
                         run={**FAST, "cycles": 8})


def _study(workers):
    calls = []
    res = lap_joint_study([synthetic_joint(4), synthetic_joint(6)], PROTOCOLS, SETTINGS,
                          fields=(), workers=workers,
                          progress=lambda done, total: calls.append((done, total)))
    return res, calls


def test_protocol_runs_in_two_workers_give_the_numbers_of_one_process():
    one, calls_one = _study(1)
    two, calls_two = _study(2)
    total = 2 * len(PROTOCOLS)
    expected = [(k, total) for k in range(1, total + 1)]
    assert calls_one == expected and calls_two == expected
    assert one.mesh.dissipation.shape == (2, len(PROTOCOLS))
    # the same arithmetic in another process: equal far below any tolerance of the engine
    np.testing.assert_allclose(two.mesh.dissipation, one.mesh.dissipation, rtol=1e-12,
                               atol=0.0)
    assert two.mesh.steady_state.tolist() == one.mesh.steady_state.tolist()
    assert [r.solution.cycles_run for r in two.runs] == [r.solution.cycles_run
                                                         for r in one.runs]
    for a, b in zip(one.runs, two.runs, strict=True):
        np.testing.assert_allclose(b.solution.cycle_start_states,
                                   a.solution.cycle_start_states, rtol=0.0,
                                   atol=1e-12 * np.max(np.abs(a.solution.cycle_start_states)))
    for a, b in zip(one.bolt_forces, two.bolt_forces, strict=True):
        np.testing.assert_allclose(b.assembled, a.assembled, rtol=1e-12)
        np.testing.assert_allclose(b.cycle, a.cycle, rtol=1e-12)


def test_an_error_of_a_run_in_a_worker_reaches_the_caller_as_itself():
    """A run that fails in a worker raises what it raises in this process (an error with
    its key), not a pickling error or a broken pool."""
    joint = synthetic_joint(4)
    system = joint_system(joint, SETTINGS)
    # a five-bolt order on the three-bolt joint: refused by the run's assembly
    task = (joint, standard_protocol("sequential", 5), SETTINGS, (), system)
    messages = []
    for workers in (1, 2):
        with pytest.raises(InputError) as err:
            protocol_runs([task, task], workers)
        assert err.value.key == "protocols"
        messages.append(str(err.value))
    assert messages[0] == messages[1]


def test_study_settings_check_the_run_values_before_any_run():
    with pytest.raises(InputError) as err:
        StudySettings(preload=1e4, service_amplitude=1500.0, friction=0.3,
                      run={**FAST, "step_tol": 0.0})
    assert err.value.key == "run.step_tol"


@pytest.mark.parametrize("workers", [0, -1, 1.5, True, "2"])
def test_workers_must_be_a_whole_number_of_at_least_one(workers):
    with pytest.raises(InputError, match="workers"):
        protocol_runs([], workers)


@pytest.mark.parametrize("error", [
    InputError("lap_joint.preload", "must be positive"),
    CaseError("run.cycles", "must be >= 1"),
    ModelError("friction", "ill posed", remedy=("accept_ill_posed", True, "run anyway")),
    InadmissibleInitialState(3, -0.5, "slips outside the cone", separated=True),
    IncrementalSolverError("no Newton solution"),
])
def test_errors_survive_the_trip_from_a_worker_process(error):
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is type(error)
    assert str(back) == str(error)
    assert back.__dict__ == error.__dict__


@pytest.mark.parametrize(("key", "value"), [
    ("cycles", 0), ("cycles", 2.5), ("steps_per_cycle", -3), ("min_cycles", True),
    ("tol", -1e-3), ("tol", float("inf")), ("tol", float("nan")), ("step_tol", 0.0),
    ("step_tol", "1e-4"),
    ("replay", "yes"),
])
def test_run_settings_made_in_python_are_checked_like_the_case_files(key, value):
    with pytest.raises(InputError) as err:
        RunSettings(**{key: value})
    assert err.value.key == f"run.{key}"


def test_only_the_lap_joint_model_takes_workers():
    assert takes_workers("lap_joint")
    assert not takes_workers("discrete3d")
    assert not takes_workers("halfspace")


def test_run_refuses_workers_for_a_model_of_one_simulation(tmp_path, capsys):
    case = example_path("discrete3d_three_node.toml")
    code = main(["run", str(case), "--out", str(tmp_path / "out"), "--workers", "2", "-q"])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "--workers" in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("value", ["0", "two"])
def test_run_refuses_a_worker_count_that_is_not_a_whole_number(value, tmp_path, capsys):
    case = example_path("lap_joint_assembly.toml")
    with pytest.raises(SystemExit) as ex:
        main(["run", str(case), "--out", str(tmp_path / "out"), "--workers", value])
    err = capsys.readouterr().err.strip()
    assert ex.value.code == 2
    assert len(err.splitlines()) == 1 and "--workers" in err, err
    assert not (tmp_path / "out").exists()


def test_python_run_passes_workers_to_the_lap_joint_study_only():
    """slipcycle.run's ``workers`` reaches the protocol runs of a lap_joint case and is
    ignored by a model of one simulation (its numbers unchanged)."""
    plain = slipcycle.run(example_path("discrete3d_three_node.toml"))
    given = slipcycle.run(example_path("discrete3d_three_node.toml"), workers=2)
    assert given.dissipation_per_cycle == plain.dissipation_per_cycle
