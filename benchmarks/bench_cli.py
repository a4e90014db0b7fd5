"""Start-up of the command line and of sweep workers.

- ``slipcycle --help``: no numerical stack is imported (median of 5 runs);
- ``slipcycle run`` of the half-space sphere example (400 steps per cycle, 3 cycles: a
  solve of about 50 ms), writing summary.json, result.nc and 5 figures: warm (median of 5
  runs after one that fills the caches) and cold, i.e. the first run after installation,
  with an empty Numba cache (a private ``NUMBA_CACHE_DIR`` per run, so the project's cache
  is left alone; median of 3). Wall time, and the CPU time (user + system) of the command
  and every process it started (the figure workers), from ``getrusage(RUSAGE_CHILDREN)``:
  on a loaded machine the wall time grows with the load, the CPU time much less;
- a sweep worker: from creating a local pool to the first (trivial) task done, once the
  fork server of this process runs (what every worker of a sweep costs), and for the first
  pool of a process (the server starts and imports the sweep engine and Numba once).

Each is a fresh process, timed from outside (``time.perf_counter`` around
``subprocess.run``).
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SPHERE = HERE.parent / "src" / "slipcycle" / "examples" / "halfspace_sphere.toml"
CLI = [sys.executable, "-m", "slipcycle.cli.main"]


def _cpu_children() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _time(argv, env=None, cwd=None) -> float:
    return _time_cpu(argv, env, cwd)[0]


def _time_cpu(argv, env=None, cwd=None) -> tuple[float, float]:
    """(wall, CPU) [s] of one command, CPU of every process it started and waited for."""
    c0, t0 = _cpu_children(), time.perf_counter()
    subprocess.run(argv, check=True, capture_output=True, env=env, cwd=cwd)
    return time.perf_counter() - t0, _cpu_children() - c0


def _medians(samples: list[tuple[float, float]]) -> tuple[float, float]:
    return (statistics.median(s[0] for s in samples),
            statistics.median(s[1] for s in samples))


def help_time(repeat: int = 5) -> float:
    return statistics.median(_time([*CLI, "--help"]) for _ in range(repeat))


def run_warm(repeat: int = 5) -> tuple[float, float]:
    """(wall, CPU) [s], medians of ``repeat`` runs once the caches are filled."""
    with tempfile.TemporaryDirectory() as tmp:
        _time([*CLI, "run", str(SPHERE), "--out", f"{tmp}/w", "-q"])     # fill caches
        return _medians([_time_cpu([*CLI, "run", str(SPHERE), "--out", f"{tmp}/o{i}", "-q"])
                         for i in range(repeat)])


def run_cold(repeat: int = 3) -> tuple[float, float]:
    """(wall, CPU) [s] of the first run after installation: no compiled kernel on disk
    (Numba compiles); medians of ``repeat`` runs, each with an empty cache."""
    samples = []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            env = {**os.environ, "NUMBA_CACHE_DIR": f"{tmp}/numba-cache"}
            samples.append(_time_cpu([*CLI, "run", str(SPHERE), "--out", f"{tmp}/o", "-q"],
                                     env=env))
    return _medians(samples)


_WORKER = """
import sys, time
from concurrent.futures import ProcessPoolExecutor
from slipcycle.sweep.core import _local_pool, run_group

def main():
    t0 = time.perf_counter()
    with _local_pool(1) as pool:
        pool.submit(run_group, abs, [-1]).result()
    first = time.perf_counter() - t0
    ready = []
    for _ in range(5):
        t0 = time.perf_counter()
        with _local_pool(2) as pool:
            list(pool.map(run_group, [abs, abs], [[-1], [-2]]))
        ready.append(time.perf_counter() - t0)
    ready.sort()
    print(first, ready[len(ready) // 2])

if __name__ == "__main__":
    main()
"""


def worker_ready() -> tuple[float, float]:
    """(first pool of a process, later pools) [s]: creating a local pool of workers and
    getting a trivial task back from each."""
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "workers.py"
        script.write_text(_WORKER)
        out = subprocess.run([sys.executable, str(script)], check=True, capture_output=True,
                             text=True).stdout.split()
    return float(out[0]), float(out[1])


def benchmarks() -> list[dict]:
    rows = []
    t = help_time()
    rows.append({"name": "slipcycle --help (median of 5)", "value": t, "unit": "s",
                 "target": "< 0.5", "ok": t < 0.5})
    t, cpu = run_warm()
    rows.append({"name": "slipcycle run sphere example, warm (median of 5)", "value": t,
                 "unit": "s", "target": "< 1.5", "ok": t < 1.5})
    rows.append({"name": "slipcycle run sphere example, warm: CPU, all processes",
                 "value": cpu, "unit": "s"})
    t, cpu = run_cold()
    rows.append({"name": "slipcycle run sphere example, cold (median of 3)",
                 "value": t, "unit": "s", "target": "< 15", "ok": t < 15})
    rows.append({"name": "slipcycle run sphere example, cold: CPU, all processes",
                 "value": cpu, "unit": "s"})
    first, ready = worker_ready()
    rows.append({"name": "sweep workers ready (2 workers, fork server running)",
                 "value": ready, "unit": "s", "target": "< 1", "ok": ready < 1})
    rows.append({"name": "sweep workers ready, first pool (fork server starts)",
                 "value": first, "unit": "s"})
    return rows


if __name__ == "__main__":  # pragma: no cover
    for r in benchmarks():
        print(r)
