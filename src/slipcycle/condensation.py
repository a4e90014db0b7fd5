"""Static condensation (Schur complement) with one sparse factorisation.

For a symmetric positive definite K partitioned into interior (i) and boundary (b)
degrees of freedom,

    S = K_bb − K_bi K_ii⁻¹ K_ib,        r = K_bi K_ii⁻¹ f_i − f_b,

so that the forces needed at the boundary to hold displacements u_b are S u_b + r
(Guyan, 1965). The interior is put in a fill-reducing order, METIS nested dissection of
the graph of K_ii (Karypis & Kumar 1998, through ``pymetis``; far less fill than minimum
degree for three-dimensional meshes), the boundary is placed last, and the whole matrix
is factorised once; S is read off the trailing block of the factor (partial
elimination), so that no dense right-hand sides are solved.

Two factorisations do this, chosen by what is installed:

* **CHOLMOD** (Chen, Davis, Hager & Rajamanickam 2008), the supernodal sparse Cholesky
  factorisation of SuiteSparse, through ``cvxopt.cholmod`` (Andersen, Dahl &
  Vandenberghe; the ``cholmod`` extra, GPL-3.0-or-later; its wheels bundle CHOLMOD and
  OpenBLAS). With M = K + diag(0, D), D = |diag K_bb| (a shift of the boundary block
  only, so that M is positive definite even when S is only semidefinite, e.g. a body
  held by its contact nodes alone), the factor M = L Lᵀ has L_bb L_bbᵀ = S + D, and one
  forward solve L y = f gives r = −L_bb y_b. The trailing block L_bb is read from
  CHOLMOD's supernodes in place (:func:`_supernodal_tail`; through
  ``cvxopt.cholmod.getfactor`` should that layout not check out). Half the work and
  storage of an LU, with dense kernels on the separator fronts: about 20 s and 2.6 GB
  for 2·10⁵ DOF with 3072 boundary DOF.
* **SuperLU** (Li 2005, :func:`scipy.sparse.linalg.splu`, symmetric mode, diagonal
  pivots): the fallback without ``cvxopt`` or ``pymetis``, and whenever CHOLMOD does
  not factorise M (an interior that is not positive definite: the errors below then
  come from this path). The load columns are appended to the matrix as extra columns
  (with identity rows), so that the same partial elimination leaves f_b − K_bi K_ii⁻¹ f_i
  beside S = L_bb U_bb. Without ``pymetis`` the interior is ordered by SuperLU's minimum
  degree (two factorisations).

Both paths refuse an interior block that is singular, nearly singular or not positive
definite with one :class:`SingularModelError` (the pivots of K_ii, in the elimination
order, must be positive and above 1e-13 of the largest).

Used by the finite-element reduction (:mod:`slipcycle.fe`) and by the readers of reduced
models exported from FE codes (:mod:`slipcycle.io.fe_formats`): one condensation engine.

References
----------
Guyan, R. J. (1965). Reduction of stiffness and mass matrices. AIAA Journal 3(2), 380.
Chen, Y., Davis, T. A., Hager, W. W. & Rajamanickam, S. (2008). Algorithm 887: CHOLMOD,
supernodal sparse Cholesky factorization and update/downdate. ACM TOMS 35(3), 22.
Andersen, M. S., Dahl, J. & Vandenberghe, L. CVXOPT: Python software for convex
optimization, version 1.3 (cvxopt.org).
Li, X. S. (2005). An overview of SuperLU. ACM TOMS 31(3), 302–325.
Karypis, G. & Kumar, V. (1998). A fast and high quality multilevel scheme for partitioning
irregular graphs. SIAM J. Sci. Comput. 20(1), 359–392.
George, A. (1973). Nested dissection of a regular finite element mesh. SIAM J. Numer.
Anal. 10(2), 345–363.
"""

from __future__ import annotations

import ctypes
import threading

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

__all__ = ["SingularModelError", "cholmod_available", "nested_dissection", "schur_complement"]


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


# --------------------------------------------------------------------------------------
# CHOLMOD (supernodal Cholesky) through cvxopt
# --------------------------------------------------------------------------------------

# cvxopt.cholmod keeps its options in one module-level dict (and CHOLMOD one Common):
# one factorisation at a time changes and restores them
_CHOLMOD_LOCK = threading.Lock()


def _cvxopt_cholmod():
    """``(cholmod, matrix, spmatrix)`` of cvxopt, or None when it is not installed."""
    try:
        from cvxopt import cholmod, matrix, spmatrix
    except ImportError:
        return None
    return cholmod, matrix, spmatrix


def _int_matrix(matrix, a: np.ndarray):
    """A cvxopt integer matrix of ``a`` (its int_t is 64 bits, buffer format 'l' or 'q')."""
    for code in ("l", "q"):
        if np.dtype(code).itemsize == 8:
            try:
                return matrix(np.ascontiguousarray(a, dtype=np.dtype(code)))
            except TypeError:
                continue
    return matrix(np.asarray(a, dtype=np.int64).tolist(), tc="i")


def cholmod_available() -> bool:
    """True when :func:`schur_complement` can use CHOLMOD (``cvxopt`` and ``pymetis``)."""
    try:
        import pymetis  # noqa: F401
    except ImportError:
        return False
    return _cvxopt_cholmod() is not None


class _CholmodFactor(ctypes.Structure):
    """``cholmod_factor`` of CHOLMOD's public header (cholmod.h), 64-bit integer version.

    Read only, to take the trailing supernodes of a numeric factor without converting
    the whole factor to a sparse matrix; every field used is checked against
    cvxopt's own answers (:func:`_supernodal_tail`).
    """

    _fields_ = ([(k, ctypes.c_size_t) for k in ("n", "minor")]
                + [(k, ctypes.c_void_p) for k in ("Perm", "ColCount", "IPerm")]
                + [("nzmax", ctypes.c_size_t)]
                + [(k, ctypes.c_void_p) for k in ("p", "i", "x", "z", "nz", "next", "prev")]
                + [(k, ctypes.c_size_t)
                   for k in ("nsuper", "ssize", "xsize", "maxcsize", "maxesize")]
                + [(k, ctypes.c_void_p) for k in ("super", "pi", "px", "s")]
                + [(k, ctypes.c_int) for k in ("ordering", "is_ll", "is_super",
                                               "is_monotonic", "itype", "xtype", "dtype",
                                               "useGPU")])


def _view(address: int, count: int, offset: int = 0, ctype=ctypes.c_int64) -> np.ndarray:
    """A NumPy view of ``count`` C values at ``address`` + ``offset`` elements."""
    ptr = ctypes.cast(int(address) + int(offset) * ctypes.sizeof(ctype), ctypes.POINTER(ctype))
    return np.ctypeslib.as_array(ptr, shape=(int(count),))


def _supernodal_tail(F, n: int, start: int, perm: np.ndarray, diag: np.ndarray):
    """Dense trailing block L[start:, start:] of a supernodal CHOLMOD factor, or None.

    Reads the supernodes that hold columns ≥ ``start`` (dense column-major blocks) in
    place. Returns None, so that the caller takes the factor through the public
    ``cholmod.getfactor`` instead, unless the factor's header reads as a successful
    supernodal LLᵀ of order ``n`` with 64-bit integers and double values, its
    permutation equals ``perm`` and the diagonal read equals ``diag`` (from
    ``cholmod.diag``).
    """
    get = ctypes.PYFUNCTYPE(ctypes.c_void_p, ctypes.py_object, ctypes.c_char_p)(
        ("PyCapsule_GetPointer", ctypes.pythonapi))  # a prototype of our own: pythonapi's
    try:                                             # shared one is left as it is
        address = get(F, b"CHOLMOD FACTOR D L")
    except (ValueError, TypeError):
        return None
    if not address:
        return None
    L = _CholmodFactor.from_address(address)
    ns = L.nsuper
    if not (L.n == n and L.minor == n and L.is_ll == 1 and L.is_super == 1
            and L.itype == 2 and L.xtype == 1 and L.dtype == 0 and 0 < ns <= n
            and L.Perm and L.super and L.pi and L.px and L.s and L.x):
        return None                                   # CHOLMOD_LONG, _REAL, _DOUBLE
    sup = _view(L.super, ns + 1).copy()
    pi = _view(L.pi, ns + 1).copy()
    px = _view(L.px, ns + 1).copy()
    if (sup[0] != 0 or sup[-1] != n or np.any(np.diff(sup) <= 0) or pi[0] != 0
            or pi[-1] != L.ssize or np.any(np.diff(pi) < np.diff(sup)) or px[0] != 0
            or px[-1] > L.xsize or not np.array_equal(_view(L.Perm, n), perm)):
        return None
    m = n - start
    T = np.zeros((m, m))
    for k in range(int(np.searchsorted(sup, start, side="right")) - 1, ns):
        k0, k1 = int(sup[k]), int(sup[k + 1])
        nrow, ncol = int(pi[k + 1] - pi[k]), k1 - k0
        if int(px[k + 1] - px[k]) < nrow * ncol:
            return None
        rows = _view(L.s, nrow, pi[k])
        if rows[-1] >= n or not np.array_equal(rows[:ncol], np.arange(k0, k1)):
            return None                   # a supernode's rows: its own columns, then below
        block = _view(L.x, nrow * ncol, px[k], ctypes.c_double).reshape(ncol, nrow).T
        c0 = max(start - k0, 0)
        keep = rows >= start
        T[np.ix_(rows[keep] - start, np.arange(k0 + c0, k1) - start)] = block[keep, c0:]
    T = np.tril(T)                        # the strict upper part of a diagonal block is junk
    if not np.array_equal(np.diag(T), diag[start:]):
        return None
    return T


def _schur_cholmod(K: sp.csc_matrix, ni: int, loads: np.ndarray, perm: np.ndarray):
    """S and r by one supernodal Cholesky of K with a shifted boundary block, or None.

    None means CHOLMOD did not factorise the matrix (it is not positive definite: an
    interior that is not, or a boundary block that the shift does not make so) and the
    caller goes on with SuperLU, which then gives the errors.
    """
    cholmod, matrix, spmatrix = _cvxopt_cholmod()
    n = K.shape[0]
    order = np.concatenate([perm, np.arange(ni, n)])
    dk = np.abs(K.diagonal())
    shift = dk[ni:].copy()
    shift[shift == 0.0] = dk.max() if dk.max() > 0.0 else 1.0
    M = sp.tril(0.5 * (K + K.T) + sp.diags(np.concatenate([np.zeros(ni), shift])),
                format="coo")
    A = spmatrix(matrix(np.ascontiguousarray(M.data, dtype=float)),
                 _int_matrix(matrix, M.row), _int_matrix(matrix, M.col), (n, n))
    del M
    with _CHOLMOD_LOCK:
        return _factor_and_read(cholmod, matrix, A, n, ni, order, loads, shift)


def _factor_and_read(cholmod, matrix, A, n, ni, order, loads, shift):
    """The CHOLMOD part of :func:`_schur_cholmod` (cvxopt's options set and restored)."""
    nb = n - ni
    saved = dict(cholmod.options)
    cholmod.options.clear()
    # the given order as it is (no AMD, no postorder): the boundary stays last
    cholmod.options.update(supernodal=2, nmethods=1, postorder=False)
    try:
        try:
            F = cholmod.symbolic(A, p=_int_matrix(matrix, order), uplo="L")
            cholmod.numeric(A, F)
        except (ArithmeticError, ValueError):         # not positive definite
            return None
        got = matrix(np.arange(n, dtype=float))
        cholmod.solve(F, got, sys=7)                  # P·(0, 1, …): the order used
        used = np.rint(np.asarray(got).ravel()).astype(np.int64)
        if not np.array_equal(np.sort(used[ni:]), np.arange(ni, n)):
            return None
        diag = np.asarray(cholmod.diag(F)).ravel()
        _check_pivots(diag[:ni] ** 2)                 # the pivots of the LU of K_ii
        m = loads.shape[1]
        Y = np.zeros((nb, m))
        if m:
            B = matrix(np.asfortranarray(loads[used]))
            cholmod.solve(F, B, sys=4)                # L y = P f
            Y = np.asarray(B)[ni:]
        Lbb = _supernodal_tail(F, n, ni, used, diag)
        if Lbb is None:                               # public, slower path: the whole L
            Lf = cholmod.getfactor(F)[ni:, ni:]
            colptr, rowind, values = (np.asarray(a).ravel() for a in Lf.CCS)
            Lbb = sp.csc_matrix((values, rowind, colptr), shape=(nb, nb)).toarray()
            del Lf
        del F
    finally:
        cholmod.options.clear()
        cholmod.options.update(saved)
    back = np.empty(nb, np.int64)                     # factor position of each boundary DOF
    back[used[ni:] - ni] = np.arange(nb)
    Lbb = Lbb[back]
    S = Lbb @ Lbb.T
    S[np.diag_indices(nb)] -= shift
    r = -(Lbb @ Y)
    return 0.5 * (S + S.T), r


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

    The interior block is ordered by METIS nested dissection (:func:`nested_dissection`),
    the boundary DOFs are placed last, and the whole matrix is factorised once without
    pivoting (K is SPD); the trailing block of the factor then holds the Schur complement
    (partial elimination), which avoids 2N triangular solves with dense right-hand sides.
    With ``cvxopt`` (and ``pymetis``) installed the factorisation is CHOLMOD's supernodal
    Cholesky of K with the boundary block shifted by D = |diag K_bb|, S = L_bb L_bbᵀ − D,
    and r = −L_bb y_b from one forward solve L y = f (see the module notes). Otherwise, or
    when CHOLMOD finds the matrix not positive definite, it is SuperLU's LU: the load
    columns are appended to the matrix as extra columns (with identity rows), so that the
    same partial elimination leaves f_b − K_bi K_ii⁻¹ f_i beside S = L_bb U_bb. Without
    ``pymetis``, or should SuperLU reorder the matrix anyway (or meet a zero pivot), the
    function falls back to the minimum-degree path and, failing that, to block solves
    with the interior factors.

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

    Raises
    ------
    SingularModelError
        K_ii is singular, nearly singular (a pivot below 1e-13 of the largest) or not
        positive definite.
    """
    K = sp.csc_matrix(K)
    n = K.shape[0]
    ni = n_interior
    nb = n - ni
    loads = np.zeros((n, 0)) if loads is None else np.asarray(loads, float).reshape(n, -1)
    perm = nested_dissection(K[:ni, :ni]) if ni > 0 else None
    if ni > 0 and nb > 0 and _cvxopt_cholmod() is not None:
        order = perm
        if order is None and sp.triu(K[:ni, :ni], k=1).nnz == 0:
            order = np.arange(ni)                     # a diagonal K_ii: any order will do
        out = _schur_cholmod(K, ni, loads, order) if order is not None else None
        if out is not None:
            return out
    K_bi = sp.csr_matrix(K[ni:, :ni])
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
