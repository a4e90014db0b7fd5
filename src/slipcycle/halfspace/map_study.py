"""The rough-surface dissipation map Ŵ(P̂1, Q̂1, φ) (``slipcycle map``).

The case names ``model = "halfspace"`` and holds a ``[map]`` table whose keys ``P1_hat``,
``Q1_hat`` and ``phase`` are each a list of values or a table ``{start, stop, num}``; the
optional ``fig7_P1_hat`` (default 0.4) and ``fig7_Q1_hat`` (default [0.2, 0.4, 0.6, 0.8])
select the curves of Barber 2012, Fig. 7, and ``[run]`` may set ``steps_per_cycle`` and
``sliders``. ``[halfspace]`` and ``[loading]`` tables may be present (so a run case can
carry its map) and are not used: Ŵ is dimensionless; W = λ_c γσ f² P0 Ŵ.
"""

from __future__ import annotations

import time

import numba
import numpy as np
import xarray as xr

from slipcycle.halfspace.wmap import w_hat_map
from slipcycle.io import CaseError, RunOutputs
from slipcycle.io.sizes import check_memory, memory_limit
from slipcycle.plot.halfspace import w_hat_cubic_law, w_hat_vs_phase

__all__ = ["map_memory_estimate", "parse_map_case", "w_hat_study", "cubic_law_slope",
           "CUBIC_LAW_Q1_HAT", "FIG7_PHASE"]

#: phases [rad] of the Fig. 7 curves
FIG7_PHASE = np.linspace(-np.pi, np.pi, 73)
#: Q̂1 of the small-amplitude points (P̂1 = 0, φ = 0); the slope uses the first five
CUBIC_LAW_Q1_HAT = np.geomspace(0.01, 0.5, 12)


def map_memory_estimate(n_points: int, steps_per_cycle: int, n_sliders: int,
                        threads: int | None = None) -> float:
    """Bytes the map needs.

    Ŵ on the grid (with its Dataset and netCDF copies, ~32 B per point) and, per thread,
    one point's load path (~48 B per step: two cycles and two assembly ramps) and slider
    state (~64 B per slider).

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
    return 32.0 * n_points + threads * (48.0 * steps + 64.0 * (n_sliders + 1))


def parse_map_case(case):
    """Grid and settings of a map case, validated before any computation.

    Parameters
    ----------
    case : Case
        ``model = "halfspace"`` with a ``[map]`` table (see :mod:`slipcycle.halfspace.map_study`).

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
    fig_Q1 = np.atleast_1d(sec.array("fig7_Q1_hat", [0.2, 0.4, 0.6, 0.8], ge=0.0, le=1.0))
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
    """Ŵ over a grid, the Fig. 7 curves and the cubic law at small amplitude.

    Parameters
    ----------
    P1, Q1, ph, fig_P1, fig_Q1, settings
        As returned by :func:`parse_map_case`.

    Returns
    -------
    RunOutputs
        ``dataset``: ``W_hat`` (P1_hat, Q1_hat, phase), NaN where the load path reaches
        gross slip; ``fig7_W_hat`` (fig7_Q1_hat, fig7_phase) at ``fig_P1`` over
        :data:`FIG7_PHASE`; ``cubic_law_Q1_hat``/``cubic_law_W_hat`` at P̂1 = 0, φ = 0.
        ``summary``: ``grid_points``, ``gross_slip_points``, ``wall_time_s``,
        ``settings``, ``cubic_law_slope`` (:func:`cubic_law_slope`), ``fig7_P1_hat``,
        ``fig7_phase_of_max`` [rad] and ``fig7_W_hat_max`` per Q̂1, ``units``.
        ``figures``: ``w_hat_vs_phase`` and ``w_hat_cubic_law``.
    """
    t0 = time.perf_counter()
    W = w_hat_map(P1, Q1, ph, **settings)
    # Fig. 7 curves and the cubic law on their own fine grids
    fig_phase = FIG7_PHASE
    W7 = w_hat_map([fig_P1], fig_Q1, fig_phase, **settings)[0]
    q_small = CUBIC_LAW_Q1_HAT
    W_small = w_hat_map([0.0], q_small, [0.0], **settings)[0, :, 0]
    elapsed = time.perf_counter() - t0
    slope = cubic_law_slope(q_small, W_small)
    attrs = {"units": "1", "long_name": "W / (lambda_c gamma_sigma f^2 P0), nan: gross slip"}
    p1_attrs = {"units": "1", "long_name": "P1 / P0"}
    q1_attrs = {"units": "1", "long_name": "Q1 / (f P0)"}
    ph_attrs = {"units": "rad", "long_name": "phase lag of Q behind P"}
    ds = xr.Dataset(
        {"W_hat": (("P1_hat", "Q1_hat", "phase"), W, attrs)},
        coords={"P1_hat": ("P1_hat", P1, p1_attrs), "Q1_hat": ("Q1_hat", Q1, q1_attrs),
                "phase": ("phase", ph, ph_attrs)},
    )
    fig7 = xr.Dataset({"W_hat": (("P1_hat", "Q1_hat", "phase"), W7[None], attrs)},
                      coords={"P1_hat": [fig_P1], "Q1_hat": fig_Q1, "phase": fig_phase})
    ds["fig7_W_hat"] = (("fig7_Q1_hat", "fig7_phase"), W7,
                        {**attrs, "long_name": f"W_hat at P1_hat = {fig_P1:g}"})
    ds = ds.assign_coords(fig7_Q1_hat=("fig7_Q1_hat", fig_Q1, q1_attrs),
                          fig7_phase=("fig7_phase", fig_phase, ph_attrs))
    ds["cubic_law_Q1_hat"] = ("cubic_law_point", q_small, q1_attrs)
    ds["cubic_law_W_hat"] = ("cubic_law_point", W_small,
                             {**attrs, "long_name": "W_hat at P1_hat = 0, phase = 0"})
    i_max = np.nanargmax(W7, axis=1)
    summary = {
        "model": "halfspace",
        "analysis": "w_hat_map",
        "grid_points": int(W.size),
        "gross_slip_points": int(np.isnan(W).sum()),
        "wall_time_s": elapsed,
        "settings": settings,
        "cubic_law_slope": slope,
        "fig7_P1_hat": fig_P1,
        "fig7_phase_of_max": dict(zip(map(str, fig_Q1), fig_phase[i_max].tolist(),
                                      strict=True)),
        "fig7_W_hat_max": dict(zip(map(str, fig_Q1), np.nanmax(W7, axis=1).tolist(),
                                   strict=True)),
        "dissipation_per_cycle": None,
        "units": {"grid_points": "1", "gross_slip_points": "1", "wall_time_s": "s",
                  "settings.steps_per_cycle": "1", "settings.n_sliders": "1",
                  "cubic_law_slope": "1", "fig7_P1_hat": "1", "fig7_phase_of_max": "rad",
                  "fig7_W_hat_max": "1"},
    }
    figures = {
        "w_hat_vs_phase": lambda: w_hat_vs_phase(fig7, fig_P1),
        "w_hat_cubic_law": lambda: w_hat_cubic_law(q_small, W_small,
                                                   f"P̂1 = 0, φ = 0 (slope {slope:.3f})"),
    }
    return RunOutputs(summary=summary, dataset=ds, figures=figures,
                      flags={"model": ("halfspace",), "analysis": ("w_hat_map",)})
