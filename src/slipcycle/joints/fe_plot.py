"""Figure of a mesh study: dissipation per cycle against node spacing, with the fit.

Log-log axes where every value is positive, so that a power law f − c ∝ hᵖ shows its
order; the fitted curve c + k hᵖ (Richardson, through the last three meshes) and the
extrapolated value c are drawn when the study gives them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from slipcycle.joints.convergence import MeshConvergence

__all__ = ["mesh_convergence_figure"]


def mesh_convergence_figure(spacing: Sequence[float], values: Sequence[float | None],
                            mc: MeshConvergence | None, title: str = ""):
    """Dissipation per cycle [J] against node spacing h [m].

    Parameters
    ----------
    spacing : sequence of float, shape (m,)
        Node spacing of each mesh [m].
    values : sequence of float or None, shape (m,)
        Dissipation per cycle of each mesh [J] (None: no steady cycle).
    mc : MeshConvergence or None
        The study (fit and extrapolation drawn when available).
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
    if mc is not None and mc.observed_order is not None and mc.extrapolated is not None \
            and len(h) >= 3:
        p, c = mc.observed_order, mc.extrapolated
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
    verdict = "not assessed" if mc is None else (
        "mesh-converged" if mc.converged else "NOT mesh-converged")
    ax.set_title(f"{title}\n{verdict}" if title else verdict)
    ax.legend()
    return fig
