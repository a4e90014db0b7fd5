"""Well-posedness of the rate problem: the critical friction coefficient.

With all nodes in contact, a set I of nodes slipping with directions S = diag(±1) moves
at rates given by the principal submatrix (A + f S B)_II. The rate problem (a linear
complementarity problem) has a unique solution for every load rate if and only if every
such matrix is a P-matrix (Klarbring, 1990; Klarbring & Pang, 1998). Since all principal
minors are positive at f = 0 (A is positive definite), the critical coefficient is the
smallest f > 0 at which one of the minors det(A_II + f S_I B_II) vanishes:

    f_crit = min over I, S of  1 / max{|μ| : μ real eigenvalue of A_II⁻¹ S_I B_II}.

(``det(I + f X) = Π(1 + f μ_k)`` vanishes for real f > 0 only at f = −1/μ_k with μ_k real
and negative; S and −S give opposite μ, so both signs are covered by |μ|.)

Per-node coefficients f_j = κ f̂_j are handled by scaling the rows of B by f̂_j = f_j/max f
and reporting the critical max f.

Methods
-------
- ``exact`` (N ≤ ``exact_max_nodes``): enumeration of all (3^N − 1)/2 subset/sign pairs.
- ``bound`` (larger N): an upper estimate from all subsets of one and two nodes (closed
  form) and the full set with sign patterns of the diagonal of B, and a certified lower
  bound from the symmetric part: with D = diag(A), Â = D^-½ A D^-½, B̂ = D^-½ B D^-½, every
  A + f S B with f < λ_min(Â)/‖B̂‖₂ has a positive-definite symmetric part after diagonal
  scaling and so is a P-matrix, with all its principal submatrices.

References
----------
A. Klarbring, "Examples of non-uniqueness and non-existence of solutions to quasistatic
contact problems with friction", Ingenieur-Archiv 60 (1990) 529–541.
A. Klarbring, J.-S. Pang, "Existence of solutions to discrete semicoercive frictional contact
problems", SIAM J. Optim. 8 (1998) 414–442.
L.-E. Andersson, "Existence results for quasistatic contact problems with Coulomb friction",
Appl. Math. Optim. 42 (2000) 169–202.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations, product

import numpy as np

__all__ = ["CriticalFriction", "critical_friction", "is_p_matrix"]


@dataclass(frozen=True)
class CriticalFriction:
    """Result of :func:`critical_friction`.

    Attributes
    ----------
    f_crit : float
        Critical (largest) friction coefficient; ``inf`` if there is none (e.g. B = 0). With
        ``method == "bound"`` an upper estimate (a failing subset was found at this f).
    lower_bound : float
        Certified: every f below this value is well posed.
    method : str
        ``"exact"`` or ``"bound"``.
    nodes : tuple of int
        The subset I whose minor vanishes at f_crit (empty if f_crit is inf).
    signs : tuple of int
        Slip-direction signs S on that subset.
    """

    f_crit: float
    lower_bound: float
    method: str
    nodes: tuple = ()
    signs: tuple = ()


def is_p_matrix(M: np.ndarray, tol: float = 0.0) -> bool:
    """True if every principal minor of the (small) square matrix M exceeds ``tol``."""
    n = M.shape[0]
    for m in range(1, n + 1):
        for idx in combinations(range(n), m):
            if np.linalg.det(M[np.ix_(idx, idx)]) <= tol:
                return False
    return True


def _lower_bound(A: np.ndarray, Bt: np.ndarray) -> float:
    d = 1.0 / np.sqrt(np.diag(A))
    Ah = A * d[:, None] * d[None, :]
    Bh = Bt * d[:, None] * d[None, :]
    nb = np.linalg.norm(Bh, 2)
    if nb == 0.0:
        return np.inf
    return float(np.linalg.eigvalsh(Ah)[0] / nb)


def _kappa_from_eigs(mu: np.ndarray) -> np.ndarray:
    """Smallest 1/|μ| over real nonzero eigenvalues along the last axis (inf if none)."""
    real = np.abs(mu.imag) <= 1e-12 * np.maximum(np.abs(mu.real), 1e-300)
    mag = np.where(real & (np.abs(mu.real) > 0), np.abs(mu.real), 0.0)
    best = mag.max(axis=-1)
    with np.errstate(divide="ignore"):
        return np.where(best > 0, 1.0 / best, np.inf)


def _exact(A: np.ndarray, Bt: np.ndarray):
    n = A.shape[0]
    best, best_I, best_S = np.inf, (), ()
    for m in range(1, n + 1):
        subsets = np.array(list(combinations(range(n), m)))
        signs = np.array([(1,) + s for s in product((1, -1), repeat=m - 1)], dtype=float)
        Aii = A[subsets[:, :, None], subsets[:, None, :]]          # (ns, m, m)
        Bii = Bt[subsets[:, :, None], subsets[:, None, :]]
        X0 = np.linalg.solve(Aii, Bii)                              # A⁻¹ B, (ns, m, m)
        Ainv = np.linalg.inv(Aii)
        # A⁻¹ S B = (A⁻¹ scaled by columns S) B
        X = np.einsum("aij,sj,ajk->saik", Ainv, signs, Bii) if m > 1 else X0[None]
        mu = np.linalg.eigvals(X.reshape(-1, m, m)).reshape(signs.shape[0], len(subsets), m)
        kap = _kappa_from_eigs(mu)
        k = np.unravel_index(np.argmin(kap), kap.shape)
        if kap[k] < best:
            best = float(kap[k])
            best_I = tuple(int(i) for i in subsets[k[1]])
            best_S = tuple(int(s) for s in signs[k[0]])
    return best, best_I, best_S


def _search(A: np.ndarray, Bt: np.ndarray):
    n = A.shape[0]
    best, best_I, best_S = np.inf, (), ()
    # single nodes: A_jj + κ s B_jj = 0
    bd = np.abs(np.diag(Bt))
    with np.errstate(divide="ignore"):
        k1 = np.where(bd > 0, np.diag(A) / np.where(bd > 0, bd, 1.0), np.inf)
    j = int(np.argmin(k1))
    if k1[j] < best:
        best, best_I, best_S = float(k1[j]), (j,), (1,)
    # pairs: quadratic det in κ
    if n >= 2:
        i, j = np.triu_indices(n, 1)
        a11, a22, a12, a21 = A[i, i], A[j, j], A[i, j], A[j, i]
        b11, b22, b12, b21 = Bt[i, i], Bt[j, j], Bt[i, j], Bt[j, i]
        c0 = a11 * a22 - a12 * a21
        for s2 in (1.0, -1.0):
            c1 = b11 * a22 + s2 * a11 * b22 - b12 * a21 - s2 * a12 * b21
            c2 = s2 * (b11 * b22 - b12 * b21)
            kap = np.full(i.size, np.inf)
            lin = np.abs(c2) <= 1e-14 * (np.abs(c1) + np.abs(c0))
            # huge stiffness ratios overflow the discriminant: no finite root, as wanted
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                kl = np.where(lin & (c1 != 0), np.abs(c0 / c1), np.inf)
                disc = c1 * c1 - 4 * c2 * c0
                sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
                r1 = np.abs((-c1 + sq) / (2 * c2))
                r2 = np.abs((-c1 - sq) / (2 * c2))
                kq = np.fmin(r1, r2)
            kap = np.where(lin, kl, np.where(disc >= 0, kq, np.inf))
            kap = np.where(np.isfinite(kap), kap, np.inf)
            k = int(np.argmin(kap))
            if kap[k] < best:
                best, best_I, best_S = float(kap[k]), (int(i[k]), int(j[k])), (1, int(s2))
    # the full set with sign patterns from the diagonal of B
    for S in (np.sign(np.diag(Bt)) + (np.diag(Bt) == 0), np.ones(n)):
        X = np.linalg.solve(A, S[:, None] * Bt)
        kap = float(_kappa_from_eigs(np.linalg.eigvals(X)[None])[0])
        if kap < best:
            best, best_I, best_S = kap, tuple(range(n)), tuple(int(s) for s in S)
    return best, best_I, best_S


def critical_friction(A: np.ndarray, B: np.ndarray, friction: np.ndarray | float | None = None,
                      exact_max_nodes: int = 10) -> CriticalFriction:
    """Critical friction coefficient f_crit of the rate problem (Klarbring's P-condition).

    Parameters
    ----------
    A, B : (N, N) arrays
        Tangential stiffness and normal–tangential coupling [N/m].
    friction : float or (N,) array, optional
        The model's coefficients. Only their ratios matter: with per-node f_j the result is
        the critical value of max_j f_j with the ratios kept.
    exact_max_nodes : int
        Enumerate exactly up to this N, use bounds above it.

    Returns
    -------
    CriticalFriction
    """
    A = np.asarray(A, float)
    B = np.asarray(B, float)
    n = A.shape[0]
    f = np.ones(n) if friction is None else np.broadcast_to(np.asarray(friction, float), (n,))
    shape = f / f.max() if f.max() > 0 else np.ones(n)
    Bt = shape[:, None] * B
    lower = _lower_bound(A, Bt)
    if not np.any(Bt):
        return CriticalFriction(np.inf, np.inf, "exact")
    if n <= exact_max_nodes:
        best, I, S = _exact(A, Bt)
        return CriticalFriction(best, min(lower, best), "exact", I, S)
    best, I, S = _search(A, Bt)
    return CriticalFriction(best, min(lower, best), "bound", I, S)
