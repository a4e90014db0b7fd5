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

__all__ = ["Axis", "SweepStore", "run_sweep", "SweepError", "fingerprint"]


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
            val = np.asarray(result[name])
            if val.shape != cshape:
                raise ValueError(f"output {name!r} of cell {index}: shape {val.shape}, "
                                 f"expected {cshape}")
            self.group[name][index] = val.astype(dtype)
        self.group["done"][index] = True

    def read(self) -> dict:
        """All outputs as NumPy arrays (missing cells hold the fill value)."""
        return {name: np.asarray(self.group[name][...]) for name in self.schema}


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


def run_sweep(fn: Callable[[dict], Mapping], axes: list[Axis], store_path, *,
              description: Mapping | None = None, resume: bool = False,
              workers: int | None = None, scheduler=None, progress: bool = True,
              stop_after: int | None = None, attrs: Mapping | None = None,
              desc: str = "sweep") -> SweepStore:
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
        Local processes (default ``os.cpu_count()``); 1 runs in this process.
    scheduler : str or distributed.Client, optional
        Address of an existing Dask scheduler (or a client): run the tasks there.
    progress : bool
        Show a tqdm progress bar with ETA on stderr.
    stop_after : int, optional
        Stop after this many cells were computed in this call (to test interruption).

    Returns
    -------
    SweepStore
    """
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
        computed = 0
    else:
        if store.path.exists() and any(store.path.iterdir()):
            raise SweepError("--store", f"{store.path} exists and is not a sweep store")
        first = cells[0]
        res0 = fn(_params(axes, first))
        store.create(_schema_of(res0), {**(dict(attrs) if attrs else {}),
                                        "description": json.loads(json.dumps(
                                            description or {}, default=str))})
        store.write(first, res0)
        todo = cells[1:]
        computed = 1
    if stop_after is not None:
        todo_run = todo[:max(0, stop_after - computed)]
    else:
        todo_run = todo
    bar = _progress(len(cells), progress, desc)
    bar.update(len(cells) - len(todo))
    try:
        if not todo_run:
            return store
        if scheduler is not None:
            _run_dask(fn, axes, store, todo_run, scheduler, bar)
        elif (workers or os.cpu_count() or 1) <= 1 or len(todo_run) == 1:
            for idx in todo_run:
                store.write(idx, fn(_params(axes, idx)))
                bar.update(1)
        else:
            _run_pool(fn, axes, store, todo_run, workers or os.cpu_count() or 1, bar)
    finally:
        bar.close()
    return store


def _run_pool(fn, axes, store, todo, workers, bar):
    import multiprocessing as mp

    # "spawn" avoids forking a process that holds Numba/Dask threads
    ctx = mp.get_context("spawn")
    max_inflight = 4 * workers
    it = iter(todo)
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        pending = {}
        try:
            for idx in itertools.islice(it, max_inflight):
                pending[pool.submit(fn, _params(axes, idx))] = idx
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in finished:
                    idx = pending.pop(fut)
                    store.write(idx, fut.result())
                    bar.update(1)
                    nxt = next(it, None)
                    if nxt is not None:
                        pending[pool.submit(fn, _params(axes, nxt))] = nxt
        except BaseException:
            for fut in pending:
                fut.cancel()
            raise


def _run_dask(fn, axes, store, todo, scheduler, bar):
    from distributed import Client, as_completed

    own = not hasattr(scheduler, "submit")
    client = Client(scheduler) if own else scheduler
    try:
        futures = {}
        for idx in todo:
            fut = client.submit(fn, _params(axes, idx), pure=False)
            futures[fut] = idx
        try:
            for fut in as_completed(list(futures)):
                store.write(futures[fut], fut.result())
                bar.update(1)
        except BaseException:
            client.cancel(list(futures))
            raise
    finally:
        if own:
            client.close()


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
