"""The shakedown study of a discrete case: safe region, λ1, λ2 and λ3/λ4 brackets from a
scan over λ and initial conditions, narrowed by checkpointed bisection (``slipcycle
shakedown``).

The safe shakedown region S(λ) and λ1, λ2 come from linear programs
(:mod:`slipcycle.discrete.shakedown`; Klarbring, Ciavarella & Barber 2007; Ahn, Bertocchi
& Barber 2008). λ3 (every node slips in every steady cycle) and λ4 (all nodes slip or
separate at one instant) are bracketed by simulations over ``lam_points`` values of λ in
[0, ``lam_max``] and ``starts`` random admissible initial slips plus the case's own
initial condition (Andersson, Barber & Ahn 2013: the steady state depends on the start).
The scan goes through the sweep engine (``out/scan.zarr``, resumable, local processes or
Dask); the grid brackets are then bisected in λ to ``lam_tol`` × ``lam_max``, each trial λ
simulated from the same starts, its runs checkpointed in ``out/refine.json`` after every
step so that a resumed study does not recompute them.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import ClassVar

import numpy as np
import xarray as xr

from slipcycle.coupled.sizes import cells_bytes, check_memory
from slipcycle.discrete.basins import run_record
from slipcycle.discrete.shakedown import (
    constraint_names,
    lambda1,
    lambda2,
    polygon_vertices,
    refine_brackets,
    safe_region,
    sample_initial_slips,
    simulation_brackets,
)
from slipcycle.discrete.steady import simulate
from slipcycle.io import Case, CaseError
from slipcycle.plot import shakedown as plots
from slipcycle.result import STEADY_STATES, StudyResult
from slipcycle.studies.basins import lam_start_task, load_discrete_case
from slipcycle.sweep import Axis, SweepError, run_sweep
from slipcycle.sweep.core import TaskRunner, fingerprint
from slipcycle.sweep.dataset import StudyStatus, as_case_error

__all__ = ["shakedown_study", "ShakedownResult", "check_sizes", "TrialRuns", "SUMMARY_UNITS",
           "SUMMARY_FLAGS"]

#: unit of every numeric summary entry (λ values are load factors: "1"; nested entries
#: by their path)
SUMMARY_UNITS = {
    "n_nodes": "1", "lambda1": "1", "lambda1_bracket": "1", "lambda2": "1",
    "lambda3_bracket": "1", "lambda4_bracket": "1", "lambda3_grid_bracket": "1",
    "lambda4_grid_bracket": "1", "constraints.G": "N/m", "constraints.h0": "N",
    "constraints.m": "N", "constraints.theta_extreme": "rad", "last_safe_state": "m",
    "lam": "1", "dissipation_per_cycle": "J", "refinement_runs": "1",
    "refinement.lam_tol": "1", "refinement.lam_tol_relative": "1",
    "refinement.trial_lam": "1", "refinement.runs": "1", "refinement.runs_computed": "1",
    "scan.lam": "1", "scan.starts": "1", "scan.seed": "1", "linear_programs": "1",
    "lp_wall_time_s": "s", "safe_region_vertices": "m", "refinement.steps": "1",
    "scan.class_counts": "1",
    **{f"{b}_evidence.{k}": u for b in ("lambda3", "lambda4") for k, u in (
        ("lam", "1"), ("dissipation_per_cycle", "J"), ("n_slipping", "1"),
        ("memory_erased", "1"), ("cycles_run", "1"))},
}

#: every word of the categorical summary entries
SUMMARY_FLAGS = {
    "steady_state": STEADY_STATES,
    "regime": ("below_lambda1", "between_lambda1_and_lambda2", "above_lambda2"),
    "extreme_method": ("constant", "exact_single_harmonic", "breakpoints",
                       "harmonic_refined", "sampled_refined"),
}


def _panels(dc, region, l1, l2, lam_case, seed):
    """Trajectory panels (N = 2): below λ1, between λ1 and λ2 (or the case λ), above λ2."""
    lams = []
    if np.isfinite(l1) and l1 > 0:
        lams.append(0.7 * l1)
    if np.isfinite(l2) and l2 > l1:
        lams.append(lam_case if l1 < lam_case < l2 else 0.5 * (l1 + l2))
    if np.isfinite(l2):
        lams.append(1.15 * l2 if l2 > 0 else 0.5)
    run = dc.run
    panels = []
    for lam in lams:
        load = dc.load.with_lam(lam)
        V = sample_initial_slips(dc.system, load, 5, seed=seed)
        P = polygon_vertices(region, lam)
        if len(P) >= 3:                       # one start inside the safe region
            V = np.vstack([V[:4], P.mean(axis=0)[None]])
        traj = []
        for v0 in V:
            res = simulate(dc.system, load, initial_slip=v0, cycles=min(run["cycles"], 30),
                           steps_per_cycle=min(run["steps_per_cycle"], 200), tol=run["tol"])
            v = np.vstack([v0[None], res.x[:, :, :2].reshape(-1, 2)])
            traj.append((v, res.steady_state))
        panels.append({"lam": lam, "trajectories": traj})
    return panels


def shakedown_study(case: Case, out, *, lam_max: float | None = None, lam_points: int = 21,
                    starts: int = 8, seed: int = 0, tol: float = 1e-9, lam_tol: float = 1e-3,
                    workers: int | None = None, scheduler=None, resume: bool = False,
                    progress: bool = True, stop_after: int | None = None) -> StudyStatus:
    """Safe region, λ1, λ2 and refined λ3/λ4 brackets of a discrete case.

    Parameters
    ----------
    case : Case
        A ``model = "discrete"`` case (its own λ is ``loading.lam``).
    out : path
        Directory of the scan store ``scan.zarr`` and the checkpoint ``refine.json``.
    lam_max : float, optional
        Largest λ simulated (default 2 λ2, or max(2 λ, 1) when λ2 is not finite or 0).
    lam_points : int
        λ values of the scan, >= 2.
    starts : int
        Random admissible initial slips per λ (plus the case's own start), >= 0.
    seed : int
        Seed of the random starts (the same stream at every λ).
    tol : float
        Relative tolerance of λ1, in (0, 1).
    lam_tol : float
        Width to which the λ3/λ4 brackets are bisected, relative to ``lam_max``, in
        (0, 1] (1: no refinement).
    workers, scheduler, resume, progress, stop_after
        See :func:`~slipcycle.sweep.core.run_sweep`; ``resume`` also re-uses the trial
        runs of ``refine.json``.

    Returns
    -------
    StudyStatus
        ``result`` (:class:`ShakedownResult`) and ``outputs`` (``result.to_outputs()``)
        once the scan is complete: ``summary`` (``lambda1``, ``lambda2``,
        ``lambda3_bracket``, ``lambda4_bracket`` refined, the grid brackets, the extreme
        constraints, the evidence runs, ``refinement``, ``scan``, the case's own run,
        ``units``: :data:`SUMMARY_UNITS`), ``dataset`` (classes and dissipation over
        (lam, start) and (trial_lam, start), G, h0, m, θ extreme) and ``figures``
        (``dissipation_vs_lambda``; for N = 2 ``safe_region_panels``). None while scan
        cells are missing (``stop_after``).

    Raises
    ------
    CaseError
        A bad option (named by its command-line spelling, e.g. ``--lam-points``), a scan
        too large for memory, or a refused store, before any simulation.
    """
    out = Path(out)
    cpath = str(case.path) if case.path else None
    dc = load_discrete_case(case.text, cpath)
    if lam_points < 2:
        raise CaseError("--lam-points", f"must be >= 2, got {lam_points}")
    if starts < 0:
        raise CaseError("--starts", f"must be >= 0, got {starts}")
    if lam_max is not None and not (np.isfinite(lam_max) and lam_max > 0):
        raise CaseError("--lam-max", f"must be a finite number > 0, got {lam_max}")
    if not 0 < tol < 1:
        raise CaseError("--tol", f"must be in (0, 1), got {tol}")
    if not (np.isfinite(lam_tol) and 0 < lam_tol <= 1):
        raise CaseError("--lam-tol", f"must be in (0, 1] (a fraction of lam_max), got "
                        f"{lam_tol}")
    n = dc.system.n_nodes
    check_sizes(n, lam_points, starts, lam_tol)
    t0 = time.perf_counter()
    region = safe_region(dc.system, dc.load)
    l2, v_last = lambda2(region)
    l1info = lambda1(region, l2, tol=tol)
    l1 = l1info["lambda1"]
    t_lp = time.perf_counter() - t0
    lam_case = float(dc.load.p.lam)
    lam_max = lam_max or (2.0 * l2 if np.isfinite(l2) and l2 > 0 else
                          max(2.0 * lam_case, 1.0))
    lams = tuple(np.linspace(0.0, lam_max, lam_points).tolist())
    axes = [Axis("lam", lams), Axis("start", tuple(range(starts + 1)))]
    fn = partial(lam_start_task, case_text=case.text, case_path=cpath,
                 n_random=starts, seed=seed)
    lam_tol_abs = lam_tol * lam_max
    ckpt = out / "refine.json"
    # one pool (or Dask client) for the scan and the bisection
    with TaskRunner(workers, scheduler) as runner:
        try:
            store = run_sweep(fn, axes, out / "scan.zarr",
                              description={"case": case.text, "lams": lams,
                                           "starts": starts, "seed": seed},
                              resume=resume, runner=runner,
                              progress=progress, stop_after=stop_after,
                              desc="λ scan", group_by=("lam",))
        except SweepError as exc:
            raise as_case_error(exc) from None
        done = store.done()
        if not done.all():
            return StudyStatus(None, int(done.sum()), int(done.size))
        data = store.read()
        cls = data["steady_state"]
        recs = []
        for i, lam in enumerate(lams):
            for s in range(starts + 1):
                if cls[i, s] == STEADY_STATES.index("inadmissible"):
                    continue
                recs.append((lam, _label(s), _record({k: v[i, s] for k, v in data.items()})))
        br = simulation_brackets(recs, n)
        trials = TrialRuns(runner, fn, starts, ckpt, {
            "case": case.text, "starts": starts, "seed": seed}, resume,
            progress)
        ref = refine_brackets(br, trials, lam_tol_abs, n)
    trial_lams = sorted(ref.trials)

    own = run_record(dc.system, dc.load, initial_slip=dc.initial_slip, protocol=dc.protocol,
                     **{"cycles": dc.run["cycles"], "steps_per_cycle":
                        dc.run["steps_per_cycle"], "tol": dc.run["tol"],
                        "min_cycles": dc.run["min_cycles"]})
    regime = ("below_lambda1" if lam_case < l1 else
              "between_lambda1_and_lambda2" if lam_case <= l2 else "above_lambda2")
    names = constraint_names(n)
    result = ShakedownResult(
        wall_time_s=time.perf_counter() - t0, n_nodes=n, lambda1=l1,
        lambda1_bracket=tuple(l1info["bracket"]), lambda2=l2,
        lambda3_bracket=tuple(ref.brackets["lambda3"]),
        lambda4_bracket=tuple(ref.brackets["lambda4"]),
        lambda3_grid_bracket=tuple(br.lambda3_bracket),
        lambda4_grid_bracket=tuple(br.lambda4_bracket),
        redundant_above_lambda1=tuple(names[k] for k in l1info["redundant_above"]),
        region=region, last_safe_state=v_last, lam=lam_case, regime=regime,
        steady_state=STEADY_STATES[int(own["steady_state"])],
        dissipation_per_cycle=float(own["dissipation_per_cycle"]),
        evidence=dict(ref.evidence),
        refinement={
            "lam_tol": lam_tol_abs, "lam_tol_relative": lam_tol,
            "method": "bisection in λ from the grid brackets, every start at every trial "
                      "λ; assumes the criterion is monotone in λ above the bracket",
            "trial_lam": trial_lams, "runs": ref.runs, "runs_computed": trials.computed,
            "steps": {k: [[lam, ok] for lam, ok in v] for k, v in ref.steps.items()},
            "checkpoint": str(ckpt)},
        scan_lam=np.array(lams), seed=seed, scan_store=str(out / "scan.zarr"), scan=data,
        trial_lam=np.array(trial_lams), trials=trials.arrays(trial_lams, n),
        linear_programs=l1info["lps"] + 1, lp_wall_time_s=t_lp, discrete_case=dc)
    return StudyStatus(result.to_outputs(), int(done.size), int(done.size), result)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class ShakedownResult(StudyResult):
    """Safe region, λ1…λ4 and the λ scan of a discrete case (``slipcycle shakedown``).

    Load factors λ are dimensionless [1] (the load is λ times the case's load).

    Attributes
    ----------
    wall_time_s : float
        Wall time of the study in this call (linear programs, scan, bisection) [s].
    n_nodes : int
        Nodes N of the system.
    lambda1 : float
        Largest λ with every one of the 2N constraints active (Klarbring, Ciavarella &
        Barber 2007) [1]; ``lambda1_bracket`` (lo, hi) of its bisection.
    lambda2 : float
        Largest λ with a non-empty safe region S(λ) (Barber 2012) [1]; inf when unbounded.
    lambda3_bracket, lambda4_bracket : (float, float or None)
        Refined brackets of λ3 (every node slips in every steady cycle) and λ4 (all nodes
        slip or separate at one instant) [1]; hi None when not reached.
    lambda3_grid_bracket, lambda4_grid_bracket : (float, float or None)
        The same brackets on the scan grid [1].
    redundant_above_lambda1 : tuple of str
        Constraints that become redundant just above λ1.
    region : SafeRegion
        Extreme constraints G [N/m], h0 [N], m [N], θ extreme [rad] and their method.
    last_safe_state : ndarray, shape (N,)
        The slip state [m] left in S(λ2).
    lam : float
        The case's own λ [1]; ``regime`` says where it lies against λ1 and λ2.
    steady_state : str
        Class of the case's own run; ``dissipation_per_cycle`` its dissipation [J].
    evidence : dict
        ``"lambda3"``/``"lambda4"`` → the runs at the final lo and hi of each bracket.
    refinement : dict
        The bisection: ``lam_tol`` [1], ``lam_tol_relative``, ``trial_lam``, ``runs``,
        ``runs_computed``, ``steps``, ``checkpoint`` path.
    scan_lam : ndarray, shape (L,)
        λ values of the scan [1]; ``seed`` of its random starts; ``scan_store`` its path.
    scan : dict of str to ndarray
        Stored scan outputs over (lam, start): ``steady_state`` codes
        (:data:`~slipcycle.result.STEADY_STATES`), ``dissipation_per_cycle`` [J],
        ``dissipation_per_node`` [J] (last axis node), ``n_slipping``, ``memory_erased``,
        ``initial_slip`` [m].
    trial_lam : ndarray, shape (T,)
        Trial λ values of the bisection [1]; ``trials`` their runs over (trial_lam, start)
        (same keys as ``scan``).
    linear_programs : int
        Linear programs solved; ``lp_wall_time_s`` their time [s].
    discrete_case : DiscreteCase
        The validated case (for the trajectory panels).
    """

    model: ClassVar[str] = "discrete"
    analysis: ClassVar[str] = "shakedown"
    FLAGS: ClassVar[dict] = SUMMARY_FLAGS

    n_nodes: int
    lambda1: float
    lambda1_bracket: tuple
    lambda2: float
    lambda3_bracket: tuple
    lambda4_bracket: tuple
    lambda3_grid_bracket: tuple
    lambda4_grid_bracket: tuple
    redundant_above_lambda1: tuple
    region: object
    last_safe_state: np.ndarray
    lam: float
    regime: str
    steady_state: str
    dissipation_per_cycle: float
    evidence: dict
    refinement: dict
    scan_lam: np.ndarray
    seed: int
    scan_store: str
    scan: dict
    trial_lam: np.ndarray
    trials: dict
    linear_programs: int
    lp_wall_time_s: float
    discrete_case: object

    def headline(self) -> list[tuple]:
        """λ1, λ2, the refined λ3/λ4 brackets, the case's λ and its regime."""
        return [("lambda1", self.lambda1, "1"), ("lambda2", self.lambda2, "1"),
                ("lambda3_bracket", self.lambda3_bracket, "1"),
                ("lambda4_bracket", self.lambda4_bracket, "1"), ("lam", self.lam, "1"),
                ("regime", self.regime, ""), ("steady_state", self.steady_state, ""),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """``summary.json`` of ``slipcycle shakedown`` (units: :data:`SUMMARY_UNITS`).

        Returns
        -------
        dict
            ``lambda1``, ``lambda2``, ``lambda3_bracket``, ``lambda4_bracket`` (refined),
            the grid brackets, the extreme constraints, the evidence runs,
            ``refinement``, ``scan``, the case's own run, for N = 2
            ``safe_region_vertices`` [m]; ``units``.
        """
        region, cls = self.region, self.scan["steady_state"]
        summary = {
            "model": "discrete", "analysis": "shakedown", "n_nodes": self.n_nodes,
            "lambda1": self.lambda1, "lambda1_bracket": list(self.lambda1_bracket),
            "lambda2": self.lambda2,
            "lambda3_bracket": list(self.lambda3_bracket),
            "lambda4_bracket": list(self.lambda4_bracket),
            "lambda3_grid_bracket": list(self.lambda3_grid_bracket),
            "lambda4_grid_bracket": list(self.lambda4_grid_bracket),
            "redundant_above_lambda1": list(self.redundant_above_lambda1),
            "extreme_method": region.method,
            "constraints": {"names": constraint_names(self.n_nodes), "G": region.G,
                            "h0": region.h0, "m": region.m,
                            "theta_extreme": region.theta_extreme},
            "last_safe_state": self.last_safe_state,
            "lam": self.lam, "regime": self.regime,
            "steady_state": self.steady_state,
            "dissipation_per_cycle": self.dissipation_per_cycle,
            "lambda3_evidence": self.evidence["lambda3"],
            "lambda4_evidence": self.evidence["lambda4"],
            "refinement_runs": self.refinement["runs"],
            "refinement": dict(self.refinement),
            "scan": {"lam": self.scan_lam.tolist(), "starts": int(cls.shape[1]),
                     "seed": self.seed, "store": self.scan_store,
                     "class_counts": {STEADY_STATES[c]: int((cls == c).sum())
                                      for c in np.unique(cls)}},
            "linear_programs": self.linear_programs, "lp_wall_time_s": self.lp_wall_time_s,
            "units": dict(SUMMARY_UNITS),
        }
        if self.n_nodes == 2:
            summary["safe_region_vertices"] = polygon_vertices(region, self.lam)
        return summary

    def _build_dataset(self) -> xr.Dataset:
        """Classes and dissipation over (lam, start) and (trial_lam, start), G, h0, m and
        θ extreme over the constraints.

        The only place the Dataset of a shakedown study is built.

        Returns
        -------
        xarray.Dataset
        """
        region, data = self.region, self.scan
        cls = data["steady_state"]
        ds = xr.Dataset(
            {"steady_state": (("lam", "start"), cls, {
                "units": "1", "flag_meanings": " ".join(STEADY_STATES)}),
             "dissipation_per_cycle": (("lam", "start"), data["dissipation_per_cycle"],
                                       {"units": "J"}),
             "dissipation_per_node": (("lam", "start", "node"), data["dissipation_per_node"],
                                      {"units": "J"}),
             "n_slipping": (("lam", "start"), data["n_slipping"], {"units": "1"}),
             "memory_erased": (("lam", "start"), data["memory_erased"], {"units": "1"}),
             "initial_slip": (("lam", "start", "node"), data["initial_slip"], {"units": "m"}),
             "G": (("constraint", "node"), region.G, {"units": "N/m"}),
             "h0": (("constraint",), region.h0, {"units": "N"}),
             "m": (("constraint",), region.m, {"units": "N"}),
             "theta_extreme": (("constraint",), region.theta_extreme, {"units": "rad"})},
            coords={"lam": ("lam", self.scan_lam, {"units": "1"}),
                    "start": ("start", np.arange(cls.shape[1]), {"units": "1"})})
        l2 = self.lambda2
        ds.attrs.update({"lambda1": self.lambda1, "lambda2": l2 if np.isfinite(l2) else -1.0})
        if self.trial_lam.size:
            trial, tdims = self.trials, ("trial_lam", "start")
            ds = ds.assign_coords(trial_lam=("trial_lam", self.trial_lam, {"units": "1"}))
            ds["trial_steady_state"] = (tdims, trial["steady_state"], {
                "units": "1", "flag_meanings": " ".join(STEADY_STATES)})
            ds["trial_dissipation_per_cycle"] = (tdims, trial["dissipation_per_cycle"],
                                                 {"units": "J"})
            ds["trial_n_slipping"] = (tdims, trial["n_slipping"], {"units": "1"})
            ds["trial_memory_erased"] = (tdims, trial["memory_erased"], {"units": "1"})
            ds["trial_initial_slip"] = (tdims + ("node",), trial["initial_slip"],
                                        {"units": "m"})
        return ds

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """``dissipation_vs_lambda`` and, for N = 2 with finite λ2, ``safe_region_panels``
        (trajectories below λ1, between λ1 and λ2, above λ2).

        Returns
        -------
        dict of str to callable
        """
        l1, l2, trial = self.lambda1, self.lambda2, self.trials
        refined = {"lambda3": self.lambda3_bracket, "lambda4": self.lambda4_bracket}
        figures = {"dissipation_vs_lambda": lambda: plots.dissipation_vs_lambda(
            self.scan_lam, self.scan["dissipation_per_cycle"], self.scan["steady_state"],
            l1, l2, self.lambda3_grid_bracket, self.lambda4_grid_bracket, refined=refined,
            trials=(self.trial_lam, trial["dissipation_per_cycle"], trial["steady_state"])
            if self.trial_lam.size else None)}
        if self.n_nodes == 2 and np.isfinite(l2):
            figures["safe_region_panels"] = lambda: plots.safe_region_panels(
                self.region, _panels(self.discrete_case, self.region, l1, l2, self.lam,
                                     self.seed), l1, l2)
        return figures


def check_sizes(n: int, lam_points: int, starts: int, lam_tol: float) -> None:
    """Refuse a scan whose stored runs cannot be held in memory (before any work).

    The scan holds ``lam_points`` × (``starts`` + 1) runs of ``n`` nodes, the bisection
    at most 2 log2(1/``lam_tol``) + 2 trial λ values of as many starts each.

    Raises
    ------
    CaseError
        Naming ``--starts`` or ``--lam-points``, with the bytes needed and the limit.
    """
    cells = starts + 1
    check_memory("--starts", cells_bytes(cells, n) + 8.0 * cells * n * 8,
                 f"{starts:g} random starts per λ ({n} nodes)")
    trials = 2 * (np.log2(1.0 / lam_tol) + 2)
    check_memory("--lam-points", cells_bytes((lam_points + trials) * cells, n),
                 f"{lam_points:g} λ values × {cells:g} starts ({n} nodes)")


def _label(s: int) -> str:
    return "case" if s == 0 else f"random {s}"


def _record(cell: dict) -> dict:
    """A scan cell (codes, NumPy scalars) as a run record for the brackets."""
    return {"steady_state": STEADY_STATES[int(cell["steady_state"])],
            "dissipation_per_cycle": float(cell["dissipation_per_cycle"]),
            "n_slipping": int(cell["n_slipping"]),
            "memory_erased": bool(cell["memory_erased"]),
            "cycles_run": int(cell["cycles_run"])}


class TrialRuns:
    """``evaluate`` of :func:`~slipcycle.discrete.shakedown.refine_brackets`: runs every
    start at the trial λ values (in parallel through ``runner``) and keeps them in a JSON
    checkpoint, rewritten atomically after every step and re-used on resume.

    The checkpoint maps ``repr(λ)`` (exact round trip) to the trial's cell records and
    carries a fingerprint of what they depend on (case text, number of starts, seed).
    Records of a trial λ do not depend on the grid or on ``--lam-tol``, so a resumed run
    with a smaller tolerance re-uses the trials of a coarser one.
    """

    def __init__(self, runner, fn, starts: int, path: Path, depends: dict, resume: bool,
                 progress: bool):
        self.runner, self.fn, self.starts, self.path = runner, fn, starts, path
        self.fp = fingerprint(depends)
        self.cells: dict[str, list] = {}
        self.computed = 0            # runs computed in this call (not from the checkpoint)
        self.progress = progress
        # temporary checkpoints of an earlier call killed while saving (only this
        # command writes .refine-*.json in its output directory)
        for stale in path.parent.glob(".refine-*.json"):
            stale.unlink(missing_ok=True)
        if resume and path.exists():
            try:
                data = json.loads(path.read_text())
            except (OSError, ValueError):
                data = {}
            if data.get("fingerprint") == self.fp:
                self.cells = data.get("trials", {})

    def __call__(self, lams: list[float]) -> dict:
        todo = [lam for lam in lams if repr(lam) not in self.cells]
        if todo:
            t0 = time.perf_counter()
            params = [{"lam": lam, "start": s} for lam in todo for s in range(self.starts + 1)]
            out = self.runner.map(self.fn, params)
            self.computed += len(out)
            k = self.starts + 1
            for j, lam in enumerate(todo):
                self.cells[repr(lam)] = [
                    {**_record(r), "initial_slip": np.asarray(r["initial_slip"]).tolist()}
                    for r in out[j * k:(j + 1) * k]]
            self._save()
            if self.progress:
                print(f"λ bisection: {len(params)} runs at λ = "
                      f"{', '.join(f'{lam:.6g}' for lam in todo)} "
                      f"({time.perf_counter() - t0:.1f} s)", file=sys.stderr, flush=True)
        res = {}
        for lam in lams:
            res[lam] = [(_label(s), {k: v for k, v in c.items() if k != "initial_slip"})
                        for s, c in enumerate(self.cells[repr(lam)])
                        if c["steady_state"] != "inadmissible"]
        return res

    def arrays(self, lams: list, n: int) -> dict:
        """Trial runs as (trial λ, start) arrays (codes; NaN where not admissible)."""
        T, S = len(lams), self.starts + 1
        out = {"steady_state": np.zeros((T, S), np.int64),
               "dissipation_per_cycle": np.full((T, S), np.nan),
               "n_slipping": np.full((T, S), -1, np.int64),
               "memory_erased": np.zeros((T, S), bool),
               "initial_slip": np.full((T, S, n), np.nan)}
        for i, lam in enumerate(lams):
            for s, r in enumerate(self.cells[repr(lam)]):
                out["steady_state"][i, s] = STEADY_STATES.index(r["steady_state"])
                out["dissipation_per_cycle"][i, s] = r["dissipation_per_cycle"]
                out["n_slipping"][i, s] = r["n_slipping"]
                out["memory_erased"][i, s] = r["memory_erased"]
                out["initial_slip"][i, s] = np.asarray(r["initial_slip"], float)
        return out

    def _save(self) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".refine-", suffix=".json", dir=self.path.parent)
        try:
            with os.fdopen(fd, "w") as fh:
                json.dump({"fingerprint": self.fp, "trials": self.cells}, fh)
            os.replace(tmp, self.path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
