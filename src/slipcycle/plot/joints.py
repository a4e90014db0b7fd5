"""Figures of the tightening-order study of a bolted joint (from its Dataset).

Each function takes the Dataset built by ``LapJointResult.to_dataset()`` (dimensions
``protocol``, ``node``, ``bolt``, ``cycle``, ``mesh``) and returns a matplotlib Figure; no
physics is computed here. Nodes are drawn at their (x, y) coordinates.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch

__all__ = ["dissipation_by_protocol", "slip_maps", "dissipation_maps", "dissipation_by_bolt",
           "dissipation_history", "CLASS_COLOURS"]

#: colours of the node classes stuck, slipping, separating
CLASS_COLOURS = ("#4c72b0", "#dd8452", "#8c8c8c")


def _names(ds) -> list[str]:
    """Protocol names (the ``protocol_name`` labels of a CF-completed Dataset)."""
    key = "protocol_name" if "protocol_name" in ds.coords else "protocol"
    return [str(p) for p in np.asarray(ds[key])]


def _grid(count: int, size: float = 3.4):
    cols = min(count, 2)
    rows = -(-count // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(size * 1.6 * cols, size * rows),
                             squeeze=False, constrained_layout=True)
    for ax in axes.ravel()[count:]:
        ax.set_visible(False)
    return fig, axes.ravel()


def dissipation_by_protocol(ds):
    """Steady dissipation per cycle of each protocol, with the mesh error as error bars.

    Parameters
    ----------
    ds : xarray.Dataset
        ``dissipation`` [J] (protocol), ``dissipation_error`` [J] (NaN or inf where not
        estimated), ``dissipation_extrapolated`` [J].

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = _names(ds)
    d = np.asarray(ds["dissipation"], float)
    err = np.asarray(ds["dissipation_error"], float)
    ext = np.asarray(ds["dissipation_extrapolated"], float)
    fig, ax = plt.subplots(figsize=(1.4 * len(names) + 2.5, 3.6), constrained_layout=True)
    pos = np.arange(len(names))
    shown = np.where(np.isfinite(err), err, 0.0)
    ax.bar(pos, d * 1e6, color="#4c72b0", label="finest mesh")
    if np.any(shown > 0):
        ax.errorbar(pos, d * 1e6, yerr=shown * 1e6, fmt="none", ecolor="k", capsize=4,
                    label="estimated mesh error")
    if np.any(np.isfinite(ext)):
        ax.plot(pos, ext * 1e6, "D", color="#c44e52", label="extrapolated h → 0")
    for k in np.flatnonzero(~np.isfinite(err) & np.isfinite(d)):
        if not np.isnan(err[k]):  # inf: vanishes under refinement
            ax.annotate("not converged", (pos[k], d[k] * 1e6), ha="center", va="bottom",
                        fontsize=8, color="#c44e52")
    ax.set_xticks(pos, names)
    ax.set_ylabel("dissipation per cycle [µJ]")
    ax.set_title("steady dissipation by tightening protocol")
    ax.legend(fontsize=8, loc="lower right")
    return fig


def _protocol_panels(ds, draw, title: str):
    names = _names(ds)
    fig, axes = _grid(len(names))
    x, y = np.asarray(ds["x"]) * 1e3, np.asarray(ds["y"]) * 1e3
    for j, (ax, name) in enumerate(zip(axes, names, strict=False)):
        draw(ax, ds.isel(protocol=j), x, y)
        order = str(ds["order"].isel(protocol=j).values)
        ax.set_title(f"{name}: {order}", fontsize=9)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.set_aspect("equal")
    fig.suptitle(title)
    return fig, axes


def slip_maps(ds):
    """Stuck / slipping / separating nodes over the steady cycle, one panel per protocol.

    Parameters
    ----------
    ds : xarray.Dataset
        ``node_class`` (protocol, node), coordinates ``x``, ``y`` [m].

    Returns
    -------
    matplotlib.figure.Figure
    """
    cmap = ListedColormap(CLASS_COLOURS)

    def draw(ax, sub, x, y):
        ax.scatter(x, y, c=np.asarray(sub["node_class"]), cmap=cmap, vmin=-0.5, vmax=2.5,
                   s=14, edgecolors="none")

    fig, axes = _protocol_panels(ds, draw, "node classes over the steady cycle")
    handles = [Patch(color=c, label=w) for c, w in
               zip(CLASS_COLOURS, ("permanently stuck", "slipping", "separating"),
                   strict=True)]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8,
               bbox_to_anchor=(0.5, -0.02))
    return fig


def dissipation_maps(ds):
    """Dissipation per unit area of each node over the steady cycle, per protocol (one
    colour scale for every panel).

    Returns
    -------
    matplotlib.figure.Figure
    """
    q = np.asarray(ds["dissipation_per_area"], float)
    vmax = float(np.nanmax(q)) if np.any(q > 0) else 1.0

    def draw(ax, sub, x, y):
        sc = ax.scatter(x, y, c=np.asarray(sub["dissipation_per_area"]), cmap="magma_r",
                        vmin=0.0, vmax=vmax, s=14, edgecolors="none")
        ax.figure.colorbar(sc, ax=ax, label="J/m² per cycle", shrink=0.8)

    fig, _ = _protocol_panels(ds, draw, "dissipation per unit area over the steady cycle")
    return fig


def dissipation_by_bolt(ds):
    """Dissipation per cycle in each bolt region, grouped by protocol.

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = _names(ds)
    region = np.asarray(ds["dissipation_per_region"], float)   # (protocol, bolt)
    k = region.shape[1]
    fig, ax = plt.subplots(figsize=(1.2 * k * len(names) / 2 + 3.0, 3.6),
                           constrained_layout=True)
    width = 0.8 / len(names)
    pos = np.arange(k)
    for j, name in enumerate(names):
        ax.bar(pos + (j - (len(names) - 1) / 2) * width, region[j] * 1e6, width,
               label=name)
    ax.set_xticks(pos, [f"bolt {b}" for b in range(k)])
    ax.set_ylabel("dissipation per cycle [µJ]")
    ax.set_title("dissipation per bolt region")
    ax.legend(fontsize=8)
    return fig


def dissipation_history(ds):
    """Dissipation of each cycle after the assembly, per protocol (the approach to the
    steady state).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = plt.subplots(figsize=(5.5, 3.6), constrained_layout=True)
    cycle = np.asarray(ds["cycle"])
    for j, name in enumerate(_names(ds)):
        h = np.asarray(ds["dissipation_history"].isel(protocol=j), float)
        ax.plot(cycle, h * 1e6, "o-", ms=3, label=name)
    ax.set_xlabel("cycle")
    ax.set_ylabel("dissipation [µJ]")
    ax.set_title("dissipation per cycle after the assembly")
    ax.legend(fontsize=8)
    return fig
