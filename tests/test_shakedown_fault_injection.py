"""`slipcycle shakedown` killed (SIGKILL) at random moments and resumed gives the numbers
of an uninterrupted run, bit for bit, and leaves no stray files or processes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
CASE = EXAMPLES / "shakedown_triangle.toml"
# a small scan: 5 λ values × 3 starts, bisection to 5 % of lam_max
ARGS = ["--lam-points", "5", "--starts", "2", "--lam-tol", "0.05", "--workers", "1",
        "--no-progress"]
MAIN = "import sys; from slipcycle.cli.main import main; sys.exit(main())"
#: when each interrupted attempt is killed, as fractions of an uninterrupted run's duration
#: (seeded, spread over imports, the λ scan and the bisection); any two add up to less than
#: one, so the first two attempts are killed however fast or loaded the machine is
KILL_FRACTIONS = [float(t) for t in np.random.default_rng(7).uniform(0.1, 0.45, 4)]
#: entries that legitimately differ between runs (times, paths, provenance, work done)
VOLATILE = {"wall_time_s", "lp_wall_time_s", "metadata", "runs_computed", "checkpoint",
            "store"}


def _cmd(out: Path, resume: bool) -> list[str]:
    return [sys.executable, "-c", MAIN, "shakedown", str(CASE), "--out", str(out),
            *ARGS, *(["--resume"] if resume else [])]


def _numbers(obj):
    """The summary without volatile entries."""
    if isinstance(obj, dict):
        return {k: _numbers(v) for k, v in obj.items() if k not in VOLATILE}
    if isinstance(obj, list):
        return [_numbers(v) for v in obj]
    return obj


def _session_alive(sid: int) -> list[int]:
    """PIDs still running in session ``sid`` (the killed command and any children)."""
    out = subprocess.run(["ps", "-e", "-o", "pid=,sid=,stat="], capture_output=True,
                         text=True, check=True).stdout
    return [int(p) for p, s, st in (line.split()[:3] for line in out.splitlines())
            if int(s) == sid and not st.startswith("Z")]


def _strays(root: Path) -> list[str]:
    """Temporary or partial files and directories anywhere under ``root``."""
    bad = []
    for p in root.rglob("*"):
        name = p.name
        if ".partial" in name or name.startswith(".refine-") or ".old-" in name \
                or name.startswith("tmp"):
            bad.append(str(p.relative_to(root)))
    return bad


@pytest.mark.slow
def test_shakedown_killed_at_random_moments_then_resumed_is_bit_identical(tmp_path):
    ref = tmp_path / "ref"
    t_ref = time.monotonic()
    subprocess.run(_cmd(ref, False), check=True, capture_output=True, timeout=300)
    t_ref = time.monotonic() - t_ref
    out = tmp_path / "run"
    kills = 0
    for delay in (f * t_ref for f in KILL_FRACTIONS):
        # --resume continues a scan store; before there is one, start plainly
        proc = subprocess.Popen(_cmd(out, (out / "scan.zarr").exists()), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        t0 = time.monotonic()
        while proc.poll() is None and time.monotonic() - t0 < delay:
            time.sleep(0.05)
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
            kills += 1
        proc.wait(timeout=60)
        time.sleep(0.2)
        assert _session_alive(proc.pid) == [], "processes survived the killed command"
    assert kills >= 2, "the kill moments missed the run"
    # and once while the results are being written (the staging directory exists)
    proc = subprocess.Popen(_cmd(out, (out / "scan.zarr").exists()),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    while proc.poll() is None and not list(tmp_path.glob(".run.partial-*")):
        time.sleep(0.01)
    staged = proc.poll() is None
    proc.kill()
    proc.wait(timeout=60)
    assert staged, "the command ended before writing its results"
    done = subprocess.run(_cmd(out, (out / "scan.zarr").exists()), capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr

    a = json.loads((ref / "summary.json").read_text())
    b = json.loads((out / "summary.json").read_text())
    assert _numbers(a) == _numbers(b)
    assert a["units"]["dissipation_per_cycle"] == "J" and a["units"]["lambda1"] == "1"
    with xr.open_dataset(ref / "result.nc") as da, xr.open_dataset(out / "result.nc") as db:
        assert set(da.data_vars) == set(db.data_vars)
        for name in da.data_vars:
            np.testing.assert_array_equal(da[name].values, db[name].values, err_msg=name)
    assert _strays(tmp_path) == []
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in ref.iterdir())
