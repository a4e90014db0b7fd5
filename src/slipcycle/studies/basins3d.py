"""``slipcycle basins`` for ``model = "discrete3d"`` cases: steady state over initial
conditions as a resumable study.

The same question as :mod:`~slipcycle.discrete3d.basins` (which cycle does a coupled
system reach from a given start? Andersson, Barber & Ahn 2013; Barber 2012, §3.1), run
through the sweep engine (:func:`slipcycle.sweep.run_sweep`: a Zarr store, ``--resume``,
``--workers``): every start is one cell, run to its steady state by
:func:`~slipcycle.discrete3d.steady.simulate3d`, the one engine of the model. Starts are
random initial slips admissible at θ = 0 (:func:`~slipcycle.discrete3d.basins.random_starts`,
in a box of half-width :func:`start_scale`) or assembly protocols
(:func:`~slipcycle.studies.common.read_protocols`).

Class codes are the positions in :data:`slipcycle.result.STEADY_STATES` (:data:`STEADY_CODES`),
as in every store of the project.
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

from slipcycle.discrete3d.basins import distinct_values, random_starts
from slipcycle.discrete3d.case import read_discrete3d_case
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.steady import InadmissibleInitialState3D, simulate3d
from slipcycle.errors import SolverError
from slipcycle.io import Case, CaseError
from slipcycle.loading.nodal import force_scale
from slipcycle.plot.interface3d import basin_dissipation
from slipcycle.result import STEADY_STATES
from slipcycle.studies.common import BasinsStudyResult, model_case, read_protocols
from slipcycle.sweep import Axis, SweepError, run_sweep
from slipcycle.sweep.dataset import StudyStatus, as_case_error

__all__ = ["STEADY_CODES", "Basins3DResult", "basins3d_study",
           "run_record3d", "start_scale", "load_discrete3d_case"]

#: class codes of the study's ``steady_state``: the one list of steady-state words,
#: :data:`slipcycle.result.STEADY_STATES` (the codes of the 2-D studies too)
STEADY_CODES = STEADY_STATES

#: fraction of the displacement scale F/k (largest load over the largest stiffness) that
#: bounds each random initial slip component
START_SCALE = 0.2

SUMMARY_UNITS = {
    "lam": "1", "n_nodes": "1", "starts": "1", "class_counts": "1",
    "dissipation_per_cycle.min": "J", "dissipation_per_cycle.max": "J",
    "attractors": "J", "both_outcomes": "1", "start_scale": "m", "wall_time_s": "s",
}
SUMMARY_FLAGS = {"mode": ("random", "protocols")}


def _code(state: str) -> int:
    return STEADY_CODES.index(state)


def run_record3d(system: FrictionalSystem3D, load: Load3D, *, initial_slip=None,
                 protocol=None, **run) -> dict:
    """One run to the steady state as a record of numbers.

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
    initial_slip : (N, 2) array, optional
        Slip at θ = 0 [m].
    protocol : (S, 3N) array, optional
        Assembly load states [q^w, p^w] [N].
    **run
        Settings of :func:`~slipcycle.discrete3d.steady.simulate3d`.

    Returns
    -------
    dict
        ``steady_state`` (code of :data:`STEADY_CODES`), ``dissipation_per_cycle`` [J],
        ``dissipation_per_node`` (N,) [J], ``cycles_run``, ``residual`` [1],
        ``n_slipping``, ``n_separating``, ``memory_erased``.
    """
    n = system.n_nodes
    try:
        res = simulate3d(system, load, initial_slip=initial_slip, protocol=protocol,
                         record=False, **run)
    except (InadmissibleInitialState3D, SolverError) as exc:
        code = _code("inadmissible" if isinstance(exc, InadmissibleInitialState3D)
                     else "failed")
        return {"steady_state": code, "dissipation_per_cycle": np.nan,
                "dissipation_per_node": np.full(n, np.nan), "cycles_run": 0,
                "residual": np.nan, "n_slipping": -1, "n_separating": -1,
                "memory_erased": False}
    return {"steady_state": _code(res.steady_state),
            "dissipation_per_cycle": res.dissipation_per_cycle,
            "dissipation_per_node": np.asarray(res.dissipation_per_node, float),
            "cycles_run": res.cycles_run, "residual": float(res.residual),
            "n_slipping": len(res.slipping_nodes),
            "n_separating": len(res.separating_nodes),
            "memory_erased": bool(res.all_slip_or_separated)}


def start_scale(system: FrictionalSystem3D, load: Load3D, steps_per_cycle: int) -> float:
    """Half-width [m] of the box of random initial slips: :data:`START_SCALE` × F/k (F the
    largest load over the cycle samples, k the largest diagonal stiffness)."""
    vals = load.cycle_samples(steps_per_cycle)[1]
    return START_SCALE * force_scale(vals) / system.stiffness_scale()


# --- sweep tasks (module level: picklable for process pools and Dask) ------------------
@functools.lru_cache(maxsize=8)
def load_discrete3d_case(case_text: str, case_path: str | None):
    """The validated :class:`~slipcycle.discrete3d.case.Discrete3DCase` of a case text
    (cached per process). Tables other than the model's (e.g. ``[basins]``) are ignored."""
    return read_discrete3d_case(model_case(case_text, case_path, (
        "model", "title", "description", "discrete3d", "loading", "run", "output")))


def _run(dc) -> dict:
    return dict(dc.run)


def start_task(params: dict, case_text: str, case_path, V: tuple, lam: float) -> dict:
    """Sweep task: steady state from initial slip ``V[params["index"]]`` ((N, 2) [m])."""
    dc = load_discrete3d_case(case_text, case_path)
    v = np.asarray(V[int(params["index"])], float)
    return run_record3d(dc.system, dc.load.with_lam(lam), initial_slip=v, **_run(dc))


def protocol_task(params: dict, case_text: str, case_path, protocols: tuple, lam: float
                  ) -> dict:
    """Sweep task: steady state after assembly protocol ``params["index"]``."""
    dc = load_discrete3d_case(case_text, case_path)
    p = np.asarray(protocols[int(params["index"])], float)
    return run_record3d(dc.system, dc.load.with_lam(lam), protocol=p, **_run(dc))


def basins3d_study(case: Case, out, *, grid: int | None = None, random: int | None = None,
                   protocols: Path | None = None, v1_range: str | None = None,
                   v2_range: str | None = None, lam: float | None = None, seed: int = 0,
                   workers: int | None = None, scheduler=None, resume: bool = False,
                   progress: bool = True, stop_after: int | None = None) -> StudyStatus:
    """Steady state (class, dissipation per cycle) of a ``discrete3d`` case over initial
    conditions.

    At most one of ``random`` and ``protocols`` (default 16 random starts); ``grid``,
    ``v1_range`` and ``v2_range`` (the 2-D model's map over two scalar slips) are refused.

    Parameters
    ----------
    case : Case
        A ``model = "discrete3d"`` case (its ``initial_slip``/``protocol`` are replaced by
        the starts).
    out : path
        Directory of the store ``basins.zarr``.
    random : int, optional
        Random initial slips admissible at θ = 0, each component uniform in
        ±:func:`start_scale` (``seed``).
    protocols : Path, optional
        TOML file of assembly protocols (:func:`~slipcycle.studies.common.read_protocols`).
    lam : float, optional
        Load factor λ (default the case's ``loading.lam``).
    workers, scheduler, resume, progress, stop_after
        See :func:`~slipcycle.sweep.core.run_sweep`.

    Returns
    -------
    StudyStatus
        ``result`` (:class:`Basins3DResult`) and ``outputs`` once every cell is done.

    Raises
    ------
    CaseError
        A bad option (named by its command-line spelling) before any simulation.
    """
    out = Path(out)
    for key, value in (("--grid", grid), ("--v1", v1_range), ("--v2", v2_range)):
        if value is not None:
            raise CaseError(key, "maps two scalar slips of the 2-D model; a discrete3d case "
                                 "takes --random or --protocols")
    if random is not None and protocols is not None:
        raise CaseError("--random", "give either --random or --protocols, not both")
    cpath = str(case.path) if case.path else None
    dc = load_discrete3d_case(case.text, cpath)
    n = dc.system.n_nodes
    if lam is not None and not (np.isfinite(lam) and lam >= 0):
        raise CaseError("--lam", f"must be a finite number >= 0, got {lam}")
    lam = float(lam) if lam is not None else float(getattr(dc.load.p, "lam", 1.0))
    load = dc.load.with_lam(lam)
    scale = None
    if protocols is None:
        mode = "random"
        count = 16 if random is None else random
        if count < 1:
            raise CaseError("--random", f"must be >= 1, got {count}")
        scale = start_scale(dc.system, load, dc.run["steps_per_cycle"])
        try:
            V = random_starts(dc.system, load, count, scale, seed=seed)
        except ValueError as exc:
            raise CaseError("--random", str(exc)) from None
        fn = partial(start_task, case_text=case.text, case_path=cpath,
                     V=tuple(v.tolist() for v in V), lam=lam)
        axes = [Axis("index", tuple(range(count)))]
        desc = {"mode": mode, "lam": lam, "V": V.tolist()}
    else:
        mode = "protocols"
        protos = read_protocols(protocols, n, pairs=True)
        fn = partial(protocol_task, case_text=case.text, case_path=cpath,
                     protocols=tuple(p.tolist() for p in protos), lam=lam)
        axes = [Axis("index", tuple(range(len(protos))))]
        desc = {"mode": mode, "lam": lam, "protocols": [p.tolist() for p in protos]}
    t0 = time.perf_counter()
    try:
        store = run_sweep(fn, axes, out / "basins.zarr",
                          description={"case": case.text, **desc}, resume=resume,
                          workers=workers, scheduler=scheduler, progress=progress,
                          stop_after=stop_after, desc="basins")
    except SweepError as exc:
        raise as_case_error(exc) from None
    wall = time.perf_counter() - t0
    done = store.done()
    if not done.all():
        return StudyStatus(None, int(done.sum()), int(done.size))
    result = Basins3DResult(wall_time_s=wall, mode=mode, lam=lam, n_nodes=n,
                            data=store.read(), store=store, axes=tuple(axes),
                            start_scale=scale)
    return StudyStatus(result.to_outputs(), int(done.size), int(done.size), result)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class Basins3DResult(BasinsStudyResult):
    """Steady state of a ``discrete3d`` case over initial conditions (``slipcycle basins``).

    Attributes
    ----------
    wall_time_s : float
        Wall time of the runs in this call [s].
    mode : str
        ``random`` or ``protocols``.
    lam : float
        Load factor λ of the runs [1].
    n_nodes : int
        Nodes N of the system.
    data : dict of str to ndarray
        The stored outputs over the starts (leading axis: start): ``steady_state`` (codes
        of :data:`STEADY_CODES`), ``dissipation_per_cycle`` [J], ``dissipation_per_node``
        [J] (last axis: node), ``cycles_run``, ``residual``, ``n_slipping``,
        ``n_separating``, ``memory_erased``.
    store : SweepStore
        The store the runs were kept in (the Dataset is read from it).
    axes : tuple of Axis
        The sweep axes of ``store``.
    start_scale : float or None
        Half-width of the box of random initial slips [m] (random starts only).
    """

    model: ClassVar[str] = "discrete3d"
    FLAGS: ClassVar[dict] = SUMMARY_FLAGS

    start_scale: float | None = None

    def attractors(self, rtol: float = 1e-6) -> list[float]:
        """Distinct steady dissipations per cycle (within ``rtol`` of the largest) over the
        starts that converged [J]."""
        D = np.asarray(self.data["dissipation_per_cycle"], float)
        return distinct_values(D[self.converged], rtol)

    def headline(self) -> list[tuple]:
        """Mode, λ, starts, class counts, distinct steady dissipations."""
        return [("mode", self.mode, ""), ("lam", self.lam, "1"),
                ("starts", int(self.steady_state.size), "1"),
                ("class_counts", self.class_counts, "1"),
                ("attractors", self.attractors(), "J"),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """``summary.json`` of ``slipcycle basins`` for a ``discrete3d`` case.

        Returns
        -------
        dict
            ``mode``, ``lam``, ``n_nodes``, ``starts``, ``class_counts``,
            ``dissipation_per_cycle`` {min, max} [J] over the converged starts,
            ``attractors`` [J], ``both_outcomes`` (shakedown and cyclic slip both
            reached), ``steady_state_codes``, ``start_scale`` [m], ``wall_time_s`` [s];
            ``units``.
        """
        cls = self.steady_state
        ok = self.converged
        D = np.asarray(self.data["dissipation_per_cycle"], float)
        return {"model": self.model, "analysis": self.analysis, "mode": self.mode,
                "lam": self.lam, "n_nodes": self.n_nodes, "starts": int(cls.size),
                "class_counts": self.class_counts,
                "dissipation_per_cycle": {
                    "min": float(np.min(D[ok])) if ok.any() else None,
                    "max": float(np.max(D[ok])) if ok.any() else None},
                "attractors": self.attractors(),
                "both_outcomes": bool((cls == 0).any() and (cls == 1).any()),
                "steady_state_codes": list(STEADY_CODES),
                "start_scale": self.start_scale, "wall_time_s": self.wall_time_s,
                "units": dict(SUMMARY_UNITS)}

    def _build_dataset(self) -> xr.Dataset:
        """Class codes, dissipation [J], cycles run, residual, slipping and separating
        nodes, memory erased and ``converged`` over the starts.

        Returns
        -------
        xarray.Dataset
        """
        return self.store_dataset(residual="1", n_separating="1")

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """``basin_dissipation``: dissipation per cycle reached from every start, coloured
        by class.

        Returns
        -------
        dict of str to callable
        """
        return {"basin_dissipation": lambda: basin_dissipation(
            self.steady_state, np.asarray(self.data["dissipation_per_cycle"], float),
            STEADY_CODES, self.lam)}
