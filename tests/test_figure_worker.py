"""Figures drawn by the command line's worker processes (:mod:`slipcycle.cli.figure_worker`)
are the figures drawn in the process, and the staged write of
:func:`slipcycle.io.results.write_outputs` holds with them: a figure that fails leaves no
result and no staging directory, and the error is the one raised in the worker."""

from __future__ import annotations

import errno
import functools
import os
import signal
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from slipcycle.examples import example_text
from slipcycle.io import CaseError, write_outputs

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="figure workers are forked, on Linux only")


@pytest.fixture(scope="module")
def sphere_outputs():
    import slipcycle

    text = example_text("halfspace_sphere").replace("steps_per_cycle = 400",
                                                    "steps_per_cycle = 60")
    return slipcycle.run(text).to_outputs()


@pytest.fixture
def worker(monkeypatch):
    """A started worker, whatever the number of CPUs of the machine running the tests."""
    from slipcycle.cli import figure_worker

    monkeypatch.setattr(figure_worker, "_safe_to_fork", lambda: True)
    w = figure_worker.FigureWorker.start()
    assert w is not None
    yield w
    w.close()


def _pixels(directory: Path) -> dict[str, np.ndarray]:
    from PIL import Image

    return {p.name: np.asarray(Image.open(p)) for p in sorted(directory.glob("*.png"))}


def _raise(exc: BaseException):
    raise exc


def test_worker_draws_the_same_figure_files_as_the_process_itself(tmp_path, sphere_outputs,
                                                                   worker):
    write_outputs(tmp_path / "here", sphere_outputs)
    write_outputs(tmp_path / "workers", sphere_outputs, draw=worker.draw)
    assert worker._sent   # handed over, not drawn here
    here = _pixels(tmp_path / "here" / "figures")
    there = _pixels(tmp_path / "workers" / "figures")
    assert sorted(here) == sorted(f"{n}.png" for n in sphere_outputs.figures)
    assert sorted(there) == sorted(here)
    for name in here:
        np.testing.assert_array_equal(there[name], here[name], err_msg=name)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["here", "workers"]


def test_figure_that_fails_in_a_worker_raises_its_error_and_leaves_no_result(
        tmp_path, sphere_outputs, worker):
    figures = dict(sphere_outputs.figures)
    figures["broken"] = functools.partial(_raise, ValueError("no such variable"))
    outputs = type(sphere_outputs)(summary=sphere_outputs.summary,
                                   dataset=sphere_outputs.dataset, figures=figures)
    with pytest.raises(ValueError, match="no such variable") as info:
        write_outputs(tmp_path / "out", outputs, draw=worker.draw)
    assert "Traceback" in str(info.value.__cause__)   # the worker's, for a bug report
    assert list(tmp_path.iterdir()) == []


def test_file_system_error_in_a_worker_is_a_user_error_naming_the_output(
        tmp_path, sphere_outputs, worker):
    figures = {"full": functools.partial(
        _raise, OSError(errno.ENOSPC, "No space left on device"))}
    outputs = type(sphere_outputs)(summary=sphere_outputs.summary, figures=figures)
    with pytest.raises(CaseError, match="No space left on device") as info:
        write_outputs(tmp_path / "out", outputs, draw=worker.draw)
    assert str(tmp_path / "out") in str(info.value)
    assert list(tmp_path.iterdir()) == []


def test_failure_beside_the_figures_stops_the_workers_and_leaves_no_result(
        tmp_path, sphere_outputs, worker):
    def failing_report(path):
        raise OSError(errno.EIO, "Input/output error")

    outputs = type(sphere_outputs)(summary=sphere_outputs.summary,
                                   dataset=sphere_outputs.dataset,
                                   figures=sphere_outputs.figures,
                                   extra_files={"report.txt": failing_report})
    (tmp_path / "out").mkdir()
    earlier = '{"metadata": {"slipcycle_version": "0"}}\n'   # an earlier result
    (tmp_path / "out" / "summary.json").write_text(earlier)
    with pytest.raises(CaseError, match="Input/output error"):
        write_outputs(tmp_path / "out", outputs, draw=worker.draw)
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["summary.json"]
    assert (tmp_path / "out" / "summary.json").read_text() == earlier


def test_figures_that_cannot_be_pickled_are_drawn_in_the_process(tmp_path, sphere_outputs,
                                                                 worker):
    make = sphere_outputs.figures["hysteresis"]
    outputs = type(sphere_outputs)(summary=sphere_outputs.summary,
                                   figures={"hysteresis": lambda: make()})
    write_outputs(tmp_path / "out", outputs, draw=worker.draw)
    assert [p.name for p in (tmp_path / "out" / "figures").iterdir()] == ["hysteresis.png"]


def test_half_space_figures_can_be_handed_to_another_process(sphere_outputs):
    import pickle

    figures = pickle.loads(pickle.dumps(sphere_outputs.figures))
    assert sorted(figures) == sorted(sphere_outputs.figures)


def test_interrupt_while_workers_draw_stops_them_and_leaves_no_result(tmp_path, sphere_outputs,
                                                                      worker):
    def interrupted(path):
        raise KeyboardInterrupt

    outputs = type(sphere_outputs)(summary=sphere_outputs.summary,
                                   figures=sphere_outputs.figures,
                                   extra_files={"report.txt": interrupted})
    with pytest.raises(KeyboardInterrupt):
        write_outputs(tmp_path / "out", outputs, draw=worker.draw)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ChildProcessError):   # the worker was stopped and reaped
        os.waitpid(worker._pid, os.WNOHANG)


def test_interrupt_during_the_netcdf_write_is_raised_once_the_file_is_complete():
    """xarray's writer cannot be interrupted safely (its HDF5 lock stays held): Ctrl-C is
    held back for the duration of the write, then raised."""
    from slipcycle.io.results import _interrupt_deferred

    done = []
    with pytest.raises(KeyboardInterrupt):
        with _interrupt_deferred():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
            done.append(True)
    assert done == [True]


#: one small case of every model that ``slipcycle run`` solves: example, text replacements
#: and dotted overrides that keep it quick (the figures, not the numbers, are under test)
MODEL_CASES = {
    "halfspace": ("halfspace_sphere", {"steps_per_cycle = 400": "steps_per_cycle = 60"}, {}),
    "discrete": ("discrete_two_node", {"steps_per_cycle = 400": "steps_per_cycle = 60"}, {}),
    "discrete3d": ("discrete3d_three_node", {"steps_per_cycle = 100": "steps_per_cycle = 40"},
                   {}),
    "rods": ("rods_microslip", {}, {}),
    "fe": ("fe_block_nu03", {"steps_per_cycle = 400": "steps_per_cycle = 40"}, {}),
    # the demo's coarse joint, one protocol
    "lap_joint": ("bolted_lap_joint", {}, {"lap_joint.protocols.names": ["simultaneous"]}),
}


def _model_outputs(model: str):
    import tomllib

    import slipcycle
    from slipcycle.api import apply_overrides, toml_text
    from slipcycle.demo import LAP_JOINT_DEMO

    example, replace, overrides = MODEL_CASES[model]
    text = example_text(example)
    for old, new in replace.items():
        assert old in text, (example, old)
        text = text.replace(old, new)
    if model == "lap_joint":
        text = toml_text(apply_overrides(tomllib.loads(text), {**LAP_JOINT_DEMO, **overrides}))
    outputs = slipcycle.run(text).to_outputs()
    assert tomllib.loads(text)["model"] == model
    return outputs


def test_every_model_that_run_solves_is_covered_here():
    from slipcycle.registry import RUN_MODELS

    assert sorted(MODEL_CASES) == sorted(RUN_MODELS)


@pytest.mark.parametrize("model", sorted(MODEL_CASES))
def test_worker_draws_every_models_figures_and_they_match_the_serial_ones(tmp_path, model,
                                                                           worker):
    import pickle

    outputs = _model_outputs(model)
    assert outputs.figures, model
    # the figures travel to the worker pickled (a plot function named with its data)
    pickle.dumps(outputs.figures)
    write_outputs(tmp_path / "here", outputs)
    write_outputs(tmp_path / "workers", outputs, draw=worker.draw)
    assert worker._sent, f"{model}: figures drawn in the process, not by the worker"
    here = _pixels(tmp_path / "here" / "figures")
    there = _pixels(tmp_path / "workers" / "figures")
    assert sorted(here) == sorted(f"{n}.png" for n in outputs.figures)
    assert sorted(there) == sorted(here)
    for name in here:
        np.testing.assert_array_equal(there[name], here[name], err_msg=f"{model}: {name}")
