"""The rough-surface dissipation map Ŵ(P̂1, Q̂1, φ) (``slipcycle map``).

The case names ``model = "halfspace"`` and holds a ``[map]`` table whose keys ``P1_hat``,
``Q1_hat`` and ``phase`` are each a list of values or a table ``{start, stop, num}``; the
optional ``fig7_P1_hat`` (default 0.4) and ``fig7_Q1_hat`` (default [0.2, 0.4, 0.6, 0.8])
select the curves of Barber 2012, Fig. 7, and ``[run]`` may set ``steps_per_cycle`` and
``sliders``. ``[halfspace]`` and ``[loading]`` tables may be present (so a run case can
carry its map) and are not used: Ŵ is dimensionless; W = λ_c γσ f² P0 Ŵ.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import ClassVar

import numba
import numpy as np
import xarray as xr

from slipcycle.halfspace.wmap import CHUNK, LANES, w_hat_map
from slipcycle.io import CaseError, RunOutputs
from slipcycle.io.sizes import check_memory, memory_limit
from slipcycle.plot.halfspace import w_hat_cubic_law, w_hat_vs_phase
from slipcycle.result import StudyResult

log = logging.getLogger("slipcycle")

__all__ = ["map_memory_estimate", "parse_map_case", "w_hat_study", "w_hat_map_study",
           "WHatMapResult",
           "cubic_law_slope",
           "CUBIC_LAW_Q1_HAT", "FIG7_PHASE"]

#: phases [rad] of the Fig. 7 curves
FIG7_PHASE = np.linspace(-np.pi, np.pi, 73)
#: Q̂1 of the small-amplitude points (P̂1 = 0, φ = 0); the slope uses the first five
CUBIC_LAW_Q1_HAT = np.geomspace(0.01, 0.5, 12)


def map_memory_estimate(n_points: int, steps_per_cycle: int, n_sliders: int,
                        threads: int | None = None) -> float:
    """Bytes the map needs.

    Ŵ on the grid (with its Dataset and netCDF copies, the order the points are shared
    out in and the batches of lanes, ~48 B per point) and, per thread, the load paths of
    :data:`~slipcycle.halfspace.wmap.LANES` points driven together (~48 B per step: two
    cycles and two assembly ramps), their slider states (~64 B per slider) and the slider
    forces of their first cycle at every chunk end (16 B per slider and chunk of
    :data:`~slipcycle.halfspace.wmap.CHUNK` steps). The unlumped bed of each P̂1 (~8 B per
    slider and step) and the cosines of the cycles (8 B per phase and step) are small
    beside these.

    Parameters
    ----------
    n_points : int
        Grid points P̂1 × Q̂1 × φ.
    steps_per_cycle, n_sliders : int
        ``[run]`` settings of the map.
    threads : int, optional
        Numba threads (default: the current number).

    Returns
    -------
    float
        Bytes.
    """
    threads = numba.get_num_threads() if threads is None else threads
    steps = 2 * steps_per_cycle + 2 * 20
    chunks = steps_per_cycle // CHUNK + 1
    return 48.0 * n_points + threads * LANES * (48.0 * steps + 64.0 * (n_sliders + 1)
                                                + 16.0 * chunks * (n_sliders + 1))


def parse_map_case(case):
    """Grid and settings of a map case, validated before any computation.

    Parameters
    ----------
    case : Case
        ``model = "halfspace"`` with a ``[map]`` table (see :mod:`slipcycle.studies.w_hat_map`).

    Returns
    -------
    P1, Q1, phase : 1-D arrays
        Grid of P̂1 = P1/P0, Q̂1 = Q1/(f P0) and φ [rad].
    fig_P1 : float
        P̂1 of the Fig. 7 curves.
    fig_Q1 : 1-D array
        Q̂1 of the Fig. 7 curves.
    settings : dict
        ``steps_per_cycle`` and ``n_sliders`` for :func:`~slipcycle.halfspace.wmap.w_hat_map`.

    Raises
    ------
    CaseError
        A missing ``[map]`` table, a bad or unknown key, or a map too large for memory.
    """
    if "map" not in case.data:
        raise CaseError("map", "required table [map] is missing; a half-space case without a "
                        "[map] table is run with `slipcycle run`")
    sec = case.section("map")
    P1 = sec.grid("P1_hat", {"start": 0.0, "stop": 0.8, "num": 9}, ge=0.0, le=0.999999)
    Q1 = sec.grid("Q1_hat", {"start": 0.05, "stop": 0.95, "num": 19}, ge=0.0, le=1.0)
    ph = sec.grid("phase", {"start": -np.pi, "stop": np.pi, "num": 37}, ge=-2 * np.pi,
                  le=2 * np.pi)
    fig_P1 = sec.float("fig7_P1_hat", 0.4, ge=0.0, lt=1.0)
    fig_Q1 = sec.values("fig7_Q1_hat", [0.2, 0.4, 0.6, 0.8], ge=0.0, le=1.0)
    if fig_Q1.size == 0:   # no curve to draw (the grids refuse an empty list themselves)
        raise sec.error("fig7_Q1_hat", "must hold at least one value, got an empty list")
    run = case.section("run", required=False)
    settings = {"steps_per_cycle": run.int("steps_per_cycle", 200, ge=16),
                "n_sliders": run.int("sliders", 100, ge=10)}
    sizes = {"map.P1_hat": P1.size, "map.Q1_hat": Q1.size, "map.phase": ph.size}
    n_points = P1.size * Q1.size * ph.size
    need = map_memory_estimate(n_points, settings["steps_per_cycle"], settings["n_sliders"])
    if need > memory_limit():
        # blame what asks most: the grid axis with most points, or a [run] count
        asks = {"run.steps_per_cycle": settings["steps_per_cycle"] / 200,
                "run.sliders": settings["n_sliders"] / 100,
                **{k: v / 37 for k, v in sizes.items()}}
        key = max(asks, key=asks.get)
        what = {"run.steps_per_cycle": f"{settings['steps_per_cycle']} steps per cycle",
                "run.sliders": f"{settings['n_sliders']} sliders"}.get(
                    key, f"a grid of {n_points} points")
        check_memory(key, need, what)
    # a run case may carry a [map] table: its physical tables are accepted, not used
    for name in ("halfspace", "loading"):
        if name in case.data:
            case.section(name).ignore()
    case.finish()
    return P1, Q1, ph, fig_P1, fig_Q1, settings


def cubic_law_slope(Q1_hat: np.ndarray, W_hat: np.ndarray, points: int = 5) -> float:
    """Slope of log Ŵ against log Q̂1 over the first ``points`` (smallest) amplitudes.

    At small amplitude Ŵ = (2/3) Q̂1³ (Barber 2012), so the slope tends to 3.
    """
    return float(np.polyfit(np.log(Q1_hat[:points]), np.log(W_hat[:points]), 1)[0])


def w_hat_study(P1: np.ndarray, Q1: np.ndarray, ph: np.ndarray, fig_P1: float,
                fig_Q1: np.ndarray, settings: dict) -> RunOutputs:
    """What ``slipcycle map`` writes: ``w_hat_map_study(...).to_outputs()``.

    Parameters
    ----------
    P1, Q1, ph, fig_P1, fig_Q1, settings
        As returned by :func:`parse_map_case`.

    Returns
    -------
    RunOutputs
        See :func:`w_hat_map_study`.
    """
    return w_hat_map_study(P1, Q1, ph, fig_P1, fig_Q1, settings).to_outputs()


def w_hat_map_study(P1: np.ndarray, Q1: np.ndarray, ph: np.ndarray, fig_P1: float,
                    fig_Q1: np.ndarray, settings: dict) -> WHatMapResult:
    """Ŵ over a grid, the Fig. 7 curves and the cubic law at small amplitude.

    Parameters
    ----------
    P1, Q1, ph : ndarray, shapes (I,), (J,), (K,)
        Grid of P̂1 = P1/P0 [1], Q̂1 = Q1/(f P0) [1] and φ [rad] (:func:`parse_map_case`).
    fig_P1 : float
        P̂1 of the Fig. 7 curves [1].
    fig_Q1 : ndarray, shape (M,)
        Q̂1 of the Fig. 7 curves [1].
    settings : dict
        ``steps_per_cycle`` and ``n_sliders`` for :func:`~slipcycle.halfspace.wmap.w_hat_map`.

    Returns
    -------
    WHatMapResult
        Its ``to_outputs()`` is what ``slipcycle map`` writes. ``dataset``: ``W_hat``
        (P1_hat, Q1_hat, phase), NaN where the load path reaches gross slip;
        ``fig7_W_hat`` (fig7_Q1_hat, fig7_phase) at ``fig_P1`` over :data:`FIG7_PHASE`;
        ``cubic_law_Q1_hat``/``cubic_law_W_hat`` at P̂1 = 0, φ = 0. ``summary``:
        ``grid_points``, ``gross_slip_points``, ``wall_time_s``, ``settings``,
        ``cubic_law_slope`` (:func:`cubic_law_slope`), ``fig7_P1_hat``,
        ``fig7_phase_of_max`` [rad] and ``fig7_W_hat_max`` per Q̂1, ``units``.
        ``figures``: ``w_hat_vs_phase`` and ``w_hat_cubic_law``.
    """
    t0 = time.perf_counter()
    # Fig. 7 curves first: when every one reaches gross slip there is nothing to draw, and
    # the case is refused before the (larger) map runs
    W7 = w_hat_map([fig_P1], fig_Q1, FIG7_PHASE, **settings)[0]
    _gross_slip_curves(fig_P1, fig_Q1, W7)   # refuses, or warns about, empty curves
    W = w_hat_map(P1, Q1, ph, **settings)
    W_small = w_hat_map([0.0], CUBIC_LAW_Q1_HAT, [0.0], **settings)[0, :, 0]
    return WHatMapResult(wall_time_s=time.perf_counter() - t0, P1_hat=P1, Q1_hat=Q1,
                         phase=ph, W_hat=W, fig7_P1_hat=fig_P1, fig7_Q1_hat=fig_Q1,
                         fig7_phase=FIG7_PHASE, fig7_W_hat=W7,
                         cubic_law_Q1_hat=CUBIC_LAW_Q1_HAT, cubic_law_W_hat=W_small,
                         settings=settings)


def _gross_slip_curves(fig_P1: float, fig_Q1: np.ndarray, W7: np.ndarray) -> list[float]:
    """Q̂1 of the Fig. 7 curves that reach gross slip at every phase (Ŵ all NaN).

    Refuses (``map.fig7_Q1_hat``) when that is every curve, and says on stderr which
    curves are left out when it is some of them. No gross slip at any phase needs
    Q̂1 < 1 − P̂1 (the smallest normal load is (1 − P̂1) P0).

    Returns
    -------
    list of float
        Q̂1 [1] of the curves without a value.
    """
    empty = [float(q) for q, w in zip(fig_Q1, W7, strict=True) if not np.any(np.isfinite(w))]
    if not empty:
        return empty
    hint = f"Q̂1 < 1 − P̂1 = {1 - fig_P1:.3g} never slips grossly"
    if len(empty) == fig_Q1.size:
        raise CaseError("map.fig7_Q1_hat", f"every Fig. 7 curve (Q̂1 = "
                        f"{', '.join(f'{q:g}' for q in empty)}) at fig7_P1_hat = {fig_P1:g} "
                        f"reaches gross slip at every phase: nothing to draw; {hint}")
    log.warning("map: the Fig. 7 curves Q̂1 = %s reach gross slip at every phase at "
                "fig7_P1_hat = %g and are not drawn (%s)", ", ".join(f"{q:g}" for q in empty),
                fig_P1, hint)
    return empty


_ATTRS = {"units": "1", "long_name": "W / (lambda_c gamma_sigma f^2 P0), nan: gross slip"}
_P1_ATTRS = {"units": "1", "long_name": "P1 / P0"}
_Q1_ATTRS = {"units": "1", "long_name": "Q1 / (f P0)"}
_PH_ATTRS = {"units": "rad", "long_name": "phase lag of Q behind P"}


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class WHatMapResult(StudyResult):
    """The rough-surface dissipation map Ŵ(P̂1, Q̂1, φ) (``slipcycle map``; Barber 2012).

    Ŵ = W / (λ_c γσ f² P0) is dimensionless; P̂1 = P1/P0, Q̂1 = Q1/(f P0).

    Attributes
    ----------
    wall_time_s : float
        Wall time of the three maps [s].
    P1_hat, Q1_hat, phase : ndarray, shapes (I,), (J,), (K,)
        Grid axes [1], [1], [rad].
    W_hat : ndarray, shape (I, J, K)
        Ŵ on the grid [1]; NaN where the load path reaches gross slip.
    fig7_P1_hat : float
        P̂1 of the Fig. 7 curves [1].
    fig7_Q1_hat, fig7_phase : ndarray, shapes (M,), (F,)
        Q̂1 [1] and phases [rad] of the Fig. 7 curves.
    fig7_W_hat : ndarray, shape (M, F)
        Ŵ along the Fig. 7 curves [1].
    cubic_law_Q1_hat, cubic_law_W_hat : ndarray, shape (C,)
        Small-amplitude points at P̂1 = 0, φ = 0 [1] (Ŵ → (2/3) Q̂1³).
    settings : dict
        ``steps_per_cycle`` and ``n_sliders`` used.
    """

    model: ClassVar[str] = "halfspace"
    analysis: ClassVar[str] = "w_hat_map"
    FLAGS: ClassVar[dict] = {"model": ("halfspace",), "analysis": ("w_hat_map",)}

    P1_hat: np.ndarray
    Q1_hat: np.ndarray
    phase: np.ndarray
    W_hat: np.ndarray
    fig7_P1_hat: float
    fig7_Q1_hat: np.ndarray
    fig7_phase: np.ndarray
    fig7_W_hat: np.ndarray
    cubic_law_Q1_hat: np.ndarray
    cubic_law_W_hat: np.ndarray
    settings: dict

    @property
    def cubic_law_slope(self) -> float:
        """Slope of log Ŵ against log Q̂1 at small amplitude (→ 3) [1]."""
        return cubic_law_slope(self.cubic_law_Q1_hat, self.cubic_law_W_hat)

    def headline(self) -> list[tuple]:
        """Grid points, gross-slip points, the cubic-law slope and the wall time."""
        return [("grid_points", int(self.W_hat.size), "1"),
                ("gross_slip_points", int(np.isnan(self.W_hat).sum()), "1"),
                ("cubic_law_slope", self.cubic_law_slope, "1"),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """``summary.json`` of ``slipcycle map``.

        Returns
        -------
        dict
            ``grid_points``, ``gross_slip_points``, ``wall_time_s`` [s], ``settings``,
            ``cubic_law_slope``, ``fig7_P1_hat``, ``fig7_phase_of_max`` [rad] and
            ``fig7_W_hat_max`` per Q̂1 (keyed by ``str(Q̂1)``), ``units``.
        """
        W, W7, q = self.W_hat, self.fig7_W_hat, self.fig7_Q1_hat
        # a curve in gross slip at every phase has no maximum: null, not an error
        drawn = np.any(np.isfinite(W7), axis=1)
        i_max = [int(np.nanargmax(w)) if ok else None for w, ok in zip(W7, drawn, strict=True)]
        phase_max = [float(self.fig7_phase[i]) if i is not None else None for i in i_max]
        w_max = [float(np.nanmax(w)) if ok else None for w, ok in zip(W7, drawn, strict=True)]
        return {
            "model": "halfspace",
            "analysis": "w_hat_map",
            "grid_points": int(W.size),
            "gross_slip_points": int(np.isnan(W).sum()),
            "wall_time_s": self.wall_time_s,
            "settings": self.settings,
            "cubic_law_slope": self.cubic_law_slope,
            "fig7_P1_hat": self.fig7_P1_hat,
            "fig7_phase_of_max": dict(zip(map(str, q), phase_max, strict=True)),
            "fig7_W_hat_max": dict(zip(map(str, q), w_max, strict=True)),
            "fig7_gross_slip_Q1_hat": [float(v) for v in q[~drawn]],
            "dissipation_per_cycle": None,
            "units": {"grid_points": "1", "gross_slip_points": "1", "wall_time_s": "s",
                      "settings.steps_per_cycle": "1", "settings.n_sliders": "1",
                      "cubic_law_slope": "1", "fig7_P1_hat": "1", "fig7_phase_of_max": "rad",
                      "fig7_W_hat_max": "1", "fig7_gross_slip_Q1_hat": "1"},
        }

    def _build_dataset(self) -> xr.Dataset:
        """``W_hat`` (P1_hat, Q1_hat, phase), ``fig7_W_hat`` (fig7_Q1_hat, fig7_phase) and
        ``cubic_law_Q1_hat``/``cubic_law_W_hat`` (cubic_law_point).

        The only place the Dataset of a Ŵ map is built.

        Returns
        -------
        xarray.Dataset
        """
        ds = xr.Dataset(
            {"W_hat": (("P1_hat", "Q1_hat", "phase"), self.W_hat, _ATTRS)},
            coords={"P1_hat": ("P1_hat", self.P1_hat, _P1_ATTRS),
                    "Q1_hat": ("Q1_hat", self.Q1_hat, _Q1_ATTRS),
                    "phase": ("phase", self.phase, _PH_ATTRS)},
        )
        ds["fig7_W_hat"] = (("fig7_Q1_hat", "fig7_phase"), self.fig7_W_hat,
                            {**_ATTRS, "long_name": f"W_hat at P1_hat = {self.fig7_P1_hat:g}"})
        ds = ds.assign_coords(fig7_Q1_hat=("fig7_Q1_hat", self.fig7_Q1_hat, _Q1_ATTRS),
                              fig7_phase=("fig7_phase", self.fig7_phase, _PH_ATTRS))
        ds["cubic_law_Q1_hat"] = ("cubic_law_point", self.cubic_law_Q1_hat, _Q1_ATTRS)
        ds["cubic_law_W_hat"] = ("cubic_law_point", self.cubic_law_W_hat,
                                 {**_ATTRS, "long_name": "W_hat at P1_hat = 0, phase = 0"})
        return ds

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """``w_hat_vs_phase`` (Barber 2012, Fig. 7) and ``w_hat_cubic_law``.

        Returns
        -------
        dict of str to callable
        """
        # the plot takes the Fig. 7 curves as a (P1_hat, Q1_hat, phase) array
        # curves in gross slip at every phase have nothing to draw (listed in the summary)
        drawn = np.any(np.isfinite(self.fig7_W_hat), axis=1)
        curves = {"P1_hat": [self.fig7_P1_hat], "Q1_hat": self.fig7_Q1_hat[drawn],
                  "phase": self.fig7_phase}
        W7 = self.fig7_W_hat[drawn][None]

        def vs_phase():
            fig7 = xr.Dataset({"W_hat": (("P1_hat", "Q1_hat", "phase"), W7, _ATTRS)},
                              coords=curves)
            return w_hat_vs_phase(fig7, self.fig7_P1_hat)

        label = f"P̂1 = 0, φ = 0 (slope {self.cubic_law_slope:.3f})"
        return {"w_hat_vs_phase": vs_phase,
                "w_hat_cubic_law": lambda: w_hat_cubic_law(
                    self.cubic_law_Q1_hat, self.cubic_law_W_hat, label)}
