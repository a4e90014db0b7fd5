"""Basins of attraction: steady state versus initial condition (SPEC §2, seed 001 §3.1).

For a coupled system the steady state depends on the initial condition (Ahn, Bertocchi &
Barber 2008; Andersson, Barber & Ahn 2013). This module maps it:

- :func:`run_record` — one steady-state run as a flat record of numbers (class code,
  dissipation, slipping nodes, memory erased), using the compiled contact-only kernel of
  :mod:`~slipcycle.discrete.fastcycle` where it applies and the general solver
  :func:`~slipcycle.discrete.steady.simulate` otherwise (assembly protocols, separation);
- :func:`basin_row` / :func:`basin_grid_axes` — N = 2 maps over a (v1, v2) grid of initial
  slip states at θ = 0, one grid row per sweep cell (:mod:`slipcycle.sweep`);
- :func:`initial_conditions_task` — any N: a list of protocols or random admissible states;
- :func:`box_counting_dimension` — dimension of the boundaries between classes (fractal
  basin boundaries near unstable orbits, seed 001 §3.1).

Class codes are :data:`slipcycle.sweep.case.STEADY_CODES`:
0 shakedown, 1 cyclic_slip, 2 ratcheting, 3 not_converged, 4 inadmissible, 5 failed.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.optimize import linprog

from slipcycle.discrete.fastcycle import steady_states_batch
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import FrictionalSystem
from slipcycle.discrete.shakedown import admissible_region_at, sample_initial_slips
from slipcycle.discrete.steady import InadmissibleInitialState, simulate
from slipcycle.sweep.case import STEADY_CODES

__all__ = ["run_record", "run_records", "basin_row", "admissible_box",
           "box_counting_dimension", "class_code", "load_discrete_case",
           "basin_row_task", "lam_start_task"]

INADMISSIBLE = STEADY_CODES.index("inadmissible")


def class_code(state: str) -> int:
    """Integer code of a steady-state class (see module docstring)."""
    return STEADY_CODES.index(state) if state in STEADY_CODES else STEADY_CODES.index("failed")


def _empty_record(n: int, code: int) -> dict:
    return {"steady_state": code, "dissipation_per_cycle": np.nan,
            "dissipation_per_node": np.full(n, np.nan), "cycles_run": 0,
            "residual": np.nan, "n_slipping": -1, "memory_erased": False}


def _from_simulate(res) -> dict:
    return {"steady_state": class_code(res.steady_state),
            "dissipation_per_cycle": res.dissipation_per_cycle,
            "dissipation_per_node": np.asarray(res.dissipation_per_node, float),
            "cycles_run": res.cycles_run, "residual": float(res.residual),
            "n_slipping": len(res.slipping_nodes),
            "memory_erased": bool(res.all_slip_or_separated)}


def run_records(system: FrictionalSystem, load: DiscreteLoad, V0, *, cycles: int = 40,
                steps_per_cycle: int = 100, tol: float = 1e-8, min_cycles: int = 1) -> dict:
    """Steady states from many initial slip states (M, N) [m] at θ = 0.

    Runs the compiled kernel on all of them; those it does not handle (a node separates)
    are re-run with :func:`simulate`; inadmissible starts get code 4.

    Returns
    -------
    dict of arrays with a leading dimension M: ``steady_state`` (int code),
    ``dissipation_per_cycle`` [J], ``dissipation_per_node`` (M, N) [J], ``cycles_run``,
    ``residual``, ``n_slipping``, ``memory_erased``.
    """
    n = system.n_nodes
    V0 = np.atleast_2d(np.asarray(V0, float))
    run = {"cycles": cycles, "steps_per_cycle": steps_per_cycle, "tol": tol,
           "min_cycles": min_cycles}
    b = steady_states_batch(system, load, V0, **run)
    out = {
        "steady_state": np.array([class_code(s) for s in b["steady_state"]], np.int64),
        "dissipation_per_cycle": b["dissipation_per_node"].sum(axis=1),
        "dissipation_per_node": b["dissipation_per_node"].copy(),
        "cycles_run": b["cycles_run"].astype(np.int64),
        "residual": b["residual"].copy(),
        "n_slipping": b["slipping"].sum(axis=1).astype(np.int64),
        "memory_erased": b["memory_erased"].copy(),
    }
    for i in np.flatnonzero(b["code"] < 0):
        if b["steady_state"][i] == "inadmissible":
            rec = _empty_record(n, INADMISSIBLE)
        else:
            rec = run_record(system, load, initial_slip=V0[i], engine="general", **run)
        for k, v in rec.items():
            out[k][i] = v
    return out


def run_record(system: FrictionalSystem, load: DiscreteLoad, *, initial_slip=None,
               protocol=None, engine: str = "auto", cycles: int = 40,
               steps_per_cycle: int = 100, tol: float = 1e-8, min_cycles: int = 1) -> dict:
    """One steady-state run as a record of numbers (see :func:`run_records`).

    ``engine``: ``auto`` (compiled kernel for an initial slip state, general solver for
    assembly protocols and as fallback), ``general`` (always :func:`simulate`).
    """
    n = system.n_nodes
    run = {"cycles": cycles, "steps_per_cycle": steps_per_cycle, "tol": tol,
           "min_cycles": min_cycles}
    if initial_slip is not None and engine == "auto":
        out = run_records(system, load, np.asarray(initial_slip, float)[None], **run)
        return {k: (v[0] if np.ndim(v) else v) for k, v in out.items()}
    try:
        res = simulate(system, load, initial_slip=initial_slip, protocol=protocol,
                       record=False, **run)
    except InadmissibleInitialState:
        return _empty_record(n, INADMISSIBLE)
    return _from_simulate(res)


def admissible_box(system: FrictionalSystem, load: DiscreteLoad, pad: float = 0.05
                   ) -> np.ndarray:
    """Bounding box (N, 2) [m] of the slip states admissible at θ = 0 with all nodes in
    contact (2N LPs), padded by ``pad`` of its width; NaN rows if none is admissible."""
    n = system.n_nodes
    G, b = admissible_region_at(system, load, 0.0)
    box = np.full((n, 2), np.nan)
    for i in range(n):
        for k, sgn in enumerate((1.0, -1.0)):
            c = np.zeros(n)
            c[i] = sgn
            res = linprog(c, A_ub=G, b_ub=b, bounds=[(None, None)] * n, method="highs")
            if res.status == 0:
                box[i, k] = res.x[i]
    w = box[:, 1] - box[:, 0]
    return np.column_stack([box[:, 0] - pad * w, box[:, 1] + pad * w])


def basin_row(system: FrictionalSystem, load: DiscreteLoad, v1: np.ndarray, v2: float,
              **run) -> dict:
    """One row of an N = 2 basin map: starts (v1[i], v2), i = 0..n1−1 (see
    :func:`run_records`)."""
    v1 = np.asarray(v1, float)
    V0 = np.column_stack([v1, np.full(v1.size, float(v2))])
    return run_records(system, load, V0, **run)


# --- sweep tasks (module level: picklable for process pools and Dask) ------------------
@functools.lru_cache(maxsize=8)
def load_discrete_case(case_text: str, case_path: str | None):
    """The validated :class:`~slipcycle.discrete.case.DiscreteCase` of a case text
    (cached per process). Tables other than the model's (e.g. ``[basins]``) are ignored."""
    from pathlib import Path

    from slipcycle.discrete.case import read_discrete_case
    from slipcycle.io.case import Case, parse_case_text

    base = parse_case_text(case_text, Path(case_path) if case_path else None)
    data = {k: v for k, v in base.data.items()
            if k in ("model", "title", "description", "discrete", "loading", "run")}
    return read_discrete_case(Case(base.model, data, case_text, base.path), record=False)


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
            rec = _empty_record(n, INADMISSIBLE)
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


# --- box counting ---------------------------------------------------------------------
def box_counting_dimension(labels: np.ndarray, min_boxes: int = 4,
                           valid: np.ndarray | None = None) -> dict:
    """Box-counting dimension of the boundaries between classes of a 2-D label map.

    A cell is a boundary cell if a 4-neighbour has another label (both cells ``valid``:
    the edge of the admissible region is not a basin boundary). For box sizes
    s = 1, 2, 4, … (cells), N(s) boxes contain boundary cells; the dimension is the slope
    of log N(s) against log(1/s) (least squares over sizes with at least ``min_boxes``
    boxes across). A smooth boundary gives ≈ 1, a space-filling (fractal) one up to 2.

    Parameters
    ----------
    labels : (n1, n2) int array
    valid : (n1, n2) bool array, optional
        Cells that take part (default all), e.g. the admissible starts.

    Returns
    -------
    dict
        ``dimension`` (float, NaN without boundary), ``sizes``, ``counts``,
        ``boundary_cells``.
    """
    L = np.asarray(labels)
    ok = np.ones(L.shape, bool) if valid is None else np.asarray(valid, bool)
    edge = np.zeros(L.shape, bool)
    dx = (L[1:, :] != L[:-1, :]) & ok[1:, :] & ok[:-1, :]
    dy = (L[:, 1:] != L[:, :-1]) & ok[:, 1:] & ok[:, :-1]
    edge[1:, :] |= dx
    edge[:-1, :] |= dx
    edge[:, 1:] |= dy
    edge[:, :-1] |= dy
    nb = int(edge.sum())
    sizes, counts = [], []
    s = 1
    while min(L.shape) // s >= min_boxes:
        n1, n2 = -(-L.shape[0] // s), -(-L.shape[1] // s)
        pad = np.zeros((n1 * s, n2 * s), bool)
        pad[:L.shape[0], :L.shape[1]] = edge
        c = int(pad.reshape(n1, s, n2, s).any(axis=(1, 3)).sum())
        sizes.append(s)
        counts.append(c)
        s *= 2
    sizes, counts = np.array(sizes), np.array(counts)
    ok = counts > 0
    if nb == 0 or ok.sum() < 2:
        return {"dimension": float("nan"), "sizes": sizes.tolist(),
                "counts": counts.tolist(), "boundary_cells": nb}
    slope = np.polyfit(np.log(1.0 / sizes[ok]), np.log(counts[ok]), 1)[0]
    return {"dimension": float(slope), "sizes": sizes.tolist(), "counts": counts.tolist(),
            "boundary_cells": nb}
