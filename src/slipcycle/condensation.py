"""Static condensation (Schur complement) with one sparse factorisation.

For a symmetric positive definite K partitioned into interior (i) and boundary (b)
degrees of freedom,

    S = K_bb − K_bi K_ii⁻¹ K_ib,        r = K_bi K_ii⁻¹ f_i − f_b,

so that the forces needed at the boundary to hold displacements u_b are S u_b + r
(Guyan, 1965). The matrix is factorised by SuperLU (:func:`scipy.sparse.linalg.splu`,
minimum-degree ordering of Kᵀ+K for the interior, boundary last, symmetric mode,
diagonal pivots — K is SPD); S is read off the trailing blocks of the factors.

Used by the finite-element reduction (:mod:`slipcycle.fe`) and by the readers of reduced
models exported from FE codes (:mod:`slipcycle.io.fe_formats`): one condensation engine.

References
----------
Guyan, R. J. (1965). Reduction of stiffness and mass matrices. AIAA Journal 3(2), 380.
Li, X. S. (2005). An overview of SuperLU. ACM TOMS 31(3), 302–325.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

__all__ = ["SingularModelError", "schur_complement"]


class SingularModelError(ValueError):
    """The interior stiffness is singular: the model is not supported against rigid motion."""


def factorize(K_ii: sp.spmatrix):
    """Sparse LU factorisation of the (SPD) interior block; raises SingularModelError."""
    try:
        lu = splu(sp.csc_matrix(K_ii), permc_spec="MMD_AT_PLUS_A",
                  options={"SymmetricMode": True, "DiagPivotThresh": 0.0})
    except RuntimeError as exc:  # "Factor is exactly singular"
        raise SingularModelError(
            "the stiffness with every contact node held fixed is singular: some body or "
            "part of a body is not supported (check supports, ties and contact tags)"
        ) from exc
    signed = lu.U.diagonal()
    if signed.min() < 0.0:  # LU without pivoting of an SPD matrix has positive pivots
        raise SingularModelError(
            "the stiffness with every contact node held fixed is not positive definite "
            f"(a negative pivot, {signed.min():.3e}): check the material constants")
    diag = np.abs(signed)
    if diag.min() <= 1e-13 * diag.max():
        raise SingularModelError(
            "the stiffness with every contact node held fixed is (nearly) singular: a body "
            f"is not supported against rigid motion (pivot ratio {diag.min() / diag.max():.2e})")
    return lu


def schur_complement(K: sp.spmatrix, n_interior: int, loads: np.ndarray | None = None,
                     block: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """Condense the first ``n_interior`` DOFs of ``K`` out.

    The interior block is ordered by SuperLU's minimum-degree ordering (taken from a
    first factorisation of K_ii), the boundary DOFs are placed last, and the whole matrix
    is factorised once without pivoting (K is SPD). The trailing blocks of the factors
    then hold the Schur complement, S = L_bb U_bb (partial Gaussian elimination), which
    avoids 2N triangular solves with dense right-hand sides. Should SuperLU reorder the
    matrix anyway, the function falls back to block solves with the interior factors.

    Parameters
    ----------
    K : sparse matrix, shape (n, n)
        Symmetric positive definite stiffness, interior DOFs first, N/m.
    n_interior : int
        Number of interior DOFs; the remaining nb = n − n_interior are kept.
    loads : numpy.ndarray, shape (n, m), optional
        Generalised nodal forces of m load cases, N.
    block : int
        Number of right-hand sides solved at once in the fallback.

    Returns
    -------
    S : numpy.ndarray, shape (nb, nb)
        Reduced stiffness (symmetrised), N/m.
    r : numpy.ndarray, shape (nb, m)
        Boundary forces of each load case with the boundary held at zero, N.
    """
    K = sp.csc_matrix(K)
    n = K.shape[0]
    ni = n_interior
    nb = n - ni
    loads = np.zeros((n, 0)) if loads is None else np.asarray(loads, float).reshape(n, -1)
    lu_i = factorize(K[:ni, :ni])
    order = np.concatenate([np.argsort(lu_i.perm_c), np.arange(ni, n)])
    Kq = K[order][:, order].tocsc()
    try:
        lu = splu(Kq, permc_spec="NATURAL",
                  options={"SymmetricMode": True, "DiagPivotThresh": 0.0})
        natural = (np.array_equal(lu.perm_c, np.arange(n))
                   and np.array_equal(lu.perm_r, np.arange(n)))
    except RuntimeError:
        natural = False
    K_bi = sp.csr_matrix(K[ni:, :ni])
    # load cases: a few solves with the interior factors, r = K_bi K_ii⁻¹ f_i − f_b
    Y = lu_i.solve(np.asfortranarray(loads[:ni])) if loads.shape[1] else np.zeros((ni, 0))
    r = np.asarray(K_bi @ Y) - loads[ni:]
    if natural:
        S = lu.L[ni:, ni:].toarray() @ lu.U[ni:, ni:].toarray()
        return 0.5 * (S + S.T), r
    K_ib = sp.csc_matrix(K[:ni, ni:])
    S = np.asarray(K[ni:, ni:].todense(), dtype=float)
    for start in range(0, nb, block):
        cols = slice(start, min(start + block, nb))
        X = lu_i.solve(np.asfortranarray(K_ib[:, cols].toarray()))
        S[:, cols] -= K_bi @ X
    return 0.5 * (S + S.T), r
