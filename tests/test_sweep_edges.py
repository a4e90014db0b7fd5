"""Sweeps at their edges: Ctrl-C on a pool, cells of different sizes, failing cells,
duplicate values and the workers' verbosity ("Nothing lost")."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from slipcycle.studies import case_sweep
from slipcycle.studies.case_sweep import make_task, run_case_sweep
from slipcycle.sweep import Axis, run_sweep
from slipcycle.sweep.core import SweepInterrupted, SweepStore

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
FAILED = 5      # code of "failed" in every store (slipcycle.result.STEADY_STATES)


def small_case() -> str:
    return ((EXAMPLES / "discrete_two_node.toml").read_text()
            .replace("cycles = 40  ", "cycles = 8  ")
            .replace("steps_per_cycle = 400", "steps_per_cycle = 60"))


def fe_case() -> str:
    """A four-element block whose every run warns that mesh convergence is not assessed."""
    return """model = "fe"
[fe]
geometry = "block_on_rigid"
width = 0.04
height = 0.02
E = 210e9
nu = 0.3
elements = 4
thickness = 0.01
[fe.discrete]
friction = 0.5
cycles = 10
steps_per_cycle = 40
[fe.discrete.mean]
normal = 2.0e-6
[fe.discrete.amplitude]
tangential = 3e-6
[fe.convergence]
refinements = [1]
"""


def read_store(path: Path) -> tuple[dict, np.ndarray]:
    import zarr

    st = SweepStore(path, [], "")
    st.group = zarr.open_group(str(path), mode="r")
    st.shape = st.group["done"].shape
    return st.read(), st.done()


def same_arrays(a: dict, b: dict) -> None:
    assert set(a) == set(b)
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


# -- Ctrl-C on a pool of workers ------------------------------------------------------------

def interrupting(params, inner, parent, marks, at):
    """Run the cell; the first cell to finish after ``at - 1`` others sends Ctrl-C to the
    sweep instead of returning at once. A cell that finished before leaves a mark (its λ)
    as it returns."""
    out = inner(params)
    done = [n for n in os.listdir(marks) if n != "interrupter"]
    if len(done) >= at - 1:
        try:
            os.close(os.open(os.path.join(marks, "interrupter"), os.O_CREAT | os.O_EXCL))
        except FileExistsError:
            return out              # finished after the interrupt: not required
        os.kill(parent, signal.SIGINT)
        time.sleep(0.5)             # the sweep stops before this cell returns
        return out
    Path(marks, f"{params['loading.lam']!r}").touch()
    return out


GRID = [Axis("loading.lam", tuple(np.round(np.linspace(0.6, 1.0, 12), 6).tolist()))]


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="SIGINT reaches the main thread")
def test_interrupted_pool_sweep_stores_every_finished_cell_and_resumes_identically(tmp_path):
    task = make_task(small_case(), None)
    ref = run_sweep(task, GRID, tmp_path / "ref.zarr", workers=1, progress=False).read()
    marks = tmp_path / "marks"
    marks.mkdir()
    path = tmp_path / "s.zarr"
    stopping = partial(interrupting, inner=task, parent=os.getpid(), marks=str(marks), at=5)
    with pytest.raises(SweepInterrupted) as info:
        run_sweep(stopping, GRID, path, workers=2, progress=False)
    finished = [float(p.name) for p in marks.iterdir() if p.name != "interrupter"]
    assert len(finished) >= 4
    data, done = read_store(path)
    lams = list(GRID[0].values)
    assert all(done[lams.index(lam)] for lam in finished), (finished, done)
    assert info.value.done == done.sum() < done.size
    st = run_sweep(task, GRID, path, workers=2, progress=False, resume=True)
    same_arrays(st.read(), ref)


def test_ctrl_c_ends_a_pool_sweep_at_once_with_one_line_saying_how_to_resume(write_case,
                                                                            tmp_path):
    psutil = pytest.importorskip("psutil")
    case = write_case(small_case().replace("steps_per_cycle = 60", "steps_per_cycle = 2000"))
    out = tmp_path / "o"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    # a session of its own: Ctrl-C at a terminal reaches every process of the group
    proc = subprocess.Popen([sys.executable, "-m", "slipcycle.cli.main", "sweep", str(case),
                             "--set", "loading.lam=0.6:1.0:40", "--out", str(out),
                             "--workers", "2", "--no-progress"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env,
                            start_new_session=True, text=True)
    done = out / "sweep.zarr" / "done" / "c"
    try:
        end = time.monotonic() + 60
        while time.monotonic() < end and proc.poll() is None and not (
                done.exists() and sum(1 for p in done.rglob("*") if p.is_file()) >= 2):
            time.sleep(0.05)
        assert proc.poll() is None, proc.stderr.read()
        workers = psutil.Process(proc.pid).children(recursive=True)
        os.killpg(proc.pid, signal.SIGINT)
        t0 = time.monotonic()
        _, err = proc.communicate(timeout=20)
        assert time.monotonic() - t0 < 10
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("interrupted:") and "--resume" in lines[0]
    gone = psutil.wait_procs(workers, timeout=5)[1]
    assert not gone, f"still running: {[p.pid for p in gone]}"


# -- outputs whose size depends on the cell -------------------------------------------------

def vector_of(params):
    """A cell whose vector output has as many entries as its ``n``."""
    n = int(params["n"])
    return {"v": np.arange(1.0, n + 1), "k": np.arange(n), "total": float(n)}


def test_vectors_of_different_sizes_are_padded_to_the_longest(tmp_path):
    axes = [Axis("n", (3, 5, 2))]
    st = run_sweep(vector_of, axes, tmp_path / "a.zarr", workers=1, progress=False)
    data = st.read()
    assert data["v"].shape == (3, 5)
    np.testing.assert_array_equal(data["v"][0], [1, 2, 3, np.nan, np.nan])
    np.testing.assert_array_equal(data["v"][2], [1, 2, np.nan, np.nan, np.nan])
    np.testing.assert_array_equal(data["k"][1], [0, 1, 2, 3, 4])
    np.testing.assert_array_equal(data["k"][2], [0, 1, -1, -1, -1])
    # stopped after the short first cell, resumed: the same store
    part = tmp_path / "b.zarr"
    run_sweep(vector_of, axes, part, workers=1, progress=False, stop_after=1)
    st = run_sweep(vector_of, axes, part, workers=2, progress=False, resume=True)
    same_arrays(st.read(), data)


def test_sweep_over_the_mesh_size_pads_the_nodes_with_nan(run_cli, write_case, tmp_path):
    import xarray as xr

    code, _, err = run_cli("sweep", write_case(fe_case()), "--set", "fe.elements=2,3",
                           "--out", tmp_path / "o", "--workers", "1", "--no-progress", "-q")
    assert code == 0, err
    with xr.open_dataset(tmp_path / "o" / "result.nc") as ds:
        d = ds["dissipation_per_node"].values
    assert d.shape == (2, 7)
    assert np.isnan(d[0, 5:]).all() and np.isfinite(d[0, :5]).all()
    assert np.isfinite(d[1]).all()


# -- failing cells --------------------------------------------------------------------------

def test_a_failing_run_is_stored_as_failed_and_the_sweep_goes_on(run_cli, write_case,
                                                                 tmp_path, monkeypatch):
    from slipcycle.errors import SolverError

    real = case_sweep.run

    def run(case):
        if case.data["loading"]["lam"] == 0.8:
            raise SolverError("no solution of the rate problem at step 3")
        return real(case)

    monkeypatch.setattr(case_sweep, "run", run)      # the cells run in this process
    out = tmp_path / "o"
    code, stdout, err = run_cli("sweep", write_case(small_case()), "--set",
                                "loading.lam=0.7,0.8,0.9", "--out", out, "--workers", "1",
                                "--no-progress")
    assert code == 0, err
    assert "1 of 3 runs failed" in err and "no solution of the rate problem" in err
    s = json.loads((out / "summary.json").read_text())
    assert s["failed_runs"] == 1
    assert "no solution of the rate problem" in s["first_failure"]
    assert "loading.lam = 0.8" in s["first_failure"]
    data, done = read_store(out / "sweep.zarr")
    assert done.all()
    assert data["steady_state_class"][1] == FAILED
    assert data["steady_state_class"][0] != FAILED and data["steady_state_class"][2] != FAILED
    assert np.isnan(data["dissipation_per_cycle"][1])
    assert np.isfinite(data["dissipation_per_cycle"][[0, 2]]).all()
    assert "no solution" in data["error"][1] and data["error"][0] == ""


def test_a_first_cell_that_fails_does_not_lose_the_outputs_of_the_others(tmp_path,
                                                                         monkeypatch):
    from slipcycle.errors import CaseError
    from slipcycle.io.case import parse_case_text

    real = case_sweep.run

    def run(case):
        if case.data["loading"]["lam"] == 0.7:
            raise CaseError("loading.lam", "too small for this run")
        return real(case)

    monkeypatch.setattr(case_sweep, "run", run)
    case = parse_case_text(small_case())
    status = run_case_sweep(case, ["loading.lam=0.7,0.9"], tmp_path, workers=1,
                            progress=False)
    data = status.outputs.dataset
    assert int(data["steady_state_class"][0]) == FAILED
    assert np.isfinite(float(data["dissipation_per_cycle"][1]))
    assert status.outputs.summary["failed_runs"] == 1


# -- refused values, verbosity ----------------------------------------------------------------

@pytest.mark.parametrize("spec", ["loading.lam=0.5,1.0,1.0", "loading.lam=1:1:3",
                                  "loading.lam=1,1.0"])
def test_duplicate_values_of_an_axis_are_refused_naming_the_key(spec, run_cli, write_case,
                                                                tmp_path):
    out = tmp_path / "o"
    code, _, err = run_cli("sweep", write_case(small_case()), "--set", spec, "--out", out,
                           "--workers", "1", "--no-progress")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith("error: --set loading.lam:") and "more than once" in err
    assert not out.exists()


def test_quiet_silences_the_pool_workers_too(run_cli, write_case, tmp_path):
    case = write_case(fe_case())
    # the case warns once per run (checked in this process)
    code, _, err = run_cli("sweep", case, "--set", "fe.elements=4", "--out", tmp_path / "a",
                           "--workers", "1", "--no-progress")
    assert code == 0 and err.count("slipcycle: mesh convergence") == 1, err
    env = {**os.environ, "MPLBACKEND": "Agg"}
    quiet = subprocess.run([sys.executable, "-m", "slipcycle.cli.main", "sweep", str(case),
                            "--set", "fe.discrete.friction=0.4,0.5", "--workers", "2",
                            "--no-progress", "--out", str(tmp_path / "b"), "-q"],
                           capture_output=True, text=True, env=env, timeout=300)
    assert quiet.returncode == 0, quiet.stderr
    assert quiet.stderr == "" and quiet.stdout == ""
