"""Sweeps refused up front: one line ``error: <option>: <problem>``, exit 2, nothing left
behind (issue "Trustworthy outputs")."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from slipcycle.sweep import core

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


def small_case() -> str:
    return ((EXAMPLES / "discrete_two_node.toml").read_text()
            .replace("cycles = 40  ", "cycles = 8  ")
            .replace("steps_per_cycle = 400", "steps_per_cycle = 60"))


def one_line_error(code, err, key):
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and re.match(rf"error: {re.escape(key)}[ :]", lines[0]), err
    assert "Traceback" not in err


def nothing_in(path: Path) -> bool:
    return not path.exists() and not list(path.parent.glob(f".{path.name}*"))


@pytest.mark.parametrize("value", ["0", "-3", "two"])
def test_workers_below_one_are_refused(value, run_cli, write_case, tmp_path):
    out = tmp_path / "o"
    code, _, err = run_cli("sweep", write_case(small_case()), "--set", "loading.lam=1,0.9",
                           "--out", out, "--workers", value, "--no-progress")
    one_line_error(code, err, "--workers")
    assert nothing_in(out)


def test_resume_without_a_store_is_refused(run_cli, write_case, tmp_path):
    out = tmp_path / "o"
    code, _, err = run_cli("sweep", write_case(small_case()), "--set", "loading.lam=1,0.9",
                           "--out", out, "--resume", "--workers", "1", "--no-progress")
    one_line_error(code, err, "--resume")
    assert nothing_in(out)


@pytest.mark.parametrize("sets", [["loading.lam=0:1:1000000000"],
                                  ["loading.lam=0:1:40000", "discrete.friction=0.1:0.5:25000"]])
def test_a_billion_cells_are_refused_before_any_work(sets, run_cli, write_case, tmp_path):
    out = tmp_path / "o"
    args = [a for s in sets for a in ("--set", s)]
    t0 = time.perf_counter()
    code, _, err = run_cli("sweep", write_case(small_case()), *args, "--out", out,
                           "--workers", "1", "--no-progress")
    assert time.perf_counter() - t0 < 5.0
    one_line_error(code, err, "--set")
    assert "1000000000 cells" in err and re.search(r"\d+(\.\d+)? [GT]B", err), err
    assert nothing_in(out)


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:9", "garbage", "tcp://no host:x"])
def test_unreachable_scheduler_fails_fast_naming_the_option(address, run_cli, write_case,
                                                            tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    assert core.SCHEDULER_TIMEOUT_S <= 10
    monkeypatch.setattr(core, "SCHEDULER_TIMEOUT_S", 1.0)   # the test's own patience
    out = tmp_path / "o"
    t0 = time.perf_counter()
    code, _, err = run_cli("sweep", write_case(small_case()), "--set", "loading.lam=1,0.9",
                           "--out", out, "--scheduler", address, "--no-progress")
    assert time.perf_counter() - t0 < 8.0
    one_line_error(code, err, "--scheduler")
    assert nothing_in(out)


def _options_of_sweep() -> set[str]:
    from slipcycle.cli.main import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if hasattr(a, "choices") and a.choices)
    return {o for a in sub.choices["sweep"]._actions for o in a.option_strings}


def test_messages_name_only_options_that_exist(run_cli, write_case, tmp_path):
    case = write_case(small_case())
    out = tmp_path / "o"
    base = ("sweep", case, "--out", out, "--workers", "1", "--no-progress")
    code, _, err = run_cli(*base, "--set", "loading.lam=1,0.9")
    assert code == 0, err
    errors = [run_cli(*base, "--set", "loading.lam=1,0.9")[2],             # exists
              run_cli(*base, "--set", "loading.lam=1,0.95", "--resume")[2]]  # another
    options = _options_of_sweep()
    for err in errors:
        assert err.startswith("error: ") and err.count("\n") == 1, err
        named = set(re.findall(r"--[a-z][a-z-]*", err))
        assert named and named <= options, (err, named - options)
    assert (out / "result.nc").exists()      # the finished sweep is untouched


def test_a_second_sweep_on_the_same_store_stops_at_once(run_cli, write_case, tmp_path):
    """Another process holds the store: a second sweep (resume or not) ends in one line
    naming the store, at once, and changes nothing in it."""
    case = write_case(small_case())
    out = tmp_path / "o"
    args = ("sweep", case, "--set", "loading.lam=0.8,0.9,1", "--out", out, "--workers", "1",
            "--no-progress")
    code, _, err = run_cli(*args, "--stop-after", "1")
    assert code == 0, err
    store = out / "sweep.zarr"
    before = {p: p.stat().st_mtime_ns for p in store.rglob("*")}
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time\n"
         "from slipcycle.sweep.core import lock_store\n"
         "with lock_store(sys.argv[1]):\n    print('locked', flush=True)\n    time.sleep(60)",
         str(store)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        for extra in (("--resume",), ()):
            t0 = time.perf_counter()
            code, _, err = run_cli(*args, *extra)
            assert time.perf_counter() - t0 < 3.0
            one_line_error(code, err, "--out")
            assert str(store) in err and "in use" in err and str(holder.pid) in err
        assert {p: p.stat().st_mtime_ns for p in store.rglob("*")
                if p.name != core.LOCK_NAME} == {p: t for p, t in before.items()
                                                 if p.name != core.LOCK_NAME}
    finally:
        holder.kill()
        holder.wait()
    code, _, err = run_cli(*args, "--resume")          # the lock died with its holder
    assert code == 0, err
    assert not (store / core.LOCK_NAME).exists()


def test_the_store_lock_is_released_and_removed_however_the_block_ends(tmp_path):
    store = tmp_path / "a" / "s.zarr"
    with pytest.raises(RuntimeError), core.lock_store(store):
        assert (store / core.LOCK_NAME).exists()
        with core.lock_store(store):                   # nested in one process
            pass
        assert (store / core.LOCK_NAME).exists()
        raise RuntimeError
    # no store was created in it: nothing is left, not even the parent it made
    assert not store.exists() and not store.parent.exists()
    assert os.listdir(tmp_path) == []


def test_foreign_content_at_the_store_path_is_refused_and_kept(run_cli, write_case,
                                                               tmp_path):
    out = tmp_path / "o"
    (out / "sweep.zarr").mkdir(parents=True)
    (out / "sweep.zarr" / "notes.txt").write_text("mine")
    code, _, err = run_cli("sweep", write_case(small_case()), "--set", "loading.lam=1,0.9",
                           "--out", out, "--workers", "1", "--no-progress")
    one_line_error(code, err, "--out")
    assert sorted(p.name for p in (out / "sweep.zarr").iterdir()) == ["notes.txt"]
