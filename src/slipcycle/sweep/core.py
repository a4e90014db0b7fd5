"""Resumable parallel parameter sweeps stored in Zarr (one cell per run).

A sweep is the Cartesian product of named axes. Every grid cell is computed by a task
function ``fn(params) -> dict`` (``params`` maps axis names to the cell's values) that
returns numbers or fixed-shape numeric arrays. Results go into a Zarr group:

- one array per output, shape ``grid_shape + cell_shape``, chunked one cell per chunk, so
  every finished run is written on its own as soon as it returns; the outputs are those
  of every cell together (a cell without an output holds its fill value: NaN, -1, False
  or ""), and a per-cell vector is as long as the longest one, shorter ones padded with
  the fill value (a sweep over a mesh size: ``dissipation_per_node`` of 9 and 13 nodes is
  stored over 13 nodes), so the store does not depend on the order cells finish in;
- a ``done`` boolean array (one chunk per cell), set *after* the cell's outputs are
  written, so a cell is either complete or absent;
- attributes: the axes, the output schema and a fingerprint of the sweep (the task's
  description), which ``resume`` checks before re-using a store.

:func:`run_sweep` computes the missing cells (all of them for a new store) on

- one process (``workers=1``),
- a local process pool (default, ``workers`` processes), or
- an existing Dask cluster (``scheduler="tcp://host:port"`` or a ``distributed.Client``),

with a tqdm progress bar (ETA). Only the calling process writes to the store. If a task
raises, the cells already finished (those still running included) stay stored and the
error propagates; ``resume=True`` later computes only what is missing, giving results
identical to an uninterrupted sweep. Ctrl-C (SIGINT) stops a sweep on local workers at
once: the workers ignore it and are ended by the sweep, every cell that finished is
stored, and :class:`SweepInterrupted` (a ``KeyboardInterrupt``) says how many.

Trust: a sweep holds an exclusive lock on its store (:class:`lock_store`; a second sweep
on it stops at once); a store is marked created only once all its arrays exist, and
temporary files of writes a kill interrupted are removed on resume, so a sweep killed at
any moment resumes to the same results; local worker processes die with the process that
started them (:func:`_die_with_parent`); grids of more than :data:`MAX_CELLS` cells and
unreachable Dask schedulers are refused before anything is created. A task may return
:class:`CellOutputs` to describe its outputs (units, CF flags), stored on the arrays.

Performance notes (measured on the 2-core reference machine, ``benchmarks/
bench_shakedown.py``): local workers are forked from a fork server that imported the task's
module and initialised Numba once (:func:`pool_context`), so a worker pays only its case
validation and the loading of its kernels from Numba's disk cache; each local worker gets
``cores // workers`` Numba threads so that ``prange`` kernels do not oversubscribe the
cores; ``group_by`` sends cells that share per-process cached set-up (the random starts of
one λ: 24 LPs) to one worker as one task, so the set-up is done once per group rather
than once per worker; a group that fills a box of the grid is written with one Zarr call
per output (≈ 2 ms per chunk). :class:`TaskRunner` keeps a pool alive across the steps of
a sequential algorithm (the λ3/λ4 bisection of ``slipcycle shakedown``).
"""

from __future__ import annotations

import copy
import gc
import hashlib
import itertools
import json
import logging
import math
import os
import re
import shutil
import signal
import sys
import threading
from collections.abc import Callable, Mapping
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from slipcycle.errors import InputError
from slipcycle.io.sizes import format_bytes

__all__ = ["Axis", "SweepStore", "run_sweep", "SweepError", "fingerprint", "TaskRunner",
           "run_group", "worker_threads", "CellOutputs", "lock_store", "check_size",
           "connect_scheduler", "MAX_CELLS", "SCHEDULER_TIMEOUT_S", "pool_context",
           "WORKER_PRELOAD", "SweepInterrupted"]

#: most cells one sweep may have: a store keeps one Zarr chunk file per cell and output,
#: and the sweep keeps a few hundred bytes of bookkeeping per cell in memory
MAX_CELLS = 1_000_000

#: bytes of memory per cell that a sweep needs at least (index tuples, task lists, the
#: ``done`` flags and one float per output read back at the end, for a handful of outputs)
_BYTES_PER_CELL = 400

#: seconds to wait for a Dask scheduler to answer before giving up
SCHEDULER_TIMEOUT_S = 5.0

#: name of the lock file inside a store (present only while a sweep runs on it)
LOCK_NAME = ".slipcycle.lock"

#: temporary files Zarr writes before renaming them into place (left by a killed write)
_ZARR_PARTIAL = re.compile(r"\.[0-9a-f]{32}\.partial$")


class SweepError(InputError):
    """An invalid sweep request (``key`` names the offending option or key)."""


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a sweep; every cell that finished is stored.

    Attributes
    ----------
    path : Path
        The store (absent when no cell had finished: nothing to resume).
    done, total : int
        Cells stored, and cells of the grid.
    """

    def __init__(self, path, done: int, total: int):
        super().__init__(f"sweep interrupted with {done} of {total} cells done")
        self.path, self.done, self.total = Path(path), int(done), int(total)


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


class CellOutputs(dict):
    """One cell's outputs (name -> number or fixed-shape array), with ``attrs``: output
    name -> attributes describing it (``units``, CF ``flag_values``/``flag_meanings``).

    A task may return a plain dict; attributes, when given, are stored on the store's
    arrays and every cell must give the same ones.
    """

    def __init__(self, values=(), attrs: Mapping | None = None):
        super().__init__(values)
        self.attrs = {k: dict(v) for k, v in (attrs or {}).items()}

    def __reduce__(self):
        # picklable for process pools and Dask, attributes included
        return (CellOutputs, (dict(self), self.attrs))


def _jsonable_attrs(attrs: Mapping) -> dict:
    return json.loads(json.dumps({k: dict(v) for k, v in attrs.items()}, default=_to_jsonable))


_TEXT = "text"


class SweepStore:
    """The Zarr group of one sweep.

    Parameters
    ----------
    path : str or Path
        Directory of the Zarr store.
    axes : list of Axis
    fingerprint : str
        Identifies the computation; a store with another fingerprint is not resumed.

    Notes
    -----
    The group's ``fingerprint`` attribute is written last when a store is created, so a
    store without it is one whose creation was interrupted (no cell of it is done).
    """

    def __init__(self, path, axes: list[Axis], fingerprint: str):
        import zarr

        self.path = Path(path)
        self.axes = list(axes)
        self.fp = fingerprint
        self.shape = tuple(a.size for a in self.axes)
        self._zarr = zarr
        self.group = None
        self._schema = None

    # -- creation / opening ---------------------------------------------------------------
    def state(self) -> str:
        """``"absent"``, ``"empty"`` (only a lock file or temporary files: a sweep killed
        before its first cell), ``"partial"`` (creation interrupted), ``"complete"`` or
        ``"foreign"`` (something else)."""
        if not self.path.exists():
            return "absent"
        if not self.path.is_dir():
            return "foreign"
        meta = self.path / "zarr.json"
        if not meta.exists() and not (self.path / ".zgroup").exists():
            names = [p.name for p in self.path.iterdir()]
            ok = all(n == LOCK_NAME or _ZARR_PARTIAL.search(n) for n in names)
            return "empty" if ok else "foreign"
        try:
            attrs = dict(self._zarr.open_group(str(self.path), mode="r").attrs)
        except Exception:  # noqa: BLE001 - unreadable metadata: not a store of ours
            return "foreign"
        if "fingerprint" in attrs:
            return "complete"
        return "partial" if attrs.get("slipcycle_sweep") == "creating" else "foreign"

    def exists(self) -> bool:
        """Whether a complete store (created, possibly with missing cells) is there."""
        return self.state() == "complete"

    def open_existing(self) -> None:
        """Open for resuming; checks axes and fingerprint."""
        g = self._zarr.open_group(str(self.path), mode="a")
        attrs = dict(g.attrs)
        if attrs.get("fingerprint") != self.fp:
            raise SweepError("--resume", f"the store {self.path} holds a different sweep "
                             "(case, --set values or settings changed); use a new --out")
        self.group = g

    def clear(self) -> None:
        """Remove everything but the lock file (an interrupted creation, left-over Zarr
        temporary files); only while holding the lock."""
        for p in self.path.iterdir():
            if p.name == LOCK_NAME:
                continue
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p)
            else:
                p.unlink()

    def remove_partials(self) -> int:
        """Delete temporary files of Zarr writes that a killed sweep left; only while
        holding the lock. Returns how many."""
        n = 0
        for root, _, files in os.walk(self.path):
            for f in files:
                if _ZARR_PARTIAL.search(f):
                    os.unlink(os.path.join(root, f))
                    n += 1
        return n

    def create(self, schema: Mapping[str, tuple], attrs: Mapping | None = None,
               output_attrs: Mapping | None = None) -> None:
        """Create the arrays: ``schema`` maps output name to (cell_shape, dtype);
        ``output_attrs`` maps output name to its attributes (units, flags)."""
        self.path.mkdir(parents=True, exist_ok=True)
        # mode "a", not "w": "w" would delete the lock file held in the directory
        g = self._zarr.open_group(str(self.path), mode="a",
                                  attributes={"slipcycle_sweep": "creating"})
        self.group = g
        oattrs = _jsonable_attrs(output_attrs or {})
        for name, (cshape, dtype) in schema.items():
            self._add(name, cshape, dtype, oattrs.get(name))
        self._create(g, "done", self.shape, (1,) * len(self.shape), np.dtype(bool), False)
        for a in self.axes:
            vals = np.asarray(a.values)
            if vals.dtype.kind in "fiub":
                self._create(g, f"axis_{a.name}", vals.shape, vals.shape, vals.dtype, 0)
                g[f"axis_{a.name}"][...] = vals
        # the fingerprint last: its presence marks a completely created store
        g.attrs.update({
            "axes": [[a.name, [_to_jsonable(v) for v in a.values]] for a in self.axes],
            "schema": _schema_attr(schema),
            "output_attrs": oattrs,
            **(dict(attrs) if attrs else {}),
            "slipcycle_sweep": "created",
            "fingerprint": self.fp,
        })
        self._schema = None

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
        """Output name -> (cell shape, dtype). The cell shape is read from the array
        itself: a kill between growing an array and updating the ``schema`` attribute
        leaves the array right."""
        if self._schema is None:
            nd = len(self.shape)
            self._schema = {k: (tuple(self.group[k].shape[nd:]),
                                _TEXT if v[1] == _TEXT else np.dtype(v[1]))
                            for k, v in self.group.attrs["schema"].items()}
        return self._schema

    @property
    def output_attrs(self) -> dict:
        """Output name -> its attributes (units, CF flags) as the task described them."""
        return dict(self.group.attrs.get("output_attrs", {}))

    def check_attrs(self, result) -> None:
        """Refuse a cell whose output attributes differ from the store's (a model that
        changes the meaning of an output between cells)."""
        given = getattr(result, "attrs", None)
        if not given:
            return
        have = self.output_attrs
        for name, at in _jsonable_attrs(given).items():
            if name in self.schema and name in result and have.get(name, {}) != at:
                raise ValueError(f"sweep output {name!r}: attributes {at} differ from the "
                                 f"store's {have.get(name, {})}")

    def fit(self, result: Mapping) -> None:
        """Make room for one cell's ``result``: an array for each output the store lacks
        (the cells before hold its fill value) and longer per-cell vectors where the
        result's are longer than any before (shorter ones are padded when written)."""
        self.check_attrs(result)
        schema, grown = self.schema, {}
        for name, (cshape, dtype) in _schema_of(result).items():
            if name not in schema:
                grown[name] = (cshape, dtype)
                continue
            have, kind = schema[name]
            if _is_text(dtype) != _is_text(kind) or len(cshape) != len(have):
                raise ValueError(f"sweep output {name!r}: {_describe(cshape, dtype)} in one "
                                 f"cell, {_describe(have, kind)} in another")
            big = tuple(max(a, b) for a, b in zip(cshape, have, strict=True))
            if big != have:
                self.group[name].resize(self.shape + big)
                grown[name] = (big, kind)
        if not grown:
            return
        given = _jsonable_attrs(getattr(result, "attrs", None) or {})
        oattrs = self.output_attrs
        for name, (cshape, dtype) in grown.items():
            if name not in schema:
                self._add(name, cshape, dtype, given.get(name))
                if given.get(name):
                    oattrs[name] = given[name]
        # the attributes after the arrays: a kill in between leaves arrays that the next
        # cell with these outputs creates again
        self.group.attrs.update({"schema": {**self.group.attrs["schema"],
                                            **_schema_attr(grown)},
                                 "output_attrs": oattrs})
        self._schema = None

    def _add(self, name, cshape, dtype, attrs) -> None:
        cshape = tuple(cshape)
        dt = str if _is_text(dtype) else np.dtype(dtype)
        self._create(self.group, name, self.shape + cshape,
                     (1,) * len(self.shape) + (cshape or ()), dt, _fill(dtype))
        if attrs:
            self.group[name].attrs.update(attrs)

    def done(self) -> np.ndarray:
        return np.asarray(self.group["done"][...], bool)

    def write(self, index: tuple, result: Mapping) -> None:
        """Write one cell's outputs, then mark it done."""
        self.fit(result)
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
        for r in results:
            self.fit(r)
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
            block = np.empty(box + cshape, object if _is_text(dtype) else dtype)
            for k, r in enumerate(results):
                block[tuple(p[k] for p in pos)] = _checked(name, indices[k], r[name], cshape,
                                                           dtype)
            self.group[name][sel] = block.astype(str) if _is_text(dtype) else block
        self.group["done"][sel] = np.ones(box, bool)

    def _write_one(self, name, index, value, cshape, dtype):
        self.group[name][index] = _checked(name, index, value, cshape, dtype)

    def read(self) -> dict:
        """All outputs as NumPy arrays (missing cells hold the fill value; text as
        fixed-width unicode)."""
        out = {}
        for name, (_, dtype) in self.schema.items():
            arr = np.asarray(self.group[name][...])
            # via object: NumPy's variable-width StringDType casts to no fixed width
            out[name] = arr.astype(object).astype(str) if _is_text(dtype) else arr
        return out


def _is_text(dtype) -> bool:
    return isinstance(dtype, str) and dtype == _TEXT


def _describe(cshape, dtype) -> str:
    return f"{'text' if _is_text(dtype) else 'numbers'} of shape {tuple(cshape)}"


def _schema_attr(schema: Mapping) -> dict:
    """``schema`` as the store's ``schema`` attribute (JSON)."""
    return {k: [list(v[0]), _TEXT if _is_text(v[1]) else np.dtype(v[1]).str]
            for k, v in schema.items()}


def _fill(dtype):
    """The value of a cell not (yet) written, of an output of ``dtype``: "" for text, NaN
    for floats, False for booleans, -1 for integers."""
    if _is_text(dtype):
        return ""
    kind = np.dtype(dtype).kind
    return np.nan if kind == "f" else (False if kind == "b" else -1)


def _checked(name, index, value, cshape, dtype) -> np.ndarray:
    """One cell's output ``name`` as ``dtype`` and shape ``cshape``: a shorter vector is
    padded with the fill value (NaN for numbers); anything else is refused."""
    val = np.asarray(value)
    if val.ndim != len(cshape) or any(a > b for a, b in zip(val.shape, cshape, strict=True)):
        raise ValueError(f"output {name!r} of cell {index}: shape {val.shape}, "
                         f"expected {cshape}")
    if _is_text(dtype):
        if val.dtype.kind not in "UT":
            raise ValueError(f"output {name!r} of cell {index}: expected text, got "
                             f"{val.dtype}")
        val = val.astype(str)
    elif val.dtype.kind not in "biuf":
        raise ValueError(f"output {name!r} of cell {index}: expected a number, got "
                         f"{val.dtype}")
    elif np.dtype(dtype).kind in "iub" and val.dtype.kind == "f" and \
            not np.all(np.isfinite(val) & (val == np.round(val))):
        # an integer output (a class code, a count) given as a fraction in this cell:
        # casting would cut it silently
        raise ValueError(f"output {name!r} of cell {index}: {val.tolist()} is not a whole "
                         "number, as the output is in other cells")
    else:
        val = val.astype(dtype)
    if val.shape == tuple(cshape):
        return val
    out = np.full(cshape, _fill(dtype), object if _is_text(dtype) else dtype)
    out[tuple(slice(0, n) for n in val.shape)] = val
    return out.astype(str) if _is_text(dtype) else out


def _cells(shape):
    return list(itertools.product(*(range(s) for s in shape)))


def _params(axes, index):
    return {a.name: a.values[i] for a, i in zip(axes, index, strict=True)}


def _schema_of(result: Mapping) -> dict:
    schema = {}
    for k, v in result.items():
        arr = np.asarray(v)
        if arr.dtype.kind in "UT":
            schema[k] = (arr.shape, _TEXT)
            continue
        if arr.dtype.kind not in "biuf":
            raise TypeError(f"sweep output {k!r} must be numeric or text, got {arr.dtype}")
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


def _worker_init(threads: int, parent: int | None = None, logs: tuple | None = None
                 ) -> None:
    """Initializer of local worker processes.

    Caps Numba's threads so that ``workers`` processes × threads do not oversubscribe the
    cores (``prange`` kernels), and ties the worker's life to the sweep's process
    ``parent``: a worker blocked on the task queue would otherwise outlive a killed
    parent for ever (:func:`_die_with_parent`). Ctrl-C is the sweep's to handle: a worker
    ignores SIGINT (the terminal sends it to the whole process group; a worker stopped
    halfway through a queue operation could leave its pool waiting for ever) and is ended
    by the sweep (:func:`_end_workers`). ``logs``: the sweep's logging (:func:`_log_setup`),
    which the worker follows (``--quiet``, ``--verbose``).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if parent is not None:
        _die_with_parent(parent)
    if logs is not None:
        _follow_logs(*logs)
    import numba
    from numba.np.ufunc import parallel

    # Numba guards the launch of its threads with a lock shared by the processes forked
    # from the launching one (it takes the fork server's "forkserver" for "fork"): a
    # named semaphore, which a worker ended by the sweep (:func:`_end_workers`) cannot
    # release, and which the resource tracker then reports as leaked on the terminal.
    # No process is forked from a worker, so a lock of this process protects the same.
    if getattr(parallel, "_backend_init_process_lock", False) is None:
        parallel._backend_init_process_lock = threading.RLock()
    numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    _limit_blas_threads(threads)


def _limit_blas_threads(threads: int) -> None:
    """Cap the BLAS/OpenMP thread pools of this worker at ``threads``: the workers share
    the cores, and BLAS threads that wait by spinning slow every worker down many times
    over (a case's well-posedness check, eigenvalues of N × N matrices, took seconds
    instead of milliseconds with two workers of two BLAS threads each on two cores).
    Uses ``threadpoolctl`` where installed; otherwise the pools stay as they are."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - optional
        return
    threadpool_limits(limits=max(1, int(threads)))


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - someone else's process
        return True
    return True


def _die_with_parent(parent: int, poll_s: float = 0.5) -> None:
    """End this process when ``parent`` (the sweep's process) ends.

    On Linux the kernel sends SIGKILL at the death of the process that started this one
    (``prctl(PR_SET_PDEATHSIG)``): the sweep's process for ``spawn`` workers, or the fork
    server, which itself ends when the sweep's process ends, for forked workers
    (:func:`pool_context`). A daemon thread that watches the direct parent (and the
    sweep's process) covers other systems and the moment before the ``prctl`` call.
    """
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            import signal

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL, 0, 0, 0)      # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):               # pragma: no cover - no prctl
            pass
    direct = os.getppid()             # the sweep's process, or the fork server
    if direct != parent and not _pid_alive(parent):     # the sweep died already
        os._exit(1)

    def watch():
        import time

        # a dead direct parent re-parents this process (getppid changes)
        while os.getppid() == direct and (direct == parent or _pid_alive(parent)):
            time.sleep(poll_s)
        os._exit(1)

    threading.Thread(target=watch, name="slipcycle-parent-watch", daemon=True).start()


_LOGGER = "slipcycle"


def _log_setup() -> tuple[int, str | None]:
    """The level of this process's ``slipcycle`` logger and the format of its handler,
    for the workers to follow (forked from a fork server, they inherit neither)."""
    log = logging.getLogger(_LOGGER)
    fmt = next((h.formatter._fmt for h in log.handlers if h.formatter is not None), None)
    return log.getEffectiveLevel(), fmt


def _follow_logs(level: int, fmt: str | None) -> None:
    """Give this worker's ``slipcycle`` logger the sweep's level and format (stderr)."""
    log = logging.getLogger(_LOGGER)
    log.setLevel(level)
    if fmt is not None and not log.handlers:
        handler = logging.StreamHandler()
        handler.setFormatter(logging.Formatter(fmt))
        log.addHandler(handler)
        log.propagate = False


class _Writer:
    """Writes finished tasks into the store as they arrive; a new store is created from
    the first result that arrives and grows as later ones need (:meth:`SweepStore.fit`),
    so nothing finished waits in memory, and the store does not depend on the order."""

    def __init__(self, store: SweepStore, create, bar):
        self.store = store
        self.create = create
        self.bar = bar

    @property
    def ready(self) -> bool:
        return self.store.group is not None

    def put(self, indices: list[tuple], results: list) -> None:
        if not self.ready:
            self.create(results[0])
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
    check_size([a.size for a in axes], "sweep")
    if workers is not None and int(workers) < 1:
        raise SweepError("--workers", f"must be >= 1, got {workers}")
    if runner is not None:
        workers, scheduler = runner.workers, runner.scheduler
    fp = fingerprint({"description": description or {},
                      "axes": [[a.name, [_to_jsonable(v) for v in a.values]] for a in axes]})
    store = SweepStore(store_path, axes, fp)
    if resume and not store.path.exists():
        raise no_store_to_resume(store.path)
    # connect before anything is created: an unreachable scheduler leaves nothing behind
    client, own_client = None, False
    if scheduler is not None:
        if runner is not None:
            client = runner.client()
        else:
            client, own_client = connect_scheduler(scheduler)
    try:
        with lock_store(store.path):
            return _run_locked(fn, axes, store, resume=resume, workers=workers,
                               client=client, progress=progress, stop_after=stop_after,
                               attrs=attrs, description=description, desc=desc,
                               group_by=group_by, runner=runner)
    finally:
        if own_client:
            client.close()


def no_store_to_resume(path) -> SweepError:
    """The error of ``--resume`` where no sweep was ever started."""
    return SweepError("--resume", f"there is no sweep store at {path} to resume; run "
                      "without --resume to start the sweep")


def _run_locked(fn, axes, store, *, resume, workers, client, progress, stop_after, attrs,
                description, desc, group_by, runner) -> SweepStore:
    """:func:`run_sweep` once the store is locked by this process."""
    cells = _cells(store.shape)
    state = store.state()
    if state == "complete":
        if not resume:
            raise SweepError("--out", f"{store.path} already holds a sweep; pass --resume "
                             "to complete it or choose another --out")
        store.open_existing()
        store.remove_partials()         # temporary files of writes a kill interrupted
        done = store.done()
        todo = [c for c in cells if not done[c]]
    elif state == "foreign":
        raise SweepError("--out", f"{store.path} exists and is not a sweep store")
    else:
        # absent, or left by a sweep killed before its store was created: start afresh
        store.clear()
        todo = cells
    # a new store computes one cell at least, so that it exists
    todo_run = todo if stop_after is None else todo[:max(int(state != "complete"),
                                                          stop_after)]
    tasks = _groups(todo_run, axes, group_by)
    meta = {**(dict(attrs) if attrs else {}),
            "description": json.loads(json.dumps(description or {}, default=str))}
    bar = _progress(len(cells), progress, desc)
    bar.update(len(cells) - len(todo))

    def create(res0):
        store.create(_schema_of(res0), meta, getattr(res0, "attrs", None))

    writer = _Writer(store, create, bar)
    try:
        if not tasks:
            return store
        nproc = workers or os.cpu_count() or 1
        if client is not None:
            _run_dask(fn, axes, tasks, client, writer)
        elif nproc <= 1 or len(tasks) == 1:
            for task in tasks:
                writer.put(task, run_group(fn, [_params(axes, i) for i in task]))
        elif runner is not None:
            _run_pool(fn, axes, tasks, nproc, writer, runner.pool(fn))
        else:
            with _local_pool(min(nproc, len(tasks)), fn) as pool:
                _run_pool(fn, axes, tasks, min(nproc, len(tasks)), writer, pool)
    except KeyboardInterrupt:
        # every finished cell is stored by now: say how many, for the resume message
        try:
            done = int(store.done().sum()) if writer.ready else 0
        except Exception:  # noqa: BLE001 - interrupted while creating the store: no cell
            done = 0
        raise SweepInterrupted(store.path, done, len(cells)) from None
    finally:
        bar.close()
    return store


def check_size(sizes, key: str = "--set") -> int:
    """Refuse, before any work, a grid of more than :data:`MAX_CELLS` cells.

    Parameters
    ----------
    sizes : sequence of int
        Number of values of each axis.
    key : str
        The option named in the error.

    Returns
    -------
    int
        The number of cells.

    Raises
    ------
    SweepError
        Naming the cell count and an estimate of the memory the sweep would need.
    """
    cells = math.prod(int(s) for s in sizes)
    if cells > MAX_CELLS:
        raise SweepError(key, f"{cells} cells would need an estimated "
                         f"{format_bytes(cells * (_BYTES_PER_CELL + 8 * len(sizes)))} of "
                         f"memory (and {cells} files per output); a sweep may have at most "
                         f"{MAX_CELLS} cells: use fewer values")
    return cells


class _Lock:
    def __init__(self, fd: int, path: Path, made: list[Path]):
        self.fd, self.path, self.made, self.count = fd, path, made, 1


_HELD: dict[str, _Lock] = {}


class lock_store:  # noqa: N801 - used like a function: ``with lock_store(path):``
    """Hold an exclusive lock on a sweep store for the duration of a ``with`` block.

    A lock file inside the store is locked with ``fcntl.flock``; the kernel releases the
    lock when the process ends, however it ends, so a killed sweep never blocks a later
    ``--resume``. Another process asking for the same store fails at once with a
    :class:`SweepError` naming the store; the same process may nest locks on one store.
    On leaving the outermost block the lock file is removed, and so is the store
    directory (with the parents this lock created) when it holds nothing but what a sweep
    left before creating its store; other content is never touched.
    """

    def __init__(self, path):
        self.path = Path(path)
        self.key = os.path.realpath(self.path)

    def __enter__(self):
        held = _HELD.get(self.key)
        if held is not None:
            held.count += 1
            return self
        _HELD[self.key] = _acquire(self.path)
        return self

    def __exit__(self, *exc):
        held = _HELD[self.key]
        held.count -= 1
        if held.count:
            return
        del _HELD[self.key]
        try:
            if SweepStore(self.path, [], "").state() not in ("empty", "partial"):
                os.unlink(self.path / LOCK_NAME)    # a store, or someone else's files
            else:                   # nothing worth keeping: leave no trace of this sweep
                shutil.rmtree(self.path, ignore_errors=True)
                for d in reversed(held.made[:-1]):
                    try:
                        d.rmdir()
                    except OSError:
                        break
        except OSError:             # pragma: no cover - removed meanwhile
            pass
        finally:
            os.close(held.fd)


def _acquire(path: Path) -> _Lock:
    import fcntl

    lock = path / LOCK_NAME
    for _ in range(20):
        made = []
        p = path
        while not p.exists():
            made.insert(0, p)
            p = p.parent
        path.mkdir(parents=True, exist_ok=True)
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except FileNotFoundError:   # the directory was removed meanwhile: again
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                pid = os.read(fd, 32).decode().strip()
            finally:
                os.close(fd)
            by = f" (process {pid})" if pid.isdigit() else ""
            raise SweepError("--out", f"the sweep store {path} is in use by another "
                             f"sweep{by}; wait for it to end or choose another --out"
                             ) from None
        try:
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if not same:                # the holder removed the file as we opened it: again
            os.close(fd)
            continue
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        return _Lock(fd, path, made)
    raise SweepError("--out", f"could not lock the sweep store {path}")  # pragma: no cover


#: a Dask scheduler address: protocol://host:port (host a name, IPv4 or [IPv6]) or inproc://
_SCHEDULER_ADDRESS = re.compile(
    r"(?:(?:tcp|tls|ucx|ws|wss)://)?(?:\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):\d{1,5}"
    r"|inproc://\S+")


def connect_scheduler(address, timeout: float | None = None):
    """A Dask client for ``address`` (or ``address`` itself if it is a client).

    Returns
    -------
    (client, own) : own is True when this call connected (the caller closes it)

    Raises
    ------
    SweepError
        Naming ``--scheduler`` when the address is malformed or nothing answers within
        ``timeout`` seconds (default :data:`SCHEDULER_TIMEOUT_S`).
    """
    if hasattr(address, "submit"):
        return address, False
    text = str(address).strip()
    # refuse a malformed address before a Client exists: a Client that fails in its
    # constructor can outlive the failure and be met again by later work in this process
    if not _SCHEDULER_ADDRESS.fullmatch(text):
        raise SweepError("--scheduler", f"{text!r} is not a scheduler address (expected "
                         "tcp://host:port, e.g. tcp://127.0.0.1:8786)")
    import dask
    from distributed import Client

    timeout = SCHEDULER_TIMEOUT_S if timeout is None else timeout
    saved = copy.deepcopy(dask.config.config)
    reason = None
    try:
        client = Client(text, timeout=timeout)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        # a failed Client leaves "scheduler: dask.distributed" in the global config, which
        # would send this process's later dask work (xarray writes) to no client
        dask.config.config.clear()
        dask.config.config.update(saved)
        reason = " ".join(str(exc).split()) or type(exc).__name__
    if reason is not None:
        # the failed Client is held only by the traceback's reference cycle: collect it
        # now, so that no later work in this process can find it as the default client
        gc.collect()
        raise SweepError("--scheduler", f"cannot connect to a Dask scheduler at {text!r}: "
                         f"{reason}")
    return client, True


#: modules the fork server of local workers imports once (see :func:`pool_context`)
WORKER_PRELOAD = ("slipcycle.sweep.core", "slipcycle.sweep._preload")


def _task_modules(fn) -> list[str]:
    """The modules that define ``fn`` (a function or a ``functools.partial`` of one)."""
    while isinstance(fn, partial):
        fn = fn.func
    mod = getattr(fn, "__module__", None)
    return [mod] if mod and mod.startswith("slipcycle.") else []


def pool_context(fn=None):
    """The multiprocessing context of local workers.

    A fork server (POSIX) that has imported the sweep engine, the module of the task
    ``fn`` (NumPy, SciPy, the model) and initialised Numba once
    (:mod:`slipcycle.sweep._preload`): each worker is then a fork of that warm,
    single-threaded server, ready in a fraction of a second and sharing its compiled
    kernels through Numba's on-disk cache, instead of a fresh interpreter importing
    everything again (``spawn``: 1-2 s per worker, more on a loaded machine). The server
    starts with the first pool of this process and serves every later one; it holds no
    Numba or Dask threads, so forking it is safe. ``spawn`` where fork servers do not
    exist (Windows) or ``SLIPCYCLE_WORKER_START=spawn``.
    """
    import multiprocessing as mp

    method = os.environ.get("SLIPCYCLE_WORKER_START", "forkserver")
    if method not in mp.get_all_start_methods():
        method = "spawn"
    ctx = mp.get_context(method)
    if method == "forkserver":
        # the list is read when the server starts (first pool); later calls change nothing
        ctx.set_forkserver_preload([*WORKER_PRELOAD, *_task_modules(fn)])
    return ctx


def _local_pool(workers: int, fn=None):
    """A process pool (:func:`pool_context`) whose workers share out the cores' Numba
    threads, die with this process, ignore Ctrl-C and follow this process's logging."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=pool_context(fn),
                               initializer=_worker_init,
                               initargs=(worker_threads(workers), os.getpid(), _log_setup()))


#: seconds between two looks at the Ctrl-C flag while waiting for workers
_POLL_S = 0.2

#: seconds a Ctrl-C waits for results on their way back from the workers (finished cells
#: whose result is still in the pipe) before the workers are ended
_GRACE_S = 0.25


@contextmanager
def _deferred_interrupt():
    """Within the block, Ctrl-C (SIGINT) sets the yielded event instead of raising
    ``KeyboardInterrupt`` wherever the main thread is (halfway through a Zarr write, or
    inside the pool's bookkeeping); a second Ctrl-C raises at once. Outside the main
    thread, where no handler can be set, the event is never set."""
    stop = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def on_sigint(signum, frame):
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()

    old = signal.signal(signal.SIGINT, on_sigint)
    try:
        yield stop
    finally:
        signal.signal(signal.SIGINT, old if old is not None else signal.default_int_handler)


def _end_workers(pool: ProcessPoolExecutor) -> None:
    """End the pool's worker processes now (their running cells are dropped: ``resume``
    computes them) and shut the pool down without waiting for its tasks."""
    # the executor keeps its processes in a private mapping; ending them is the only way
    # to stop a running task, and a pool shut down while its workers still wait on the
    # task queue is what left interrupted sweeps hanging at exit
    procs = list((getattr(pool, "_processes", None) or {}).values())
    for p in procs:
        try:
            p.terminate()
        except (OSError, ValueError):   # pragma: no cover - already gone
            pass
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        p.join(5.0)
        if p.is_alive():                # pragma: no cover - ignored SIGTERM
            p.kill()
            p.join(1.0)


def _run_pool(fn, axes, tasks, workers, writer, pool):
    """Run ``tasks`` on a local ``pool``, writing each result as it arrives.

    At most ``4 * workers`` tasks are queued at a time. On Ctrl-C the loop stops at once,
    keeps every task that finished and ends the workers; when a task fails, the tasks
    still running finish and are kept first; then the exception propagates.
    """
    it = iter(tasks)
    pending = {}

    def submit(task):
        pending[pool.submit(run_group, fn, [_params(axes, i) for i in task])] = task

    with _deferred_interrupt() as stop:
        try:
            for task in itertools.islice(it, 4 * workers):
                submit(task)
            while pending:
                if stop.is_set():
                    raise KeyboardInterrupt
                finished, _ = wait(pending, timeout=_POLL_S, return_when=FIRST_COMPLETED)
                # keep every success of this batch before a failure in it propagates
                for fut in sorted(finished, key=lambda f: f.exception() is not None):
                    task = pending.pop(fut)
                    writer.put(task, fut.result())
                    nxt = next(it, None)
                    if nxt is not None:
                        submit(nxt)
        except BaseException as exc:
            interrupted = isinstance(exc, KeyboardInterrupt)
            try:
                _keep_finished(pending, writer, None if interrupted else stop)
            finally:
                if interrupted or stop.is_set():
                    _end_workers(pool)
            raise


def _keep_finished(pending: dict, writer, stop: threading.Event | None) -> None:
    """After a failure or Ctrl-C: cancel the tasks not started, wait for the running
    ones unless ``stop`` is None (Ctrl-C) or gets set, and write every success."""
    for fut in pending:
        fut.cancel()
    running = [f for f in pending if not f.done()]
    if stop is None and running:
        wait(running, timeout=_GRACE_S)
    while stop is not None and running and not stop.is_set():
        wait(running, timeout=_POLL_S)
        running = [f for f in running if not f.done()]
    for fut, task in pending.items():
        if fut.done() and not fut.cancelled() and fut.exception() is None:
            try:
                writer.put(task, fut.result())
            except Exception:  # noqa: BLE001 - the first error is the one reported
                pass


def _run_dask(fn, axes, tasks, client, writer):
    from distributed import as_completed

    futures = {}
    for task in tasks:
        fut = client.submit(run_group, fn, [_params(axes, i) for i in task], pure=False)
        futures[fut] = task
    try:
        for fut in as_completed(list(futures)):
            task = futures.pop(fut)
            writer.put(task, fut.result())
    except BaseException:
        client.cancel([f for f in futures if f.status != "finished"])
        for fut, task in futures.items():       # finished, not yet written: keep them
            if fut.status == "finished":
                try:
                    writer.put(task, fut.result())
                except Exception:  # noqa: BLE001 - the first error is the one reported
                    pass
        raise


class TaskRunner:
    """Runs batches of independent tasks, keeping local worker processes (or a Dask
    client) alive between batches: for sequential algorithms whose steps are parallel,
    such as the bisection of λ3/λ4 brackets.

    ``workers``/``scheduler`` as for :func:`run_sweep`. Use as a context manager;
    :meth:`map` returns results in the order of its inputs.
    """

    def __init__(self, workers: int | None = None, scheduler=None):
        if workers is not None and int(workers) < 1:
            raise SweepError("--workers", f"must be >= 1, got {workers}")
        self.workers = workers or os.cpu_count() or 1
        self.scheduler = scheduler
        self._pool = None
        self._client = None
        self._own_client = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close(interrupted=exc[0] is not None and issubclass(exc[0], KeyboardInterrupt))

    def close(self, interrupted: bool = False) -> None:
        """Shut the pool down (``interrupted``: end its workers at once, their running
        tasks dropped) and close an own Dask client."""
        if self._pool is not None:
            if interrupted:
                _end_workers(self._pool)
            self._pool.shutdown(cancel_futures=True)
            self._pool = None
        if self._client is not None and self._own_client:
            self._client.close()
        self._client = None

    def client(self):
        """The Dask client (connected on first use)."""
        if self._client is None:
            self._client, self._own_client = connect_scheduler(self.scheduler)
        return self._client

    def pool(self, fn=None) -> ProcessPoolExecutor:
        """The local process pool (started on first use; ``fn``: a task it will run,
        whose module the workers import once, see :func:`pool_context`)."""
        if self._pool is None:
            self._pool = _local_pool(self.workers, fn)
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
        futs = [self.pool(fn).submit(fn, p) for p in params]
        try:
            return [f.result() for f in futs]
        except BaseException:
            for f in futs:
                f.cancel()
            raise


def parse_values(spec: str, key: str) -> list:
    """Values of ``--set key=VALUES``: ``start:stop:num`` (inclusive linspace) or ``a,b,c``.

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
            check_size([num], f"--set {key}")     # before allocating the values
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
