"""Safe shakedown region and critical load factors λ1…λ4 (Klarbring, Ciavarella & Barber
2007; Ahn, Bertocchi & Barber 2008).

With every node in contact (w = 0) the Coulomb inequalities |q_j| ≤ f_j p_j are 2N
half-spaces in slip space. Constraint k = (j, s), s = ±1, reads

    s q_j + f_j p_j ≥ 0   ⇔   −(s A_j + f_j B_j) · v ≤ s q^w_j(θ) + f_j p^w_j(θ)

(s = +1: q_j ≥ −f p_j, the constraint that drives positive slip, Barber's II/IV;
s = −1: q_j ≤ +f p_j, Barber's I/III). The loads are p^w = p0 + λ p̃(θ),
q^w = q0 + λ q̃(θ) (plus load cases with time functions mean + λ g̃(θ)), so the right-hand
side is c0_k + λ c1_k(θ) with zero-mean c1_k. A slip state v is safe for the whole cycle
iff it satisfies every constraint at its *extreme position*

    G v ≤ h(λ) = h0 + λ m,     G_k = −(s A_j + f_j B_j),  h0_k = c0_k,  m_k = min_θ c1_k(θ)

(λ ≥ 0). This polyhedron S(λ) is the safe shakedown region. Definitions:

- λ2 = sup{λ : S(λ) ≠ ∅} — one linear program in (v, λ);
- λ1 = sup{λ : all 2N constraints are non-redundant in S(μ) for every μ ≤ λ}; a
  constraint is redundant if the LP max G_k v over the other constraints does not exceed
  h_k (Ahn, Bertocchi & Barber 2008: a quadrilateral safe region for N = 2 guarantees
  shakedown, a triangle does not). It is bracketed by a scan and bisection;
- λ3 = smallest λ at which every node slips in every steady cycle, λ4 = smallest λ at
  which all nodes slip or separate at one instant; both are bracketed by simulation over
  λ and a set of initial conditions (:func:`simulation_brackets`), then the brackets are
  narrowed by bisection in λ (:func:`refine_brackets`, assumes the criterion monotone
  above the bracket).

Extreme positions m_k are exact for one harmonic (m = −|c_h|), found by dense sampling
and bounded Brent refinement for several harmonics, exact at the breakpoints for
piecewise-linear (tabulated) loads, and by dense sampling with refinement otherwise.

References
----------
A. Klarbring, M. Ciavarella, J. R. Barber, "Shakedown in elastic contact problems with
Coulomb friction", Int. J. Solids Struct. 44 (2007) 8355–8365.
Y. J. Ahn, E. Bertocchi, J. R. Barber, "Shakedown of coupled two-dimensional discrete
frictional systems", J. Mech. Phys. Solids 56 (2008) 3433–3440.
L.-E. Andersson, J. R. Barber, Y. J. Ahn, "Attractors in frictional systems subjected to
periodic loads", SIAM J. Appl. Math. 73 (2013) 1097–1116.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linprog, minimize_scalar

from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import FrictionalSystem
from slipcycle.loading import HarmonicLoad

__all__ = ["FrictionConstraints", "friction_constraints", "SafeRegion", "safe_region",
           "lambda2", "lambda1", "redundant_constraints",
           "polygon_vertices", "admissible_region_at", "sample_initial_slips",
           "simulation_brackets", "Brackets", "constraint_names", "run_criteria",
           "refine_brackets", "Refinement", "extreme_constraints", "safe_vertices"]

TWO_PI = 2.0 * np.pi


def constraint_names(n: int) -> list[str]:
    """Labels of the 2N constraints in the order of :class:`SafeRegion` rows.

    Row 2j is (node j, s = +1): q_j ≥ −f p_j (positive slip); row 2j+1 is (node j, s = −1):
    q_j ≤ f p_j (negative slip). For N = 2 these are Barber's II, I, IV, III. Nodes are
    numbered from 0, as in every summary, Dataset and figure.
    """
    if n == 2:
        return ["II (node 0, q=−fp)", "I (node 0, q=+fp)", "IV (node 1, q=−fp)",
                "III (node 1, q=+fp)"]
    return [f"node {j} {'q=−fp' if s > 0 else 'q=+fp'}" for j in range(n) for s in (1, -1)]


@dataclass(frozen=True)
class FrictionConstraints:
    """The 2N all-contact Coulomb constraints of a discrete system, in slip space.

    Constraint k = (j, s), s = ±1, with every node in contact (w = 0), so that
    q = q^w + A v and p = p^w + B v:

        s q_j + f_j p_j ≥ 0   ⇔   D_k · v + c_k ≥ 0,
        D_k = s A_j + f_j B_j,   c_k = s q^w_j + f_j p^w_j.

    Row 2j is s = +1 (q_j ≥ −f_j p_j, drives positive slip), row 2j+1 is s = −1
    (q_j ≤ f_j p_j); the order of :func:`constraint_names`. The safe-region LP uses the
    "≤" form G v ≤ c with G = −D (:func:`safe_region`, :func:`admissible_region_at`); the
    sampled reference :func:`extreme_constraints` the "≥" form D v ≥ −c.

    Attributes
    ----------
    rows : (2N, N) array
        D_k = s A_j + f_j B_j [N/m].
    node : (2N,) int array
        j of each row.
    sign : (2N,) array
        s of each row, ±1.
    friction : (2N,) array
        f_j of each row.

    References
    ----------
    A. Klarbring, M. Ciavarella, J. R. Barber, Int. J. Solids Struct. 44 (2007)
    8355–8365, eq. (9); Y. J. Ahn, E. Bertocchi, J. R. Barber, J. Mech. Phys. Solids 56
    (2008) 3433–3440, §2.
    """

    rows: np.ndarray
    node: np.ndarray
    sign: np.ndarray
    friction: np.ndarray

    @property
    def n_nodes(self) -> int:
        return self.rows.shape[1]

    def rhs(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:
        """c = s q_j + f_j p_j for tangential and normal loads q, p (..., N) [N] → (..., 2N)."""
        q, p = np.asarray(q, float), np.asarray(p, float)
        return self.sign * q[..., self.node] + self.friction * p[..., self.node]

    def load_matrix(self) -> np.ndarray:
        """S (2N, 2N) with c = S [q; p] for stacked loads r = [q, p] [dimensionless]."""
        n = self.n_nodes
        S = np.zeros((2 * n, 2 * n))
        k = np.arange(2 * n)
        S[k, self.node] = self.sign
        S[k, n + self.node] = self.friction
        return S


def friction_constraints(system: FrictionalSystem) -> FrictionConstraints:
    """The 2N all-contact friction constraints of ``system`` (:class:`FrictionConstraints`).

    The one place that builds their geometry; :func:`safe_region`,
    :func:`admissible_region_at` (hence the basin maps and the random initial states) and
    :func:`extreme_constraints` all use it.

    Parameters
    ----------
    system : FrictionalSystem
        A, B (N, N) [N/m] and the friction coefficients f (N,).

    Returns
    -------
    FrictionConstraints
        Rows s A_j + f_j B_j [N/m] in the order (j, s = +1), (j, s = −1), j = 0…N−1.
    """
    n = system.n_nodes
    f = np.asarray(system.friction, dtype=float)
    node = np.repeat(np.arange(n), 2)
    sign = np.tile([1.0, -1.0], n)
    rows = np.zeros((2 * n, n))
    for k in range(2 * n):
        j = node[k]
        rows[k] = sign[k] * system.A[j] + f[j] * system.B[j]
    return FrictionConstraints(rows, node, sign, f[node])


@dataclass(frozen=True)
class SafeRegion:
    """S(λ) = {v : G v ≤ h0 + λ m} (all nodes in contact).

    Attributes
    ----------
    G : (2N, N) array
        Constraint normals −(s A_j + f_j B_j) [N/m]; row 2j is s = +1, row 2j+1 is s = −1.
    h0 : (2N,) array
        s q0_j + f_j p0_j: right-hand sides of the mean load [N].
    m : (2N,) array
        min over θ of the zero-mean periodic part per unit λ, ≤ 0 [N].
    theta_extreme : (2N,) array
        Cycle angle [rad] at which each constraint reaches its extreme position.
    method : str
        How ``m`` was found: ``exact_single_harmonic``, ``harmonic_refined``,
        ``breakpoints`` or ``sampled_refined``.
    """

    G: np.ndarray
    h0: np.ndarray
    m: np.ndarray
    theta_extreme: np.ndarray
    method: str

    @property
    def n_nodes(self) -> int:
        return self.G.shape[1]

    def h(self, lam: float) -> np.ndarray:
        """Extreme right-hand sides h(λ) = h0 + λ m (2N,) [N]."""
        return self.h0 + lam * self.m

    def contains(self, v: np.ndarray, lam: float, tol: float = 0.0) -> np.ndarray:
        """Whether slip states v (..., N) [m] lie in S(λ) (with slack ``tol`` [N])."""
        return np.all(np.asarray(v) @ self.G.T <= self.h(lam) + tol, axis=-1)

    @property
    def names(self) -> list[str]:
        """Labels of the 2N rows (:func:`constraint_names`)."""
        return constraint_names(self.n_nodes)

    def vertices(self, lam: float) -> np.ndarray:
        """N = 2: vertices of S(λ), (k, 2) [m] (:func:`polygon_vertices`)."""
        return polygon_vertices(self, lam)

    @property
    def scale(self) -> float:
        """Force scale of the right-hand sides [N]."""
        return float(max(np.max(np.abs(self.h0)), np.max(np.abs(self.m)), 1e-300))


# ---------------------------------------------------------------------------------------
# extreme positions
# ---------------------------------------------------------------------------------------
def _periodic_part(system: FrictionalSystem, load: DiscreteLoad):
    """c0 (2N,) and a function θ (n,) → c1(θ) (n, 2N) of the constraint right-hand sides."""
    S = friction_constraints(system).load_matrix()   # rows k, columns [q, p]
    mean_load = load.with_lam(0.0)
    unit_load = load.with_lam(1.0)
    c0 = S @ mean_load(np.array([0.0]))[0]

    def c1(theta):
        theta = np.atleast_1d(np.asarray(theta, float))
        return (unit_load(theta) - mean_load(theta)) @ S.T

    return c0, c1


def _harmonic_order(load: DiscreteLoad) -> int | None:
    """Highest harmonic if every part is harmonic, else None."""
    funcs = [load.p, load.q] + [c.time for c in load.cases]
    if not all(isinstance(fn, HarmonicLoad) for fn in funcs):
        return None
    H = 0
    for fn in funcs:
        nz = np.flatnonzero(np.any(fn.amplitudes != 0, axis=1))
        if nz.size:
            H = max(H, int(nz[-1]) + 1)
    return H


def _refine_minima(c1, k: int, grid: np.ndarray, vals: np.ndarray) -> tuple[float, float]:
    """Bounded Brent refinement of the smallest sampled minima of c1[:, k] (periodic)."""
    n = grid.size - 1                      # grid[-1] = 2π repeats grid[0]
    y = vals[:n]
    cand = np.flatnonzero((y <= np.roll(y, 1)) & (y <= np.roll(y, -1)))
    cand = cand[np.argsort(y[cand])][:8]
    best_t, best = float(grid[int(np.argmin(y))]), float(np.min(y))
    d = grid[1] - grid[0]
    for i in cand:
        res = minimize_scalar(lambda t: float(c1(np.array([t]))[0, k]),
                              bounds=(grid[i] - d, grid[i] + d), method="bounded",
                              options={"xatol": 1e-13})
        if res.fun < best:
            best, best_t = float(res.fun), float(np.mod(res.x, TWO_PI))
    return best, best_t


def safe_region(system: FrictionalSystem, load: DiscreteLoad, samples: int = 4096
                ) -> SafeRegion:
    """Extreme constraint positions and the polyhedron S(λ) = {v : G v ≤ h0 + λ m}.

    Parameters
    ----------
    system : FrictionalSystem
    load : DiscreteLoad
        Its λ is irrelevant: S(λ) is returned for every λ.
    samples : int
        Sampling density for several harmonics or mixed loads (refined by Brent's method).

    Returns
    -------
    SafeRegion
    """
    n = system.n_nodes
    G = -friction_constraints(system).rows
    c0, c1 = _periodic_part(system, load)
    H = _harmonic_order(load)
    m = np.zeros(2 * n)
    th_ext = np.zeros(2 * n)
    if H == 0:
        method = "constant"
    elif H == 1 or (H is not None and _single_harmonic(load, H)):
        # c1(θ) = a cos hθ + b sin hθ exactly; min = −sqrt(a² + b²)
        h = H if H == 1 else _single_harmonic(load, H)
        a = c1(np.array([0.0]))[0]
        b = c1(np.array([np.pi / (2 * h)]))[0]
        m = -np.hypot(a, b)
        th_ext = np.mod((np.arctan2(b, a) + np.pi) / h, TWO_PI / h)
        method = "exact_single_harmonic"
    elif load.piecewise_linear():
        bp = load.breakpoints()
        vals = c1(bp)
        idx = np.argmin(vals, axis=0)
        m = vals[idx, np.arange(2 * n)]
        th_ext = bp[idx]
        method = "breakpoints"
    else:
        npts = max(samples, 64 * (H or 1))
        grid = np.linspace(0.0, TWO_PI, npts + 1)
        vals = c1(grid)
        for k in range(2 * n):
            m[k], th_ext[k] = _refine_minima(c1, k, grid, vals[:, k])
        method = "harmonic_refined" if H is not None else "sampled_refined"
    m = np.minimum(m, 0.0)
    return SafeRegion(G, c0, m, th_ext, method)


def _single_harmonic(load: DiscreteLoad, H: int) -> int:
    """The harmonic order if exactly one harmonic is non-zero anywhere, else 0."""
    funcs = [load.p, load.q] + [c.time for c in load.cases]
    used = set()
    for fn in funcs:
        used |= {int(i) + 1 for i in np.flatnonzero(np.any(fn.amplitudes != 0, axis=1))}
    return next(iter(used)) if len(used) == 1 else 0


# ---------------------------------------------------------------------------------------
# λ2 and λ1 by linear programs
# ---------------------------------------------------------------------------------------
def lambda2(region: SafeRegion, lam_max: float = 1e12) -> tuple[float, np.ndarray | None]:
    """λ2 = max λ with S(λ) ≠ ∅, by one LP in (v, λ) (HiGHS).

    Returns
    -------
    lam2 : float
        ``inf`` if S(λ) is non-empty for every λ (up to ``lam_max``); ``-inf`` if even the
        mean load admits no safe state (S(0) = ∅).
    v : (N,) array or None
        A slip state [m] in S(λ2) (the last safe state).
    """
    G, h0, m = region.G, region.h0, region.m
    n = G.shape[1]
    A_ub = np.hstack([G, -m[:, None]])
    c = np.zeros(n + 1)
    c[-1] = -1.0
    bounds = [(None, None)] * n + [(0.0, lam_max)]
    res = linprog(c, A_ub=A_ub, b_ub=h0, bounds=bounds, method="highs")
    if res.status == 2:
        return -np.inf, None
    if res.status != 0:
        raise RuntimeError(f"λ2 linear program failed: {res.message}")
    lam = float(res.x[-1])
    if lam >= lam_max * (1 - 1e-9):
        return np.inf, res.x[:n]
    return lam, res.x[:n]


def redundant_constraints(region: SafeRegion, lam: float, rtol: float = 1e-9
                          ) -> np.ndarray | None:
    """Which of the 2N extreme constraints are redundant in S(λ) (2N bool), or None if
    S(λ) is empty.

    Constraint k is redundant when max G_k v over the other 2N − 1 constraints is at most
    h_k(λ) + tol (it neither cuts nor defines a facet of S(λ)); tol = rtol × force scale.
    """
    G, h = region.G, region.h(lam)
    n2, n = G.shape
    tol = rtol * region.scale
    feas = linprog(np.zeros(n), A_ub=G, b_ub=h, bounds=[(None, None)] * n, method="highs")
    if feas.status == 2:
        return None
    out = np.zeros(n2, bool)
    for k in range(n2):
        keep = np.arange(n2) != k
        res = linprog(-G[k], A_ub=G[keep], b_ub=h[keep], bounds=[(None, None)] * n,
                      method="highs")
        if res.status == 3:            # unbounded: the constraint cuts
            continue
        if res.status != 0:
            raise RuntimeError(f"redundancy LP failed for constraint {k}: {res.message}")
        out[k] = -res.fun <= h[k] + tol
    return out


def lambda1(region: SafeRegion, lam2: float | None = None, *, scan: int = 64,
            tol: float = 1e-9, rtol: float = 1e-9) -> dict:
    """λ1 = sup{λ : every constraint non-redundant in S(μ) for all 0 ≤ μ ≤ λ}.

    A scan of ``scan`` values on [0, λ2] finds the first λ with a redundant constraint;
    bisection then brackets the transition to ``tol`` (relative to λ2).

    Returns
    -------
    dict
        ``lambda1`` (float; lower end of the final bracket), ``bracket`` (lo, hi),
        ``redundant_above`` (indices of the constraints redundant at ``hi``),
        ``lps`` (number of LPs solved).
    """
    if lam2 is None:
        lam2 = lambda2(region)[0]
    n2 = region.G.shape[0]
    lps = 0

    def bad(lam):
        nonlocal lps
        lps += n2 + 1
        red = redundant_constraints(region, lam, rtol)
        return red is None or bool(red.any()), red

    if not np.isfinite(lam2) or lam2 <= 0:
        if lam2 == -np.inf:
            return {"lambda1": -np.inf, "bracket": (-np.inf, -np.inf), "redundant_above": [],
                    "lps": 0}
        top = 1e6 if lam2 == np.inf else 0.0
    else:
        top = lam2
    b0, red0 = bad(0.0)
    if b0:
        return {"lambda1": 0.0, "bracket": (0.0, 0.0),
                "redundant_above": [] if red0 is None else np.flatnonzero(red0).tolist(),
                "lps": lps}
    lo, hi, red_hi = 0.0, None, None
    for lam in np.linspace(0.0, top, scan + 1)[1:]:
        b, red = bad(lam)
        if b:
            hi, red_hi = float(lam), red
            break
        lo = float(lam)
    if hi is None:
        return {"lambda1": top, "bracket": (top, top), "redundant_above": [], "lps": lps}
    scale = max(abs(top), 1.0)
    while hi - lo > tol * scale:
        mid = 0.5 * (lo + hi)
        b, red = bad(mid)
        if b:
            hi, red_hi = mid, red
        else:
            lo = mid
    red_idx = [] if red_hi is None else np.flatnonzero(red_hi).tolist()
    return {"lambda1": lo, "bracket": (lo, hi), "redundant_above": red_idx, "lps": lps}


def polygon_vertices(region: SafeRegion, lam: float, rtol: float = 1e-9) -> np.ndarray:
    """N = 2: vertices of S(λ) in counter-clockwise order, (k, 2) [m] (empty if S(λ) = ∅)."""
    G, h = region.G, region.h(lam)
    if G.shape[1] != 2:
        raise ValueError("polygon_vertices needs N = 2")
    tol = rtol * region.scale
    pts = []
    for a in range(len(h)):
        for b in range(a + 1, len(h)):
            M = G[[a, b]]
            if abs(np.linalg.det(M)) <= 1e-12 * np.abs(M).max() ** 2:
                continue
            p = np.linalg.solve(M, h[[a, b]])
            if np.all(G @ p <= h + tol):
                pts.append(p)
    if not pts:
        return np.zeros((0, 2))
    pts = np.array(pts)
    c = pts.mean(axis=0)
    order = np.argsort(np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0]))
    pts = pts[order]
    keep = [0]
    span = max(np.ptp(pts), 1e-300)
    for i in range(1, len(pts)):
        if np.linalg.norm(pts[i] - pts[keep[-1]]) > 1e-9 * span:
            keep.append(i)
    return pts[keep]


def extreme_constraints(system: FrictionalSystem, load: DiscreteLoad, steps: int = 720
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Extreme positions of the 2N all-contact friction constraints in v-space, sampled.

    A brute-force reference for :func:`safe_region` (same rows from
    :func:`friction_constraints`, in the "≥" form: G here is −G there) and the geometry of
    the single-run v-space figure.

    Constraint (j, s), s = ±1: s q_j + f_j p_j ≥ 0 with w = 0, i.e.
    (s A_j + f_j B_j) · v ≥ −(s q^w_j(θ) + f_j p^w_j(θ)). Its extreme position is the largest
    right-hand side over the cycle.

    Returns
    -------
    G : (2N, N) array
        Rows s A_j + f_j B_j [N/m].
    h : (2N,) array
        max over θ of the right-hand side [N]; the safe region is {v : G v ≥ h}.

    Notes
    -----
    ``steps`` + 1 samples of θ over [0, 2π]; the maxima are those of the samples (exact
    for loads whose extreme lies on a sample, below the true one by O(steps⁻²) otherwise).
    """
    n = system.n_nodes
    th = np.linspace(0, 2 * np.pi, steps + 1)
    r = load(th)
    fc = friction_constraints(system)
    return fc.rows, np.max(-fc.rhs(r[:, :n], r[:, n:]), axis=0)



def safe_vertices(G: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Vertices of the N = 2 safe region {v : G v ≥ h}.

    Parameters
    ----------
    G : (m, 2) array [N/m], h : (m,) array [N]
        Constraints, e.g. from :func:`extreme_constraints`.

    Returns
    -------
    (k, 2) array
        Vertices [m] in counter-clockwise order (empty when the region is empty or
        unbounded in the pairwise intersections).
    """
    verts = []
    m = G.shape[0]
    tol = 1e-9 * max(float(np.abs(h).max()), np.finfo(float).tiny)
    for a in range(m):
        for b in range(a + 1, m):
            M = G[[a, b]]
            if abs(np.linalg.det(M)) > 1e-12 * np.abs(M).max() ** 2:
                p = np.linalg.solve(M, h[[a, b]])
                if np.all(G @ p >= h - tol):
                    verts.append(p)
    if not verts:
        return np.zeros((0, 2))
    P = np.array(verts)
    c = P.mean(axis=0)
    return P[np.argsort(np.arctan2(P[:, 1] - c[1], P[:, 0] - c[0]))]



# ---------------------------------------------------------------------------------------
# initial conditions
# ---------------------------------------------------------------------------------------
def admissible_region_at(system: FrictionalSystem, load: DiscreteLoad, theta: float = 0.0
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Slip states admissible with all nodes in contact at one instant: {v : G v ≤ b}.

    Returns G (2N, N) [N/m] and b (2N,) [N] at angle ``theta`` for the load's own λ.
    """
    n = system.n_nodes
    r = load(np.array([theta]))[0]
    fc = friction_constraints(system)
    return -fc.rows, fc.rhs(r[:n], r[n:])


def sample_initial_slips(system: FrictionalSystem, load: DiscreteLoad, count: int,
                         seed: int = 0, shrink: float = 0.98) -> np.ndarray:
    """``count`` random slip states (count, N) [m] admissible at θ = 0 with all nodes in
    contact: random convex combinations of LP vertices of {v : G v ≤ b} (any N), shrunk
    towards their mean by ``shrink`` so that no state lies on a friction limit.

    Returns an empty (0, N) array if no admissible state exists.
    """
    n = system.n_nodes
    G, b = admissible_region_at(system, load, 0.0)
    rng = np.random.default_rng(seed)
    verts = []
    n_dirs = min(4 * n, 2 * n + 8, 24)
    box = 10.0 * (np.max(np.abs(b)) + 1.0) / max(np.min(np.abs(np.diag(system.A))), 1e-300)
    for d in range(n_dirs):
        c = (rng.standard_normal(n) if d >= min(2 * n, 16)
             else np.eye(n)[d // 2] * (1 if d % 2 else -1))
        res = linprog(c, A_ub=G, b_ub=b, bounds=[(-box, box)] * n, method="highs")
        if res.status == 0:
            verts.append(res.x)
    if not verts:
        return np.zeros((0, n))
    V = np.array(verts)
    W = rng.dirichlet(np.full(len(V), 0.3), size=count)
    pts = W @ V
    centre = V.mean(axis=0)
    return centre + shrink * (pts - centre)


# ---------------------------------------------------------------------------------------
# λ3, λ4 by simulation
# ---------------------------------------------------------------------------------------
@dataclass
class Brackets:
    """λ3 and λ4 brackets with the runs that support them.

    Attributes
    ----------
    lam : (L,) array
        Load factors simulated.
    runs : list of dict
        One per (λ, initial condition): ``lam``, ``start`` (label), ``steady_state``,
        ``dissipation_per_cycle`` [J], ``slipping_nodes``, ``memory_erased``, ``cycles_run``.
    lambda3_bracket, lambda4_bracket : (lo, hi)
        hi: smallest simulated λ from which on every run meets the criterion (None if none
        does); lo: the largest simulated λ below hi where some run fails it (0 if none).
    """

    lam: np.ndarray
    runs: list = field(default_factory=list)
    lambda3_bracket: tuple = (None, None)
    lambda4_bracket: tuple = (None, None)


def _bracket(lams: np.ndarray, ok: np.ndarray) -> tuple:
    """(largest λ failing below the final all-ok stretch, first λ of that stretch)."""
    if not ok[-1]:
        return (float(lams[-1]), None)
    i = len(ok) - 1
    while i > 0 and ok[i - 1]:
        i -= 1
    return (float(lams[i - 1]) if i > 0 else 0.0, float(lams[i]))


def run_criteria(rec: dict, n_nodes: int) -> dict:
    """The λ3 and λ4 criteria for one run record (``steady_state`` as a string).

    Returns ``{"lambda3": every node slips in a converged steady cycle, "lambda4": memory
    erased (all nodes slip or separate at one instant of the steady cycle)}``.
    """
    conv = rec["steady_state"] in ("cyclic_slip", "shakedown", "ratcheting")
    return {"lambda3": bool(conv and rec["n_slipping"] == n_nodes),
            "lambda4": bool(rec["memory_erased"])}


def simulation_brackets(results: list[tuple[float, str, dict]], n_nodes: int) -> Brackets:
    """Brackets of λ3, λ4 from steady-state runs.

    Parameters
    ----------
    results : list of (lam, start label, record)
        ``record`` has the keys of :func:`slipcycle.discrete.basins.run_record`
        (``steady_state``, ``dissipation_per_cycle``, ``n_slipping``, ``memory_erased``…).
    n_nodes : int
    """
    lams = np.unique([r[0] for r in results])
    every_slip = np.ones(len(lams), bool)
    erased = np.ones(len(lams), bool)
    runs = []
    for lam, label, rec in results:
        i = int(np.searchsorted(lams, lam))
        ok = run_criteria(rec, n_nodes)
        every_slip[i] &= ok["lambda3"]
        erased[i] &= ok["lambda4"]
        runs.append({"lam": float(lam), "start": label, **rec})
    b = Brackets(lams, runs)
    b.lambda3_bracket = _bracket(lams, every_slip)
    b.lambda4_bracket = _bracket(lams, erased)
    return b


@dataclass
class Refinement:
    """λ3/λ4 brackets refined by bisection (:func:`refine_brackets`).

    Attributes
    ----------
    brackets : dict
        ``"lambda3"``/``"lambda4"`` → (lo, hi): refined brackets (the grid bracket where it
        could not be refined: hi is None, lo = hi, or lo was not simulated).
    grid_brackets : dict
        The brackets of the grid scan.
    evidence : dict
        ``"lambda3"``/``"lambda4"`` → the runs at the final lo and hi (dicts as in
        :attr:`Brackets.runs`).
    trials : dict
        Trial λ → its runs (list of dicts as in :attr:`Brackets.runs`), every λ simulated
        for the bisection, in the order computed.
    steps : dict
        ``"lambda3"``/``"lambda4"`` → list of (trial λ, criterion met) in bisection order.
    """

    brackets: dict
    grid_brackets: dict
    evidence: dict
    trials: dict
    steps: dict

    @property
    def runs(self) -> int:
        """Number of runs at trial λ values."""
        return sum(len(v) for v in self.trials.values())


def refine_brackets(brackets: Brackets, evaluate, tol: float, n_nodes: int,
                    max_steps: int = 200) -> Refinement:
    """Bisect the λ3 and λ4 brackets of a grid scan until hi − lo ≤ ``tol``.

    At each step the midpoint of every bracket still wider than ``tol`` is simulated from
    the whole set of starts (``evaluate``); if every admissible run there meets the
    criterion (:func:`run_criteria`) it becomes the new hi, else the new lo. The λ3 and λ4
    bisections advance together, so a step costs at most two trial λ values, and share
    trial λ values (when their brackets coincide, one simulation serves both).

    The result keeps the definitions: hi is a simulated λ at which every run meets the
    criterion and lo one at which some run fails it, so the transition lies in (lo, hi].
    **Bisection assumes the criterion is monotone in λ above lo**, i.e. that it holds
    for every λ in [hi, grid hi] once it holds at hi; the grid scan checks this only at
    the grid λ values. If the criterion switched back and forth inside the grid bracket,
    the refined bracket would still contain *a* transition (fail at lo, pass at hi), but
    not necessarily the last one, so λ3/λ4 = "smallest λ from which on every run meets
    the criterion" could lie higher.

    Parameters
    ----------
    brackets : Brackets
        The grid scan (:func:`simulation_brackets`).
    evaluate : callable
        ``evaluate(lams) -> {lam: [(start label, record), ...]}`` for a list of λ values:
        the runs from every start (same starts and seeding rule as the grid scan; records
        as for :func:`simulation_brackets`; inadmissible starts may be left out or carry
        ``steady_state == "inadmissible"`` and are skipped).
    tol : float
        Absolute width at which a bracket is final (> 0).
    n_nodes : int
    max_steps : int
        Safety limit on bisection steps.

    Returns
    -------
    Refinement
    """
    if not tol > 0:
        raise ValueError(f"tol must be > 0, got {tol}")
    runs_at: dict[float, list] = {}
    for r in brackets.runs:
        runs_at.setdefault(float(r["lam"]), []).append(r)
    trials: dict[float, list] = {}
    grid = {"lambda3": tuple(brackets.lambda3_bracket),
            "lambda4": tuple(brackets.lambda4_bracket)}
    state = {}
    for name, (lo, hi) in grid.items():
        if hi is not None and lo is not None and lo < hi and lo in runs_at:
            state[name] = [float(lo), float(hi)]
    steps: dict[str, list] = {name: [] for name in grid}

    def passes(name, lam):
        return all(run_criteria(r, n_nodes)[name] for r in runs_at[lam]
                   if r["steady_state"] != "inadmissible")

    for _ in range(max_steps):
        mids = {name: 0.5 * (lo + hi) for name, (lo, hi) in state.items() if hi - lo > tol}
        if not mids:
            break
        new = sorted({m for m in mids.values() if m not in runs_at})
        if new:
            got = evaluate(new)
            for lam in new:
                runs = [{"lam": float(lam), "start": label, **rec} for label, rec in got[lam]]
                runs_at[lam] = trials[lam] = runs
        for name, mid in mids.items():
            ok = passes(name, mid)
            steps[name].append((mid, ok))
            state[name][1 if ok else 0] = mid
    final = {name: (tuple(state[name]) if name in state else grid[name]) for name in grid}
    evidence = {name: [r for lam in dict.fromkeys(final[name]) if lam in runs_at
                       for r in runs_at[lam]] for name in grid}
    return Refinement(final, grid, evidence, trials, steps)
