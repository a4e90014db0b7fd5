"""The periodic state of the cycle map, found without cycling to it.

Let Φ map the state x = [v, w] at the start of a load cycle to the state one cycle later.
Between events every rate is constant and independent of the state (it depends on the
modes and the load rate only), and each event time is an affine function of the state, so
on the set of states that share one sequence of modes and events Φ is *affine*:
Φ(x) = M x + c, with the Jacobian a product of rank-one factors, one per event,

    M = (I − u_E a_Eᵀ) ⋯ (I − u_1 a_1ᵀ),   u_e = (ẋ_e⁻ − ẋ_e⁺) / ġ_e,

where a_e is the gradient of the event function g_e (f p ± q, p or w of the node) and ġ_e its
rate before the event (:mod:`~slipcycle.discrete.evolution`). The cycle map of a frictional
system is thus piecewise affine (Andersson, Barber & Ahn 2013 study its attractors); plain
cycling x_{c+1} = Φ(x_c) converges geometrically, at the rate of the spectral radius of M,
which for coupled FE-reduced models is often close to 1.

Memory. Every u_e vanishes outside the coordinates S of the nodes that slip or separate
in the cycle; the other nodes keep the slip their history gave them (Barber 2012, §3: the
permanently stuck nodes make the steady state a set, not a point). With r = Φ(x) − x, plain
cycling from x converges to

    x_∞ = x + Σ_k M^k r = x + (I − M)^D r,

the Drazin inverse (Campbell & Meyer, *Generalized Inverses of Linear Transformations*,
1979, §7): it changes only S, keeps the components of the neutral directions of M (e.g. the
reactions p = q = 0 of a node that stays open, or a stuck node's slip) and contracts the
rest. For a consistent system of index one, GMRES started from zero stays in the Krylov
space of (I − M, r) ⊂ range(I − M) and returns exactly this solution (Brown & Walker,
"GMRES on (nearly) singular systems", SIAM J. Matrix Anal. Appl. 18 (1997) 37–51); the
Ritz values of the Arnoldi process estimate the spectrum of M on that space, and the step
is refused unless all of them lie inside the unit circle (plain cycling would then not
converge to it). :func:`periodic_step` does this with the rank-one factors applied in
sequence (O(E |S|) per product, E events per cycle; Golub & Van Loan, *Matrix
Computations*, 4th ed., §6.1 GMRES and §2.1.5 rank-one updates). The small least-squares
problem of GMRES is solved by the truncated SVD of Arnoldi's Hessenberg matrix (Golub &
Van Loan §5.5.8): a direction in which I − M is below :data:`NEUTRAL` of its largest
singular value is neutral (a stuck node's memory, a slip that round-off lets into the
Krylov space), and the minimum-norm solution leaves it alone as the Drazin inverse does,
instead of dividing r's round-off component along it by ~0 (on the 401-node FE block
this threw the step 10⁷ increments off and every step was refused).

The step is exact only while the sequence of events stays the same, and the cycle map
changes piece as event times cross load samples, so it is used as Newton's method on the
piecewise-affine map: :func:`~slipcycle.discrete.steady.simulate` takes a step when the
same nodes slipped in the last two cycles, refuses one whose cycles would reverse a one-way
slip (:func:`stays_one_way`: plain cycling would leave the piece and freeze that node
elsewhere), and checks every step by one more exact cycle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

#: singular values of I − M below this fraction of the largest count as neutral directions
NEUTRAL = 1e-8

__all__ = ["CycleJacobian", "cycle_jacobian", "periodic_step", "PeriodicStep",
           "stays_one_way"]


@dataclass(frozen=True)
class CycleJacobian:
    """The Jacobian M of one cycle on the moving coordinates S, as rank-one factors.

    Attributes
    ----------
    S : (m,) int array
        Indices into x = [v, w] (2N,) of the coordinates some event moves.
    U : (E, m) array
        u_e restricted to S, one row per event [1 / (N/m·m)… in the units of x / g].
    A : (E, m) array
        Gradients a_e of the event functions restricted to S.
    """

    S: np.ndarray
    U: np.ndarray
    A: np.ndarray

    def apply(self, v: np.ndarray) -> np.ndarray:
        """(I − M) v for v (m,)."""
        return v - _apply_map(self.U, self.A, v.copy())


@njit(cache=True)
def _apply_map(U, A, v):
    """M v = (I − u_E a_Eᵀ) ⋯ (I − u_1 a_1ᵀ) v, in place; O(E m)."""
    E, m = U.shape
    for e in range(E):
        s = 0.0
        for i in range(m):
            s += A[e, i] * v[i]
        if s != 0.0:
            for i in range(m):
                v[i] -= U[e, i] * s
    return v


def cycle_jacobian(log: list, K: np.ndarray, friction: np.ndarray,
                   max_entries: int = 50_000_000) -> CycleJacobian | None:
    """Assemble the rank-one factors recorded over one cycle.

    Parameters
    ----------
    log : list of (kind, node, idx, u)
        ``Evolution.jacobian_log`` of one cycle: the event kind (0: f p + q = 0 reached,
        1: f p − q = 0, 2: p = 0, 3: w = 0), its node, and u_e at the indices ``idx``.
    K : (2N, 2N) array
        Reduced stiffness [N/m].
    friction : (N,) array
    max_entries : int
        Refuse (return None) when E·m exceeds this (memory).

    Returns
    -------
    CycleJacobian or None
    """
    n = K.shape[0] // 2
    log = [e for e in log if e[2].size]
    if not log:
        return CycleJacobian(np.zeros(0, int), np.zeros((0, 0)), np.zeros((0, 0)))
    S = np.unique(np.concatenate([e[2] for e in log]))
    E, m = len(log), S.size
    if E * m > max_entries:
        return None
    kinds = np.array([e[0] for e in log])
    nodes = np.array([e[1] for e in log])
    U = np.zeros((E, m))
    for k, (_, _, idx, u) in enumerate(log):
        U[k, np.searchsorted(S, idx)] = u
    # gradients of g = f p + q, f p − q, p (rows of K) and w (a unit vector)
    f = np.asarray(friction, float)[nodes]
    Kq = K[np.ix_(nodes, S)]
    Kp = K[np.ix_(n + nodes, S)]
    sq = np.where(kinds == 0, 1.0, np.where(kinds == 1, -1.0, 0.0))
    sp = np.where(kinds <= 1, f, np.where(kinds == 2, 1.0, 0.0))
    A = sq[:, None] * Kq + sp[:, None] * Kp
    gap = np.flatnonzero(kinds == 3)
    if gap.size:
        pos = np.searchsorted(S, n + nodes[gap])
        hit = (pos < m) & (S[np.minimum(pos, m - 1)] == n + nodes[gap])
        A[gap[hit], pos[hit]] = 1.0
    return CycleJacobian(S, np.ascontiguousarray(U), np.ascontiguousarray(A))


@dataclass(frozen=True)
class PeriodicStep:
    """Outcome of :func:`periodic_step`.

    Attributes
    ----------
    delta : (2N,) array or None
        x_∞ − x, None when refused.
    reason : str
        Why it was refused ("" when taken).
    spectral_radius : float
        Largest |eigenvalue| of M estimated on the Krylov space (Ritz values).
    iterations : int
        Arnoldi steps.
    """

    delta: np.ndarray | None
    reason: str
    spectral_radius: float
    iterations: int


def periodic_step(jac: CycleJacobian, r: np.ndarray, scale: float, *,
                  rtol: float = 1e-11, max_iter: int = 200) -> PeriodicStep:
    """x_∞ − x = (I − M)^D r for the increment r = Φ(x) − x of one cycle.

    Parameters
    ----------
    jac : CycleJacobian
        The cycle map's Jacobian recorded over the cycle that produced ``r``.
    r : (2N,) array
        Increment of the start-of-cycle state over that cycle [m].
    scale : float
        Displacement scale [m]: a component of r outside S above ``rtol·scale`` is a drift
        no periodic state removes (refused).
    rtol : float
        Relative residual of the GMRES solve.
    max_iter : int
        Largest Krylov dimension.

    Returns
    -------
    PeriodicStep
    """
    S = jac.S
    rS = r[S]
    out = np.ones(r.size, bool)
    out[S] = False
    if np.any(np.abs(r[out]) > rtol * scale):
        return PeriodicStep(None, "drift outside the coordinates the events move", np.nan, 0)
    beta = float(np.linalg.norm(rS))
    delta = np.zeros(r.size)
    if beta == 0.0:
        return PeriodicStep(delta, "", 0.0, 0)
    m = S.size
    kmax = min(m, max_iter)
    Q = np.zeros((kmax + 1, m))
    H = np.zeros((kmax + 1, kmax))     # Arnoldi's Hessenberg matrix (for the Ritz values)
    R = np.zeros((kmax + 1, kmax))     # its QR factor by Givens rotations
    cs = np.zeros(kmax)
    sn = np.zeros(kmax)
    g = np.zeros(kmax + 1)             # rotated right-hand side β e₁
    g[0] = beta
    Q[0] = rS / beta
    k = 0
    for k in range(kmax):
        w = jac.apply(Q[k])
        for _ in range(2):  # classical Gram–Schmidt, twice (orthogonal to round-off)
            h = Q[:k + 1] @ w
            H[:k + 1, k] += h
            w -= h @ Q[:k + 1]
        H[k + 1, k] = np.linalg.norm(w)
        col = H[:k + 2, k].copy()
        for i in range(k):
            col[i], col[i + 1] = (cs[i] * col[i] + sn[i] * col[i + 1],
                                  -sn[i] * col[i] + cs[i] * col[i + 1])
        d = np.hypot(col[k], col[k + 1])
        cs[k], sn[k] = (1.0, 0.0) if d == 0.0 else (col[k] / d, col[k + 1] / d)
        col[k], col[k + 1] = d, 0.0
        R[:k + 2, k] = col
        g[k], g[k + 1] = cs[k] * g[k], -sn[k] * g[k]
        if abs(g[k + 1]) <= rtol * beta or H[k + 1, k] <= 1e-14 * beta:
            break
        Q[k + 1] = w / H[k + 1, k]
    k += 1
    # least squares min |β e₁ − H y| by the truncated SVD of Arnoldi's Hessenberg matrix:
    # singular values of I − M at round-off level relative to the largest are neutral
    # directions (eigenvalue 1 of M: stuck memory, an open node's p = q = 0) that
    # round-off lets into the Krylov space; a triangular solve would divide r's round-off
    # component along them by ~0 and throw the state far off its piece. The minimum-norm
    # solution leaves them out, as the Drazin inverse does.
    Uh, sv, Vh = np.linalg.svd(H[:k + 1, :k], full_matrices=False)
    keep = sv > NEUTRAL * sv[0]
    rhs = np.zeros(k + 1)
    rhs[0] = beta
    c = Uh[:, keep].T @ rhs
    y = Vh[keep].T @ (c / sv[keep])
    res = float(np.linalg.norm(rhs - H[:k + 1, :k] @ y))
    if res > 1e3 * rtol * beta:
        return PeriodicStep(None, f"no solution in the Krylov space (relative residual "
                                  f"{res / beta:.2g}): drift or a neutral direction", np.nan, k)
    ritz = np.linalg.eigvals(H[:k, :k])
    # Ritz values of I − M at round-off level are the neutral directions (eigenvalue 1 of
    # M: stuck memory, the p = q = 0 of an open node) that round-off lets into the Krylov
    # space; the solution has no part along them (the step's size is checked by the
    # caller). Every other one must be a contraction of M.
    active = np.abs(ritz) > 1e-8
    rho = float(np.max(np.abs(1.0 - ritz[active]), initial=0.0))
    if not np.all(np.isfinite(ritz)) or rho >= 1.0 - 1e-9:
        return PeriodicStep(None, f"cycle map not contracting (|eigenvalue| ≈ {rho:.6g})",
                            rho, k)
    delta[S] = Q[:k].T @ y
    return PeriodicStep(delta, "", rho, k)


def stays_one_way(jac: CycleJacobian, r: np.ndarray, one_way: np.ndarray, tiny: float,
                  max_cycles: int = 5000, max_work: float = 2e9) -> bool:
    """Whether the cycles that the step stands for keep every one-way slip one way.

    On the piece, the increments of successive cycles are r, M r, M² r, …; a node that
    slips in one direction only (``one_way[j]`` = +1 or −1) has increment ``one_way[j]``·
    (M^k r)_j ≥ 0 for every k while plain cycling stays on the piece. A reversal means
    that plain cycling leaves the piece (the node stops slipping after finitely many
    cycles, frozen where the step would not put it): the step must not be taken.

    Parameters
    ----------
    jac : CycleJacobian
    r : (2N,) array
        Increment of the last cycle [m].
    one_way : (N,) int array
        +1 / −1 for a node that slipped only in that direction, 0 otherwise.
    tiny : float
        Increments below this are round-off [m].
    max_cycles, max_work : int, float
        Bounds on the linear iterations (k) and on k·E·m; False when they are reached.

    Returns
    -------
    bool
    """
    n = one_way.size
    S = jac.S
    sl = S < n
    sign = np.zeros(S.size)
    sign[sl] = one_way[S[sl]]
    if not np.any(sign):
        return True
    e = r[S].copy()
    cost = max(1, jac.U.size)
    for _ in range(int(min(max_cycles, max_work / cost))):
        if np.any(sign * e < -tiny):
            return False
        if np.max(np.abs(e)) <= tiny:
            return True
        e = _apply_map(jac.U, jac.A, e)
    return False
