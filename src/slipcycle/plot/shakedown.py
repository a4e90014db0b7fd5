"""Figures of the shakedown analysis (after Barber's Figs. 1–3; Ahn, Bertocchi & Barber 2008).

- :func:`safe_region_panels`: N = 2, one panel per load factor: the four constraints
  I–IV at their extreme positions, the safe region S(λ) shaded, trajectories in (v₀, v₁)
  from several starts ending in shakedown (green) or a cyclic-slip orbit (red);
- :func:`dissipation_vs_lambda`: any N, steady dissipation per cycle against λ for every
  start, with λ1, λ2 and the λ3, λ4 brackets marked;
- :func:`basin_map`: N = 2, steady class and dissipation over the initial slip
  (v₀, v₁), non-converged starts marked.

Nodes are numbered from 0, as in the summaries and Datasets.

Builds on :mod:`slipcycle.plot.discrete` (constraint labels, the single-run v-space
picture). Each function returns a matplotlib Figure.
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure

from slipcycle.plot import discrete as _discrete

__all__ = ["safe_region_panels", "dissipation_vs_lambda", "basin_map", "CLASS_COLORS"]

#: colours of the class codes of :data:`slipcycle.discrete.steady.STEADY_CODES`
CLASS_COLORS = ["#4caf50", "#e53935", "#8e24aa", "#fb8c00", "#e0e0e0", "#000000"]
CLASS_NAMES = ["shakedown", "cyclic slip", "ratcheting", "not converged", "inadmissible",
               "failed"]


def _draw_constraints(ax, region, lam, lo, hi, names, f=1.0):
    """Constraint lines and S(λ) in axes whose slips are in units of ``f`` metres."""
    G, h = region.G, region.h(lam) / f
    lo, hi = np.asarray(lo) / f, np.asarray(hi) / f
    xs = np.linspace(lo[0], hi[0], 2)
    for k in range(G.shape[0]):
        g = G[k]
        if abs(g[1]) > 1e-12 * np.abs(g).max():
            ax.plot(xs, (h[k] - g[0] * xs) / g[1], lw=1, label=names[k] + "$^E$")
        else:
            ax.axvline(h[k] / g[0], lw=1, label=names[k] + "$^E$")
    P = region.vertices(lam) / f
    if len(P) >= 3:
        ax.fill(P[:, 0], P[:, 1], color="#a5d6a7", zorder=0, label="safe region S(λ)")
    return P


def safe_region_panels(region, panels: list[dict], lam1: float, lam2: float) -> Figure:
    """N = 2 v-space panels.

    Parameters
    ----------
    region : SafeRegion
        Anything with ``G``, ``h(lam)``, ``names`` and ``vertices(lam)`` (S(λ) of
        :func:`slipcycle.discrete.shakedown.safe_region`).
    panels : list of dict
        Each with ``lam`` (float) and ``trajectories``: list of (v (k, 2) [m], class str).
    lam1, lam2 : float
        For the panel titles.
    """
    k = len(panels)
    fig = Figure(figsize=(5.0 * k, 4.8))
    axes = np.atleast_1d(fig.subplots(1, k, squeeze=False)).ravel()
    # the constraint labels of the single-run picture (Barber's I–IV)
    names = region.names
    for ax, pan in zip(axes, panels, strict=True):
        lam = pan["lam"]
        pts = [t[0] for t in pan["trajectories"]]
        allv = np.vstack(pts) if pts else np.zeros((0, 2))
        P = region.vertices(lam)
        if len(P):
            allv = np.vstack([allv, P])
        lo, hi = allv.min(axis=0), allv.max(axis=0)
        span = np.maximum(hi - lo, 1e-12)
        lo, hi = lo - 0.25 * span, hi + 0.25 * span
        f, unit = _discrete.scaled_unit(np.concatenate([lo, hi]), "m")
        _draw_constraints(ax, region, lam, lo, hi, names, f)
        for v, cls in pan["trajectories"]:
            col = CLASS_COLORS[0] if cls == "shakedown" else (
                CLASS_COLORS[1] if cls == "cyclic_slip" else CLASS_COLORS[3])
            v = v / f
            ax.plot(v[:, 0], v[:, 1], "-", color=col, lw=0.9)
            ax.plot(v[0, 0], v[0, 1], "o", color=col, ms=4)
            ax.plot(v[-1, 0], v[-1, 1], "s", color="k", ms=3)
        regime = ("λ < λ1: shakedown from every start" if lam < lam1 else
                  "λ1 < λ < λ2: depends on the start" if lam < lam2 else
                  "λ > λ2: no shakedown")
        ax.set_title(f"λ = {lam:.4g}  ({regime})", fontsize=9)
        ax.set_xlim(lo[0] / f, hi[0] / f)
        ax.set_ylim(lo[1] / f, hi[1] / f)
        ax.set_xlabel(f"v₀ (node 0) [{unit}]")
        ax.set_ylabel(f"v₁ (node 1) [{unit}]")
        _discrete._plain(ax)
    axes[0].plot([], [], "-", color=CLASS_COLORS[0], label="→ shakedown")
    axes[0].plot([], [], "-", color=CLASS_COLORS[1], label="→ cyclic slip")
    axes[0].legend(fontsize=6, loc="best")
    fig.suptitle(f"Safe shakedown region (λ1 = {lam1:.4g}, λ2 = {lam2:.4g}); "
                 "o start, ■ end", fontsize=10)
    fig.tight_layout()
    return fig


def dissipation_vs_lambda(lam, dissipation, classes, lam1, lam2, b3, b4, refined=None,
                          trials=None) -> Figure:
    """Steady dissipation per cycle [J] against λ for every start.

    Parameters
    ----------
    lam : (L,) array
    dissipation : (L, S) array [J]
    classes : (L, S) int array (class codes)
    lam1, lam2 : float
    b3, b4 : (lo, hi) grid brackets of λ3, λ4 (hi may be None), shaded
    refined : dict, optional
        ``"lambda3"``/``"lambda4"`` → (lo, hi) refined brackets, drawn as lines at lo
        (dotted) and hi (solid) and named in the legend.
    trials : (lam (T,), dissipation (T, S), classes (T, S)), optional
        Runs at the bisection's trial λ values (drawn as small crosses).
    """
    fig = Figure(figsize=(7, 4.5))
    ax = fig.subplots()
    fd, ud = _discrete.scaled_unit(dissipation, "J")
    dissipation = np.asarray(dissipation) / fd
    if trials is not None:
        trials = (trials[0], np.asarray(trials[1]) / fd, trials[2])
    L, S = dissipation.shape
    for code in np.unique(classes):
        sel = classes == code
        LL = np.broadcast_to(np.asarray(lam)[:, None], (L, S))[sel]
        ax.plot(LL, dissipation[sel], "o", ms=3, color=CLASS_COLORS[int(code)],
                label=CLASS_NAMES[int(code)])
    if trials is not None:
        tl, td, tc = (np.asarray(a) for a in trials)
        for code in np.unique(tc):
            sel = tc == code
            TL = np.broadcast_to(tl[:, None], tc.shape)[sel]
            ax.plot(TL, td[sel], "x", ms=4, color=CLASS_COLORS[int(code)])
    ymax = np.nanmax(dissipation) if np.isfinite(np.nanmax(dissipation, initial=np.nan)) \
        else 1.0
    for x, name, ls in ((lam1, "λ1", "--"), (lam2, "λ2", "-")):
        if np.isfinite(x):
            ax.axvline(x, color="k", ls=ls, lw=1)
            ax.text(x, ymax, name, ha="right", va="top", fontsize=9)
    for (lo, hi), name, col in ((b3, "λ3", "#1e88e5"), (b4, "λ4", "#fdd835")):
        if hi is not None:
            ax.axvspan(lo, hi, color=col, alpha=0.25, label=f"{name} grid bracket")
    for key, name, col, y in (("lambda3", "λ3", "#0d47a1", 0.9),
                              ("lambda4", "λ4", "#f57f17", 0.8)):
        lo, hi = (refined or {}).get(key, (None, None))
        if hi is not None and lo is not None:
            ax.axvline(lo, color=col, ls=":", lw=1.2)
            ax.axvline(hi, color=col, ls="-", lw=1.2,
                       label=f"{name} ∈ [{lo:.5g}, {hi:.5g}]")
            ax.text(hi, y * ymax, f" {name}", color=col, ha="left", va="top", fontsize=9)
    ax.set_xlabel("load factor λ")
    ax.set_ylabel(f"dissipation per cycle [{ud}]")
    _discrete._plain(ax)
    ax.legend(fontsize=7)
    ax.set_title("steady dissipation from many initial conditions")
    fig.tight_layout()
    return fig


def basin_map(v1, v2, classes, dissipation, region=None, lam=None) -> Figure:
    """N = 2 basin map over initial slip states at θ = 0.

    Starts that did not reach a steady state within ``run.cycles`` (class
    ``not_converged``) have their own colour and legend entry (with their count, listed
    even when 0), and are hatched on the dissipation map, whose value for them is only
    that of the last cycle run.

    Parameters
    ----------
    v1 : (n1,) array, v2 : (n2,) array
        Grid of initial slips [m] of nodes 0 and 1 (numbered from 0 like the summary).
    classes : (n2, n1) int array
        Class codes (rows: v2).
    dissipation : (n2, n1) array [J]
    region : SafeRegion, optional
        Drawn at ``lam`` on top (the safe region S(λ); anything with ``vertices(lam)``).
    """
    from matplotlib.patches import Patch

    nc = CLASS_NAMES.index("not converged")
    fig = Figure(figsize=(11.5, 4.9))
    ax1, ax2 = fig.subplots(1, 2)
    f, unit = _discrete.scaled_unit(np.r_[v1[[0, -1]], v2[[0, -1]]], "m")
    cmap = ListedColormap(CLASS_COLORS)
    norm = BoundaryNorm(np.arange(-0.5, len(CLASS_COLORS) + 0.5), cmap.N)
    ext = [v1[0] / f, v1[-1] / f, v2[0] / f, v2[-1] / f]
    ax1.imshow(classes, origin="lower", extent=ext, cmap=cmap, norm=norm, aspect="auto",
               interpolation="nearest")
    shown = sorted(set(np.unique(classes).tolist()) | {nc})
    handles = [Patch(color=CLASS_COLORS[int(c)],
                     label=f"{CLASS_NAMES[int(c)]} ({int((classes == c).sum())})")
               for c in shown]
    ax1.set_title("steady state (count of starts)")
    fd, ud = _discrete.scaled_unit(dissipation[np.isfinite(dissipation)], "J")
    D = np.ma.masked_invalid(np.asarray(dissipation, float) / fd)
    im = ax2.imshow(D, origin="lower", extent=ext, aspect="auto", interpolation="nearest",
                    cmap="viridis")
    fig.colorbar(im, ax=ax2, label=f"dissipation per cycle [{ud}]")
    ax2.set_title("steady dissipation")
    bad = classes == nc
    if bad.any():
        X, Y = np.meshgrid(np.asarray(v1) / f, np.asarray(v2) / f)
        for ax in (ax1, ax2):
            ax.contourf(X, Y, bad.astype(float), levels=[0.5, 1.5], colors="none",
                        hatches=["xxx"])
        handles.append(Patch(facecolor="none", hatch="xxx", edgecolor="k",
                             label="not converged (D of the last cycle run)"))
    if region is not None and lam is not None:
        P = region.vertices(lam) / f
        if len(P) >= 3:
            for ax in (ax1, ax2):
                ax.fill(np.r_[P[:, 0], P[0, 0]], np.r_[P[:, 1], P[0, 1]], fill=False,
                        ec="k", lw=1.2)
            handles.append(Patch(facecolor="none", edgecolor="k", label="S(λ)"))
    ax1.legend(handles=handles, fontsize=7, loc="lower left")
    for ax in (ax1, ax2):
        ax.set_xlabel(f"initial v₀ (node 0) [{unit}]")
        ax.set_ylabel(f"initial v₁ (node 1) [{unit}]")
        _discrete._plain(ax)
    fig.tight_layout()
    return fig


#: the single-run v-space picture, re-exported for the shakedown command
v_space = _discrete.v_space
