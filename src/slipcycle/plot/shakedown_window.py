"""Figure of the 3-D shakedown window: which start (assembly protocol) shakes down at
which load factor (:mod:`slipcycle.discrete3d.shakedown_window`)."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from slipcycle.plot.shakedown import CLASS_COLORS

__all__ = ["shakedown_map"]


def shakedown_map(labels, lam, codes, lambda2, limits, code_names) -> Figure:
    """Class of every start over the λ grid, λ2 of its system (dashed) and the bracket of
    its largest shakedown load factor (bar).

    Parameters
    ----------
    labels : sequence of str
        The starts (S).
    lam : (L,) array
        Load factors [1].
    codes : (S, L) int array
        Class codes (index into ``code_names``).
    lambda2 : (S,) array
    limits : (S, 2) array
        [lo, hi] per start (hi NaN: no failure on the grid).
    code_names : sequence of str

    Returns
    -------
    matplotlib.figure.Figure
    """
    codes = np.asarray(codes, int)
    lam = np.asarray(lam, float)
    s = len(labels)
    fig = Figure(figsize=(6.5, 1.2 + 0.45 * s), constrained_layout=True)
    ax = fig.add_subplot()
    colors = (CLASS_COLORS + ["#607d8b"] * len(code_names))[:len(code_names)]
    step = lam[1] - lam[0] if lam.size > 1 else lam[0]
    edges = np.concatenate([lam - step / 2, [lam[-1] + step / 2]])
    ax.pcolormesh(edges, np.arange(s + 1) - 0.5, codes, cmap=ListedColormap(colors),
                  vmin=-0.5, vmax=len(code_names) - 0.5)
    for i in range(s):
        ax.plot([lambda2[i]] * 2, [i - 0.45, i + 0.45], "k--", lw=1)
        lo, hi = limits[i]
        if np.isfinite(hi):
            ax.plot([lo, hi], [i, i], "k-", lw=3)
    for c in np.unique(codes):
        ax.plot([], [], "s", color=colors[int(c)], label=code_names[int(c)])
    ax.plot([], [], "k--", label="λ2")
    ax.plot([], [], "k-", lw=3, label="shakedown limit")
    ax.set_yticks(np.arange(s), labels)
    ax.set_xlabel("load factor λ")
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.0, 1.0))
    return fig
