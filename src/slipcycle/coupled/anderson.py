"""Anderson mixing of the start-of-cycle states: the accelerator of plain cycling that
extrapolates the fixed point of the cycle map from secant pairs (x_i, Φ(x_i)).

For a plain sequence (x_{i+1} = Φ(x_i)) it is reduced rank extrapolation (A. Sidi,
W. F. Ford and D. A. Smith, SIAM J. Numer. Anal. 23 (1986) 178–196); with jumped starts it
is Anderson mixing (D. G. Anderson, J. ACM 12 (1965) 547–560; H. F. Walker and P. Ni,
SIAM J. Numer. Anal. 49 (2011) 1715–1735), equivalent to GMRES on a linear map.
"""

from __future__ import annotations

import numpy as np

__all__ = ["anderson", "geometric"]


def geometric(states: np.ndarray, spread: float = 1.1) -> bool:
    """The changes u_i = x_{i+1} − x_i of the sequence ``states`` ((k+2, M)) shrink by
    ratios |u_{i+1}|/|u_i| < 1 that agree within the factor ``spread``: the error is then
    dominated by few slowly decaying directions of the cycle map and the extrapolation
    applies; before that (a pattern still settling) it could overshoot."""
    norms = np.linalg.norm(np.diff(states, axis=0), axis=1)
    if np.any(norms == 0.0):
        return False
    ratios = norms[1:] / norms[:-1]
    return bool(ratios.max() < 1.0 and ratios.max() <= spread * ratios.min())


def anderson(X: np.ndarray, F: np.ndarray, max_gain: float = 1e4) -> np.ndarray | None:
    """Anderson (reduced rank) extrapolation of a fixed point of P from secant pairs.

    Parameters
    ----------
    X, F : (k + 1, M) arrays
        Cycle starts x_i and their images F_i = P(x_i). For a plain sequence
        (x_{i+1} = F_i) this is reduced rank extrapolation (Sidi, Ford & Smith, SIAM J.
        Numer. Anal. 23, 1986); with jumped starts it is Anderson mixing (Anderson, J. ACM
        12, 1965; Walker & Ni, SIAM J. Numer. Anal. 49, 2011), equivalent to GMRES on a
        linear map.
    max_gain : float
        The jump from F_k may be at most this many times the last change |F_k − x_k|
        (a ratio of the sequence up to 1 − 1/max_gain); larger ones are refused.

    Returns
    -------
    (M,) array or None
        x* = Σ α_i F_i with Σ α_i = 1 minimising |Σ α_i (F_i − x_i)|; components that
        no pair moves are returned unchanged (a node stuck in every cycle keeps its
        slip). None if the problem is degenerate or the jump is implausibly large.
    """
    U = F - X                                      # (k+1, M) residuals
    moving = np.flatnonzero(np.any(U != 0.0, axis=0) | np.any(X != X[-1], axis=0))
    last = float(np.max(np.abs(U[-1]))) if moving.size else 0.0
    if last == 0.0:
        return None
    Um = U[:, moving] / last
    # α_k = 1 − Σ_{i<k} α_i: min |u_k + Σ_{i<k} α_i (u_i − u_k)|, a least-squares problem
    # solved by the SVD (minimum norm where the residuals are linearly dependent)
    W = (Um[:-1] - Um[-1]).T
    g = np.linalg.lstsq(W, -Um[-1], rcond=1e-12)[0]
    if not np.all(np.isfinite(g)):
        return None
    alpha = np.append(g, 1.0 - g.sum())
    x = F[-1].copy()
    x[moving] = alpha @ F[:, moving]
    if float(np.max(np.abs(x - F[-1]))) > max_gain * last:
        return None
    return x
