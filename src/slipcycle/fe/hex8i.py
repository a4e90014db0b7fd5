"""Stiffness of 8-node hexahedra with incompatible modes (linear isotropic elasticity).

Why this element: the bodies of a bolted joint are thin plates (a few mm thick, elements of
2–8 mm in plane, one or two through the thickness). Linear tetrahedra and fully integrated
trilinear hexahedra *lock* in bending on such meshes: their displacement fields cannot bend
without spurious shear strain (and, for the hexahedron, spurious transverse normal strain
from the Poisson effect), so they come out too stiff by tens of per cent or more. Adding to
the trilinear field of each displacement component the three quadratic bubbles
(1 − ξ²), (1 − η²), (1 − ζ²) (Wilson, Taylor, Doherty & Ghaboussi 1973) supplies exactly the
missing quadratic terms: on rectangular (right-angled box) elements the element
represents pure bending exactly, including the anticlastic Poisson terms, with a single
element through the thickness. Commercial codes offer this family as "incompatible modes"
elements (e.g. C3D8I; their versions may add further internal modes).

The bubbles are not continuous across element faces, which is harmless only if the element
still passes the patch test (reproduces any constant strain exactly). With the exact
gradients ∂P/∂x = J⁻ᵀ ∂P/∂ξ it does so only on parallelepipeds. Taylor, Beresford & Wilson
(1976) evaluate the bubble gradients with the Jacobian at the element centre and scale them,

    ∂P/∂x = (det J₀ / det J) J₀⁻ᵀ ∂P/∂ξ,

so that ∫_e ∂P/∂x dV = det J₀ J₀⁻ᵀ Σ_g ∂P/∂ξ(ξ_g) = 0 at 2×2×2 Gauss points: a constant
stress then does no work on the bubbles, they stay unexcited, and the element passes the
patch test on arbitrarily distorted (convex) shapes.

The 9 bubble amplitudes of an element are internal: they are condensed out element by
element, K_e = K_uu − K_uα K_αα⁻¹ K_αu, leaving an ordinary 24 × 24 stiffness on the eight
vertices (u_x, u_y, u_z per vertex, vertex-major).

Units: coordinates m, E Pa, stiffness N/m.

References
----------
Wilson, E. L., Taylor, R. L., Doherty, W. P. & Ghaboussi, J. (1973). Incompatible
displacement models. In *Numerical and Computer Methods in Structural Mechanics*
(S. J. Fenves et al., eds.), Academic Press, 43–57.
Taylor, R. L., Beresford, P. J. & Wilson, E. L. (1976). A non-conforming element for stress
analysis. Int. J. Numer. Meth. Eng. 10, 1211–1219.
MacNeal, R. H. & Harder, R. L. (1985). A proposed standard set of problems to test finite
element accuracy. Finite Elements in Analysis and Design 1, 3–20.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from slipcycle.errors import InputError

__all__ = ["hex8i_stiffness", "hex8i_element_matrices"]

# Natural coordinates of the vertices: bottom face ζ = −1 counter-clockwise, then the top.
_XI = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
# 2×2×2 Gauss points (weights 1) in the same order as the vertices.
_GAUSS = _XI / np.sqrt(3.0)


def _dN(points: np.ndarray) -> np.ndarray:
    """Derivatives ∂N_a/∂ξ_k of the trilinear shape functions, shape (p, 8, 3)."""
    s = 1.0 + points[:, None, :] * _XI[None, :, :]  # (p, 8, 3): (1 + ξ ξ_a) per direction
    out = np.empty_like(s)
    for k in range(3):
        others = [j for j in range(3) if j != k]
        out[..., k] = 0.125 * _XI[None, :, k] * s[..., others[0]] * s[..., others[1]]
    return out


_DN_GAUSS = _dN(_GAUSS)  # (8 points, 8 vertices, 3)
_DN_CENTRE = _dN(np.zeros((1, 3)))[0]  # (8, 3)
# ∂P_p/∂ξ_k of the bubbles P_p = 1 − ξ_p² at the Gauss points: diagonal, −2 ξ_p
_DP_GAUSS = np.einsum("gp,pk->gpk", -2.0 * _GAUSS, np.eye(3))  # (8, 3 modes, 3)


def _det3(J: np.ndarray) -> np.ndarray:
    """Determinants of a stack of 3 × 3 matrices (…, 3, 3) by cofactors (faster than LU)."""
    return (J[..., 0, 0] * (J[..., 1, 1] * J[..., 2, 2] - J[..., 1, 2] * J[..., 2, 1])
            - J[..., 0, 1] * (J[..., 1, 0] * J[..., 2, 2] - J[..., 1, 2] * J[..., 2, 0])
            + J[..., 0, 2] * (J[..., 1, 0] * J[..., 2, 1] - J[..., 1, 1] * J[..., 2, 0]))


def _inv3(J: np.ndarray, det: np.ndarray) -> np.ndarray:
    """Inverses of a stack of 3 × 3 matrices given their determinants (adjugate / det)."""
    a = np.empty_like(J)
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            # cyclic index pairs give the signed cofactor directly; adj = cofactorᵀ
            a[..., j, i] = J[..., i1, j1] * J[..., i2, j2] - J[..., i1, j2] * J[..., i2, j1]
    return a / det[..., None, None]


def _jacobians(X: np.ndarray):
    """Jacobians J_ik = ∂x_i/∂ξ_k at the Gauss points (m, 8, 3, 3) and the centre (m, 3, 3)."""
    J = np.einsum("mai,gak->mgik", X, _DN_GAUSS)
    J0 = np.einsum("mai,ak->mik", X, _DN_CENTRE)
    return J, J0


def _bad_elements(X: np.ndarray) -> np.ndarray:
    """Mask (m,) of elements whose det J is not positive (or not finite) at any of the 2×2×2
    Gauss points or at the centre."""
    J, J0 = _jacobians(X)
    det = np.concatenate([_det3(J), _det3(J0)[:, None]], axis=1)
    return ~np.all(det > 0.0, axis=1)  # `> 0` is False for NaN as well


def _raise_bad(key: str, bad: np.ndarray) -> None:
    idx = np.flatnonzero(bad)
    if idx.size:
        raise InputError(key, f"{idx.size} element(s) have a non-positive Jacobian "
                              f"determinant (first: element {idx[0]}); vertices 0-3 must be the "
                              "bottom face counter-clockwise seen from the top and 4-7 the top "
                              "face in the same order")


def _lame(E, nu, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Validated Lamé constants λ, μ per element, Pa, shape (m,), from E and ν (each a scalar
    or one per element)."""
    out = []
    for key, value in (("E", E), ("nu", nu)):
        try:
            a = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise InputError(key, f"must be a number or an array of numbers, "
                                  f"got {value!r}") from None
        if a.ndim == 0:
            a = np.full(m, float(a))
        elif a.shape != (m,):
            raise InputError(key, f"must be a scalar or have shape ({m},) (one per element), "
                                  f"got shape {a.shape}")
        out.append(a)
    E_, nu_ = out
    if not np.all(np.isfinite(E_) & (E_ > 0.0)):
        raise InputError("E", "Young's modulus must be finite and positive")
    if not np.all((nu_ >= 0.0) & (nu_ < 0.5)):  # NaN fails both comparisons
        raise InputError("nu", "Poisson's ratio must satisfy 0 <= nu < 0.5")
    lam = E_ * nu_ / ((1.0 + nu_) * (1.0 - 2.0 * nu_))
    mu = E_ / (2.0 * (1.0 + nu_))
    return lam, mu


def _condensed(X: np.ndarray, lam: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Condensed element matrices (m, 24, 24) of valid elements X (m, 8, 3)."""
    m = X.shape[0]
    J, J0 = _jacobians(X)
    det = _det3(J)  # (m, 8)
    det0 = _det3(J0)  # (m,)
    inv = _inv3(J, det)  # inv[k, i] = ∂ξ_k/∂x_i
    inv0 = _inv3(J0, det0)
    # 11 "shape functions" per Gauss point: 8 vertices, then 3 bubbles (Taylor's gradients)
    G = np.empty((m, 8, 11, 3))
    G[:, :, :8] = np.einsum("gak,mgki->mgai", _DN_GAUSS, inv)
    G[:, :, 8:] = (det0[:, None] / det)[..., None, None] * np.einsum(
        "gpk,mki->mgpi", _DP_GAUSS, inv0)
    # Every term of the isotropic stiffness is a contraction of
    # M[a,i,b,j] = Σ_g det J ∂_i φ_a ∂_j φ_b (the 8 Gauss weights are 1):
    # K[a,i,b,j] = λ ∂_iφ_a ∂_jφ_b + μ δ_ij ∇φ_a·∇φ_b + μ ∂_jφ_a ∂_iφ_b, integrated.
    Gr = G.reshape(m, 8, 33)
    M = np.matmul((det[:, :, None] * Gr).transpose(0, 2, 1), Gr)  # (m, 33, 33)
    M5 = M.reshape(m, 11, 3, 11, 3)
    K5 = np.multiply(M5.transpose(0, 1, 4, 3, 2), mu[:, None, None, None, None], order="C")
    K5 += M5 * lam[:, None, None, None, None]
    S = np.einsum("makbk->mab", M5)  # ∫ ∇φ_a·∇φ_b
    for i in range(3):
        K5[:, :, i, :, i] += mu[:, None, None] * S
    K = K5.reshape(m, 33, 33)  # dof 3a + i: the 24 vertex dofs first, then the 9 bubbles
    Kuu, Kua, Kaa = K[:, :24, :24], K[:, :24, 24:], K[:, 24:, 24:]
    Ke = Kuu - Kua @ np.linalg.solve(Kaa, Kua.transpose(0, 2, 1))
    return 0.5 * (Ke + Ke.transpose(0, 2, 1))  # condensation leaves round-off asymmetry


def hex8i_element_matrices(X, E, nu) -> np.ndarray:
    """Condensed stiffness matrices of hexahedra with incompatible modes.

    Trilinear displacements plus the bubbles (1 − ξ²), (1 − η²), (1 − ζ²) per component
    (Wilson et al. 1973), with Taylor, Beresford & Wilson's (1976) centre-Jacobian bubble
    gradients, 2×2×2 Gauss quadrature, and the 9 bubble amplitudes condensed out.

    Parameters
    ----------
    X : array_like, shape (m, 8, 3)
        Vertex coordinates of each element, m. Vertices 0–3 are the bottom face (ζ = −1) at
        (ξ, η) = (−1, −1), (1, −1), (1, 1), (−1, 1) — counter-clockwise seen from the top —
        and 4–7 the top face (ζ = +1) in the same order.
    E : float or array_like, shape (m,)
        Young's modulus, Pa (> 0).
    nu : float or array_like, shape (m,)
        Poisson's ratio, 0 ≤ ν < 0.5.

    Returns
    -------
    numpy.ndarray, shape (m, 24, 24)
        Element stiffness, N/m, symmetric positive semi-definite (six rigid-body modes);
        row/column 3 a + i is component i (x, y, z) of vertex a.

    Raises
    ------
    slipcycle.errors.InputError
        ``"X"`` for a wrong shape or an element with a non-positive Jacobian determinant at
        a Gauss point or the centre; ``"E"`` or ``"nu"`` for invalid material constants.

    References
    ----------
    Wilson, Taylor, Doherty & Ghaboussi (1973); Taylor, Beresford & Wilson (1976), Int. J.
    Numer. Meth. Eng. 10, 1211–1219.
    """
    X = np.asarray(X, dtype=float)
    if X.ndim != 3 or X.shape[1:] != (8, 3):
        raise InputError("X", f"must have shape (m, 8, 3), got {X.shape}")
    if not np.all(np.isfinite(X)):
        raise InputError("X", "coordinates must be finite")
    lam, mu = _lame(E, nu, X.shape[0])
    _raise_bad("X", _bad_elements(X))
    return _condensed(X, lam, mu)


def hex8i_stiffness(points, hexes, E, nu, *, chunk=20000) -> sp.csr_matrix:
    """Global stiffness of a mesh of hexahedra with incompatible modes (C3D8I-type).

    Each element is :func:`hex8i_element_matrices` (Wilson et al. 1973 with the
    modification of Taylor, Beresford & Wilson 1976); represents pure bending exactly on
    rectangular elements and passes the patch test on distorted ones.

    Parameters
    ----------
    points : array_like, shape (3, n)
        Node coordinates, m.
    hexes : array_like of int, shape (8, m)
        Vertices of each element: 0–3 the bottom face (ζ = −1) at natural coordinates
        (ξ, η) = (−1, −1), (1, −1), (1, 1), (−1, 1) — counter-clockwise seen from the top
        for a positively oriented element — then 4–7 the top face (ζ = +1) in the same
        order.
    E : float or array_like, shape (m,)
        Young's modulus, Pa, one value or one per element (bodies of different materials
        in one call).
    nu : float or array_like, shape (m,)
        Poisson's ratio, 0 ≤ ν < 0.5, one value or one per element.
    chunk : int, optional
        Elements processed at a time; bounds the working memory (about 50 kB per element).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (3n, 3n)
        Stiffness, N/m, unsupported (six rigid-body modes per connected body), symmetric;
        degree of freedom 3 · node + component (x, y, z).

    Raises
    ------
    slipcycle.errors.InputError
        ``"hexes"`` for wrong shapes, indices out of range, or elements with a non-positive
        Jacobian determinant at a Gauss point or the centre (the message gives their count
        and the first index); ``"points"``, ``"E"``, ``"nu"``, ``"chunk"`` for those inputs.

    References
    ----------
    Wilson, E. L., Taylor, R. L., Doherty, W. P. & Ghaboussi, J. (1973). Incompatible
    displacement models. Taylor, R. L., Beresford, P. J. & Wilson, E. L. (1976). A
    non-conforming element for stress analysis. Int. J. Numer. Meth. Eng. 10, 1211–1219.
    """
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[0] != 3:
        raise InputError("points", f"must have shape (3, n), got {points.shape}")
    if not np.all(np.isfinite(points)):
        raise InputError("points", "coordinates must be finite")
    hexes = np.asarray(hexes)
    if hexes.ndim != 2 or hexes.shape[0] != 8:
        raise InputError("hexes", f"must have shape (8, m), got {hexes.shape}")
    if hexes.size and not np.issubdtype(hexes.dtype, np.integer):
        raise InputError("hexes", f"must be integer node indices, got dtype {hexes.dtype}")
    n, m = points.shape[1], hexes.shape[1]
    if m and (hexes.min() < 0 or hexes.max() >= n):
        raise InputError("hexes", f"node indices must lie in [0, {n}), got "
                                  f"[{hexes.min()}, {hexes.max()}]")
    if isinstance(chunk, bool) or not isinstance(chunk, int | np.integer) or chunk < 1:
        raise InputError("chunk", f"must be a positive integer, got {chunk!r}")
    lam, mu = _lame(E, nu, m)
    hexes = hexes.astype(np.int64)

    # Check every element before any work: a degenerate one would make K_αα singular.
    bad = np.concatenate([_bad_elements(points.T[hexes[:, s:s + chunk].T])
                          for s in range(0, m, chunk)] or [np.zeros(0, bool)])
    _raise_bad("hexes", bad)

    N = 3 * n
    itype = np.int32 if N < 2**31 - 1 else np.int64
    K = sp.csr_matrix((N, N))
    for s in range(0, m, chunk):
        h = hexes[:, s:s + chunk].T  # (c, 8)
        Ke = _condensed(points.T[h], lam[s:s + chunk], mu[s:s + chunk])
        dofs = (3 * h[:, :, None] + np.arange(3)).reshape(-1, 24).astype(itype)
        rows = np.broadcast_to(dofs[:, :, None], Ke.shape).ravel()
        cols = np.broadcast_to(dofs[:, None, :], Ke.shape).ravel()
        # COO → CSR sums the contributions of elements sharing a node
        K = K + sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(N, N)).tocsr()
    return ((K + K.T) * 0.5).tocsr()
