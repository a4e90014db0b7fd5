"""Figures of the finite-element reduction and of its mesh studies.

- :func:`coupling` — |A|, |B|, |C| of a reduced model as images over the contact nodes;
- :func:`mesh_convergence` — dissipation per cycle against node spacing, with the fit:
  log-log axes where every value is positive, so that a power law f − c ∝ hᵖ shows its
  order; the fitted curve c + k hᵖ (Richardson, through the last three meshes) and the
  extrapolated value c are drawn when the study gives them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["coupling", "mesh_convergence"]


def coupling(A: np.ndarray, B: np.ndarray, C: np.ndarray):
    """|A|, |B|, |C| [N/m] as images over the contact nodes.

    Parameters
    ----------
    A, B, C : (N, N) arrays
        Reduced tangential stiffness, coupling and normal stiffness [N/m].

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 3.4))
    for ax, (name, M) in zip(fig.subplots(1, 3), (("A", A), ("B", B), ("C", C)),
                             strict=True):
        im = ax.imshow(np.abs(M), cmap="viridis")
        ax.set_title(f"|{name}| [N/m]")
        ax.set_xlabel("node")
        fig.colorbar(im, ax=ax, shrink=0.8)
    fig.tight_layout()
    return fig


def mesh_convergence(spacing: Sequence[float], values: Sequence[float | None],
                     observed_order: float | None = None, extrapolated: float | None = None,
                     converged: bool | None = None, title: str = ""):
    """Dissipation per cycle [J] against node spacing h [m].

    Parameters
    ----------
    spacing : sequence of float, shape (m,)
        Node spacing of each mesh [m].
    values : sequence of float or None, shape (m,)
        Dissipation per cycle of each mesh [J] (None: no steady cycle).
    observed_order, extrapolated : float or None
        The study's observed order p and Richardson extrapolation c [J] (the fit is drawn
        when both are given).
    converged : bool or None
        The study's verdict (None: not assessed).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    h = np.asarray(spacing, float)
    f = np.array([np.nan if v is None else v for v in values], float)
    fig = Figure(figsize=(5.5, 4.2), layout="constrained")
    ax = fig.subplots()
    ax.plot(h * 1e3, f, "o", color="C0", label="meshes")
    positive = np.all(np.isfinite(f) & (f > 0))
    if observed_order is not None and extrapolated is not None and len(h) >= 3:
        p, c = observed_order, extrapolated
        k = (f[-1] - f[-2]) / (h[-1] ** p - h[-2] ** p)
        hh = np.geomspace(h[-1] / 4, h[-3], 100)
        fit = c + k * hh**p
        ax.plot(hh * 1e3, np.where(fit > 0, fit, np.nan) if positive else fit, "-",
                color="C1", label=f"c + k hᵖ, p = {p:.2f}")
        if c > 0 or not positive:
            ax.axhline(c, color="C2", ls="--", label=f"extrapolated {c:.4g} J")
    if positive:
        from matplotlib.ticker import NullFormatter

        ax.set_xscale("log")
        ax.set_yscale("log")
        for axis in (ax.xaxis, ax.yaxis):  # decade labels only: minor ones overlap
            axis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("node spacing h [mm]")
    ax.set_ylabel("dissipation per cycle [J]")
    verdict = "not assessed" if converged is None else (
        "mesh-converged" if converged else "NOT mesh-converged")
    ax.set_title(f"{title}\n{verdict}" if title else verdict)
    ax.legend()
    return fig
