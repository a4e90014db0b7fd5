"""Shakedown limit λ2 of the 3-D system: a second-order cone program.

With every node in contact, a slip state v (the residual tangential reaction field is
A v, the residual normal field B v) is *safe* for the whole cycle iff at every instant
every node lies in its cone,

    | q0_j(θ) + λ q1_j(θ) + (A v)_j |  ≤  f_j ( p0_j(θ) + λ p1_j(θ) + (B v)_j ),

the loads split as r^w(θ; λ) = r0(θ) + λ r1(θ) (:meth:`~slipcycle.discrete3d.loads.Load3D.
split_lam`). The set of safe v is the *safe region* S(λ) (Klarbring, Ciavarella & Barber
2007; Ahn, Bertocchi & Barber 2008 for the 2-D polyhedron); on the cone it is convex but
not polyhedral. λ2 = sup{λ : S(λ) ≠ ∅} is the second-order cone program

    maximise λ over (v, λ)  subject to  (f_j p_j(θ_k), q_j(θ_k)) ∈ 𝒦³ for all j, k,

solved with Clarabel (Goulart & Chen 2024, an interior-point solver for conic programs).
Over the load samples θ_k the program is exact for the piecewise-linear load path the
simulation follows: for fixed v the constraint is a second-order cone in (q^w, p^w), so it
holds along a chord when it holds at its ends. For an uncoupled system (B = 0) the
frictional Melan theorem (Klarbring et al. 2007) makes λ2 the shakedown limit: below it
the system shakes down from every start, above it it cannot.

With separation (:func:`lambda2_open`) a node is held in its cone only at the samples
where the elastic solution has it closed; an open node's residual force vanishes and its
gap must stay open, the open degrees of freedom condensed out per sample
(:mod:`~slipcycle.discrete3d.separation`). The contact sets are taken from the elastic
solution (first with the assembly's slip at λ = 0, then with the program's safe state)
rather than made unknowns, which keeps the program convex; at the fixed point its safe
state is certified by a fresh elastic solution. A node that changes state inside a load
interval makes the sampled program approximate: it converges at second order in the
sample spacing (tested). The program is sparse: the slip response of a contact set (its
closed nodes' reactions and open nodes' gaps per slip, a Schur complement of K) is a
variable tied to v once per distinct set, and each sample's cone touches three entries
of it and λ, so the dense part grows with the distinct sets, not with the samples (a
joint whose sets do not change over the cycle has one dense block however finely the
cycle is sampled). :func:`lambda2_polygonal` brackets the cone program by two
linear programs (inscribed and circumscribed polygons, HiGHS), and
:func:`lambda1_bracket` brackets λ1 (every start shakes down below it) by simulation.

References
----------
A. Klarbring, M. Ciavarella, J. R. Barber, "Shakedown in elastic contact problems with
Coulomb friction", Int. J. Solids Struct. 44 (2007) 8355–8365. Y. J. Ahn, E. Bertocchi,
J. R. Barber, J. Mech. Phys. Solids 56 (2008) 3433–3440. P. J. Goulart, Y. Chen,
"Clarabel: an interior-point solver for conic programs with quadratic objectives",
arXiv:2405.12762 (2024).
"""

from __future__ import annotations

from dataclasses import dataclass

import clarabel
import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.separation import (
    closed_rows,
    elastic_open_set,
    elastic_reactions,
    open_sets,
)
from slipcycle.discrete3d.steady import simulate3d
from slipcycle.errors import SolverError
from slipcycle.kernels.threads import single_threaded

__all__ = ["SafeRegion3D", "lambda2_socp", "is_safe", "SafeRegionOpen3D", "lambda2_open",
           "lambda2_polygonal", "is_safe_open", "safe_start", "shakedown_limit",
           "Lambda1Bracket", "lambda1_bracket"]


@dataclass(frozen=True)
class SafeRegion3D:
    """Result of :func:`lambda2_socp`.

    Attributes
    ----------
    lambda2 : float
        Largest load factor with a non-empty safe region (``lam_max`` if the program hit
        that cap, 0 if even λ = 0 has no safe state, then ``feasible`` is False).
    safe_slip : (N, 2) array
        A safe slip state at λ2 [m] (residual tangential reactions A v).
    feasible : bool
        Whether some λ ≥ 0 has a safe state.
    status : str
        Clarabel's status.
    samples : int
        Load samples of the program.
    """

    lambda2: float
    safe_slip: np.ndarray
    feasible: bool
    status: str
    samples: int


def lambda2_socp(system: FrictionalSystem3D, load: Load3D, steps_per_cycle: int = 100,
                 *, lam_max: float = 1e6, tol: float = 1e-9) -> SafeRegion3D:
    """λ2 by the second-order cone program of the module docstring.

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
        Its λ is ignored (the program scales the periodic part).
    steps_per_cycle : int
        Load samples (the cycle samples of the simulation, breakpoints included).
    lam_max : float
        Cap on λ (a load whose periodic part never leaves the cones has no finite λ2).
    tol : float
        Clarabel's gap and feasibility tolerances.

    Returns
    -------
    SafeRegion3D

    Raises
    ------
    SolverError
        If Clarabel stops without a solution or a certificate.
    """
    n = system.n_nodes
    theta, _ = load.cycle_samples(steps_per_cycle)
    theta = theta[:-1]
    r0, r1 = load.split_lam(theta)
    closed = np.zeros((theta.size, n), bool)
    status, y = _socp(_open_rows(system, r0, r1, closed), lam_max, tol)
    if y is None:
        return SafeRegion3D(0.0, np.zeros((n, 2)), False, status, theta.size)
    v = y[:2 * n] * _scales(system, r0, r1)[1]
    return SafeRegion3D(float(y[2 * n]), v.reshape(n, 2), True, status, theta.size)


def is_safe(system: FrictionalSystem3D, load: Load3D, v: np.ndarray,
            steps_per_cycle: int = 100, rtol: float = 1e-9) -> bool:
    """Whether the slip state v ((N, 2) or (2N,)) lies in the safe region of ``load``
    (every node inside its cone at every sample, to ``rtol`` × the load scale)."""
    n = system.n_nodes
    theta, vals = load.cycle_samples(steps_per_cycle)
    x = np.concatenate([np.asarray(v, float).reshape(2 * n), np.zeros(n)])
    r = vals + system.K @ x
    q = r[:, :2 * n].reshape(len(theta), n, 2)
    p = r[:, 2 * n:]
    scale = max(float(np.max(np.abs(vals))), 1e-300)
    return bool(np.all(system.friction * p - np.linalg.norm(q, axis=2) >= -rtol * scale))


# --- separation: the open set of each sample from the elastic solution -------------------
@dataclass(frozen=True)
class SafeRegionOpen3D:
    """Result of :func:`lambda2_open`.

    Attributes
    ----------
    lambda2 : float
        Largest load factor with a safe state whose contact sets are those of its own
        elastic solution (0 and ``feasible`` False if none exists at λ = 0).
    safe_slip : (N, 2) array
        That safe state [m]: the slip at which each node sticks while it is closed (an
        open-throughout node's entry is 0: it never carries force).
    start_slip : (N, 2) array
        The state at θ = 0 [m]: ``safe_slip``, with the nodes open at θ = 0 at their free
        elastic position (an admissible start of a simulation).
    feasible : bool
    status : str
        Clarabel's status of the last program.
    open_set : (S, N) bool array
        Open nodes at each load sample θ_k of ``theta``.
    theta : (S,) array
        The load samples [rad].
    consistent : bool
        The elastic solution at (``lambda2``, ``safe_slip``) has the sets ``open_set``
        (the fixed point was reached): the state is a certified safe state.
    iterations : int
        Programs solved (contact sets updated between them).
    """

    lambda2: float
    safe_slip: np.ndarray
    start_slip: np.ndarray
    feasible: bool
    status: str
    open_set: np.ndarray
    theta: np.ndarray
    consistent: bool
    iterations: int


#: relative step beyond λ2 at which the next contact sets are taken
_BEYOND = 1e-6


def _scales(system: FrictionalSystem3D, r0: np.ndarray, r1: np.ndarray):
    """Force scale [N] and slip scale [m] of the program's variables."""
    fs = max(float(np.max(np.abs(r0))), float(np.max(np.abs(r1))), 1e-300)
    return fs, fs / max(float(np.max(np.diag(system.K))), 1e-300)


@dataclass(frozen=True)
class _Rows:
    """The cone program of a set of contact sets, sparse.

    Variables y = [v / slip_scale (2N), λ, z]: z holds, for each distinct contact set,
    its *slip response* (the reactions of its closed nodes and the gaps of its open ones
    per slip v, in force units), tied to v once by ``A_tie y = 0`` (one dense block per
    distinct set). Each sample's rows then touch λ and three entries of z: gap rows
    ``b_gap − G_gap y ≥ 0``, cone rows ``b_cone − G_cone y ∈ 𝒦³`` (three rows
    (f p, q1, q2) per closed node and sample). Every row is divided by the force scale.
    """

    A_tie: sp.csr_matrix
    G_gap: sp.csr_matrix
    b_gap: np.ndarray
    G_cone: sp.csr_matrix
    b_cone: np.ndarray
    n_slip: int

    @property
    def n_vars(self) -> int:
        return self.A_tie.shape[1]


def _set_block(system: FrictionalSystem3D, is_open: np.ndarray, fs: float, vs: float):
    """Closed nodes c, load map L ((3k + m, 3N): reactions [q (2k), p (k)] of the closed
    nodes and gaps of the m open ones per unit load, in force units) and slip map S
    ((3k + m, 2N), per unit scaled slip) of one contact set."""
    kd = max(float(np.max(np.diag(system.K))), 1e-300)
    c, R_load, R_slip, W_load, W_slip = closed_rows(system, is_open)
    # the gaps as forces (× max diag K), so that every row has the force scale
    return c, np.vstack([R_load, kd * W_load]) / fs, np.vstack([R_slip, kd * W_slip]) * (
        vs / fs)


def _open_rows(system: FrictionalSystem3D, r0: np.ndarray, r1: np.ndarray,
               sets: np.ndarray) -> _Rows:
    """:class:`_Rows` of the program with the contact sets ``sets`` (S, N) at the load
    samples r0 + λ r1 ((S, 3N) each)."""
    n = system.n_nodes
    fs, vs = _scales(system, r0, r1)
    blocks: dict = {}
    ties, gaps, cones = [], [], []
    n_z = 0
    for k, is_open in enumerate(sets):
        key = is_open.tobytes()
        if key not in blocks:
            c, L, S = _set_block(system, is_open, fs, vs)
            # a row that no slip moves (B = 0: the normal reactions) gets no variable
            live = np.any(S != 0.0, axis=1)
            col = 2 * n + 1 + n_z + np.cumsum(live) - 1
            blocks[key] = (c, L, np.where(live, col, 0), live.astype(float))
            ties.append(sp.coo_matrix(S[live]))
            n_z += int(live.sum())
        c, L, col, live = blocks[key]
        a0, a1 = L @ r0[k], L @ r1[k]
        m = c.size
        f = system.friction[c]
        node = np.arange(m)
        # cone rows (f p, q1, q2) of each closed node: indices into a0, a1 and z
        idx = np.stack([2 * m + node, 2 * node, 2 * node + 1], axis=1).reshape(-1)
        w = np.stack([f, np.ones(m), np.ones(m)], axis=1).reshape(-1)
        cones.append((w * a0[idx], w * a1[idx], w * live[idx], col[idx]))
        g = np.arange(3 * m, a0.size)
        gaps.append((a0[g], a1[g], live[g], col[g]))
    nv = 2 * n + 1 + n_z
    # S v − z = 0 per distinct set (the λ column empty)
    tie = sp.hstack([sp.vstack(ties), sp.csr_matrix((n_z, 1)), -sp.identity(n_z)],
                    format="csr")
    G_gap, b_gap = _sparse_rows(gaps, 2 * n, nv)
    G_cone, b_cone = _sparse_rows(cones, 2 * n, nv)
    return _Rows(tie, G_gap, b_gap, G_cone, b_cone, 2 * n)


def _sparse_rows(parts, lam_col: int, nv: int):
    """Rows ``b − G y`` with G = −(λ coefficient, weight at one entry of z) from
    (b, λ coefficient, weight, z column) arrays per sample: (G (csr), b)."""
    if not parts:
        return sp.csr_matrix((0, nv)), np.zeros(0)
    b, a1, w, col = (np.concatenate(x) for x in zip(*parts, strict=True))
    rows = np.arange(b.size)
    G = sp.csr_matrix((np.concatenate([-a1, -w]),
                       (np.concatenate([rows, rows]),
                        np.concatenate([np.full(b.size, lam_col), col]))), shape=(b.size, nv))
    G.eliminate_zeros()
    return G, b


def _socp(rows: _Rows, lam_max: float, tol: float):
    """max λ over :class:`_Rows` (Clarabel): (status, y or None)."""
    nv, ns = rows.n_vars, rows.n_slip
    Gb = sp.csr_matrix(([-1.0, 1.0], ([0, 1], [ns, ns])), shape=(2, nv))
    A = sp.vstack([rows.A_tie, Gb, rows.G_gap, rows.G_cone], format="csc")
    b = np.concatenate([np.zeros(rows.A_tie.shape[0]), [0.0, lam_max], rows.b_gap,
                        rows.b_cone])
    cones = [clarabel.ZeroConeT(rows.A_tie.shape[0])] if rows.A_tie.shape[0] else []
    cones += [clarabel.NonnegativeConeT(2 + rows.b_gap.size)]
    cones += [clarabel.SecondOrderConeT(3)] * (rows.b_cone.size // 3)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = tol
    # supernodal factorisation: the ties' dense block factorises as a dense front
    # (1.5x faster than QDLDL at 203 nodes)
    settings.direct_solve_method = "faer"
    settings.max_threads = 1
    c = np.zeros(nv)
    c[ns] = -1.0
    # no quadratic term: with the ties as equality rows, a regularisation of v (least-norm
    # safe state) stalls Clarabel's first iteration where λ is capped far above λ2
    P = sp.csc_matrix((nv, nv))
    sol = clarabel.DefaultSolver(P, c, A, b, cones, settings).solve()
    status = str(sol.status)
    if "Infeasible" in status and "Dual" not in status:
        return status, None
    if "Solved" not in status:
        raise SolverError(f"the shakedown cone program stopped with status {status}")
    return status, np.asarray(sol.x)


def _sets_or_none(system, vals, v, previous):
    """:func:`open_sets`, or None where the elastic contact set does not settle."""
    try:
        return open_sets(system, vals, v, previous)
    except SolverError:
        return None


@single_threaded
def lambda2_open(system: FrictionalSystem3D, load: Load3D, steps_per_cycle: int = 100, *,
                 slip: np.ndarray | None = None, lam_max: float = 1e6, tol: float = 1e-9,
                 max_updates: int = 20) -> SafeRegionOpen3D:
    """λ2 of a system whose nodes open in part of the cycle (or throughout).

    A node is held in its cone only at the samples where it is closed; where it is open
    its force vanishes and its gap must stay non-negative (:mod:`~slipcycle.discrete3d.
    separation`). The open set of each sample is that of the elastic solution: first with
    ``slip`` at λ = 0 (the assembly's state, the periodic part off), then with the program's safe
    state and λ2, until the sets repeat. The sets are fixed within one program, so the
    program stays a second-order cone program; at the fixed point the safe state is a
    genuine one (closed nodes in their cones, open nodes with open gaps), so ``lambda2``
    is a certified lower bound of the largest load factor with a safe state, exact when
    the contact sets do not depend on the slip (B = 0, or no node changes state). With
    no node open it is :func:`lambda2_socp`.

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
    steps_per_cycle : int
        Load samples of the cycle.
    slip : (N, 2) array, optional
        Slip of the first contact sets [m] (default 0).
    lam_max, tol : float
        Cap on λ and Clarabel's tolerances.
    max_updates : int
        Most programs solved; ``consistent`` is False if the sets still changed.

    Returns
    -------
    SafeRegionOpen3D
    """
    n = system.n_nodes
    theta, _ = load.cycle_samples(steps_per_cycle)
    theta = theta[:-1]
    r0, r1 = load.split_lam(theta)
    v = np.zeros(2 * n) if slip is None else np.asarray(slip, float).reshape(2 * n)
    sets = open_sets(system, r0, v)
    _, vs = _scales(system, r0, r1)
    best, status, it = None, "", 0
    while it < max_updates:
        it += 1
        status, y = _socp(_open_rows(system, r0, r1, sets), lam_max, tol)
        if y is None:
            break
        lam, v = float(y[2 * n]), y[:2 * n] * vs
        certified = np.array_equal(_sets_or_none(system, r0 + lam * r1, v, sets), sets)
        if best is None or (certified, lam) > (best[3], best[0]):
            best = (lam, v, sets, bool(certified), status)
        # the sets just beyond λ: a node whose gap or pressure bounds λ changes state
        new = _sets_or_none(system, r0 + lam * (1 + _BEYOND) * r1, v, sets)
        if new is None or np.array_equal(new, sets):
            break
        sets = new
    if best is None:
        return SafeRegionOpen3D(0.0, np.zeros((n, 2)), np.zeros((n, 2)), False, status,
                                sets, theta, False, it)
    lam, v, sets, certified, status = best
    # an open node at θ = 0 sits where the elastic body puts it (zero force): the state
    # the engine starts from
    start = elastic_reactions(system, r0[0] + lam * r1[0], v, sets[0])[1][:2 * n]
    return SafeRegionOpen3D(lam, v.reshape(n, 2), start.reshape(n, 2), True, status, sets,
                            theta, certified, it)


@single_threaded
def lambda2_polygonal(system: FrictionalSystem3D, load: Load3D, open_set: np.ndarray,
                      facets: int, steps_per_cycle: int = 100,
                      lam_max: float = 1e6) -> tuple[float, float]:
    """Bracket of the cone program's λ2 by two linear programs (HiGHS).

    Each cone |q| ≤ f p is replaced by the regular polygon of ``facets`` sides inscribed
    in it (n_i · q ≤ f p cos(π/k)) and by the one circumscribed about it (n_i · q ≤ f p):
    the inner program's λ is a lower bound, the outer one's an upper bound of the cone
    program with the same contact sets, and the bracket closes as 1 − cos(π/k) ~ k⁻².

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
    open_set : (S, N) bool array
        Contact sets of the samples (``SafeRegionOpen3D.open_set``).
    facets : int
        k ≥ 3.
    steps_per_cycle : int
        Must be the one that gave ``open_set``.
    lam_max : float

    Returns
    -------
    (lower, upper) : floats
        λ of the inscribed and circumscribed polygons (0 if infeasible).
    """
    theta, _ = load.cycle_samples(steps_per_cycle)
    r0, r1 = load.split_lam(theta[:-1])
    rows = _open_rows(system, r0, r1, np.asarray(open_set, bool))
    nv, ns = rows.n_vars, rows.n_slip
    G, b = rows.G_cone, rows.b_cone
    Gt, G1, G2 = G[0::3], G[1::3], G[2::3]
    bt, b1, b2 = b[0::3], b[1::3], b[2::3]
    phi = 2 * np.pi * np.arange(facets) / facets
    c = np.zeros(nv)
    c[ns] = -1.0
    bounds = [(None, None)] * ns + [(0.0, lam_max)] + [(None, None)] * (nv - ns - 1)
    out = []
    for scale in (np.cos(np.pi / facets), 1.0):
        # n · (b_u − G_u y) ≤ c (b_t − G_t y)  ⇔  (c G_t − n · G_u) y ≤ c b_t − n · b_u
        A = sp.vstack([scale * Gt - np.cos(a) * G1 - np.sin(a) * G2 for a in phi]
                      + [rows.G_gap], format="csr")
        ub = np.concatenate([scale * bt - np.cos(a) * b1 - np.sin(a) * b2 for a in phi]
                            + [rows.b_gap])
        res = linprog(c, A_ub=A, b_ub=ub, A_eq=rows.A_tie, b_eq=np.zeros(rows.A_tie.shape[0]),
                      bounds=bounds, method="highs")
        if res.status == 2:
            out.append(0.0)
        elif res.status != 0:
            raise SolverError(f"the polygonal shakedown program stopped: {res.message}")
        else:
            out.append(float(res.x[ns]))
    return out[0], out[1]


@single_threaded
def is_safe_open(system: FrictionalSystem3D, load: Load3D, v: np.ndarray,
                 steps_per_cycle: int = 100, rtol: float = 1e-7) -> bool:
    """Whether v ((N, 2) or (2N,)) is safe with separation: at every sample the elastic
    solution with the closed nodes stuck at v (its own contact set, found afresh) has
    every closed node inside its cone, to ``rtol`` × the load scale."""
    n = system.n_nodes
    theta, vals = load.cycle_samples(steps_per_cycle)
    v = np.asarray(v, float).reshape(2 * n)
    scale = max(float(np.max(np.abs(vals))), 1e-300)
    for r in vals:
        is_open = elastic_open_set(system, r, v)
        c = np.flatnonzero(~is_open)
        reac, _ = elastic_reactions(system, r, v, is_open)
        q = reac[:2 * n].reshape(n, 2)[c]
        p = reac[2 * n:][c]
        if np.any(system.friction[c] * p - np.linalg.norm(q, axis=1) < -rtol * scale):
            return False
    return True


def safe_start(system: FrictionalSystem3D, load: Load3D, region: SafeRegionOpen3D,
               steps_per_cycle: int = 100) -> np.ndarray:
    """The safe state of ``region`` at θ = 0 under ``load`` (its own λ): the closed nodes
    at ``region.safe_slip``, the nodes open at θ = 0 (the elastic contact set at this λ)
    at their free elastic position ((N, 2) [m], an admissible ``initial_slip``)."""
    n = system.n_nodes
    r = load.cycle_samples(steps_per_cycle)[1][0]
    v = region.safe_slip.reshape(2 * n)
    is_open = elastic_open_set(system, r, v, region.open_set[0])
    x = elastic_reactions(system, r, v, is_open)[1]
    return x[:2 * n].reshape(n, 2)


def shakedown_limit(shakes_down, lam_hi: float, rtol: float = 1e-2,
                    lam_lo: float = 0.0) -> tuple[float, float]:
    """Bracket [lo, hi] of the largest λ at which a start shakes down, by bisection.

    Parameters
    ----------
    shakes_down : callable
        ``shakes_down(lam) -> bool``: one simulation from the start at load factor λ.
    lam_hi : float
        A load factor at which the start is known not to shake down (above λ2 nothing can)
        or the top of the search; it is simulated if ``shakes_down(lam_hi)`` is unknown.
    rtol : float
        Width of the bracket relative to ``lam_hi``.
    lam_lo : float
        A load factor at which the start shakes down (0: no periodic load).

    Returns
    -------
    (lo, hi) : floats
        ``shakes_down(lo)`` (or lo = ``lam_lo``) and not ``shakes_down(hi)``; hi =
        ``lam_hi`` and lo = ``lam_hi`` if the start shakes down at ``lam_hi`` as well.
    """
    if shakes_down(lam_hi):
        return float(lam_hi), float(lam_hi)
    lo, hi = float(lam_lo), float(lam_hi)
    while hi - lo > rtol * lam_hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if shakes_down(mid) else (lo, mid)
    return lo, hi


@dataclass(frozen=True)
class Lambda1Bracket:
    """λ1 bracketed over a set of starts (:func:`lambda1_bracket`).

    Attributes
    ----------
    lower, upper : float
        Every start shook down at ``lower``; one start (``weakest``) did not at ``upper``.
    limits : (S, 2) array
        Per start, the bracket of the largest λ at which it shakes down.
    weakest : int
        The start with the smallest upper limit.
    """

    lower: float
    upper: float
    limits: np.ndarray
    weakest: int


def lambda1_bracket(system: FrictionalSystem3D, load: Load3D, lam2: float, *,
                    starts=(), protocols=(), rtol: float = 1e-2,
                    **run) -> Lambda1Bracket:
    """λ1 (below it every start shakes down) bracketed over the given starts.

    Each start (an initial slip or an assembly protocol) is simulated with
    :func:`~slipcycle.discrete3d.steady.simulate3d` and its largest shakedown load factor
    bracketed by :func:`shakedown_limit` in [0, ``lam2``] (above λ2 no start can shake
    down: a steady state without slip is a safe state). The upper end is proved by a run
    that does not shake down; the lower end holds for the starts tried (λ1 over all
    starts can only be lower). For an uncoupled system (B = 0) the frictional Melan
    theorem gives λ1 = λ2 (Klarbring, Ciavarella & Barber 2007).

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
    lam2 : float
        λ2 of :func:`lambda2_open` (the top of every search).
    starts : sequence of (N, 2) arrays
        Initial slips at θ = 0 [m], admissible at every λ tried (a node open at θ = 0
        must sit at its free position, which moves with λ unless the periodic part
        vanishes at θ = 0; use ``protocols`` otherwise).
    protocols : sequence of (S, 3N) arrays
        Assembly load states.
    rtol : float
        Width of each bracket relative to ``lam2``.
    **run
        Settings of ``simulate3d``.

    Returns
    -------
    Lambda1Bracket
    """
    def judge(kw):
        def shakes_down(lam):
            res = simulate3d(system, load.with_lam(lam), record=False, **kw, **run)
            return res.steady_state == "shakedown"
        return shakes_down

    kws = [{"initial_slip": s} for s in starts] + [{"protocol": p} for p in protocols]
    if not kws:
        kws = [{}]
    limits = np.array([shakedown_limit(judge(kw), lam2, rtol) for kw in kws])
    weakest = int(np.argmin(limits[:, 1]))
    return Lambda1Bracket(float(np.min(limits[:, 0])), float(limits[weakest, 1]), limits,
                          weakest)
