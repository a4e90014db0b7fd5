"""Critical friction of the 3-D discrete system (isotropic Coulomb cone).

Two numbers are reported, because for the cone neither an exact enumeration nor an exact
condition is available:

1. **Sampled critical friction** ``f_crit`` (an upper estimate of the true value). The 2-D
   condition of Klarbring (1990) — every ``A_II + f S B_II`` is a P-matrix — generalises to
   the cone by replacing the slip signs S = diag(±1) by unit slip directions s_j in the
   tangent plane: with ``S = blockdiag(s_j)`` (2|I|×|I|) the rate of the radial friction
   condition of the slipping set I, ``s_jᵀ q̇_j + f_j ṗ_j = 0`` with ``v̇_j = γ_j s_j``, has
   the matrix

       M_I(s) = S_Iᵀ A_II S_I + F_I B_II S_I        (|I|×|I|),

   which must be a P-matrix for every subset I and every choice of directions (Klarbring &
   Pang 1998 for the polyhedral version of the same condition). With f_j = φ ρ_j (ρ the
   friction ratios), ``det M_I = 0`` first at φ = −1/μ for the real negative eigenvalues μ
   of ``(SᵀAS)⁻¹ F B S``; ``f_crit`` is the smallest such φ found over: every single node
   (720 directions), every pair of nodes for N ≤ 40 (24 × 24 directions, the quadratic
   det(M0 + φ M1) solved in closed form for all pairs and directions at once),
   and the full set with 32 random direction draws for N ≤ 300. It is *sampled*: a true
   f_crit can only be smaller. With one tangential direction (directions ±t1) it is the
   2-D value of the same subsets.

2. **Certified lower bound** ``lower_bound``: the incremental (load-step) problem has at
   most one solution if ``f_max < λ_min(K) / ‖[B C]‖₂``. Proof (monotonicity): for two
   solutions, δrᵀδx = δxᵀKδx; the normal terms give δp δw = −p₁w₂ − p₂w₁ ≤ 0, and the cone
   gives (q₁ − q₂)·(Δv₁ − Δv₂) ≤ f |p₁ − p₂| |Δv₁ − Δv₂| (using −q_i·Δv_i = f p_i |Δv_i|
   and |q_i| ≤ f p_i); with δp = B δv + C δw this bounds λ_min(K)‖δx‖² by
   f_max ‖[B C]‖ ‖δx‖². It is conservative (it ignores the sign structure); computed for
   N ≤ 400 (an eigenvalue problem of size 3N).

References
----------
A. Klarbring, "Examples of non-uniqueness and non-existence of solutions to quasistatic
contact problems with friction", Ing.-Arch. 60 (1990) 529–541. A. Klarbring, J.-S. Pang,
"Existence of solutions to discrete semicoercive frictional contact problems", SIAM J.
Optim. 8 (1998) 414–442. L.-E. Andersson, "Existence results for quasistatic contact
problems with Coulomb friction", Appl. Math. Optim. 42 (2000) 169–202.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CriticalFriction3D", "critical_friction_3d", "radial_matrix"]


@dataclass(frozen=True)
class CriticalFriction3D:
    """Critical friction of a 3-D system.

    Attributes
    ----------
    f_crit : float
        Sampled critical friction coefficient (an upper estimate; ``inf`` if no sampled
        subset loses the P-property), for the largest node friction f_max.
    lower_bound : float or None
        Certified bound: f_max below it guarantees a unique incremental solution.
    method : str
        What was sampled (``"sampled: single nodes, pairs, full set"``...).
    nodes : tuple of int
        The subset where ``f_crit`` was found (empty if none).
    directions : tuple of float
        Slip angles (rad, from t1) of those nodes.
    """

    f_crit: float
    lower_bound: float | None
    method: str
    nodes: tuple = ()
    directions: tuple = ()


def radial_matrix(A, B, friction_ratio, nodes, angles) -> np.ndarray:
    """``M_I(s) = SᵀA_II S + F_I B_II S`` for the slipping set ``nodes`` and slip angles
    ``angles`` (rad from t1), at unit friction scale (module docstring).

    Returns
    -------
    (|I|, |I|) array [N/m]
    """
    nodes = np.asarray(nodes, int)
    s = np.column_stack([np.cos(angles), np.sin(angles)])            # (k, 2)
    cols = np.ravel(np.column_stack([2 * nodes, 2 * nodes + 1]))
    A_II = A[np.ix_(cols, cols)].reshape(len(nodes), 2, len(nodes), 2)
    B_II = B[np.ix_(nodes, cols)].reshape(len(nodes), len(nodes), 2)
    M0 = np.einsum("ia,iajb,jb->ij", s, A_II, s)
    M1 = friction_ratio[nodes, None] * np.einsum("ijb,jb->ij", B_II, s)
    return M0, M1


def _phi_from_eig(M0, M1) -> float:
    mu = np.linalg.eigvals(np.linalg.solve(M0, M1))
    neg = mu[(np.abs(mu.imag) <= 1e-9 * np.max(np.abs(mu), initial=1.0)) & (mu.real < 0)]
    return float(np.min(-1.0 / neg.real)) if neg.size else np.inf


def _pairs(A, B, ratio, ang) -> tuple[float, tuple, tuple]:
    """Smallest positive real root φ of det(M0 + φ M1) = 0 over every pair of nodes and
    every pair of slip angles ``ang`` (k,): the 2 × 2 determinant is the quadratic
    a φ² + b φ + c, solved in closed form for all pairs and angles at once.

    Returns
    -------
    (phi, (i, k), (angle_i, angle_k)) : the first smallest root in the order pair (i < k),
    angle of i, angle of k (``inf`` and empty tuples if no positive real root).
    """
    n = B.shape[0]
    i, k = np.triu_indices(n, 1)                                    # (P,)
    s = np.column_stack([np.cos(ang), np.sin(ang)])                  # (k, 2)
    blk = A.reshape(n, 2, n, 2)
    Bn = B.reshape(n, n, 2)

    # M0 = [[s1ᵀA_ii s1, s1ᵀA_ik s2], [s2ᵀA_ki s1, s2ᵀA_kk s2]], shapes (P, k1, k2)
    a_ii = np.einsum("xa,pab,xb->px", s, blk[i, :, i, :], s)[:, :, None]
    a_kk = np.einsum("ya,pab,yb->py", s, blk[k, :, k, :], s)[:, None, :]
    a_ik = np.einsum("xa,pab,yb->pxy", s, blk[i, :, k, :], s)
    a_ki = np.einsum("ya,pab,xb->pxy", s, blk[k, :, i, :], s)
    # M1 = [[ρ_i b_ii·s1, ρ_i b_ik·s2], [ρ_k b_ki·s1, ρ_k b_kk·s2]]
    b_ii = (ratio[i, None] * (Bn[i, i] @ s.T))[:, :, None]
    b_ik = (ratio[i, None] * (Bn[i, k] @ s.T))[:, None, :]
    b_ki = (ratio[k, None] * (Bn[k, i] @ s.T))[:, :, None]
    b_kk = (ratio[k, None] * (Bn[k, k] @ s.T))[:, None, :]
    qa = b_ii * b_kk - b_ik * b_ki
    qc = a_ii * a_kk - a_ik * a_ki
    qb = a_ii * b_kk + b_ii * a_kk - a_ik * b_ki - b_ik * a_ki
    qa, qb, qc = np.broadcast_arrays(qa, qb, qc)
    phi = _smallest_positive_root(qa, qb, qc)
    j = int(np.argmin(phi))
    if not np.isfinite(phi.flat[j]):
        return np.inf, (), ()
    p, x, y = np.unravel_index(j, phi.shape)
    return float(phi.flat[j]), (int(i[p]), int(k[p])), (float(ang[x]), float(ang[y]))


def _smallest_positive_root(qa, qb, qc) -> np.ndarray:
    """Smallest positive real root of a φ² + b φ + c elementwise (``inf`` if none); a root
    with an imaginary part below 1e-12 (1 + |root|) counts as real (``numpy.roots``' test
    of the loop this replaces); a = 0 leaves the linear root, a = b = 0 none."""
    out = np.full(qa.shape, np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        quad = qa != 0
        disc = qb * qb - 4 * qa * qc
        re = -qb / (2 * qa)
        half = np.sqrt(np.abs(disc)) / (2 * np.abs(qa))
        for sign in (1.0, -1.0):
            r = np.where(disc >= 0, re + sign * half, re)
            im = np.where(disc >= 0, 0.0, half)
            ok = quad & (im < 1e-12 * (1 + np.hypot(r, im))) & (r > 0)
            out = np.where(ok, np.minimum(out, r), out)
        lin = ~quad & (qb != 0)
        r = -qc / qb
        out = np.where(lin & (r > 0), np.minimum(out, r), out)
    return out


def critical_friction_3d(A, B, C, friction, *, seed: int = 0) -> CriticalFriction3D:
    """Sampled critical friction and certified lower bound (module docstring).

    Parameters
    ----------
    A : (2N, 2N) array [N/m]
    B : (N, 2N) array [N/m]
    C : (N, N) array [N/m]
    friction : (N,) array
        Friction coefficients (their ratios weight the sampled condition).
    seed : int
        Seed of the random direction draws for the full set.

    Returns
    -------
    CriticalFriction3D
    """
    A, B, C = (np.asarray(M, float) for M in (A, B, C))
    n = C.shape[0]
    f = np.asarray(friction, float)
    fmax = float(np.max(f)) if f.size else 0.0
    ratio = f / fmax if fmax > 0 else np.ones(n)
    best, where, dirs = np.inf, (), ()
    parts = []
    if np.any(B):
        # single nodes: M = sᵀA_jj s + ρ_j b_j·s, zero at φ = sᵀAs / (−ρ b·s)
        ang = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
        s = np.column_stack([np.cos(ang), np.sin(ang)])
        idx = np.arange(n)
        Ajj = np.stack([A[2 * idx, 2 * idx], A[2 * idx, 2 * idx + 1],
                        A[2 * idx + 1, 2 * idx + 1]], axis=1)            # (N, 3)
        bjj = np.stack([B[idx, 2 * idx], B[idx, 2 * idx + 1]], axis=1)    # (N, 2)
        m0 = (Ajj[:, 0, None] * s[None, :, 0] ** 2 + 2 * Ajj[:, 1, None] * s[None, :, 0]
              * s[None, :, 1] + Ajj[:, 2, None] * s[None, :, 1] ** 2)
        m1 = ratio[:, None] * (bjj @ s.T)
        with np.errstate(divide="ignore", invalid="ignore"):
            phi = np.where(m1 < 0, -m0 / m1, np.inf)
        j, a = np.unravel_index(np.argmin(phi), phi.shape)
        if phi[j, a] < best:
            best, where, dirs = float(phi[j, a]), (int(j),), (float(ang[a]),)
        parts.append("single nodes")
        if 2 <= n <= 40:
            phi, pair, d = _pairs(A, B, ratio, np.linspace(0.0, 2 * np.pi, 24,
                                                           endpoint=False))
            if phi < best:
                best, where, dirs = phi, pair, d
            parts.append("pairs")
        if 2 < n <= 300:
            rng = np.random.default_rng(seed)
            for _ in range(32):
                angs = rng.uniform(0, 2 * np.pi, n)
                M0, M1 = radial_matrix(A, B, ratio, np.arange(n), angs)
                phi = _phi_from_eig(M0, M1)
                if phi < best:
                    best, where, dirs = phi, tuple(range(n)), tuple(map(float, angs))
            parts.append("full set (32 random directions)")
    method = "sampled: " + (", ".join(parts) if parts else "uncoupled (B = 0)")
    lower = None
    if not np.any(B):
        lower = np.inf        # a strictly convex minimisation: unique for every f
    elif n <= 400:
        K = np.block([[A, B.T], [B, C]])
        lam_min = float(np.linalg.eigvalsh(K)[0])
        norm = float(np.linalg.norm(np.hstack([B, C]), 2))
        lower = lam_min / norm if norm > 0 else np.inf
    return CriticalFriction3D(best, lower, method, where, dirs)
