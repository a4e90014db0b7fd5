"""Benchmarks of issue 4: a 201 × 201 basin map of a 2-node system (target < 10 s on the
2-core reference machine) and a 41-value λ sweep of a 200-node system with 8 initial
conditions each (case's monotonic assembly + 7 random admissible slips), on local
processes versus one process. Both go through the Zarr sweep machinery end to end.

The λ sweep groups the 8 starts of one λ into one task (``group_by=("lam",)``), as
``slipcycle shakedown`` does: the 7 random starts of a λ need 24 LPs (≈ 1.2 s for
N = 200, a third of the sweep's work), cached per process, so without grouping every
worker process recomputed them for nearly every λ. ``worker start-up`` is the extra time
of a task in a freshly spawned worker (imports, case validation with f_crit, Numba cache
loading) over the same task in a warm process; every local worker pays it once. Local
workers are forks of a fork server that imported the task's module and initialised Numba
(``slipcycle.sweep.core.pool_context``), so a worker pays only the case validation and the
loading of its kernels from Numba's disk cache; the server's start is paid once per process.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
EXAMPLE = HERE.parent / "src" / "slipcycle" / "examples" / "shakedown_triangle.toml"


def basin_map(grid: int = 201) -> float:
    """Wall time [s] of the basins study of ``grid`` × ``grid`` starts (``slipcycle basins
    --grid``: admissible box, runs, Zarr store, safe region, result), one process."""
    from slipcycle.io import read_case
    from slipcycle.studies.basins import basins_study

    case = read_case(EXAMPLE)
    with tempfile.TemporaryDirectory() as tmp:
        # warm the compiled kernels (cached on disk after the first run)
        basins_study(case, Path(tmp) / "warm", grid=4, workers=1, progress=False)
        t0 = time.perf_counter()
        status = basins_study(case, Path(tmp) / "map", grid=grid, workers=1, progress=False)
        wall = time.perf_counter() - t0
        assert status.complete
    return wall


def _lam_case(tmp: Path, n: int) -> tuple[str, str]:
    """The 200-node FE-like case of bench_discrete as a case file in ``tmp``."""
    sys.path.insert(0, str(HERE))
    from bench_discrete import case as fe_case

    system, load = fe_case(n)
    np.savez(tmp / "k.npz", A=system.A, B=system.B, C=system.C)
    fmt = lambda a: "[" + ", ".join(f"{x:.17g}" for x in a) + "]"  # noqa: E731
    text = f"""model = "discrete"
[discrete]
stiffness_file = "k.npz"
friction = 0.3
[loading]
lam = 1.0
p0 = {fmt(load.p.mean)}
q0 = {fmt(load.q.mean)}
p1 = {fmt(load.p.amplitudes[0])}
q1 = {fmt(load.q.amplitudes[0])}
q1_phase = {fmt(load.q.phases[0])}
[run]
cycles = 40
steps_per_cycle = 100
"""
    (tmp / "case.toml").write_text(text)
    return text, str(tmp / "case.toml")


def lam_sweep(workers: int, n: int = 200, lams: int = 41, starts: int = 8,
              group: bool = True) -> float:
    from slipcycle.studies.basins import lam_start_task
    from slipcycle.sweep import Axis, run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        text, path = _lam_case(Path(tmp), n)
        fn = partial(lam_start_task, case_text=text, case_path=path, n_random=starts - 1,
                     seed=0)
        axes = [Axis("lam", tuple(np.linspace(0.2, 2.2, lams).tolist())),
                Axis("start", tuple(range(starts)))]
        t0 = time.perf_counter()
        st = run_sweep(fn, axes, Path(tmp) / f"s{workers}.zarr", workers=workers,
                       progress=False, group_by=("lam",) if group else None)
        wall = time.perf_counter() - t0
        assert st.done().all()
    return wall


def worker_startup(n: int = 200) -> tuple[float, float]:
    """Extra wall time of one λ-sweep task in a fresh local worker over a warm process:
    (first pool of a process, which starts the fork server that imports the task's module
    and initialises Numba; a later pool, whose workers are forks of that server)."""
    from slipcycle.studies.basins import lam_start_task
    from slipcycle.sweep.core import _local_pool

    params = {"lam": 0.2, "start": 0}
    with tempfile.TemporaryDirectory() as tmp:
        text, path = _lam_case(Path(tmp), n)
        fn = partial(lam_start_task, case_text=text, case_path=path, n_random=0, seed=0)
        fn(params)                                  # warm this process
        t0 = time.perf_counter()
        fn(params)
        warm = time.perf_counter() - t0
        cold = []
        for _ in range(2):
            with _local_pool(1, fn) as pool:
                t0 = time.perf_counter()
                pool.submit(fn, params).result()
                cold.append(time.perf_counter() - t0)
    return cold[0] - warm, cold[1] - warm


def benchmarks() -> list[dict]:
    rows = []
    t = basin_map()
    rows.append({"name": "basin map 201x201, N=2 (basins study, numba threads, 1 process)",
                 "value": t, "unit": "s", "target": "< 10", "ok": t < 10})
    cores = os.cpu_count() or 1
    first, ts = worker_startup()
    t1 = lam_sweep(1)
    tp = lam_sweep(cores)
    rows.append({"name": "lambda sweep worker start-up (forked worker: case, kernels)",
                 "value": ts, "unit": "s", "target": "< 1", "ok": ts < 1})
    rows.append({"name": "lambda sweep worker start-up, first pool (fork server start)",
                 "value": first, "unit": "s"})
    rows.append({"name": "lambda sweep 41x8, N=200, 1 process", "value": t1, "unit": "s"})
    rows.append({"name": f"lambda sweep 41x8, N=200, {cores} local processes", "value": tp,
                 "unit": "s"})
    efficiency = t1 / tp / cores
    rows.append({"name": "lambda sweep speed-up", "value": t1 / tp, "unit": "x",
                 "target": f"~{cores}"})
    rows.append({"name": f"lambda sweep parallel efficiency ({cores} processes)",
                 "value": efficiency, "unit": "1", "target": ">= 0.9",
                 "ok": efficiency >= 0.9})
    return rows


if __name__ == "__main__":  # pragma: no cover
    for r in benchmarks():
        print(r)
