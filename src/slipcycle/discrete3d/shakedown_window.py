"""The load window in which the start decides shakedown, for 3-D systems (``slipcycle
shakedown`` of ``discrete3d`` and ``lap_joint`` cases).

A *subject* is one assembled system with its start: an initial slip, or an assembly
protocol (Barber 2012, §1 and §3: in a coupled system the loading path before the steady
cycle — e.g. the order in which bolts are tightened — decides whether it shakes down).
For every subject: λ2 with separation (:func:`~slipcycle.discrete3d.shakedown.
lambda2_open`), the class reached on a grid of load factors (the map of which start shakes
down where), and the bracket of the largest load factor at which it shakes down (the grid
step where its class first changes, bisected by :func:`~slipcycle.discrete3d.shakedown.
shakedown_limit`). Where the periodic load vanishes at θ = 0 (a service load F sin θ) the
safe state of the first subject's λ2 is one more start (it shakes down up to λ2 by
construction, so the engine's verdict on it checks λ2 independently). Over the subjects:
λ1 is bracketed by the weakest start, and the
*class window* is the range of load factors in which one start shakes down while another
does not.

References
----------
J. R. Barber, "Frictional systems under periodic loads — history-dependence, non-uniqueness
and energy dissipation", J. Phys.: Conf. Ser. 382 (2012) 012002. A. Klarbring,
M. Ciavarella, J. R. Barber, Int. J. Solids Struct. 44 (2007) 8355–8365.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import xarray as xr

from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.shakedown import lambda2_open, safe_start, shakedown_limit
from slipcycle.discrete3d.steady import InadmissibleInitialState3D, simulate3d
from slipcycle.errors import SolverError
from slipcycle.figure_task import figure_task
from slipcycle.io import CaseError
from slipcycle.result import STEADY_STATES, StudyResult

__all__ = ["Subject", "ShakedownWindow3D", "shakedown_window", "check_window_options",
           "SUMMARY_UNITS"]

#: the most load factors of one window (each is a run to the steady state per start)
MAX_LAM_POINTS = 10_000

SUMMARY_UNITS = {"lambda2": "1", "lambda1_bracket": "1", "class_window": "1",
                 "shakedown_limits": "1", "lam_max": "1", "n_nodes": "1",
                 "wall_time_s": "s"}


@dataclass(frozen=True)
class Subject:
    """One assembled system and its start.

    Attributes
    ----------
    label : str
        Its name (a protocol's name).
    system : FrictionalSystem3D
    load : Load3D
        The cycle; λ scales its periodic part.
    start : dict
        ``{"initial_slip": (N, 2)}``, ``{"protocol": (S, 3N)}`` or ``{}`` (zero slip),
        as :func:`~slipcycle.discrete3d.steady.simulate3d` takes them.
    """

    label: str
    system: FrictionalSystem3D
    load: Load3D
    start: dict = field(default_factory=dict)


def check_window_options(lam_max: float | None, lam_points: int, lam_tol: float) -> None:
    """Refuse a bad ``--lam-max``, ``--lam-points`` or ``--lam-tol`` (CaseError)."""
    if lam_max is not None and not (np.isfinite(lam_max) and lam_max > 0):
        raise CaseError("--lam-max", f"must be a finite number > 0, got {lam_max}")
    if not 2 <= lam_points <= MAX_LAM_POINTS:
        raise CaseError("--lam-points", f"must be in 2 … {MAX_LAM_POINTS} (each point is a "
                                        f"run to the steady state per start), got "
                                        f"{lam_points}")
    if not (np.isfinite(lam_tol) and 0 < lam_tol <= 1):
        raise CaseError("--lam-tol", f"must be in (0, 1], got {lam_tol}")


def _code(system, load, start, run) -> tuple[int, float]:
    """Class code (position in STEADY_STATES) and dissipation per cycle [J] of one run."""
    try:
        res = simulate3d(system, load, record=False, **start, **run)
    except InadmissibleInitialState3D:
        return STEADY_STATES.index("inadmissible"), np.nan
    except SolverError:
        return STEADY_STATES.index("failed"), np.nan
    return STEADY_STATES.index(res.steady_state), float(res.dissipation_per_cycle)


def _safe_subject(s: Subject, region, steps_per_cycle: int) -> Subject | None:
    """The safe state of ``region`` as one more start, where it is one start for every λ
    (the periodic part vanishes at θ = 0, so the open nodes' free positions do not move
    with λ); None otherwise or if no safe state exists."""
    r1 = s.load.split_lam(np.zeros(1))[1]
    if not region.feasible or np.any(r1 != 0):
        return None
    v = safe_start(s.system, s.load.with_lam(0.0), region, steps_per_cycle)
    return Subject(f"safe state ({s.label})", s.system, s.load, {"initial_slip": v})


def _limit(s: Subject, lam: np.ndarray, codes: np.ndarray, rtol: float, run) -> tuple:
    """Bracket of the largest λ at which ``s`` shakes down, from its grid classes."""
    ok = codes == 0
    if ok.all():
        return float(lam[-1]), np.nan
    first = int(np.argmin(ok))
    lo = float(lam[first - 1]) if first > 0 else 0.0
    return shakedown_limit(lambda x: _code(s.system, s.load.with_lam(x), s.start, run)[0]
                           == 0, float(lam[first]), rtol, lam_lo=lo)


def shakedown_window(subjects, *, lam_max: float | None = None, lam_points: int = 9,
                     rtol: float = 1e-2, steps_per_cycle: int = 100,
                     result_type: type | None = None, **run) -> ShakedownWindow3D:
    """λ2 of every subject, its class over a λ grid and the window of the starts.

    Parameters
    ----------
    subjects : sequence of Subject
    lam_max : float, optional
        Top of the λ grid (default 1.1 × the largest λ2).
    lam_points : int
        Grid values of λ in (0, ``lam_max``].
    rtol : float
        Width of each subject's shakedown-limit bracket relative to ``lam_max``.
    steps_per_cycle : int
        Load samples of the cone program and of the runs.
    result_type : type, optional
        A subclass of :class:`ShakedownWindow3D` to return (another model's name).
    **run
        Other settings of ``simulate3d`` (``cycles``, ``tol``, ``step_tol`` …).

    Returns
    -------
    ShakedownWindow3D
    """
    import time

    t0 = time.perf_counter()
    subjects = tuple(subjects)
    regions = [lambda2_open(s.system, s.load, steps_per_cycle) for s in subjects]
    safe = _safe_subject(subjects[0], regions[0], steps_per_cycle)
    if safe is not None:
        subjects, regions = subjects + (safe,), regions + [regions[0]]
    lam2 = np.array([r.lambda2 for r in regions])
    top = float(lam_max) if lam_max is not None else 1.1 * float(np.max(lam2))
    lam = top * np.arange(1, lam_points + 1) / lam_points
    run = dict(run, steps_per_cycle=steps_per_cycle)
    codes = np.empty((len(subjects), lam.size), int)
    diss = np.empty((len(subjects), lam.size))
    for i, s in enumerate(subjects):
        for j, x in enumerate(lam):
            codes[i, j], diss[i, j] = _code(s.system, s.load.with_lam(x), s.start, run)
    limits = np.array([_limit(s, lam, codes[i], rtol * top / float(lam[-1]), run)
                       for i, s in enumerate(subjects)])
    return (result_type or ShakedownWindow3D)(
        wall_time_s=time.perf_counter() - t0, labels=tuple(s.label for s in subjects),
        n_nodes=subjects[0].system.n_nodes, lambda2=lam2,
        lambda2_certified=np.array([r.consistent for r in regions]), lam=lam,
        steady_state=codes, dissipation_per_cycle=diss, limits=limits)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class ShakedownWindow3D(StudyResult):
    """Shakedown limits of 3-D starts (``slipcycle shakedown`` of a 3-D case).

    Attributes
    ----------
    labels : tuple of str
        The subjects (S).
    n_nodes : int
    lambda2 : (S,) array
        λ2 with separation of each subject's system [1].
    lambda2_certified : (S,) bool array
        Whether its safe state was certified by a fresh elastic solution.
    lam : (L,) array
        The λ grid [1].
    steady_state : (S, L) int array
        Class codes (positions in :data:`slipcycle.result.STEADY_STATES`).
    dissipation_per_cycle : (S, L) array
        [J].
    limits : (S, 2) array
        Bracket [lo, hi] of the largest λ at which each start shakes down (hi NaN: it
        shook down on the whole grid).
    """

    model: ClassVar[str] = "discrete3d"
    analysis: ClassVar[str] = "shakedown"
    #: the unit of λ and of every amplitude derived from it (a load factor here)
    lam_unit: ClassVar[str] = "1"

    labels: tuple
    n_nodes: int
    lambda2: np.ndarray
    lambda2_certified: np.ndarray
    lam: np.ndarray
    steady_state: np.ndarray
    dissipation_per_cycle: np.ndarray
    limits: np.ndarray

    @property
    def lambda1_bracket(self) -> tuple[float, float]:
        """[lo, hi]: every start shook down at lo, the weakest did not at hi."""
        return (float(np.min(self.limits[:, 0])), float(np.nanmin(self.limits[:, 1])))

    @property
    def class_window(self) -> tuple[float, float] | None:
        """[a, b] in which one start shakes down and another does not (None: none)."""
        a, b = float(np.nanmin(self.limits[:, 1])), float(np.max(self.limits[:, 0]))
        return (a, b) if a <= b else None

    def headline(self) -> list[tuple]:
        u = self.lam_unit
        return [("lambda2", self.lambda2.tolist(), u),
                ("lambda1_bracket", list(self.lambda1_bracket), u),
                ("class_window", self.class_window, u),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """``summary.json``: ``subjects``, ``lambda2`` (per subject), ``lambda2_certified``,
        ``lambda1_bracket``, ``class_window`` (or null), ``shakedown_limits`` (per subject
        [lo, hi]), ``lam_max``, ``steady_state_codes``; ``units``."""
        lim = [[float(a), None if np.isnan(b) else float(b)] for a, b in self.limits]
        window = self.class_window
        return {"model": self.model, "analysis": self.analysis,
                "subjects": list(self.labels), "n_nodes": self.n_nodes,
                "lambda2": self.lambda2.tolist(),
                "lambda2_certified": [bool(c) for c in self.lambda2_certified],
                "lambda1_bracket": list(self.lambda1_bracket),
                "class_window": None if window is None else list(window),
                "shakedown_limits": lim, "lam_max": float(self.lam[-1]),
                "steady_state_codes": list(STEADY_STATES),
                "wall_time_s": self.wall_time_s, "units": self.units()}

    def units(self) -> dict:
        """The summary's units: :data:`SUMMARY_UNITS` with λ's in :attr:`lam_unit`."""
        lam_keys = ("lambda2", "lambda1_bracket", "class_window", "shakedown_limits",
                    "lam_max")
        return {k: self.lam_unit if k in lam_keys else u for k, u in SUMMARY_UNITS.items()}

    def _build_dataset(self) -> xr.Dataset:
        """Class and dissipation over (subject, lam); λ2 and the limits per subject."""
        sub = np.array(self.labels, dtype=str)
        return xr.Dataset(
            {"steady_state": (("subject", "lam"), self.steady_state, {"units": "1"}),
             "dissipation_per_cycle": (("subject", "lam"), self.dissipation_per_cycle,
                                       {"units": "J"}),
             "lambda2": (("subject",), self.lambda2, {"units": self.lam_unit}),
             "shakedown_limit_lo": (("subject",), self.limits[:, 0],
                                    {"units": self.lam_unit}),
             "shakedown_limit_hi": (("subject",), self.limits[:, 1],
                                    {"units": self.lam_unit})},
            coords={"subject": sub, "lam": ("lam", self.lam, {"units": self.lam_unit})})

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """``shakedown_map``: class of every start over λ, with λ2 and the limits."""
        return {"shakedown_map": figure_task(
            "slipcycle.plot.shakedown_window:shakedown_map", list(self.labels), self.lam,
            self.steady_state, self.lambda2, self.limits, list(STEADY_STATES))}
