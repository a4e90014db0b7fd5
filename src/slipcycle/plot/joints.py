"""Figures of the tightening-order study of a bolted joint (from its Dataset).

Each function takes the Dataset built by ``LapJointResult.to_dataset()`` (dimensions
``protocol``, ``node``, ``bolt``, ``cycle``, ``mesh``) and returns a matplotlib Figure; no
physics is computed here. Nodes are drawn at their (x, y) coordinates.
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

__all__ = ["dissipation_by_protocol", "slip_maps", "dissipation_maps", "dissipation_by_bolt",
           "dissipation_history", "outline_of", "CLASS_COLOURS"]

#: colours of the node classes stuck, slipping, separating
CLASS_COLOURS = ("#4c72b0", "#dd8452", "#8c8c8c")


def _names(ds) -> list[str]:
    """Protocol names (the ``protocol_name`` labels of a CF-completed Dataset)."""
    key = "protocol_name" if "protocol_name" in ds.coords else "protocol"
    return [str(p) for p in np.asarray(ds[key])]


def _grid(count: int, aspect: float, size: float = 3.4, extra: float = 0.0):
    """Panels of ``size`` inches high whose width follows the data's ``aspect`` (width over
    height) plus ``extra`` inches (a colour bar), so equal axes leave no empty gap."""
    cols = min(count, 2)
    rows = -(-count // cols)
    # the axes get about size − 0.8 in of height (title, x label); 0.8 in for the y label
    width = (size - 0.8) * float(np.clip(aspect, 0.3, 3.0)) + extra + 0.8
    fig = Figure(figsize=(width * cols, size * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False)
    for ax in axes.ravel()[count:]:
        ax.set_visible(False)
    return fig, axes.ravel()


def dissipation_by_protocol(ds, difference_tol: float | None = None):
    """Each protocol's steady dissipation per cycle and its difference from the reference.

    The protocols usually differ by far less than the dissipation itself (parts per
    thousand), so bars from zero would look identical. The left panel gives the values on
    an axis zoomed to them; the right panel the relative differences
    (D_p − D_ref)/D_ref from the reference (first) protocol, with the band
    ±``difference_tol`` inside which the orders are said not to differ (the spread
    (max − min)/max against it is the summary's ``orders_differ``). Mesh error bars
    (``dissipation_error``) and the h → 0 extrapolation are drawn where they were
    estimated (several meshes); with one mesh the legend says so.

    Parameters
    ----------
    ds : xarray.Dataset
        ``dissipation`` [J] (protocol), ``dissipation_error`` [J] (NaN or inf where not
        estimated), ``dissipation_extrapolated`` [J], ``mesh`` dimension.
    difference_tol : float, optional
        Relative spread that counts as a difference [1] (the case's
        ``run.difference_tol``); no band without it.

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = _names(ds)
    d = np.asarray(ds["dissipation"], float)
    err = np.asarray(ds["dissipation_error"], float)
    ext = np.asarray(ds["dissipation_extrapolated"], float)
    meshes = int(ds.sizes.get("mesh", 1))
    fig = Figure(figsize=(2.2 * len(names) + 4.5, 3.8), layout="constrained")
    ax, axd = fig.subplots(1, 2)
    pos = np.arange(len(names))
    shown = np.where(np.isfinite(err), err, 0.0)
    label = f"finest of {meshes} meshes" if meshes > 1 else "one mesh (no mesh error)"
    ax.plot(pos, d * 1e6, "o", color="#4c72b0", ms=7, label=label)
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
    ax.set_xlim(-0.5, len(names) - 0.5)
    ax.set_ylabel("dissipation per cycle [µJ]")
    ax.set_title("steady dissipation", fontsize=10)
    ax.grid(alpha=0.3, axis="y")

    rel = (d - d[0]) / d[0] if d[0] != 0 else np.zeros_like(d)
    axd.bar(pos, rel * 1e3, color="#4c72b0", width=0.6, label=f"D − D({names[0]})")
    if np.any(shown > 0) and d[0] != 0:
        axd.errorbar(pos, rel * 1e3, yerr=shown / abs(d[0]) * 1e3, fmt="none", ecolor="k",
                     capsize=4, label="estimated mesh error")
    if difference_tol is not None:
        axd.axhspan(-difference_tol * 1e3, difference_tol * 1e3, color="0.85", zorder=0,
                    label=f"±difference_tol = ±{difference_tol:g}: no difference")
    axd.axhline(0, color="k", lw=0.6)
    axd.set_xticks(pos, names)
    axd.set_xlim(-0.5, len(names) - 0.5)
    spread = (d.max() - d.min()) / d.max() if d.max() > 0 else 0.0
    axd.set_ylabel(f"(D − D_ref) / D_ref [‰], ref = {names[0]}")
    axd.set_title(f"difference from {names[0]} (spread {spread:.3g})", fontsize=10)
    handles = ax.get_legend_handles_labels()[0] + axd.get_legend_handles_labels()[0]
    fig.legend(handles=handles, fontsize=8, loc="outside lower center",
               ncol=min(len(handles), 3))
    axd.grid(alpha=0.3, axis="y")
    fig.suptitle("steady dissipation by tightening protocol")
    return fig


def outline_of(description) -> dict | None:
    """The interface outline of a lap joint from its description (None without one).

    Parameters
    ----------
    description : mapping
        ``overlap_m``, ``plate_width_m``, ``bolt_diameter_m``, ``washer_diameter_m`` and
        ``bolt_centres_m`` ((K, 2) [m], relative to the centre of the overlap), as the
        joint's contact describes itself.

    Returns
    -------
    dict or None
        ``overlap`` (x0, x1, y0, y1) [m], ``centres`` (K, 2) [m], ``hole_diameter``,
        ``washer_diameter`` [m]; the holes and washers are left out (``centres`` empty)
        when the description has no bolt centres.
    """
    if not description or "overlap_m" not in description \
            or "plate_width_m" not in description:
        return None
    c, w = float(description["overlap_m"]), float(description["plate_width_m"])
    centres = np.asarray(description.get("bolt_centres_m", np.zeros((0, 2))), float)
    return {"overlap": (-c / 2, c / 2, -w / 2, w / 2), "centres": centres.reshape(-1, 2),
            "hole_diameter": float(description.get("bolt_diameter_m", 0.0)),
            "washer_diameter": float(description.get("washer_diameter_m", 0.0))}


def _draw_outline(ax, outline) -> None:
    """The overlap of the plates (solid), bolt holes (solid) and washers (dashed), mm."""
    from matplotlib.patches import Circle, Rectangle

    x0, x1, y0, y1 = (1e3 * v for v in outline["overlap"])
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec="k", lw=1.2,
                           label="overlap of the plates"))
    for k, (x, y) in enumerate(outline["centres"] * 1e3):
        ax.add_patch(Circle((x, y), 0.5e3 * outline["hole_diameter"], fill=False, ec="k",
                            lw=1.0, label="bolt hole" if k == 0 else None))
        ax.add_patch(Circle((x, y), 0.5e3 * outline["washer_diameter"], fill=False,
                            ec="0.3", lw=0.9, ls="--", label="washer" if k == 0 else None))


def _node_patches(ax, ds, x, y, values, **kw):
    """Each node as a disc of diameter 0.84 √A, A its tributary area ``node_area``
    (inside the square of that area, with a margin for graded meshes), coloured by
    ``values``: the discs fill the interface at any mesh and figure size, barely
    overlapping."""
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle

    radius = 0.42 * np.sqrt(np.asarray(ds["node_area"], float)) * 1e3
    coll = PatchCollection([Circle((a, b), r) for a, b, r in zip(x, y, radius, strict=True)],
                           edgecolors="none", **kw)
    coll.set_array(np.asarray(values, float))
    ax.add_collection(coll)
    return coll


def _protocol_panels(ds, draw, title: str, outline=None, extra: float = 0.0):
    names = _names(ds)
    x, y = np.asarray(ds["x"]) * 1e3, np.asarray(ds["y"]) * 1e3
    if outline is not None:
        x0, x1, y0, y1 = (1e3 * v for v in outline["overlap"])
    else:
        x0, x1, y0, y1 = x.min(), x.max(), y.min(), y.max()
    pad = 0.04 * max(x1 - x0, y1 - y0)
    fig, axes = _grid(len(names), (x1 - x0) / max(y1 - y0, 1e-300), extra=extra)
    for j, (ax, name) in enumerate(zip(axes, names, strict=False)):
        draw(ax, ds.isel(protocol=j), x, y)
        if outline is not None:
            _draw_outline(ax, outline)
        order = str(ds["order"].isel(protocol=j).values)
        ax.set_title(f"{name}: {order}", fontsize=9)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.set_xlim(x0 - pad, x1 + pad)
        ax.set_ylim(y0 - pad, y1 + pad)
        ax.set_aspect("equal")
    fig.suptitle(title)
    return fig, axes


def _outline_handles(outline) -> list:
    from matplotlib.lines import Line2D

    if outline is None:
        return []
    handles = [Line2D([], [], color="k", lw=1.2, label="overlap, bolt holes")]
    if len(outline["centres"]):
        handles.append(Line2D([], [], color="0.3", lw=0.9, ls="--", label="washers"))
    return handles


def slip_maps(ds, description=None):
    """Stuck / slipping / separating nodes over the steady cycle, one panel per protocol.

    Each node is a disc of diameter 0.84 √(its tributary area), so the discs fill the
    interface; the overlap of the plates, the bolt holes and the
    washers are outlined (from the joint's ``description``, see :func:`outline_of`).

    Parameters
    ----------
    ds : xarray.Dataset
        ``node_class`` (protocol, node), ``node_area`` [m²], coordinates ``x``, ``y`` [m].
    description : mapping, optional
        The joint's description (geometry [m]); no outline without it.

    Returns
    -------
    matplotlib.figure.Figure
    """
    cmap = ListedColormap(CLASS_COLOURS)
    outline = outline_of(description)

    def draw(ax, sub, x, y):
        coll = _node_patches(ax, ds, x, y, np.asarray(sub["node_class"]), cmap=cmap)
        coll.set_clim(-0.5, 2.5)

    fig, axes = _protocol_panels(ds, draw, "node classes over the steady cycle", outline)
    handles = [Patch(color=c, label=w) for c, w in
               zip(CLASS_COLOURS, ("permanently stuck", "slipping", "separating"),
                   strict=True)] + _outline_handles(outline)
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=8)
    return fig


def dissipation_maps(ds, description=None):
    """Dissipation per unit area of each node over the steady cycle, per protocol (one
    colour scale for every panel; nodes as discs of their area, the joint outlined as in
    :func:`slip_maps`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    q = np.asarray(ds["dissipation_per_area"], float)
    vmax = float(np.nanmax(q)) if np.any(q > 0) else 1.0
    outline = outline_of(description)

    def draw(ax, sub, x, y):
        coll = _node_patches(ax, ds, x, y, np.asarray(sub["dissipation_per_area"]),
                             cmap="magma_r")
        coll.set_clim(0.0, vmax)
        ax.figure.colorbar(coll, ax=ax, label="J/m² per cycle", shrink=0.8)

    fig, _ = _protocol_panels(ds, draw, "dissipation per unit area over the steady cycle",
                              outline, extra=0.9)
    handles = _outline_handles(outline)
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncol=len(handles),
                   fontsize=8)
    return fig


def dissipation_by_bolt(ds):
    """Dissipation per cycle in each bolt region, grouped by protocol (the legend below
    the axes, clear of the bars).

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = _names(ds)
    region = np.asarray(ds["dissipation_per_region"], float)   # (protocol, bolt)
    k = region.shape[1]
    fig = Figure(figsize=(1.2 * k * len(names) / 2 + 3.0, 4.0), layout="constrained")
    ax = fig.subplots()
    width = 0.8 / len(names)
    pos = np.arange(k)
    for j, name in enumerate(names):
        ax.bar(pos + (j - (len(names) - 1) / 2) * width, region[j] * 1e6, width,
               label=name)
    ax.set_xticks(pos, [f"bolt {b}" for b in range(k)])
    ax.set_ylabel("dissipation per cycle [µJ]")
    ax.set_title("dissipation per bolt region")
    fig.legend(fontsize=8, loc="outside lower center", ncol=min(len(names), 4))
    return fig


def dissipation_history(ds):
    """Dissipation of each cycle after the assembly, per protocol (the approach to the
    steady state).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(5.5, 3.6), layout="constrained")
    ax = fig.subplots()
    cycle = np.asarray(ds["cycle"])
    for j, name in enumerate(_names(ds)):
        h = np.asarray(ds["dissipation_history"].isel(protocol=j), float)
        ax.plot(cycle, h * 1e6, "o-", ms=3, label=name)
    ax.set_xlabel("cycle")
    ax.set_ylabel("dissipation [µJ]")
    ax.set_title("dissipation per cycle after the assembly")
    ax.legend(fontsize=8)
    return fig
