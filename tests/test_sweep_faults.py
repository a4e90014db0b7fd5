"""Killed sweeps: no worker outlives its sweep, and ``--resume`` after kills at random
moments gives results bit-identical to an uninterrupted sweep, with no stray files or
processes (issue "Trustworthy outputs")."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

psutil = pytest.importorskip("psutil")
pytest.importorskip("zarr")

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="process bookkeeping through /proc")

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


def small_case(steps: int = 60) -> str:
    return ((EXAMPLES / "discrete_two_node.toml").read_text()
            .replace("cycles = 40  ", "cycles = 8  ")
            .replace("steps_per_cycle = 400", f"steps_per_cycle = {steps}"))


GRID = "loading.lam=0.6:1.0:40"


def start_sweep(case: Path, out: Path, *extra: str) -> subprocess.Popen:
    """``slipcycle sweep`` in a child process; its stderr goes to a file (a pipe closed
    by the test would kill orphaned workers on their next write and hide them)."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    with open(case.with_suffix(".log"), "a") as log:
        return subprocess.Popen([sys.executable, "-m", "slipcycle.cli.main", "sweep",
                                 str(case), "--set", GRID, "--out",
                                 str(out), "--no-progress", *extra],
                                stdout=subprocess.DEVNULL, stderr=log, env=env)


def descendants(pid: int) -> list:
    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


def alive(procs) -> list:
    out = []
    for p in procs:
        try:
            if p.is_running() and p.status() != psutil.STATUS_ZOMBIE:
                out.append(p)
        except psutil.NoSuchProcess:
            pass
    return out


def kill_all(procs) -> None:
    """Clean-up of the test itself: the processes it started, by pid."""
    for p in alive(procs):
        try:
            p.kill()
        except psutil.NoSuchProcess:
            pass


def wait_for(cond, timeout: float, step: float = 0.05) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(step)
    return cond()


def test_killing_the_sweep_kills_its_worker_processes(write_case, tmp_path):
    """SIGKILL to the main process of a sweep on two local workers: no worker survives
    it (they would wait on the task queue for ever)."""
    case = write_case(small_case(steps=400))
    proc = start_sweep(case, tmp_path / "o", "--workers", "2")
    seen = []
    try:
        assert wait_for(lambda: len(descendants(proc.pid)) >= 2 or proc.poll() is not None,
                        60), "no workers started"
        assert proc.poll() is None, case.with_suffix(".log").read_text()
        wait_for(lambda: (tmp_path / "o" / "sweep.zarr" / "zarr.json").exists(), 30)
        seen = descendants(proc.pid)
        assert proc.poll() is None and len(seen) >= 2
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        assert wait_for(lambda: not alive(seen), 5.0), \
            f"still running: {[p.pid for p in alive(seen)]}"
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        kill_all(seen)


def cells_done(store: Path) -> int:
    """Cells marked done (chunk files of the ``done`` array), read without Zarr."""
    d = store / "done" / "c"
    return sum(1 for p in d.rglob("*") if p.is_file() and "partial" not in p.name) \
        if d.exists() else 0


def _store_arrays(out: Path) -> dict:
    import zarr

    g = zarr.open_group(str(out / "sweep.zarr"), mode="r")
    return {k: np.asarray(g[k][...]) for k in g.attrs["schema"]} | {
        "done": np.asarray(g["done"][...])}


def test_resume_after_kills_at_random_moments_is_bit_identical(run_cli, write_case,
                                                               tmp_path):
    # cells of about 0.15 s (3000 load samples per cycle), so that a kill lands while
    # cells are being computed, not after the last one
    case = write_case(small_case(steps=3000))
    ref = tmp_path / "ref"
    code, _, err = run_cli("sweep", case, "--set", GRID, "--out", ref,
                           "--workers", "1", "--no-progress")
    assert code == 0, err
    out = tmp_path / "out"
    store = out / "sweep.zarr"
    rng = random.Random(20240607)
    started = []
    done_after_kill = []
    try:
        for k in range(3):
            extra = ("--resume",) if store.exists() else ()
            workers = ("--workers", "2" if k == 1 else "1")
            before = cells_done(store)
            proc = start_sweep(case, out, *workers, *extra)
            # the first kill at any moment (start-up included), the others while cells
            # are being computed and written (on two workers in the second run)
            if k:
                wait_for(lambda p=proc, n=before, pool=k == 1: cells_done(store) > n and (
                    len(descendants(p.pid)) >= 2 or not pool) or p.poll() is not None, 60)
            time.sleep(rng.uniform(0.0, 1.0) if k else rng.uniform(0.5, 4.0))
            started += descendants(proc.pid)
            proc.send_signal(signal.SIGKILL)
            proc.wait()
            done_after_kill.append(cells_done(store))
        extra = ("--resume",) if store.exists() else ()
        code, _, err = run_cli("sweep", case, "--set", GRID, "--out",
                               out, "--workers", "1", "--no-progress", *extra)
        assert code == 0, err
        wait_for(lambda: not alive(started), 5.0)
        survivors = [p.pid for p in alive(started)]
    finally:
        kill_all(started)
    assert not survivors, f"processes of killed sweeps still running: {survivors}"
    assert done_after_kill and any(0 < d < 40 for d in done_after_kill), done_after_kill
    a, b = _store_arrays(ref), _store_arrays(out)
    assert set(a) == set(b)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    with xr.open_dataset(ref / "result.nc") as da, xr.open_dataset(out / "result.nc") as db:
        xr.testing.assert_identical(da.drop_attrs(deep=False), db.drop_attrs(deep=False))
    # nothing stray: no lock, no temporary Zarr or staging files, no processes
    assert sorted(p.name for p in out.iterdir()) == ["result.nc", "summary.json",
                                                     "sweep.zarr"]
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []
    stray = [p for p in store.rglob("*") if p.name.startswith(".") or "partial" in p.name]
    assert not stray
