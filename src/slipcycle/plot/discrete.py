"""Figures of the coupled discrete model (SPEC §2).

- :func:`slip_and_tractions`: slip v_j(θ) and tractions q_j(θ) with the limits ±f p_j(θ)
  over the last cycle run;
- :func:`hysteresis`: q–v loops per node over the last cycle (the enclosed area is the
  dissipation D_j = −∮ q_j dv_j);
- :func:`v_space`: for N = 2, the four friction constraints (seed 001 eq. 3) at their
  extreme positions over the cycle, the safe shakedown region they leave, and the
  trajectory of the state in (v_1, v_2).

Each function returns a matplotlib Figure and does not call ``plt.show``.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["slip_and_tractions", "hysteresis", "v_space", "MAX_NODES_SHOWN"]

MAX_NODES_SHOWN = 8


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
        The dataset of :func:`slipcycle.discrete.case.run_case`.
    """
    last = ds.isel(cycle=-1)
    theta = np.asarray(ds["theta"])
    nodes = _nodes_to_show(ds)
    fig = Figure(figsize=(8, 6))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    for j in nodes:
        (line,) = ax1.plot(theta, last["slip"].values[:, j], label=f"node {j}")
        c = line.get_color()
        ax2.plot(theta, last["tangential_reaction"].values[:, j], color=c)
        lim = last["friction_limit"].values[:, j]
        ax2.plot(theta, lim, color=c, ls=":", lw=0.8)
        ax2.plot(theta, -lim, color=c, ls=":", lw=0.8)
    ax1.set_ylabel("slip v [m]")
    ax2.set_ylabel("q [N] (dotted: ±f p)")
    ax2.set_xlabel("θ [rad]")
    ax1.set_title(f"last cycle ({int(ds['cycle'].values[-1])})")
    ax1.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


def hysteresis(ds) -> Figure:
    """q–v loop of each node over the last cycle; the legend gives D_j."""
    last = ds.isel(cycle=-1)
    nodes = _nodes_to_show(ds)
    k = len(nodes)
    cols = min(k, 4)
    rows = int(np.ceil(k / cols))
    fig = Figure(figsize=(3.0 * cols, 2.6 * rows))
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    for ax, j in zip(axes, nodes, strict=False):
        v = last["slip"].values[:, j]
        q = last["tangential_reaction"].values[:, j]
        ax.plot(v, q, lw=1)
        ax.set_title(f"node {j}: D = {float(ds['dissipation_per_node'][j]):.3g} J", fontsize=8)
        ax.set_xlabel("v [m]", fontsize=8)
        ax.set_ylabel("q [N]", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in axes[k:]:
        ax.set_visible(False)
    fig.tight_layout()
    return fig


def extreme_constraints(system, load, steps: int = 720):
    """Extreme positions of the 2N all-contact friction constraints in v-space.

    Constraint (j, s), s = ±1: s q_j + f_j p_j ≥ 0 with w = 0, i.e.
    (s A_j + f_j B_j) · v ≥ −(s q^w_j(θ) + f_j p^w_j(θ)). Its extreme position is the largest
    right-hand side over the cycle.

    Returns
    -------
    G : (2N, N) array
        Rows s A_j + f_j B_j [N/m].
    h : (2N,) array
        max over θ of the right-hand side [N]; the safe region is {v : G v ≥ h}.
    """
    n = system.n_nodes
    th = np.linspace(0, 2 * np.pi, steps + 1)
    r = load(th)
    qw, pw = r[:, :n], r[:, n:]
    f = system.friction
    G, h = [], []
    for j in range(n):
        for s in (1.0, -1.0):
            G.append(s * system.A[j] + f[j] * system.B[j])
            h.append(np.max(-(s * qw[:, j] + f[j] * pw[:, j])))
    return np.array(G), np.array(h)


def v_space(system, load, result) -> Figure:
    """N = 2: constraint lines at their extreme positions, safe region, trajectory."""
    n = system.n_nodes
    if n != 2:
        raise ValueError("v_space needs a two-node system")
    G, h = extreme_constraints(system, load)
    v = result.x[:, :, :n].reshape(-1, n)
    v = np.vstack([result.initial_state[None, :n], v]) if result.initial_state is not None \
        else v
    lo, hi = v.min(axis=0), v.max(axis=0)
    span = np.maximum(hi - lo, 1e-12)
    # include the safe region's vertices in the view
    verts = []
    for a in range(4):
        for b in range(a + 1, 4):
            M = G[[a, b]]
            if abs(np.linalg.det(M)) > 1e-12 * np.abs(M).max() ** 2:
                p = np.linalg.solve(M, h[[a, b]])
                if np.all(G @ p >= h - 1e-9 * np.abs(h).max()):
                    verts.append(p)
    if verts:
        verts = np.array(verts)
        lo = np.minimum(lo, verts.min(axis=0))
        hi = np.maximum(hi, verts.max(axis=0))
        span = np.maximum(hi - lo, 1e-12)
    lo, hi = lo - 0.3 * span, hi + 0.3 * span
    fig = Figure(figsize=(6, 5.5))
    ax = fig.subplots()
    X, Y = np.meshgrid(np.linspace(lo[0], hi[0], 300), np.linspace(lo[1], hi[1], 300))
    P = np.stack([X, Y], axis=-1)
    safe = np.all(P @ G.T >= h, axis=-1)
    ax.contourf(X, Y, safe.astype(float), levels=[0.5, 1.5], colors=["#cfe8cf"])
    names = ["I (node 1, q=+fp)", "II (node 1, q=−fp)", "III (node 2, q=+fp)",
             "IV (node 2, q=−fp)"]
    # order of the seed: I, III are the s=−1 constraints (q = +f p), II, IV s=+1
    labels = {0: names[1], 1: names[0], 2: names[3], 3: names[2]}
    xs = np.linspace(lo[0], hi[0], 2)
    for k in range(4):
        g = G[k]
        if abs(g[1]) > 1e-12 * np.abs(g).max():
            ax.plot(xs, (h[k] - g[0] * xs) / g[1], lw=1, label=labels[k] + ", extreme")
        else:
            ax.axvline(h[k] / g[0], lw=1, label=labels[k] + ", extreme")
    ax.plot(v[:, 0], v[:, 1], "k-", lw=0.8, label="trajectory")
    ax.plot(v[0, 0], v[0, 1], "ko", ms=4, label="start")
    ax.plot(v[-1, 0], v[-1, 1], "rs", ms=4, label="end")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel("v₁ [m]")
    ax.set_ylabel("v₂ [m]")
    ax.set_title(f"v-space: {result.steady_state} (shaded: safe shakedown region)")
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig
