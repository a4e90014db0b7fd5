"""Basins of attraction: steady state versus initial condition (Ahn, Bertocchi & Barber
2008; Andersson, Barber & Ahn 2013).

For a coupled system the steady state depends on the initial condition (Ahn, Bertocchi &
Barber 2008; Andersson, Barber & Ahn 2013). This module holds the engine of its maps:

- :func:`run_record` / :func:`run_records` — steady-state runs as flat records of numbers
  (class code, dissipation, slipping nodes, memory erased), using the compiled contact-only
  kernel of :mod:`~slipcycle.discrete.fastcycle` where it applies and the general solver
  :func:`~slipcycle.discrete.steady.simulate` otherwise (assembly protocols, separation);
- :func:`basin_row` — one row of an N = 2 map over a (v1, v2) grid of initial slip states
  at θ = 0; :func:`admissible_box` — the box of admissible starts;
- :func:`box_counting_dimension` — dimension of the boundaries between classes (fractal
  basin boundaries near unstable orbits).

The study of ``slipcycle basins`` (sweep tasks, store, summary, Dataset, basin map) is
:mod:`slipcycle.studies.basins`.

Class codes are the positions in :data:`slipcycle.result.STEADY_STATES`, the one list of
steady-state words.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

from slipcycle.discrete.fastcycle import steady_states_batch
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import FrictionalSystem
from slipcycle.discrete.shakedown import admissible_region_at
from slipcycle.discrete.steady import InadmissibleInitialState, simulate
from slipcycle.result import STEADY_STATES

__all__ = ["run_record", "run_records", "basin_row", "admissible_box",
           "box_counting_dimension", "class_code", "empty_record", "INADMISSIBLE"]

INADMISSIBLE = STEADY_STATES.index("inadmissible")


def class_code(state: str) -> int:
    """Integer code of a steady-state class (see module docstring)."""
    return STEADY_STATES.index(state) if state in STEADY_STATES else STEADY_STATES.index("failed")


def empty_record(n: int, code: int) -> dict:
    """The record of a start that did not run (code ``code``: inadmissible, failed)."""
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
            rec = empty_record(n, INADMISSIBLE)
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
        return empty_record(n, INADMISSIBLE)
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
