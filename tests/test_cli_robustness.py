"""The command line under faults: killed runs, stale staging folders, a base install.

- A ``slipcycle run`` killed at any moment leaves nothing that looks like a result, and the
  repeated run gives numbers bit-identical to an uninterrupted one, with no stray files.
- A base install (no optional extras) running a command that needs one names the extra.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from conftest import case_text

from slipcycle.cli.main import main
from slipcycle.io.results import remove_stale_partials

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
CLI = [sys.executable, "-m", "slipcycle.cli.main"]

SPHERE = case_text("halfspace_sphere", loading={"P1": 20.0, "Q0": None, "phase": 1.0},
                   run={"steps_per_cycle": 200})


def _numbers(out: Path) -> tuple[dict, dict]:
    """Summary without metadata, and every variable of result.nc."""
    summary = json.loads((out / "summary.json").read_text())
    summary.pop("metadata", None)
    summary = {k: v for k, v in summary.items() if "wall_time" not in k}
    with xr.open_dataset(out / "result.nc") as ds:
        arrays = {k: ds[k].values.copy() for k in ds.variables}
    return summary, arrays


def _assert_identical(a: Path, b: Path) -> None:
    sa, va = _numbers(a)
    sb, vb = _numbers(b)
    assert sa == sb
    assert va.keys() == vb.keys()
    for k in va:
        np.testing.assert_array_equal(va[k], vb[k], err_msg=k)
    assert sorted(p.name for p in (a / "figures").iterdir()) == \
        sorted(p.name for p in (b / "figures").iterdir())


def _stray(root: Path) -> list[str]:
    return [str(p) for p in root.rglob("*") if ".partial" in p.name or ".old-" in p.name]


@pytest.mark.slow
def test_run_killed_at_random_moments_then_repeated_gives_identical_results(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(SPHERE)
    ref = tmp_path / "ref"
    t0 = time.perf_counter()
    subprocess.run([*CLI, "run", str(case), "--out", str(ref), "--quiet"], check=True)
    duration = time.perf_counter() - t0
    rng = np.random.default_rng(20261123)
    out = tmp_path / "out"
    for delay in rng.uniform(0.2, 0.95, size=3) * duration:
        proc = subprocess.Popen([*CLI, "run", str(case), "--out", str(out), "--quiet"])
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        # killed before the final rename: no result at all; after it: a complete result
        if out.exists() and any(out.iterdir()):
            assert {p.name for p in out.iterdir() if not p.name.startswith(".")} == \
                {"summary.json", "result.nc", "figures"}
    subprocess.run([*CLI, "run", str(case), "--out", str(out), "--quiet"], check=True)
    _assert_identical(ref, out)
    assert _stray(tmp_path) == []


def test_stale_staging_folders_of_dead_processes_are_removed(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    dead_pid = int(dead.stdout)
    stale = tmp_path / f".out.partial-{dead_pid}-abc123"
    stale_old = out / f".figures.old-{dead_pid}"
    live = tmp_path / f".out.partial-{os.getpid()}-def456"
    for p in (stale, stale_old, live):
        (p / "figures").mkdir(parents=True)
    removed = remove_stale_partials(out)
    assert sorted(removed) == sorted([stale, stale_old])
    assert live.exists() and not stale.exists() and not stale_old.exists()


def test_run_after_a_killed_write_cleans_its_staging_folder(tmp_path, capsys):
    case = tmp_path / "case.toml"
    case.write_text(SPHERE.replace("steps_per_cycle = 200", "steps_per_cycle = 40"))
    stale = tmp_path / ".out.partial-999999999-zzz"
    (stale / "figures").mkdir(parents=True)
    assert main(["run", str(case), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    assert not stale.exists()
    assert _stray(tmp_path) == []


_BASE_INSTALL = textwrap.dedent("""
    import sys

    # behaves as an install without the optional extras: find_spec gives None, import fails
    for name in ("zarr", "dask", "distributed", "skfem", "meshio"):
        sys.modules[name] = None
    from slipcycle.cli.main import main
    sys.exit(main(sys.argv[1:]))
""")


def _base_install(args, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", _BASE_INSTALL, *args], cwd=cwd,
                          capture_output=True, text=True)


@pytest.mark.slow
def test_base_install_names_the_extra_a_command_needs_and_runs_the_rest(tmp_path):
    (tmp_path / "case.toml").write_text(SPHERE.replace("steps_per_cycle = 200",
                                                       "steps_per_cycle = 40"))
    (tmp_path / "fe.toml").write_text((EXAMPLES / "fe_cylinder.toml").read_text())
    sweep = _base_install(["sweep", "case.toml", "--set", "loading.Q1=10,20", "--out", "s",
                           "--no-progress"], tmp_path)
    assert sweep.returncode == 2, sweep.stderr
    assert "pip install 'slipcycle[sweep]'" in sweep.stderr
    assert len(sweep.stderr.strip().splitlines()) == 1 and "Traceback" not in sweep.stderr
    reduce = _base_install(["reduce", "fe.toml", "--out", "r.npz"], tmp_path)
    assert reduce.returncode == 2, reduce.stderr
    assert "pip install 'slipcycle[fe]'" in reduce.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml", "fe.toml"]
    run = _base_install(["run", "case.toml", "--out", "r", "--quiet"], tmp_path)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "r" / "summary.json").exists()


@pytest.mark.parametrize("example", ["halfspace_sphere.toml", "discrete_two_node.toml",
                                     "rods_spec.toml", "halfspace_rough_map.toml"])
def test_every_model_refuses_sizes_against_one_memory_budget(example, tmp_path, monkeypatch,
                                                             capsys):
    monkeypatch.setenv("SLIPCYCLE_MEMORY_LIMIT", "10kB")
    command = "map" if "map" in example else "run"
    code = main([command, str(EXAMPLES / example), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "of memory (limit 10 kB)" in err, err
    assert err.count("\n") == 1 and not (tmp_path / "out").exists()


@pytest.mark.parametrize(("text", "nbytes"), [("32GB", 32e9), ("500 MB", 5e8), ("2GiB", 2**31),
                                              ("5e9", 5e9), ("", 4e9)])
def test_memory_budget_reads_sizes_from_the_environment(text, nbytes, monkeypatch):
    from slipcycle.io.sizes import memory_limit

    monkeypatch.setenv("SLIPCYCLE_MEMORY_LIMIT", text)
    assert memory_limit() == nbytes


def test_malformed_memory_budget_is_one_line_naming_the_variable(tmp_path, monkeypatch,
                                                                 capsys):
    monkeypatch.setenv("SLIPCYCLE_MEMORY_LIMIT", "lots")
    code = main(["run", str(EXAMPLES / "halfspace_sphere.toml"), "--out",
                 str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: SLIPCYCLE_MEMORY_LIMIT: ")


def test_write_together_removes_temporaries_of_a_killed_writer_and_keeps_a_live_ones(tmp_path):
    from slipcycle.io.results import write_together

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    stale = tmp_path / f".r.npz.partial-{int(dead.stdout)}-x1"
    stale_old = tmp_path / f".r.npz.old-{int(dead.stdout)}-x2"
    live = tmp_path / f".r.npz.partial-{os.getpid()}-x3"
    for p in (stale, stale_old, live):
        p.write_text("half")
    write_together([(tmp_path / "r.npz", lambda p: p.write_text("done"))])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["r.npz", live.name])
    assert (tmp_path / "r.npz").read_text() == "done"
