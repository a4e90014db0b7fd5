"""Resumable parallel parameter sweeps stored in Zarr (one cell per run).

A sweep is the Cartesian product of named axes. Every grid cell is computed by a task
function ``fn(params) -> dict`` (``params`` maps axis names to the cell's values) that
returns numbers or fixed-shape numeric arrays. Results go into a Zarr group:

- one array per output, shape ``grid_shape + cell_shape``, chunked one cell per chunk, so
  every finished run is written on its own as soon as it returns;
- a ``done`` boolean array (one chunk per cell), set *after* the cell's outputs are
  written, so a cell is either complete or absent;
- attributes: the axes, the output schema and a fingerprint of the sweep (the task's
  description), which ``resume`` checks before re-using a store.

:func:`run_sweep` computes the missing cells (all of them for a new store) on

- one process (``workers=1``),
- a local process pool (default, ``workers`` processes), or
- an existing Dask cluster (``scheduler="tcp://host:port"`` or a ``distributed.Client``),

with a tqdm progress bar (ETA). Only the calling process writes to the store. If a task
raises, the cells already finished stay stored and the error propagates; ``resume=True``
later computes only what is missing, giving results identical to an uninterrupted sweep.

Performance notes (measured on the 2-core reference machine, ``benchmarks/
bench_shakedown.py``): a spawned worker pays its imports, case validation and Numba cache
loading once (≈ 2 s for a 200-node discrete case); each local worker gets
``cores // workers`` Numba threads so that ``prange`` kernels do not oversubscribe the
cores; ``group_by`` sends cells that share per-process cached set-up (the random starts of
one λ: 24 LPs) to one worker as one task, so the set-up is done once per group rather
than once per worker; a group that fills a box of the grid is written with one Zarr call
per output (≈ 2 ms per chunk). :class:`TaskRunner` keeps a pool alive across the steps of
a sequential algorithm (the λ3/λ4 bisection of ``slipcycle shakedown``).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
from collections.abc import Callable, Mapping
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Axis", "SweepStore", "run_sweep", "SweepError", "fingerprint", "TaskRunner",
           "run_group", "worker_threads"]


class SweepError(ValueError):
    """An invalid sweep request (``key`` names the offending option or key)."""

    def __init__(self, key: str, problem: str):
        self.key = key
        self.problem = problem
        super().__init__(f"{key}: {problem}")


@dataclass(frozen=True)
class Axis:
    """One sweep axis: a name (e.g. ``loading.lam``) and its values (K,)."""

    name: str
    values: tuple

    @property
    def size(self) -> int:
        return len(self.values)


def fingerprint(obj) -> str:
    """A stable hash of a JSON-serialisable description of the sweep."""
    text = json.dumps(obj, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _to_jsonable(v):
    if isinstance(v, np.generic):
        return v.item()
    return v


class SweepStore:
    """The Zarr group of one sweep.

    Parameters
    ----------
    path : str or Path
        Directory of the Zarr store.
    axes : list of Axis
    fingerprint : str
        Identifies the computation; a store with another fingerprint is not resumed.
    """

    def __init__(self, path, axes: list[Axis], fingerprint: str):
        import zarr

        self.path = Path(path)
        self.axes = list(axes)
        self.fp = fingerprint
        self.shape = tuple(a.size for a in self.axes)
        self._zarr = zarr
        self.group = None

    # -- creation / opening ---------------------------------------------------------------
    def exists(self) -> bool:
        return (self.path / "zarr.json").exists() or (self.path / ".zgroup").exists()

    def open_existing(self) -> None:
        """Open for resuming; checks axes and fingerprint."""
        g = self._zarr.open_group(str(self.path), mode="a")
        attrs = dict(g.attrs)
        if attrs.get("fingerprint") != self.fp:
            raise SweepError("--resume", f"the store {self.path} holds a different sweep "
                             "(case, --set values or settings changed); use a new --store")
        self.group = g

    def create(self, schema: Mapping[str, tuple], attrs: Mapping | None = None) -> None:
        """Create the arrays: ``schema`` maps output name to (cell_shape, dtype)."""
        g = self._zarr.open_group(str(self.path), mode="w")
        nd = len(self.shape)
        for name, (cshape, dtype) in schema.items():
            cshape = tuple(cshape)
            dtype = np.dtype(dtype)
            fill = np.nan if dtype.kind == "f" else (False if dtype.kind == "b" else -1)
            self._create(g, name, self.shape + cshape, (1,) * nd + (cshape or ()), dtype, fill)
        self._create(g, "done", self.shape, (1,) * nd, np.dtype(bool), False)
        for a in self.axes:
            vals = np.asarray(a.values)
            if vals.dtype.kind in "fiub":
                self._create(g, f"axis_{a.name}", vals.shape, vals.shape, vals.dtype, 0)
                g[f"axis_{a.name}"][...] = vals
        g.attrs.update({
            "fingerprint": self.fp,
            "axes": [[a.name, [_to_jsonable(v) for v in a.values]] for a in self.axes],
            "schema": {k: [list(v[0]), np.dtype(v[1]).str] for k, v in schema.items()},
            **(dict(attrs) if attrs else {}),
        })
        self.group = g

    @staticmethod
    def _create(g, name, shape, chunks, dtype, fill):
        if hasattr(g, "create_array"):
            g.create_array(name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill,
                           overwrite=True)
        else:  # pragma: no cover - zarr 2
            g.create_dataset(name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill,
                             overwrite=True)

    # -- cells ------------------------------------------------------------------------------
    @property
    def schema(self) -> dict:
        return {k: (tuple(v[0]), np.dtype(v[1])) for k, v in self.group.attrs["schema"].items()}

    def done(self) -> np.ndarray:
        return np.asarray(self.group["done"][...], bool)

    def write(self, index: tuple, result: Mapping) -> None:
        """Write one cell's outputs, then mark it done."""
        for name, (cshape, dtype) in self.schema.items():
            if name not in result:
                continue
            self._write_one(name, index, result[name], cshape, dtype)
        self.group["done"][index] = True

    def write_many(self, indices: list[tuple], results: list) -> None:
        """Write several cells' outputs, then mark them done.

        Cells that fill a box of the grid (e.g. every start of one λ) are written with one
        Zarr call per output; others cell by cell.
        """
        if len(indices) == 1:
            self.write(indices[0], results[0])
            return
        idx = np.array(indices)
        lo, hi = idx.min(axis=0), idx.max(axis=0)
        box = tuple(int(h - l + 1) for l, h in zip(lo, hi, strict=True))
        if len({tuple(i) for i in indices}) != len(indices) or \
                int(np.prod(box)) != len(indices):
            for i, r in zip(indices, results, strict=True):
                self.write(i, r)
            return
        sel = tuple(slice(int(l), int(h) + 1) for l, h in zip(lo, hi, strict=True))
        pos = tuple((idx - lo).T)
        for name, (cshape, dtype) in self.schema.items():
            if not all(name in r for r in results):
                for i, r in zip(indices, results, strict=True):
                    if name in r:
                        self._write_one(name, i, r[name], cshape, dtype)
                continue
            block = np.empty(box + cshape, dtype)
            for k, r in enumerate(results):
                block[tuple(p[k] for p in pos)] = _checked(name, indices[k], r[name], cshape,
                                                           dtype)
            self.group[name][sel] = block
        self.group["done"][sel] = np.ones(box, bool)

    def _write_one(self, name, index, value, cshape, dtype):
        self.group[name][index] = _checked(name, index, value, cshape, dtype)

    def read(self) -> dict:
        """All outputs as NumPy arrays (missing cells hold the fill value)."""
        return {name: np.asarray(self.group[name][...]) for name in self.schema}


def _checked(name, index, value, cshape, dtype) -> np.ndarray:
    """One cell's output ``name`` as ``dtype``, refused if its shape is not ``cshape``."""
    val = np.asarray(value)
    if val.shape != cshape:
        raise ValueError(f"output {name!r} of cell {index}: shape {val.shape}, "
                         f"expected {cshape}")
    return val.astype(dtype)


def _cells(shape):
    return list(itertools.product(*(range(s) for s in shape)))


def _params(axes, index):
    return {a.name: a.values[i] for a, i in zip(axes, index, strict=True)}


def _schema_of(result: Mapping) -> dict:
    schema = {}
    for k, v in result.items():
        arr = np.asarray(v)
        if arr.dtype.kind not in "biuf":
            raise TypeError(f"sweep output {k!r} must be numeric, got {arr.dtype}")
        dtype = np.float64 if arr.dtype.kind == "f" else (
            np.bool_ if arr.dtype.kind == "b" else np.int64)
        schema[k] = (arr.shape, dtype)
    return schema


def _progress(total, enabled, desc):
    from tqdm import tqdm

    return tqdm(total=total, disable=not enabled, desc=desc, unit="run", smoothing=0.1,
                dynamic_ncols=True)


def _groups(todo: list[tuple], axes: list[Axis], group_by) -> list[list[tuple]]:
    """Split cells into tasks: one cell each, or all cells sharing the ``group_by`` axes'
    values (in grid order, groups ordered by their first cell)."""
    if not group_by:
        return [[c] for c in todo]
    if isinstance(group_by, str):
        group_by = (group_by,)
    names = [a.name for a in axes]
    unknown = [g for g in group_by if g not in names]
    if unknown:
        raise SweepError("group_by", f"unknown axes {unknown}; the axes are {names}")
    dims = [names.index(g) for g in group_by]
    groups: dict[tuple, list[tuple]] = {}
    for c in todo:
        groups.setdefault(tuple(c[d] for d in dims), []).append(c)
    return list(groups.values())


def run_group(fn: Callable[[dict], Mapping], params: list[dict]) -> list:
    """Run ``fn`` on several parameter sets in order, in one process (one sweep task)."""
    return [fn(p) for p in params]


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity where known)."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def worker_threads(workers: int) -> int:
    """Numba threads per local worker process: the cores shared out, at least 1."""
    return max(1, usable_cores() // max(1, workers))


def _worker_init(threads: int) -> None:
    """Initializer of local worker processes: cap Numba's threads so that ``workers``
    processes × threads do not oversubscribe the cores (``prange`` kernels)."""
    import numba

    numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))


class _Writer:
    """Writes finished tasks into the store; creates a new store from the first cell's
    result (grid order, so the schema does not depend on which task finishes first) and
    buffers earlier-finishing tasks until then."""

    def __init__(self, store: SweepStore, first: tuple | None, create, bar):
        self.store = store
        self.first = first
        self.create = create
        self.bar = bar
        self.buffer: list[tuple[list, list]] = []

    @property
    def ready(self) -> bool:
        return self.store.group is not None

    def put(self, indices: list[tuple], results: list) -> None:
        if not self.ready:
            if self.first not in indices:
                self.buffer.append((indices, results))
                return
            self.create(results[indices.index(self.first)])
            self.store.write_many(indices, results)
            self.bar.update(len(indices))
            for idx, res in self.buffer:
                self.store.write_many(idx, res)
                self.bar.update(len(idx))
            self.buffer.clear()
            return
        self.store.write_many(indices, results)
        self.bar.update(len(indices))


def run_sweep(fn: Callable[[dict], Mapping], axes: list[Axis], store_path, *,
              description: Mapping | None = None, resume: bool = False,
              workers: int | None = None, scheduler=None, progress: bool = True,
              stop_after: int | None = None, attrs: Mapping | None = None,
              desc: str = "sweep", group_by: tuple[str, ...] | None = None,
              runner: TaskRunner | None = None) -> SweepStore:
    """Compute every missing cell of a sweep into a Zarr store.

    Parameters
    ----------
    fn : callable
        ``fn(params) -> dict`` of numeric outputs; must be picklable (a module-level
        function or a ``functools.partial`` of one) for process pools and Dask.
    axes : list of Axis
    store_path : str or Path
        Zarr directory. An existing store is refused unless ``resume``.
    description : mapping
        JSON-serialisable description of the computation (fingerprinted).
    resume : bool
        Re-use an existing store of the same sweep; compute only its missing cells.
    workers : int, optional
        Local processes (default ``os.cpu_count()``); 1 runs in this process. Each local
        worker gets ``cores // workers`` Numba threads (:func:`worker_threads`).
    scheduler : str or distributed.Client, optional
        Address of an existing Dask scheduler (or a client): run the tasks there.
    progress : bool
        Show a tqdm progress bar with ETA on stderr.
    stop_after : int, optional
        Stop after this many cells were computed in this call (to test interruption).
    group_by : tuple of str, optional
        Axis names: the missing cells that share these axes' values form one task, run in
        order in one worker process and written together (one Zarr call per output). Use
        it when cells share expensive set-up that a task caches per process (e.g. the
        random starts of one λ); without it every cell is a task.
    runner : TaskRunner, optional
        Run on this runner's local pool or Dask client (kept alive for later work, e.g. a
        refinement after the sweep); ``workers`` and ``scheduler`` are then its own.

    Returns
    -------
    SweepStore

    Notes
    -----
    A new store is created from the result of the grid's first cell, whichever process
    computes it, so its outputs do not depend on the order in which tasks finish; the
    main process only writes. Results do not depend on ``workers``, ``scheduler`` or
    ``group_by``: every cell is computed by the same call ``fn(params)``.
    """
    if runner is not None:
        workers, scheduler = runner.workers, runner.scheduler
    fp = fingerprint({"description": description or {},
                      "axes": [[a.name, [_to_jsonable(v) for v in a.values]] for a in axes]})
    store = SweepStore(store_path, axes, fp)
    cells = _cells(store.shape)
    if store.exists():
        if not resume:
            raise SweepError("--store", f"{store.path} already exists; pass --resume to "
                             "complete it or choose another directory")
        store.open_existing()
        done = store.done()
        todo = [c for c in cells if not done[c]]
        first = None
    else:
        if store.path.exists() and any(store.path.iterdir()):
            raise SweepError("--store", f"{store.path} exists and is not a sweep store")
        todo = cells
        first = cells[0]
    todo_run = todo if stop_after is None else todo[:max(int(first is not None), stop_after)]
    tasks = _groups(todo_run, axes, group_by)
    meta = {**(dict(attrs) if attrs else {}),
            "description": json.loads(json.dumps(description or {}, default=str))}
    bar = _progress(len(cells), progress, desc)
    bar.update(len(cells) - len(todo))
    writer = _Writer(store, first, lambda res0: store.create(_schema_of(res0), meta), bar)
    try:
        if not tasks:
            return store
        nproc = workers or os.cpu_count() or 1
        if scheduler is not None:
            _run_dask(fn, axes, tasks, runner.client() if runner else scheduler, writer)
        elif nproc <= 1 or len(tasks) == 1:
            for task in tasks:
                writer.put(task, run_group(fn, [_params(axes, i) for i in task]))
        elif runner is not None:
            _run_pool(fn, axes, tasks, nproc, writer, runner.pool())
        else:
            with _local_pool(min(nproc, len(tasks))) as pool:
                _run_pool(fn, axes, tasks, min(nproc, len(tasks)), writer, pool)
    finally:
        bar.close()
    return store


def _local_pool(workers: int):
    """A ``spawn`` process pool whose workers share out the cores' Numba threads."""
    import multiprocessing as mp

    # "spawn" avoids forking a process that holds Numba/Dask threads
    return ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"),
                               initializer=_worker_init,
                               initargs=(worker_threads(workers),))


def _run_pool(fn, axes, tasks, workers, writer, pool):
    max_inflight = 4 * workers
    it = iter(tasks)
    pending, task_of = {}, {}
    first_fut = None

    def submit(task):
        nonlocal first_fut
        fut = pool.submit(run_group, fn, [_params(axes, i) for i in task])
        pending[fut] = task_of[fut] = task
        if writer.first in task:
            first_fut = fut

    try:
        for task in itertools.islice(it, max_inflight):
            submit(task)
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                task = pending.pop(fut)
                writer.put(task, fut.result())
                nxt = next(it, None)
                if nxt is not None:
                    submit(nxt)
    except BaseException as exc:
        for fut in pending:
            if fut is not first_fut:
                fut.cancel()
        if not isinstance(exc, KeyboardInterrupt):
            _salvage(writer, first_fut, task_of)
        raise


def _salvage(writer, first_fut, task_of):
    """After a failure, before the store exists: wait for the task of the grid's first
    cell (submitted first, so already running) to create the store and keep the tasks
    that did finish. Nothing is kept if that task failed too."""
    if writer.ready or not writer.buffer or first_fut is None:
        return
    try:
        res = first_fut.result()
    except BaseException:  # noqa: BLE001 - the first cell failed too: nothing to keep
        return
    writer.put(task_of[first_fut], res)


def _run_dask(fn, axes, tasks, scheduler, writer):
    from distributed import Client, as_completed

    own = not hasattr(scheduler, "submit")      # an address: connect, and close after
    client = Client(scheduler) if own else scheduler
    try:
        futures = {}
        first_fut = None
        for task in tasks:
            fut = client.submit(run_group, fn, [_params(axes, i) for i in task], pure=False)
            futures[fut] = task
            if writer.first in task:
                first_fut = fut
        try:
            for fut in as_completed(list(futures)):
                writer.put(futures[fut], fut.result())
        except BaseException as exc:
            client.cancel([f for f in futures if f is not first_fut])
            if not isinstance(exc, KeyboardInterrupt):
                _salvage(writer, first_fut, futures)
            raise
    finally:
        if own:
            client.close()


class TaskRunner:
    """Runs batches of independent tasks, keeping local worker processes (or a Dask
    client) alive between batches: for sequential algorithms whose steps are parallel,
    such as the bisection of λ3/λ4 brackets.

    ``workers``/``scheduler`` as for :func:`run_sweep`. Use as a context manager;
    :meth:`map` returns results in the order of its inputs.
    """

    def __init__(self, workers: int | None = None, scheduler=None):
        self.workers = workers or os.cpu_count() or 1
        self.scheduler = scheduler
        self._pool = None
        self._client = None
        self._own_client = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None
        if self._client is not None and self._own_client:
            self._client.close()
        self._client = None

    def client(self):
        """The Dask client (connected on first use)."""
        if self._client is None:
            from distributed import Client

            self._own_client = not hasattr(self.scheduler, "submit")
            self._client = Client(self.scheduler) if self._own_client else self.scheduler
        return self._client

    def pool(self) -> ProcessPoolExecutor:
        """The local process pool (started on first use)."""
        if self._pool is None:
            self._pool = _local_pool(self.workers)
        return self._pool

    def map(self, fn: Callable[[dict], Mapping], params: list[dict]) -> list:
        """``[fn(p) for p in params]``, computed in parallel where configured."""
        if not params:
            return []
        if self.scheduler is not None:
            client = self.client()
            futs = [client.submit(fn, p, pure=False) for p in params]
            try:
                return client.gather(futs)
            except BaseException:
                client.cancel(futs)
                raise
        if self.workers <= 1 or len(params) == 1:
            return [fn(p) for p in params]
        futs = [self.pool().submit(fn, p) for p in params]
        try:
            return [f.result() for f in futs]
        except BaseException:
            for f in futs:
                f.cancel()
            raise


def parse_values(spec: str, key: str) -> list:
    """Values of ``--set key=SPEC``: ``start:stop:num`` (inclusive linspace) or ``a,b,c``.

    Integers stay integers when every value is integral and written without a point.
    """
    spec = spec.strip()
    try:
        if ":" in spec:
            parts = spec.split(":")
            if len(parts) != 3:
                raise ValueError
            start, stop = float(parts[0]), float(parts[1])
            num = int(parts[2])
            if num < 1:
                raise SweepError(f"--set {key}", f"num must be >= 1, got {num}")
            vals = np.linspace(start, stop, num).tolist()
            if all("." not in p and "e" not in p.lower() for p in parts[:2]) and all(
                    float(v).is_integer() for v in vals):
                vals = [int(v) for v in vals]
        else:
            items = [s.strip() for s in spec.split(",") if s.strip()]
            if not items:
                raise ValueError
            vals = []
            for s in items:
                if s.lower() in ("true", "false"):
                    vals.append(s.lower() == "true")
                elif "." not in s and "e" not in s.lower() and s.lstrip("+-").isdigit():
                    vals.append(int(s))
                else:
                    vals.append(float(s))
    except SweepError:
        raise
    except ValueError:
        raise SweepError(f"--set {key}", f"values must be start:stop:num or a comma list of "
                         f"numbers, got {spec!r}") from None
    if any(isinstance(v, float) and not math.isfinite(v) for v in vals):
        raise SweepError(f"--set {key}", "values must be finite")
    return vals
