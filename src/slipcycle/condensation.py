"""Static condensation (Schur complement) with one sparse factorisation.

For a symmetric positive definite K partitioned into interior (i) and boundary (b)
degrees of freedom,

    S = K_bb − K_bi K_ii⁻¹ K_ib,        r = K_bi K_ii⁻¹ f_i − f_b,

so that the forces needed at the boundary to hold displacements u_b are S u_b + r
(Guyan, 1965). The matrix is factorised by SuperLU (:func:`scipy.sparse.linalg.splu`,
symmetric mode, diagonal pivots — K is SPD) with the interior in a fill-reducing order
and the boundary last; S is read off the trailing blocks of the factors. The interior
order is METIS nested dissection of the graph of K_ii (Karypis & Kumar 1998, through
``pymetis``) when that package is installed — far less fill than minimum degree for
three-dimensional meshes — else SuperLU's minimum-degree ordering of Kᵀ+K.

Used by the finite-element reduction (:mod:`slipcycle.fe`) and by the readers of reduced
models exported from FE codes (:mod:`slipcycle.io.fe_formats`): one condensation engine.

References
----------
Guyan, R. J. (1965). Reduction of stiffness and mass matrices. AIAA Journal 3(2), 380.
Li, X. S. (2005). An overview of SuperLU. ACM TOMS 31(3), 302–325.
Karypis, G. & Kumar, V. (1998). A fast and high quality multilevel scheme for partitioning
irregular graphs. SIAM J. Sci. Comput. 20(1), 359–392.
George, A. (1973). Nested dissection of a regular finite element mesh. SIAM J. Numer.
Anal. 10(2), 345–363.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

__all__ = ["SingularModelError", "nested_dissection", "schur_complement"]


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
    _check_pivots(lu.U.diagonal())
    return lu


def _check_pivots(signed: np.ndarray) -> None:
    """Raise SingularModelError unless the pivots of an SPD LU are positive and bounded."""
    if signed.size == 0:
        return
    if signed.min() < 0.0:  # LU without pivoting of an SPD matrix has positive pivots
        raise SingularModelError(
            "the stiffness with every contact node held fixed is not positive definite "
            f"(a negative pivot, {signed.min():.3e}): check the material constants")
    diag = np.abs(signed)
    if diag.min() <= 1e-13 * diag.max():
        raise SingularModelError(
            "the stiffness with every contact node held fixed is (nearly) singular: a body "
            f"is not supported against rigid motion (pivot ratio {diag.min() / diag.max():.2e})")


def nested_dissection(K_ii: sp.spmatrix) -> np.ndarray | None:
    """METIS nested-dissection order (permutation, new → old) of a symmetric matrix's graph.

    Returns None when ``pymetis`` is not installed (the caller then uses minimum degree)
    or the matrix has no off-diagonal entries.
    """
    try:
        import pymetis
    except ImportError:
        return None
    G = sp.csr_matrix(K_ii, copy=True)
    G.setdiag(0.0)
    G.eliminate_zeros()
    if G.nnz == 0:
        return None
    G = (abs(G) + abs(G.T)).tocsr()                    # a symmetric pattern for METIS
    G.sort_indices()
    adjacency = pymetis.CSRAdjacency(G.indptr.astype(np.int64),
                                     G.indices.astype(np.int64))
    perm, _ = pymetis.nested_dissection(adjacency)
    perm = np.asarray(perm, dtype=np.int64)
    if perm.shape != (K_ii.shape[0],) or np.unique(perm).size != perm.size:
        return None
    return perm


def _natural_lu(Kq: sp.csc_matrix):
    """SuperLU of an already ordered SPD matrix; None if SuperLU permuted it anyway."""
    n = Kq.shape[0]
    try:
        lu = splu(Kq, permc_spec="NATURAL",
                  options={"SymmetricMode": True, "DiagPivotThresh": 0.0})
    except RuntimeError:
        return None
    if np.array_equal(lu.perm_c, np.arange(n)) and np.array_equal(lu.perm_r, np.arange(n)):
        return lu
    return None


def schur_complement(K: sp.spmatrix, n_interior: int, loads: np.ndarray | None = None,
                     block: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """Condense the first ``n_interior`` DOFs of ``K`` out.

    The interior block is ordered by METIS nested dissection (:func:`nested_dissection`;
    without ``pymetis``, by SuperLU's minimum-degree ordering taken from a first
    factorisation of K_ii), the boundary DOFs are placed last, and the whole matrix is
    factorised once without pivoting (K is SPD). The trailing blocks of the factors then
    hold the Schur complement, S = L_bb U_bb (partial Gaussian elimination), which avoids
    2N triangular solves with dense right-hand sides; the load columns are appended to
    the matrix as extra columns (with identity rows), so that the same partial
    elimination leaves f_b − K_bi K_ii⁻¹ f_i beside S. Should SuperLU reorder the
    matrix anyway (or meet a zero pivot), the function falls back to the minimum-degree
    path and, failing that, to block solves with the interior factors.

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
    K_bi = sp.csr_matrix(K[ni:, :ni])
    perm = nested_dissection(K[:ni, :ni]) if ni > 0 else None
    if perm is not None:
        # the load columns ride along as extra unknowns: M = [[K, F], [0, I]], so that
        # eliminating the interior leaves [[S, F_b − K_bi K_ii⁻¹ F_i], [0, I]] in the
        # trailing blocks of the factors (one factorisation, no copy of the whole L)
        m = loads.shape[1]
        order = np.concatenate([perm, np.arange(ni, n)])
        Fq = sp.csc_matrix(loads[order])
        M = sp.bmat([[K[order][:, order], Fq],
                     [None, sp.identity(m, format="csc")]], format="csc") if m else \
            K[order][:, order].tocsc()
        lu = _natural_lu(M)
        if lu is not None:
            _check_pivots(lu.U.diagonal()[:ni])
            Lt = lu.L[ni:, ni:].toarray()
            T = Lt @ lu.U[ni:, ni:].toarray()
            del Lt
            S = 0.5 * (T[:nb, :nb] + T[:nb, :nb].T)
            return S, -T[:nb, nb:]
    lu_i = factorize(K[:ni, :ni])
    order = np.concatenate([np.argsort(lu_i.perm_c), np.arange(ni, n)])
    lu = _natural_lu(K[order][:, order].tocsc())
    # load cases: a few solves with the interior factors, r = K_bi K_ii⁻¹ f_i − f_b
    Y = lu_i.solve(np.asfortranarray(loads[:ni])) if loads.shape[1] else np.zeros((ni, 0))
    r = np.asarray(K_bi @ Y) - loads[ni:]
    if lu is not None:
        S = lu.L[ni:, ni:].toarray() @ lu.U[ni:, ni:].toarray()
        return 0.5 * (S + S.T), r
    K_ib = sp.csc_matrix(K[:ni, ni:])
    S = np.asarray(K[ni:, ni:].todense(), dtype=float)
    for start in range(0, nb, block):
        cols = slice(start, min(start + block, nb))
        X = lu_i.solve(np.asfortranarray(K_ib[:, cols].toarray()))
        S[:, cols] -= K_bi @ X
    return 0.5 * (S + S.T), r
