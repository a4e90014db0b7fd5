"""Linear complementarity problems: Lemke's method (the robust fall-back of the rate
problem, see :mod:`slipcycle.discrete.rate`).

Find z ≥ 0 with y = M z + q ≥ 0 and yᵀ z = 0.

References
----------
C. E. Lemke, "Bimatrix equilibrium points and mathematical programming", Management Science
11 (1965) 681–689. R. W. Cottle, J.-S. Pang, R. E. Stone, *The Linear Complementarity
Problem*, Academic Press (1992), §4.4 (Lemke), §4.2 (principal pivoting).
"""

from __future__ import annotations

import numpy as np

__all__ = ["lemke", "lcp_residual"]


def lcp_residual(M: np.ndarray, q: np.ndarray, z: np.ndarray) -> float:
    """Largest violation of z ≥ 0, Mz + q ≥ 0 and z_i (Mz + q)_i = 0 (absolute)."""
    y = M @ z + q
    return float(max(0.0, -z.min(initial=0.0), -y.min(initial=0.0),
                     np.max(np.abs(z * y), initial=0.0)))


def lemke(M: np.ndarray, q: np.ndarray, max_pivots: int | None = None,
          tol: float = 1e-12) -> np.ndarray | None:
    """Solve the LCP(M, q) by Lemke's complementary pivoting with covering vector e = 1.

    Parameters
    ----------
    M : (n, n) array
    q : (n,) array
    max_pivots : int, optional
        Default 50 n + 50.
    tol : float
        Relative pivot tolerance.

    Returns
    -------
    (n,) array or None
        A solution z, or None on ray termination / pivot limit (no solution found; for a
        P-matrix M this does not happen).
    """
    M = np.asarray(M, float)
    q = np.asarray(q, float)
    n = q.size
    if n == 0 or np.all(q >= 0):
        return np.zeros(n)
    max_pivots = max_pivots or 50 * n + 50
    # Tableau columns: w (n), z (n), z0 (1), rhs
    T = np.zeros((n, 2 * n + 2))
    T[:, :n] = np.eye(n)
    T[:, n:2 * n] = -M
    T[:, 2 * n] = -1.0
    T[:, -1] = q
    basis = np.arange(n)
    z0 = 2 * n

    def pivot(row: int, col: int) -> None:
        T[row] /= T[row, col]
        others = T[:, col].copy()
        others[row] = 0.0
        T[:] -= np.outer(others, T[row])

    row = int(np.argmin(T[:, -1]))
    pivot(row, z0)
    leaving = basis[row]
    basis[row] = z0
    entering = leaving + n  # complement of w_row is z_row
    scale = max(1.0, np.max(np.abs(M)))
    for _ in range(max_pivots):
        col = T[:, entering]
        pos = col > tol * scale
        if not np.any(pos):
            return None  # ray termination
        ratios = np.full(n, np.inf)
        ratios[pos] = T[pos, -1] / col[pos]
        rmin = ratios.min()
        ties = np.flatnonzero(ratios <= rmin + 1e-12 * max(1.0, abs(rmin)))
        # Prefer z0 leaving (terminates), otherwise the smallest basis index (Bland-like).
        if np.any(basis[ties] == z0):
            row = int(ties[basis[ties] == z0][0])
        else:
            row = int(ties[np.argmin(basis[ties])])
        pivot(row, entering)
        leaving = basis[row]
        basis[row] = entering
        if leaving == z0:
            z = np.zeros(2 * n + 1)
            z[basis] = T[:, -1]
            return np.maximum(z[n:2 * n], 0.0)
        entering = leaving + n if leaving < n else leaving - n
    return None
