"""Figures of the 3-D discrete interface (from the Dataset of a ``discrete3d`` run).

Each function takes the Dataset built by ``DiscreteResult3D.to_dataset()`` and returns a
matplotlib Figure; no physics is computed here. Nodes are drawn at their (x, y)
coordinates (the projection of the interface on the x–y plane).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D

__all__ = ["state_map", "dissipation_map", "slip_directions", "dissipation_history",
           "basin_dissipation", "STATE_COLOURS"]

#: colours of stick, slip, separated
STATE_COLOURS = ("#4c72b0", "#dd8452", "#8c8c8c")


def _instants(ds, instants):
    n = ds.sizes["theta"]
    if instants is None:
        return list(np.linspace(0, n - 1, 5, dtype=int)[:4])
    return [int(i) for i in instants]


def _xy(ds):
    return np.asarray(ds["x"]), np.asarray(ds["y"])


def state_map(ds, instants=None):
    """Stick / slip / separation map of the last cycle at up to four sample indices.

    Parameters
    ----------
    ds : xarray.Dataset
        A ``discrete3d`` Dataset (``node_state``, coordinates ``x``, ``y``).
    instants : sequence of int, optional
        Sample indices into ``theta`` (default: four equally spaced).

    Returns
    -------
    matplotlib.figure.Figure
    """
    idx = _instants(ds, instants)
    x, y = _xy(ds)
    theta = np.asarray(ds["theta"])
    states = np.asarray(ds["node_state"].isel(cycle=-1))
    fig, axes = plt.subplots(1, len(idx), figsize=(3.2 * len(idx), 3.2), squeeze=False,
                             constrained_layout=True)
    cmap = ListedColormap(STATE_COLOURS)
    for ax, k in zip(axes[0], idx, strict=True):
        ax.scatter(x, y, c=states[k], cmap=cmap, vmin=-0.5, vmax=2.5, s=18,
                   edgecolors="none")
        ax.set_title(f"θ = {theta[k]:.2f} rad")
        ax.set_xlabel("x [m]")
        ax.set_aspect("equal", adjustable="datalim")
    axes[0][0].set_ylabel("y [m]")
    handles = [Line2D([], [], marker="o", ls="", color=c, label=lab)
               for c, lab in zip(STATE_COLOURS, ("stick", "slip", "separated"), strict=True)]
    axes[0][-1].legend(handles=handles, loc="upper right", fontsize=8)
    fig.suptitle("node states, last cycle")
    return fig


def dissipation_map(ds):
    """Dissipation per unit area of each node over the last cycle [J/m²].

    Parameters
    ----------
    ds : xarray.Dataset

    Returns
    -------
    matplotlib.figure.Figure
    """
    x, y = _xy(ds)
    d = np.asarray(ds["dissipation_per_area"])
    fig, ax = plt.subplots(figsize=(5, 4), constrained_layout=True)
    sc = ax.scatter(x, y, c=d, s=24, cmap="magma", edgecolors="none")
    fig.colorbar(sc, ax=ax, label="dissipation per cycle and area [J/m²]")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("dissipation map (last cycle)")
    return fig


def slip_directions(ds, instants=None):
    """Slip directions: the slip increment of each slipping node over the sample step
    ending at each chosen instant (arrows, global x–y components), on the node states.

    Parameters
    ----------
    ds : xarray.Dataset
    instants : sequence of int, optional
        Sample indices ≥ 1 (default: four equally spaced).

    Returns
    -------
    matplotlib.figure.Figure
    """
    idx = [max(1, k) for k in _instants(ds, instants)]
    x, y = _xy(ds)
    theta = np.asarray(ds["theta"])
    slip = np.asarray(ds["slip_global"].isel(cycle=-1))           # (theta, node, 3)
    states = np.asarray(ds["node_state"].isel(cycle=-1))
    fig, axes = plt.subplots(1, len(idx), figsize=(3.2 * len(idx), 3.2), squeeze=False,
                             constrained_layout=True)
    cmap = ListedColormap(STATE_COLOURS)
    for ax, k in zip(axes[0], idx, strict=True):
        dv = slip[k] - slip[k - 1]
        norm = np.linalg.norm(dv[:, :2], axis=1)
        m = (states[k] == 1) & (norm > 0)
        ax.scatter(x, y, c=states[k], cmap=cmap, vmin=-0.5, vmax=2.5, s=10,
                   edgecolors="none")
        if np.any(m):
            # angles "uv" (the axes are equal-aspect, so the same directions as "xy"):
            # "xy" divides by the data extent, zero for one node at the origin
            ax.quiver(x[m], y[m], dv[m, 0] / norm[m], dv[m, 1] / norm[m], angles="uv",
                      color="k", width=0.006)
        ax.set_title(f"θ = {theta[k]:.2f} rad")
        ax.set_xlabel("x [m]")
        ax.set_aspect("equal", adjustable="datalim")
    axes[0][0].set_ylabel("y [m]")
    fig.suptitle("slip directions of slipping nodes (unit arrows), last cycle")
    return fig


def dissipation_history(ds):
    """Total dissipation of every cycle [J] (approach to the steady cycle).

    Parameters
    ----------
    ds : xarray.Dataset

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = plt.subplots(figsize=(5, 3.5), constrained_layout=True)
    ax.plot(np.asarray(ds["cycle"]), np.asarray(ds["dissipation_history"]), "o-")
    ax.set_xlabel("cycle")
    ax.set_ylabel("dissipation per cycle [J]")
    ax.set_title("dissipation history")
    return fig


def basin_dissipation(codes, dissipation, code_names, lam):
    """Dissipation per cycle [J] of the steady state reached from every start of a basins
    study, coloured by the class reached (distinct levels are distinct attractors).

    Parameters
    ----------
    codes : (S,) int array
        Class code of each start (index into ``code_names``).
    dissipation : (S,) array
        Dissipation per cycle [J] (nan where no cycle was run).
    code_names : sequence of str
        Name of each class code.
    lam : float
        Load factor of the study (title).

    Returns
    -------
    matplotlib.figure.Figure
    """
    codes = np.asarray(codes)
    d = np.asarray(dissipation, float)
    fig, ax = plt.subplots(figsize=(5.5, 3.5), constrained_layout=True)
    start = np.arange(codes.size)
    for c in np.unique(codes):
        sel = codes == c
        ax.plot(start[sel], np.where(np.isfinite(d[sel]), d[sel], 0.0), "o",
                label=code_names[int(c)])
    ax.set_xlabel("start")
    ax.set_ylabel("dissipation per cycle [J]")
    ax.set_title(f"steady states over the starts, λ = {lam:g}")
    ax.legend(fontsize="small")
    return fig
