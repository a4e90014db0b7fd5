"""The basins study of a discrete case (``slipcycle basins``): steady state versus initial
condition over a grid, random starts or assembly protocols (Ahn, Bertocchi & Barber 2008;
Andersson, Barber & Ahn 2013).

- :func:`basin_row_task` / :func:`basin_block_task` — N = 2 maps over a (v1, v2) grid of
  initial slip states at θ = 0, a block of grid rows per sweep cell
  (:mod:`slipcycle.sweep`): every start of a block goes to the compiled kernel in one call
  (its threads share them out) and to the store in one write per output;
- :func:`lam_start_task`, :func:`random_task`, :func:`protocol_task` — any N: random
  admissible states or a list of protocols (:func:`read_protocols`);
- :func:`basins_study` — the whole study through the sweep engine, the summary, Dataset and
  basin map (:class:`BasinsResult`).

The runs themselves are :mod:`slipcycle.discrete.basins` (records, box counting). Class
codes are :data:`slipcycle.result.STEADY_STATES`.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import ClassVar

import numpy as np
import xarray as xr

from slipcycle.coupled.sizes import cells_bytes, check_memory
from slipcycle.discrete.basins import (
    INADMISSIBLE,
    admissible_box,
    basin_row,
    box_counting_dimension,
    empty_record,
    run_record,
    run_records,
)
from slipcycle.discrete.case import read_discrete_case
from slipcycle.discrete.shakedown import (
    lambda1,
    lambda2,
    safe_region,
    sample_initial_slips,
)
from slipcycle.io import Case, CaseError
from slipcycle.plot.shakedown import basin_map
from slipcycle.result import STEADY_STATES
from slipcycle.studies.common import (
    CONVERGED_ATTRS,
    BasinsStudyResult,
    model_case,
    read_protocols,
)
from slipcycle.sweep import Axis, SweepError, run_sweep
from slipcycle.sweep.dataset import StudyStatus, as_case_error

__all__ = ["load_discrete_case", "basin_row_task", "basin_block_task", "grid_blocks",
           "lam_start_task", "protocol_task", "random_task", "read_protocols", "parse_range",
           "basins_study", "BasinsResult", "SUMMARY_UNITS", "SUMMARY_FLAGS"]


# --- sweep tasks (module level: picklable for process pools and Dask) ------------------
@functools.lru_cache(maxsize=8)
def load_discrete_case(case_text: str, case_path: str | None):
    """The validated :class:`~slipcycle.discrete.case.DiscreteCase` of a case text
    (cached per process). Tables other than the model's (e.g. ``[basins]``) are ignored."""
    return read_discrete_case(model_case(case_text, case_path, (
        "model", "title", "description", "discrete", "loading", "run")), record=False)


def basin_row_task(params: dict, case_text: str, case_path, v1: tuple, v2: tuple,
                   lam: float | None = None, threads: int | None = None, **run) -> dict:
    """Sweep task: row ``params["row"]`` of a basin map (v1 grid × one v2 value)."""
    if threads:
        import numba

        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    dc = load_discrete_case(case_text, case_path)
    load = dc.load if lam is None else dc.load.with_lam(lam)
    settings = {**_run_settings(dc), **run}
    return basin_row(dc.system, load, np.asarray(v1), v2[int(params["row"])], **settings)


#: starts per sweep cell of a grid map: enough to keep the kernel's threads busy and the
#: store's writes few (one Zarr write per output and cell), few enough to resume finely
BLOCK_STARTS = 4096


def grid_blocks(grid: int, starts_per_block: int = BLOCK_STARTS) -> tuple[int, int]:
    """(blocks, rows per block) of a ``grid`` × ``grid`` map: rows of about
    ``starts_per_block`` starts per block, and at least two blocks (a map stopped after one
    cell is never complete)."""
    rows = max(1, min(-(-grid // 2), starts_per_block // max(grid, 1)))
    return -(-grid // rows), rows


def basin_block_task(params: dict, case_text: str, case_path, v1: tuple, v2: tuple,
                     rows: int, lam: float | None = None, threads: int | None = None,
                     **run) -> dict:
    """Sweep task: rows ``block·rows`` … ``block·rows + rows − 1`` of a basin map.

    All ``rows`` × len(v1) starts run in one call of :func:`run_records`. Rows past the
    last v2 (the last block's padding) are not run: they hold the record of an
    inadmissible start and are dropped when the map is read.

    Returns
    -------
    dict of arrays with leading dimensions (rows, len(v1)) (see :func:`run_records`).
    """
    if threads:
        import numba

        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    dc = load_discrete_case(case_text, case_path)
    load = dc.load if lam is None else dc.load.with_lam(lam)
    settings = {**_run_settings(dc), **run}
    n1, n = len(v1), dc.system.n_nodes
    first = int(params["block"]) * rows
    y = np.asarray(v2[first:first + rows], float)
    V0 = np.column_stack([np.tile(np.asarray(v1, float), y.size), np.repeat(y, n1)])
    # the kernel's threads split the starts into contiguous halves; inadmissible starts
    # (instant) cluster in the corners of the box, so the starts go in a scattered order
    order = np.random.default_rng(0).permutation(V0.shape[0])
    shuffled = run_records(dc.system, load, V0[order], **settings)
    out = {}
    for k, v in shuffled.items():
        out[k] = np.empty_like(v)
        out[k][order] = v
    pad = empty_record(n, INADMISSIBLE)
    block = {}
    for k, v in out.items():
        full = np.empty((rows * n1,) + v.shape[1:], v.dtype)
        full[:v.shape[0]] = v
        full[v.shape[0]:] = pad[k]
        block[k] = full.reshape((rows, n1) + v.shape[1:])
    return block


def _run_settings(dc) -> dict:
    r = dc.run
    return {"cycles": r["cycles"], "steps_per_cycle": r["steps_per_cycle"], "tol": r["tol"],
            "min_cycles": r["min_cycles"]}


def lam_start_task(params: dict, case_text: str, case_path, n_random: int, seed: int,
                   **run) -> dict:
    """Sweep task: load factor ``params["lam"]``, start ``params["start"]``.

    Start 0 is the case's own initial condition (its ``initial_slip`` if admissible at
    this λ, its protocol, or monotonic loading from the unloaded state); starts 1..K are
    random admissible slip states at this λ (:func:`sample_initial_slips` with ``seed``:
    the same random stream at every λ, applied to the vertices of the polytope admissible
    at θ = 0 for this λ), so a cell's result depends only on (case, λ, start, K, seed) —
    not on the process, the order of cells or which other cells are run.

    The K random starts of one λ (24 LPs for N = 200, ≈ 1 s) are computed once per
    process and λ (:func:`_starts`); sweeps group the cells of one λ into one task
    (``run_sweep(..., group_by=("lam",))``) so that they are computed once per λ in all.
    """
    dc = load_discrete_case(case_text, case_path)
    lam = float(params["lam"])
    s = int(params["start"])
    load = dc.load.with_lam(lam)
    settings = {**_run_settings(dc), **run}
    n = dc.system.n_nodes
    v0 = np.full(n, np.nan)
    if s == 0:
        rec = run_record(dc.system, load, initial_slip=dc.initial_slip, protocol=dc.protocol,
                         **settings)
        if dc.initial_slip is not None:
            v0 = np.asarray(dc.initial_slip, float)
            if rec["steady_state"] == INADMISSIBLE:
                rec = run_record(dc.system, load, **settings)
    else:
        V = _starts(case_text, case_path, lam, n_random, seed)
        if V.shape[0] < s:
            rec = empty_record(n, INADMISSIBLE)
        else:
            v0 = V[s - 1].copy()
            rec = run_record(dc.system, load, initial_slip=v0, **settings)
    rec["initial_slip"] = v0
    return rec


@functools.lru_cache(maxsize=8)
def _starts(case_text, case_path, lam, n_random, seed):
    """The K random starts (K, N) [m] of :func:`lam_start_task` at λ (cached per process;
    do not modify)."""
    dc = load_discrete_case(case_text, case_path)
    return sample_initial_slips(dc.system, dc.load.with_lam(lam), n_random, seed=seed)


# --- the basins study -----------------------------------------------------------------
#: unit of every numeric summary entry (nested entries by their path)
SUMMARY_UNITS = {
    "lam": "1", "n_nodes": "1", "lambda1": "1", "lambda2": "1", "starts": "1",
    "class_counts": "1", "dissipation_per_cycle.min": "J",
    "dissipation_per_cycle.max": "J", "both_outcomes": "1", "wall_time_s": "s",
    "boundary_box_counting_dimension": "1", "box_counting.dimension": "1",
    "box_counting.sizes": "1", "box_counting.counts": "1",
    "box_counting.boundary_cells": "1", "grid": "1",
}

#: every word of the categorical summary entries
SUMMARY_FLAGS = {"mode": ("grid", "random", "protocols")}



def parse_range(text: str, key: str) -> tuple[float, float]:
    """``"a:b"`` -> (a, b), finite with a < b; :class:`CaseError` naming ``key`` otherwise."""
    try:
        a, b = (float(x) for x in text.split(":"))
    except ValueError:
        raise CaseError(key, f"must be a:b, got {text!r}") from None
    if not (np.isfinite(a) and np.isfinite(b) and b > a):
        raise CaseError(key, f"needs finite a < b, got {text!r}")
    return a, b


def protocol_task(params, case_text, case_path, protocols, lam):
    """Sweep task: steady state after assembly protocol ``params["index"]``."""
    dc = load_discrete_case(case_text, case_path)
    load = dc.load if lam is None else dc.load.with_lam(lam)
    return run_record(dc.system, load, protocol=np.asarray(protocols[int(params["index"])]),
                      **_run_settings(dc))


def random_task(params, case_text, case_path, V):
    """Sweep task: steady state from initial slip ``V[params["index"]]`` (N,) [m]."""
    dc = load_discrete_case(case_text, case_path)
    lam = params.get("lam")
    load = dc.load if lam is None else dc.load.with_lam(lam)
    i = int(params["index"])
    out = run_records(dc.system, load, np.asarray(V)[i:i + 1], **_run_settings(dc))
    return {k: v[0] for k, v in out.items()}


def basins_study(case: Case, out, *, grid: int | None = None, random: int | None = None,
                 protocols: Path | None = None, v1_range: str | None = None,
                 v2_range: str | None = None, lam: float | None = None, seed: int = 0,
                 workers: int | None = None, scheduler=None, resume: bool = False,
                 progress: bool = True, stop_after: int | None = None) -> StudyStatus:
    """Steady state (class, dissipation per cycle) of a discrete case over initial conditions.

    At most one of ``grid``, ``random``, ``protocols`` (default: a 101 × 101 grid for
    N = 2, 64 random starts otherwise).

    Parameters
    ----------
    case : Case
        A ``model = "discrete"`` case.
    out : path
        Directory of the store ``basins.zarr``.
    grid : int, optional
        N = 2: grid points per axis of initial slips (v1, v2) at θ = 0 over the box of
        admissible states (or ``v1_range``/``v2_range``, ``"a:b"`` [m]); the box-counting
        dimension of the class boundaries is reported.
    random : int, optional
        Random admissible initial slip states (``seed``), any N.
    protocols : Path, optional
        TOML file of assembly protocols (:func:`read_protocols`), any N.
    lam : float, optional
        Load factor λ (default the case's ``loading.lam``).
    workers, scheduler, resume, progress, stop_after
        See :func:`~slipcycle.sweep.core.run_sweep` (grid rows run in parallel threads).

    Returns
    -------
    StudyStatus
        ``result`` (:class:`BasinsResult`) and ``outputs`` (``result.to_outputs()``) once
        every cell is done, None while cells are missing: ``summary`` (``mode``, ``lam``,
        ``lambda1``, ``lambda2``, ``starts``, ``class_counts``, ``dissipation_per_cycle``
        {min, max} [J], ``both_outcomes``, ``steady_state_codes``, for a grid
        ``box_counting``; ``units``: :data:`SUMMARY_UNITS`), ``dataset`` (class codes,
        dissipation, cycles run, slipping nodes, memory erased, ``converged``) and, for a
        grid, the figure ``basin_map``.

    Raises
    ------
    CaseError
        A bad option (named by its command-line spelling, e.g. ``--grid``), a map too
        large for memory, or a refused store, before any simulation.
    """
    out = Path(out)
    lam_opt, workers_opt = lam, workers
    cpath = str(case.path) if case.path else None
    dc = load_discrete_case(case.text, cpath)
    n = dc.system.n_nodes
    if lam_opt is not None and not (np.isfinite(lam_opt) and lam_opt >= 0):
        raise CaseError("--lam", f"must be a finite number >= 0, got {lam_opt}")
    lam = lam_opt if lam_opt is not None else float(dc.load.p.lam)
    load = dc.load.with_lam(lam)
    mode = "grid" if grid is not None else ("random" if random is not None else
                                            "protocols" if protocols else None)
    if mode is None:
        mode = "grid" if n == 2 else "random"
        grid = 101 if n == 2 else None
        random = None if n == 2 else 64
    if mode == "grid":
        if n != 2:
            raise CaseError("--grid", f"needs a two-node system (this one has {n} nodes); "
                            "use --random or --protocols")
        if grid < 2:
            raise CaseError("--grid", f"must be >= 2, got {grid}")
        # a grid row is one task returning arrays: per start, the class, D, D_j, counts
        # (8 numbers) held ~4 times (rows, store, Dataset, figure)
        check_memory("--grid", float(grid) ** 2 * 8 * (n + 8) * 4,
                     f"{grid:g} × {grid:g} starts")
        box = admissible_box(dc.system, load)
        if v1_range:
            box[0] = parse_range(v1_range, "--v1")
        if v2_range:
            box[1] = parse_range(v2_range, "--v2")
        if not np.all(np.isfinite(box)):
            raise CaseError("loading.lam", f"no slip state is admissible at θ = 0 for λ = "
                            f"{lam:g}; give --v1 and --v2 ranges")
        v1 = np.linspace(box[0, 0], box[0, 1], grid)
        v2 = np.linspace(box[1, 0], box[1, 1], grid)
        threads = None if (workers_opt in (None, 1) and scheduler is None) else 1
        workers = 1 if workers_opt is None and scheduler is None else workers_opt
        blocks, rows = grid_blocks(grid)
        fn = partial(basin_block_task, case_text=case.text, case_path=cpath,
                     v1=tuple(v1.tolist()), v2=tuple(v2.tolist()), rows=rows, lam=lam,
                     threads=threads)
        axes = [Axis("block", tuple(range(blocks)))]
        desc = {"mode": "grid", "lam": lam, "v1": v1.tolist(), "v2": v2.tolist()}
    elif mode == "random":
        if random < 1:
            raise CaseError("--random", f"must be >= 1, got {random}")
        check_memory("--random", cells_bytes(random, n) + 8.0 * random * n * 8,
                     f"{random:g} random starts ({n} nodes)")
        V = sample_initial_slips(dc.system, load, random, seed=seed)
        if V.shape[0] == 0:
            raise CaseError("loading.lam", f"no slip state is admissible at θ = 0 for λ = "
                            f"{lam:g}")
        fn = partial(random_task, case_text=case.text, case_path=cpath,
                     V=tuple(map(tuple, V.tolist())))
        axes = [Axis("index", tuple(range(V.shape[0])))]
        desc = {"mode": "random", "lam": lam, "V": V.tolist()}
        workers = workers_opt
    else:
        protos = read_protocols(protocols, n)
        fn = partial(protocol_task, case_text=case.text, case_path=cpath,
                     protocols=tuple(p.tolist() for p in protos), lam=lam)
        axes = [Axis("index", tuple(range(len(protos))))]
        desc = {"mode": "protocols", "lam": lam, "protocols": [p.tolist() for p in protos]}
        workers = workers_opt
    t0 = time.perf_counter()
    try:
        store = run_sweep(fn, axes, out / "basins.zarr",
                          description={"case": case.text, **desc}, resume=resume,
                          workers=workers, scheduler=scheduler,
                          progress=progress, stop_after=stop_after,
                          desc="basins")
    except SweepError as exc:
        raise as_case_error(exc) from None
    wall = time.perf_counter() - t0
    done = store.done()
    if not done.all():
        return StudyStatus(None, int(done.sum()), int(done.size))
    data = store.read()
    if mode == "grid":  # (block, row, v1, ...) -> (v2, v1, ...), padding rows dropped
        data = {k: v.reshape((-1,) + v.shape[2:])[:grid] for k, v in data.items()}
    region = safe_region(dc.system, dc.load)
    l2 = lambda2(region)[0]
    l1 = lambda1(region, l2)["lambda1"]
    grid_kw = {}
    if mode == "grid":
        # boundaries between admissible starts only: the edge of the admissible region
        # is smooth and says nothing about the dynamics
        cls = data["steady_state"]
        grid_kw = {"v1": v1, "v2": v2, "region": region, "box_counting": box_counting_dimension(
            cls, valid=cls != INADMISSIBLE)}
    result = BasinsResult(wall_time_s=wall, mode=mode, lam=lam, n_nodes=n, lambda1=l1,
                          lambda2=l2, data=data, store=None if mode == "grid" else store,
                          axes=tuple(axes), **grid_kw)
    return StudyStatus(result.to_outputs(), int(done.size), int(done.size), result)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class BasinsResult(BasinsStudyResult):
    """Steady state of a discrete case over initial conditions (``slipcycle basins``).

    Attributes
    ----------
    wall_time_s : float
        Wall time of the runs in this call [s].
    mode : str
        ``grid``, ``random`` or ``protocols``.
    lam : float
        Load factor λ of the runs [1].
    n_nodes : int
        Nodes N of the system.
    lambda1, lambda2 : float
        Shakedown load factors of the case's own load (Barber 2012) [1].
    data : dict of str to ndarray
        The stored outputs over the starts: ``steady_state`` (class codes of
        :data:`~slipcycle.result.STEADY_STATES`), ``dissipation_per_cycle`` [J],
        ``dissipation_per_node`` [J] (last axis: node), ``cycles_run``, ``n_slipping``,
        ``memory_erased``; shape (v2, v1) for a grid, (start,) otherwise.
    store : SweepStore or None
        For random starts and protocols, the store the runs were kept in (its Dataset is
        read from it, with the task's own attributes).
    axes : tuple of Axis
        The sweep axes of ``store``.
    v1, v2 : ndarray or None
        Grid of initial slips of nodes 0 and 1 [m] (grid only).
    region : SafeRegion or None
        The safe shakedown region (grid only, for the basin map).
    box_counting : dict or None
        :func:`box_counting_dimension` of the class boundaries (grid only).
    """

    model: ClassVar[str] = "discrete"
    FLAGS: ClassVar[dict] = SUMMARY_FLAGS

    lambda1: float
    lambda2: float
    v1: np.ndarray | None = None
    v2: np.ndarray | None = None
    region: object = None
    box_counting: dict | None = None

    def headline(self) -> list[tuple]:
        """Mode, λ, starts, class counts, whether both outcomes occur, λ1, λ2."""
        return [("mode", self.mode, ""), ("lam", self.lam, "1"),
                ("starts", int(self.steady_state.size), "1"),
                ("class_counts", self.class_counts, "1"),
                ("both_outcomes", self.summary()["both_outcomes"], ""),
                ("lambda1", self.lambda1, "1"), ("lambda2", self.lambda2, "1"),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """``summary.json`` of ``slipcycle basins`` (units: :data:`SUMMARY_UNITS`).

        Returns
        -------
        dict
            ``mode``, ``lam``, ``lambda1``, ``lambda2``, ``starts``, ``class_counts``,
            ``dissipation_per_cycle`` {min, max} [J] over admissible starts,
            ``both_outcomes``, ``steady_state_codes``, ``wall_time_s`` [s], for a grid
            ``boundary_box_counting_dimension``, ``box_counting`` and ``grid``; ``units``.
        """
        cls = self.steady_state
        adm = cls != INADMISSIBLE
        D = self.data["dissipation_per_cycle"]
        summary = {"model": "discrete", "analysis": "basins", "mode": self.mode,
                   "lam": self.lam, "n_nodes": self.n_nodes, "lambda1": self.lambda1,
                   "lambda2": self.lambda2, "starts": int(cls.size),
                   "class_counts": self.class_counts,
                   "dissipation_per_cycle": {
                       "min": float(np.nanmin(D[adm])) if adm.any() else None,
                       "max": float(np.nanmax(D[adm])) if adm.any() else None},
                   "both_outcomes": bool((cls == 0).any() and (cls == 1).any()),
                   "steady_state_codes": list(STEADY_STATES), "wall_time_s": self.wall_time_s,
                   "units": dict(SUMMARY_UNITS)}
        if self.mode == "grid":
            summary["boundary_box_counting_dimension"] = self.box_counting["dimension"]
            summary["box_counting"] = self.box_counting
            summary["grid"] = [int(self.v1.size), int(self.v2.size)]
        return summary

    def _build_dataset(self) -> xr.Dataset:
        """Class codes, dissipation [J], cycles run, slipping nodes, memory erased and
        ``converged`` over the starts ((v2, v1) [m] for a grid, else the sweep axis).

        The only place the Dataset of a basins study is built.

        Returns
        -------
        xarray.Dataset
        """
        if self.mode != "grid":
            return self.store_dataset()
        attrs, g = self.record_attrs(), ("v2", "v1")
        data = {name: (g + ("node",) if name == "dissipation_per_node" else g,
                       self.data[name], a) for name, a in attrs.items()}
        data["converged"] = (g, self.converged, CONVERGED_ATTRS)
        return xr.Dataset(
            data,
            coords={"v1": ("v1", self.v1, {"units": "m",
                                           "long_name": "initial slip of node 0"}),
                    "v2": ("v2", self.v2, {"units": "m",
                                           "long_name": "initial slip of node 1"})})

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """``basin_map`` (grid only): classes and dissipation over (v1, v2) with the safe
        region.

        Returns
        -------
        dict of str to callable
        """
        if self.mode != "grid":
            return {}
        return {"basin_map": lambda: basin_map(self.v1, self.v2, self.steady_state,
                                               self.data["dissipation_per_cycle"],
                                               self.region, self.lam)}
