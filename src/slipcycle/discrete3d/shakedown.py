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
sample spacing (tested). :func:`lambda2_polygonal` brackets the cone program by two
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
    status, y = _socp(*_open_rows(system, r0, r1, closed), lam_max, tol)
    if y is None:
        return SafeRegion3D(0.0, np.zeros((n, 2)), False, status, theta.size)
    v = y[:-1] * _scales(system, r0, r1)[1]
    return SafeRegion3D(float(y[-1]), v.reshape(n, 2), True, status, theta.size)


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


def _open_rows(system: FrictionalSystem3D, r0: np.ndarray, r1: np.ndarray,
               sets: np.ndarray):
    """Program rows with the contact sets ``sets`` (S, N), in scaled variables
    y = [v / slip_scale (2N), λ]: gap rows ``b_gap − G_gap y ≥ 0`` and cone rows
    ``b_cone − G_cone y ∈ 𝒦³`` ((m, 3) and (m, 3, 2N + 1): (f p, q1, q2) per closed node
    and sample), all divided by the force scale."""
    n = system.n_nodes
    fs, vs = _scales(system, r0, r1)
    kd = max(float(np.max(np.diag(system.K))), 1e-300)
    cache: dict = {}
    gaps, cones = [], []
    for k, is_open in enumerate(sets):
        key = is_open.tobytes()
        if key not in cache:
            cache[key] = closed_rows(system, is_open)
        c, R_load, R_slip, W_load, W_slip = cache[key]
        m = c.size
        # the gaps as forces (× max diag K), so that every row has the force scale
        a0 = kd * W_load @ r0[k] / fs
        gaps.append(np.column_stack([a0, kd * vs * W_slip / fs, kd * W_load @ r1[k] / fs]))
        f = system.friction[c]
        rows = np.column_stack([R_load @ r0[k] / fs, R_slip * vs / fs, R_load @ r1[k] / fs])
        q, p = rows[:2 * m].reshape(m, 2, -1), rows[2 * m:]
        cones.append(np.concatenate([(f[:, None] * p)[:, None], q], axis=1))
    gap = np.concatenate(gaps) if gaps else np.zeros((0, 2 * n + 2))
    cone = np.concatenate(cones)
    return -gap[:, 1:], gap[:, 0], -cone[:, :, 1:], cone[:, :, 0]


def _socp(G_gap, b_gap, G_cone, b_cone, lam_max: float, tol: float):
    """max λ over the rows of :func:`_open_rows` (Clarabel): (status, y or None)."""
    nv = G_cone.shape[2]
    Gb = np.zeros((2, nv))
    Gb[0, -1], Gb[1, -1] = -1.0, 1.0
    A = sp.csc_matrix(np.vstack([Gb, G_gap, G_cone.reshape(-1, nv)]))
    b = np.concatenate([[0.0, lam_max], b_gap, b_cone.reshape(-1)])
    cones = [clarabel.NonnegativeConeT(2 + b_gap.size)]
    cones += [clarabel.SecondOrderConeT(3)] * b_cone.shape[0]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = tol
    c = np.zeros(nv)
    c[-1] = -1.0
    # a tiny regularisation of v picks the safe state of least norm at λ2
    P = sp.csc_matrix(sp.diags(np.concatenate([np.full(nv - 1, 1e-9), [0.0]])))
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
        status, y = _socp(*_open_rows(system, r0, r1, sets), lam_max, tol)
        if y is None:
            break
        lam, v = float(y[-1]), y[:-1] * vs
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
    G_gap, b_gap, G_cone, b_cone = _open_rows(system, r0, r1, np.asarray(open_set, bool))
    nv = G_cone.shape[2]
    phi = 2 * np.pi * np.arange(facets) / facets
    nrm = np.column_stack([np.cos(phi), np.sin(phi)])                  # (k, 2)
    # n · (b_u − G_u y) ≤ c (b_t − G_t y)  ⇔  (c G_t − n · G_u) y ≤ c b_t − n · b_u
    nG = np.einsum("ia,mav->miv", nrm, G_cone[:, 1:])
    nb = b_cone[:, 1:] @ nrm.T                                         # (m, k)
    c = np.zeros(nv)
    c[-1] = -1.0
    out = []
    for scale in (np.cos(np.pi / facets), 1.0):
        A = (scale * G_cone[:, None, 0] - nG).reshape(-1, nv)
        b = (scale * b_cone[:, None, 0] - nb).reshape(-1)
        res = linprog(c, A_ub=np.vstack([A, G_gap]), b_ub=np.concatenate([b, b_gap]),
                      bounds=[(None, None)] * (nv - 1) + [(0.0, lam_max)], method="highs")
        if res.status == 2:
            out.append(0.0)
        elif res.status != 0:
            raise SolverError(f"the polygonal shakedown program stopped: {res.message}")
        else:
            out.append(float(res.x[-1]))
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
