"""Figures of the coupled discrete model (Barber; Ahn, Bertocchi & Barber 2008).

- :func:`slip_and_tractions`: slip v_j(θ) and tractions q_j(θ) with the limits ±f p_j(θ)
  over the last cycle run;
- :func:`hysteresis`: q–v loops per node over the last cycle (the enclosed area is the
  dissipation D_j = −∮ q_j dv_j);
- :func:`v_space`: for N = 2, the four friction constraints (Barber's I–IV) at their
  extreme positions over the cycle, the safe shakedown region they leave (with a zoomed
  panel when it is thin), and the trajectory of the state in (v₀, v₁).

Nodes are numbered from 0 in every figure, as in the summary and the Dataset's ``node``
coordinate. Axis units are scaled to the data (µm, mN, mJ, ...); nodes stuck over the
whole last cycle are said to be stuck, not drawn as round-off loops.

Each function returns a matplotlib Figure and does not call ``plt.show``.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["slip_and_tractions", "hysteresis", "v_space", "MAX_NODES_SHOWN", "scaled_unit",
           "stuck_nodes"]

MAX_NODES_SHOWN = 8

_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"),
             (1e-9, "n"), (1e-12, "p"))


def scaled_unit(values, unit: str) -> tuple[float, str]:
    """A power-of-1000 unit for data of this size: ``(factor, "µm")`` such that
    ``values / factor`` has its largest magnitude in [1, 1000).

    Tick labels then need no offset text (matplotlib's "1e-14" printed over the axis
    label) and read in the unit of the data.
    """
    m = float(np.nanmax(np.abs(values), initial=0.0)) if np.size(values) else 0.0
    if not np.isfinite(m) or m == 0.0:
        return 1.0, unit
    for factor, prefix in _PREFIXES:
        if m >= factor:
            return factor, prefix + unit
    return _PREFIXES[-1][0], _PREFIXES[-1][1] + unit


def _plain(ax) -> None:
    """No offset/scientific tick text: the unit in the label carries the scale."""
    for axis in (ax.xaxis, ax.yaxis):
        fmt = axis.get_major_formatter()
        if hasattr(fmt, "set_useOffset"):
            fmt.set_useOffset(False)
            fmt.set_scientific(False)


def stuck_nodes(ds) -> np.ndarray:
    """(N,) bool: nodes stuck over the whole last cycle.

    From the Dataset's ``permanently_stuck`` (slip length ≤ the run's tolerance, the same
    one the summary's ``permanently_stuck_nodes`` uses: max(100 tol, 1e-9) × displacement
    scale). For a Dataset without it, a node whose slip range over the last cycle is at most
    1e-9 of the largest slip magnitude is taken as stuck.
    """
    if "permanently_stuck" in ds:
        return np.asarray(ds["permanently_stuck"]).astype(bool)
    v = np.asarray(ds["slip"].isel(cycle=-1))
    scale = max(float(np.max(np.abs(v))), np.finfo(float).tiny)
    return np.ptp(v, axis=0) <= 1e-9 * scale


def _nodes_to_show(ds) -> np.ndarray:
    n = ds.sizes["node"]
    if n <= MAX_NODES_SHOWN:
        return np.arange(n)
    d = np.asarray(ds["dissipation_per_node"])
    order = np.argsort(-d, kind="stable")
    return np.sort(order[:MAX_NODES_SHOWN])


def slip_and_tractions(ds) -> Figure:
    """Slip and tangential traction with friction limits over the last cycle.

    Parameters
    ----------
    ds : xarray.Dataset
        The dataset of :func:`slipcycle.discrete.case.run_case`; nodes are numbered from
        0, as in the summary and the Dataset's ``node`` coordinate.
    """
    last = ds.isel(cycle=-1)
    theta = np.asarray(ds["theta"])
    nodes = _nodes_to_show(ds)
    v_all = last["slip"].values[:, nodes]
    q_all = np.concatenate([last["tangential_reaction"].values[:, nodes],
                            last["friction_limit"].values[:, nodes]])
    fv, uv = scaled_unit(v_all, "m")
    fq, uq = scaled_unit(q_all, "N")
    fig = Figure(figsize=(8, 6))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    for j in nodes:
        (line,) = ax1.plot(theta, last["slip"].values[:, j] / fv, label=f"node {j}")
        c = line.get_color()
        ax2.plot(theta, last["tangential_reaction"].values[:, j] / fq, color=c)
        lim = last["friction_limit"].values[:, j] / fq
        ax2.plot(theta, lim, color=c, ls=":", lw=0.8)
        ax2.plot(theta, -lim, color=c, ls=":", lw=0.8)
    ax1.set_ylabel(f"slip v [{uv}]")
    ax2.set_ylabel(f"q [{uq}] (dotted: ±f p)")
    ax2.set_xlabel("θ [rad]")
    ax1.set_title(f"last cycle ({int(ds['cycle'].values[-1])})")
    ax1.legend(fontsize=7, ncol=2)
    _plain(ax1)
    _plain(ax2)
    fig.tight_layout()
    return fig


def hysteresis(ds) -> Figure:
    """q–v loop of each node over the last cycle; each title gives D_j, the figure's the sum.

    A node stuck over the whole last cycle (:func:`stuck_nodes`) has no loop to draw: its
    slip range is below the run's tolerance (round-off, or the last creep of an approach
    to shakedown). Its panel has no axes: it says the node is stuck and gives the slip
    range against the tolerance, and its title the dissipation D_j the run computed for it
    (the summary's ``dissipation_per_node``), so the titles add up to the figure's total,
    the summary's ``dissipation_per_cycle``.
    """
    last = ds.isel(cycle=-1)
    nodes = _nodes_to_show(ds)
    stuck = stuck_nodes(ds)
    tol = float(ds.attrs.get("slip_tolerance", np.nan))
    k = len(nodes)
    cols = min(k, 4)
    rows = int(np.ceil(k / cols))
    fig = Figure(figsize=(3.2 * cols, 2.9 * rows + 0.4))
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    D = np.asarray(ds["dissipation_per_node"])
    fd, ud = scaled_unit(D, "J")
    for ax, j in zip(axes, nodes, strict=False):
        v = last["slip"].values[:, j]
        q = last["tangential_reaction"].values[:, j]
        if stuck[j]:
            rng = float(np.ptp(v))
            fr, ur = scaled_unit([rng, tol] if np.isfinite(tol) else [rng], "m")
            lim = (f" < tolerance {tol / fr:.3g} {ur}" if np.isfinite(tol) else "")
            ax.text(0.5, 0.5, f"permanently stuck\nslip range {rng / fr:.3g} {ur}{lim}\n"
                    "(within the tolerance: no loop drawn)", ha="center", va="center",
                    fontsize=8, transform=ax.transAxes)
            ax.set_axis_off()
            ax.set_title(f"node {j}: stuck, D = {D[j] / fd:.3g} {ud}", fontsize=8)
            continue
        fv, uv = scaled_unit(v, "m")
        fq, uq = scaled_unit(q, "N")
        ax.plot(v / fv, q / fq, lw=1)
        ax.set_title(f"node {j}: D = {D[j] / fd:.3g} {ud}", fontsize=8)
        ax.set_xlabel(f"v [{uv}]", fontsize=8)
        ax.set_ylabel(f"q [{uq}]", fontsize=8)
        ax.tick_params(labelsize=7)
        _plain(ax)
    for ax in axes[k:]:
        ax.set_visible(False)
    total = float(np.sum(D))
    shown = "" if k == D.size else f", {k} of {D.size} nodes shown"
    fig.suptitle(f"last cycle: D = {total / fd:.3g} {ud} in all{shown}", fontsize=9)
    fig.tight_layout()
    return fig


#: the safe region gets a zoomed panel when its extent is below this fraction of the view
ZOOM_BELOW = 0.2


def constraint_labels() -> dict[int, str]:
    """Labels of the rows of :func:`extreme_constraints` for N = 2 (Barber's I–IV; nodes
    numbered from 0 like the summary): row 2j is s = +1 (q = −f p), row 2j+1 is s = −1."""
    return {0: "II (node 0, q=−fp)", 1: "I (node 0, q=+fp)", 2: "IV (node 1, q=−fp)",
            3: "III (node 1, q=+fp)"}


def _crosses_view(g: np.ndarray, h: float, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether the line {v : g·v = h} passes through the box [lo, hi] (2-D)."""
    corners = np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]])
    s = corners @ np.asarray(g, float) - h
    return bool(s.min() <= 0.0 <= s.max())


def _draw_lines(ax, G, h, lo, hi, labels=None):
    """Draw the constraint lines; ``labels[k]`` (None: unlabelled) names line k."""
    xs = np.linspace(lo[0], hi[0], 2)
    colors = [f"C{k}" for k in range(4)]
    for k in range(G.shape[0]):
        g = G[k]
        lab = None if labels is None or labels.get(k) is None else labels[k] + ", extreme"
        if abs(g[1]) > 1e-12 * np.abs(g).max():
            ax.plot(xs, (h[k] - g[0] * xs) / g[1], lw=1, color=colors[k], label=lab)
        else:
            ax.axvline(h[k] / g[0], lw=1, color=colors[k], label=lab)


def v_space(result, G: np.ndarray, h: np.ndarray, verts: np.ndarray) -> Figure:
    """N = 2: constraint lines at their extreme positions, safe region, trajectory.

    Axes are the slips v₀, v₁ of nodes 0 and 1 (numbered from 0 like the summary), in a
    unit scaled to the data. When the safe region is small against the view (a thin
    sliver next to the trajectory) a second panel zooms on it.

    Parameters
    ----------
    result : SteadyResult
        The run: ``x`` (cycles, steps, 2N) states, ``initial_state``, ``steady_state``.
    G : (4, 2) array, h : (4,) array
        The constraints at their extreme positions, {v : G v ≥ h} [N/m, N]
        (:func:`slipcycle.discrete.shakedown.extreme_constraints`).
    verts : (k, 2) array
        Vertices of the safe region [m] (:func:`slipcycle.discrete.shakedown.safe_vertices`;
        empty when there is none).
    """
    n = G.shape[1]
    if n != 2:
        raise ValueError("v_space needs a two-node system")
    v = result.x[:, :, :n].reshape(-1, n)
    v = np.vstack([result.initial_state[None, :n], v]) if result.initial_state is not None \
        else v
    lo, hi = v.min(axis=0), v.max(axis=0)
    if len(verts):
        lo = np.minimum(lo, verts.min(axis=0))
        hi = np.maximum(hi, verts.max(axis=0))
    span = np.maximum(hi - lo, 1e-12 * max(float(np.abs(hi).max()), 1e-300))
    lo, hi = lo - 0.3 * span, hi + 0.3 * span
    f, unit = scaled_unit(np.concatenate([lo, hi]), "m")
    zoom = None
    if len(verts) >= 3:
        ext = verts.max(axis=0) - verts.min(axis=0)
        if np.min(ext / (hi - lo)) < ZOOM_BELOW:
            pad = 0.25 * np.max(ext)
            zoom = (verts.min(axis=0) - pad, verts.max(axis=0) + pad)
    if zoom is None:
        fig = Figure(figsize=(6.4, 5.8))
        ax = fig.subplots()
    else:
        fig = Figure(figsize=(11.5, 5.4))
        ax, axz = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.15, 1]})
    # the legend names only the lines that cross a panel; the others are said to lie
    # outside the view (a legend entry for a line that is nowhere drawn misleads)
    views = [(lo, hi)] + ([zoom] if zoom is not None else [])
    labels = {k: lab for k, lab in constraint_labels().items()
              if any(_crosses_view(G[k], h[k], a, b) for a, b in views)}
    outside = [lab for k, lab in constraint_labels().items() if k not in labels]

    def draw(axx, lo_, hi_, legend):
        if len(verts) >= 3:
            axx.fill(verts[:, 0] / f, verts[:, 1] / f, color="#a5d6a7", zorder=0,
                     label="safe shakedown region" if legend else None)
        _draw_lines(axx, G, h / f, lo_ / f, hi_ / f, labels if legend else None)
        axx.plot(v[:, 0] / f, v[:, 1] / f, "k-", lw=0.8,
                 label="trajectory" if legend else None)
        axx.plot(v[0, 0] / f, v[0, 1] / f, "ko", ms=4, label="start" if legend else None)
        axx.plot(v[-1, 0] / f, v[-1, 1] / f, "rs", ms=4, label="end" if legend else None)
        axx.set_xlim(lo_[0] / f, hi_[0] / f)
        axx.set_ylim(lo_[1] / f, hi_[1] / f)
        _plain(axx)

    draw(ax, lo, hi, True)
    ax.set_xlabel(f"v₀ (node 0) [{unit}]")
    ax.set_ylabel(f"v₁ (node 1) [{unit}]")
    ax.set_title(f"v-space: {result.steady_state} (shaded: safe shakedown region)", fontsize=10)
    legend = ax.legend(fontsize=7, loc="best")
    if outside:
        legend.set_title("outside the view: " + "; ".join(outside), prop={"size": 7})
    if zoom is not None:
        draw(axz, zoom[0], zoom[1], False)
        axz.set_xlabel(f"v₀ (node 0) [{unit}]")
        axz.set_ylabel(f"v₁ (node 1) [{unit}]")
        # ticks and label on the outer side, so the zoom connectors cross no text
        axz.yaxis.tick_right()
        axz.yaxis.set_label_position("right")
        axz.set_title("zoom on the safe shakedown region", fontsize=10)
        ax.indicate_inset_zoom(axz, edgecolor="0.3")
    fig.tight_layout()
    return fig
