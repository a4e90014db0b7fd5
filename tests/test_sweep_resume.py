"""Sweeps: interruption + resume, local processes and Dask give identical stores (issue 4)."""

from __future__ import annotations

import json
import operator
from functools import partial
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from slipcycle.studies.case_sweep import apply_overrides, make_task, parse_set
from slipcycle.sweep import Axis, SweepError, run_sweep
from slipcycle.sweep.core import TaskRunner, parse_values, worker_threads

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
CASE = EXAMPLES / "shakedown_triangle.toml"


def small_text():
    return CASE.read_text().replace("cycles = 60", "cycles = 20").replace(
        "steps_per_cycle = 100", "steps_per_cycle = 30")


AXES = [Axis("loading.lam", (0.5, 1.0, 1.3)), Axis("discrete.friction", (0.45, 0.5))]


def flaky(params, inner, fail_on):
    """Raise on one cell (simulates a worker dying midway)."""
    if params == fail_on:
        raise RuntimeError("worker failure")
    return inner(params)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    path = tmp_path_factory.mktemp("ref") / "s.zarr"
    st = run_sweep(make_task(small_text(), CASE), AXES, path, description={"t": 1},
                   workers=1, progress=False)
    return st.read()


def _same(a, b):
    assert set(a) == set(b)
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_reference_is_complete(reference):
    assert reference["steady_state"].shape == (3, 2)
    assert reference["dissipation_per_node"].shape == (3, 2, 2)
    assert np.all(np.isfinite(reference["dissipation_per_cycle"]))
    # more load, more dissipation (f fixed)
    d = reference["dissipation_per_cycle"]
    assert np.all(d[2] >= d[0])


def test_stopped_then_resumed_on_processes_is_identical(tmp_path, reference):
    path = tmp_path / "s.zarr"
    st = run_sweep(make_task(small_text(), CASE), AXES, path, description={"t": 1},
                   workers=1, progress=False, stop_after=2)
    assert st.done().sum() == 2
    with pytest.raises(SweepError, match="--resume"):
        run_sweep(make_task(small_text(), CASE), AXES, path, description={"t": 1},
                  workers=1, progress=False)
    with pytest.raises(SweepError, match="different sweep"):
        run_sweep(make_task(small_text(), CASE), AXES, path, description={"t": 2},
                  resume=True, workers=1, progress=False)
    st = run_sweep(make_task(small_text(), CASE), AXES, path, description={"t": 1},
                   resume=True, workers=2, progress=False)
    assert st.done().all()
    _same(st.read(), reference)


def test_worker_failure_keeps_finished_cells_and_resume_completes(tmp_path, reference):
    path = tmp_path / "s.zarr"
    task = make_task(small_text(), CASE)
    bad = partial(flaky, inner=task, fail_on={"loading.lam": 1.0, "discrete.friction": 0.5})
    with pytest.raises(RuntimeError, match="worker failure"):
        run_sweep(bad, AXES, path, description={"t": 1}, workers=2, progress=False)
    from slipcycle.sweep.core import SweepStore

    st = SweepStore(path, AXES, "")
    st.group = __import__("zarr").open_group(str(path), mode="r")
    done = st.done()
    assert 0 < done.sum() < done.size and not done[1, 1]
    st = run_sweep(task, AXES, path, description={"t": 1}, resume=True, workers=1,
                   progress=False)
    _same(st.read(), reference)


def slow_first_then_fail(params, inner, fail_on):
    """The grid's first cell is slow; ``fail_on`` fails at once: after the second cell
    finished but before the first one did, so before the store exists."""
    import time

    if params == fail_on:
        raise RuntimeError("worker failure")
    if params == {a.name: a.values[0] for a in AXES}:
        time.sleep(2.0)
    return inner(params)


def test_failure_before_the_store_exists_keeps_finished_cells(tmp_path, reference):
    """The store is created from the first cell's result; a task failing before that
    still leaves the cells that finished (first cell included) for --resume."""
    from slipcycle.sweep.core import SweepStore

    path = tmp_path / "s.zarr"
    task = make_task(small_text(), CASE)
    bad = partial(slow_first_then_fail, inner=task,
                  fail_on={"loading.lam": 1.0, "discrete.friction": 0.45})
    with pytest.raises(RuntimeError, match="worker failure"):
        run_sweep(bad, AXES, path, description={"t": 1}, workers=2, progress=False)
    st = SweepStore(path, AXES, "")
    st.group = __import__("zarr").open_group(str(path), mode="r")
    done = st.done()
    assert done[0, 0] and done[0, 1] and not done[1, 0]
    st = run_sweep(task, AXES, path, description={"t": 1}, resume=True, workers=1,
                   progress=False)
    _same(st.read(), reference)


def test_dask_cluster_gives_identical_results(tmp_path, reference):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        st = run_sweep(make_task(small_text(), CASE), AXES, tmp_path / "d.zarr",
                       description={"t": 1}, scheduler=cluster.scheduler_address,
                       progress=False)
        _same(st.read(), reference)
        st = run_sweep(make_task(small_text(), CASE), AXES, tmp_path / "g.zarr",
                       description={"t": 1}, scheduler=cluster.scheduler_address,
                       progress=False, group_by=("discrete.friction",))
        _same(st.read(), reference)
        with TaskRunner(scheduler=cluster.scheduler_address) as runner:
            assert runner.map(operator.itemgetter("x"), [{"x": 3}, {"x": 4}]) == [3, 4]


def test_grouped_tasks_stop_resume_and_processes_are_identical(tmp_path, reference):
    """Cells sharing a λ form one task (one worker, one Zarr write per output); results
    do not depend on grouping, interruption or the number of processes."""
    task = make_task(small_text(), CASE)
    path = tmp_path / "g.zarr"
    st = run_sweep(task, AXES, path, description={"t": 1}, workers=1, progress=False,
                   stop_after=3, group_by=("loading.lam",))
    assert st.done().sum() == 3 and st.done()[0].all() and st.done()[1].sum() == 1
    st = run_sweep(task, AXES, path, description={"t": 1}, workers=2, progress=False,
                   resume=True, group_by=("loading.lam",))
    _same(st.read(), reference)
    with pytest.raises(SweepError, match="group_by"):
        run_sweep(task, AXES, tmp_path / "x.zarr", workers=1, progress=False,
                  group_by=("nosuch",))
    with TaskRunner(workers=2) as runner:          # a pool kept across calls, in order
        get = operator.itemgetter("x")
        assert runner.map(get, [{"x": i} for i in range(5)]) == [0, 1, 2, 3, 4]
        assert runner.map(get, [{"x": 7}, {"x": 8}]) == [7, 8]
    assert worker_threads(2) >= 1 and worker_threads(10**6) == 1


def test_parse_values_and_overrides():
    assert parse_values("1:2:3", "k") == [1.0, 1.5, 2.0]
    assert parse_values("1:3:3", "k") == [1, 2, 3]
    assert parse_values("0.1, 2, true", "k") == [0.1, 2, True]
    for bad in ("1:2", "a,b", "1:2:0", "nan"):
        with pytest.raises(SweepError, match="--set k"):
            parse_values(bad, "k")
    axes = parse_set(["loading.p1[1]=0:1:2", "run.cycles=3,4"])
    assert [a.name for a in axes] == ["loading.p1[1]", "run.cycles"]
    data = {"loading": {"p1": [0.1, 0.2]}, "run": {}}
    new = apply_overrides(data, {"loading.p1[1]": 0.5, "run.cycles": 3})
    assert new["loading"]["p1"] == [0.1, 0.5] and new["run"]["cycles"] == 3
    assert data["loading"]["p1"] == [0.1, 0.2]
    with pytest.raises(SweepError):
        parse_set(["loading.lam"])
    with pytest.raises(SweepError):
        parse_set(["loading.lam=1:2:3", "loading.lam=1,2"])


def test_sweep_command_resume_and_errors(run_cli, tmp_path, write_case):
    case = write_case(small_text())
    a, b = tmp_path / "a", tmp_path / "b"
    args = ("sweep", case, "--set", "loading.lam=0.8:1.2:3", "--workers", "1",
            "--no-progress")
    code, out, err = run_cli(*args, "--out", a, "--stop-after", "2")
    assert code == 0, err
    assert "--resume" in out and not (a / "summary.json").exists()
    code, out, err = run_cli(*args, "--out", a, "--resume")
    assert code == 0, err
    code, out, err = run_cli(*args, "--out", b)
    assert code == 0, err
    with xr.open_dataset(a / "result.nc") as da, xr.open_dataset(b / "result.nc") as db:
        xr.testing.assert_identical(da.drop_attrs(), db.drop_attrs())
        assert da["dissipation_per_cycle"].dims == ("loading_lam",)
    s = json.loads((a / "summary.json").read_text())
    assert s["runs"] == 3 and "dissipation_per_cycle" in s
    # refused before any computation, naming the key
    code, _, err = run_cli("sweep", case, "--set", "loading.lam=1:2", "--out", tmp_path / "c")
    assert code == 2 and "--set loading.lam" in err
    code, _, err = run_cli("sweep", case, "--set", "discrete.friction=-1,0.5", "--out",
                           tmp_path / "c")
    assert code == 2 and "discrete.friction" in err
    code, _, err = run_cli("sweep", case, "--set", "nosuch.key=1,2", "--out", tmp_path / "c")
    assert code == 2 and "nosuch" in err
    code, _, err = run_cli("sweep", case, "--set", "loading.typo=1,2", "--out", tmp_path / "c")
    assert code == 2 and "loading.typo" in err
    code, _, err = run_cli(*args, "--out", b)
    assert code == 2 and "--resume" in err
