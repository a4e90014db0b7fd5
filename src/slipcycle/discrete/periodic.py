"""Plain cycling on one piece of the cycle map, followed without running its cycles.

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
which for coupled FE-reduced models is often close to 1. Every u_e vanishes outside the
coordinates S of the nodes that slip or separate in the cycle; the other nodes keep the
slip their history gave them (Barber 2012, §3: the permanently stuck nodes make the steady
state a set, not a point).

On the piece, the increments of successive cycles are r, M r, M² r, … (r = Φ(x) − x), so
cycle k starts from x + d_k, d_k = r + M r + … + M^{k−1} r: one product by M per cycle,
applied factor by factor (O(E |S|), E events; Golub & Van Loan, *Matrix Computations*,
4th ed., §2.1.5), instead of a cycle of the event-driven solver. The product also gives
each factor's coefficient c_e = a_eᵀ M_{e−1} d_k, and with it how far event e moves,
δt_e = −c_e / ġ_e. :func:`follow_piece` goes on while the cycle from x + d_k stays on the
piece:

- every event stays in its load segment: an event that passes a load sample changes the
  modes that the next segment's rates are solved with, and a node that slipped on
  through that sample may stop there instead (a change of the map that does not vanish
  with the event's move);
- every node's interval of one mode keeps a non-negative length (:class:`ModeIntervals`):
  a slip that shrinks to nothing stops for good after finitely many cycles;
- every inequality of the modes holds on every interval (:class:`PieceConstraints`): a
  stuck node that touches its friction limit on the way slips and changes the memory the
  history selects, however firmly the piece's periodic state would hold it.

Where the increments vanish first, x + d_k is plain cycling's limit with the memory the
history gives it; where the piece is left after k cycles, x + d_k is plain cycling's state
after k cycles. Both are exact, up to round-off and to the displacement below which
nothing counts (the cycling tolerance): :func:`~slipcycle.discrete.steady.simulate` skips
to them and checks each by one more exact cycle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

#: how far an event may move past the end of its load segment [rad] (round-off)
SEGMENT_TOL = 1e-12

#: round-off allowance of the inequalities, in units of the solver's thresholds
ROUND_OFF = 10.0

__all__ = ["CycleJacobian", "cycle_jacobian", "PieceConstraints", "piece_constraints",
           "slow_mode_sum",
           "ModeIntervals", "PieceRun", "follow_piece"]


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
    #: (E,) rate ġ_e of each event's function before it [N/rad or m/rad]
    rate: np.ndarray = None
    #: (E,) θ of each event and the ends of its load segment [rad]
    time: np.ndarray = None
    lo: np.ndarray = None
    hi: np.ndarray = None

    def event_shift(self, c: np.ndarray) -> np.ndarray:
        """How far each event moves for a start moved by d, from the coefficients
        c_e = a_eᵀ M_{e−1} d of the factors: δt_e = −c_e / ġ_e [rad]."""
        return -c / self.rate

    def events_moved_by(self, d: np.ndarray) -> np.ndarray:
        """(E,) how far each event moves for a start moved by d (m,) on S [rad]
        (:meth:`event_shift` of the coefficients of M d)."""
        c = np.empty(self.U.shape[0])
        _apply_map_coefficients(self.U, self.A, d.copy(), c)
        return self.event_shift(c)

    def apply(self, v: np.ndarray) -> np.ndarray:
        """(I − M) v for v (m,)."""
        return v - _apply_map(self.U, self.A, v.copy())


def _apply_map(U, A, v):
    """M v = (I − u_E a_Eᵀ) ⋯ (I − u_1 a_1ᵀ) v, in place; O(E m)."""
    return _apply_map_coefficients(U, A, v, np.empty(U.shape[0]))


def cycle_jacobian(log: list, K: np.ndarray, friction: np.ndarray,
                   max_entries: int = 50_000_000) -> CycleJacobian | None:
    """Assemble the rank-one factors recorded over one cycle.

    Parameters
    ----------
    log : list of (kind, node, idx, u, rate, θ, θ_lo, θ_hi)
        ``Evolution.jacobian_log`` of one cycle: the event kind (0: f p + q = 0 reached,
        1: f p − q = 0, 2: p = 0, 3: w = 0), its node, u_e at the indices ``idx``, the
        rate ġ_e of its event function before it, its θ and its load segment.
    K : (2N, 2N) array
        Reduced stiffness [N/m].
    friction : (N,) array
    max_entries : int
        Refuse (return None) when E·m exceeds this (memory).

    Returns
    -------
    CycleJacobian or None
    """
    if not log or not any(e[2].size for e in log):
        return CycleJacobian(np.zeros(0, int), np.zeros((0, 0)), np.zeros((0, 0)))
    # every event keeps its factor (the identity when it changes no rate), so that the
    # factors and the events of the log share their indices
    idx = np.concatenate([e[2] for e in log])
    seen = np.zeros(K.shape[0], bool)
    seen[idx] = True
    S = seen.nonzero()[0]
    E, m = len(log), S.size
    if E * m > max_entries:
        return None
    kinds = np.array([e[0] for e in log])
    nodes = np.array([e[1] for e in log])
    U = _factor_rows(np.array([e[2].size for e in log]), idx,
                     np.concatenate([e[3] for e in log]), S, K.shape[0])
    timing = {}
    if all(len(e) >= 8 for e in log):
        t = np.array([e[4:8] for e in log], float)
        timing = {"rate": t[:, 0].copy(), "time": t[:, 1].copy(), "lo": t[:, 2].copy(),
                  "hi": t[:, 3].copy()}
    # gradients of g = f p + q, f p − q, p (rows of K) and w (a unit vector)
    A = _gradients(kinds, nodes, S, K, friction)
    return CycleJacobian(S, np.ascontiguousarray(U), np.ascontiguousarray(A), **timing)


def slow_mode_sum(jac: CycleJacobian, r: np.ndarray, krylov: int = 40,
                  rates: tuple[float, float] = (0.0, 0.995)) -> np.ndarray:
    """The slowly decaying part of the increments plain cycling still has to make.

    On the piece, plain cycling from x goes on by d_∞ − r = M r + M² r + … beyond the
    cycle just run (r its increment). Where pieces change every cycle the series cannot
    be followed (:func:`follow_piece`), but the state creeps along the few eigenvectors
    of M whose eigenvalues are close to 1. Their part of the series is summed in closed
    form, Σ_{k≥1} λᵏ z = λ/(1 − λ) z, the rest is left to the next cycles: the recursive
    projection method of Shroff & Keller (1993, *SIAM J. Numer. Anal.* 30, 1099–1120),
    with the slow subspace taken from the Ritz pairs of M on the Krylov space of r
    (Arnoldi, ``krylov`` products by M, O(E m) each; Saad, *Numerical Methods for Large
    Eigenvalue Problems*, 2nd ed., §6.2). The series lies in that Krylov space, so no
    direction is moved that plain cycling would not move. Eigenvalues at or above
    ``rates[1]`` are left alone: λ = 1 is the memory of the nodes (a set of periodic
    states, Barber 2012 §3), and a piece's eigenvalue next to 1 need not be the map's.

    Parameters
    ----------
    jac : CycleJacobian
    r : (m,) array
        Increment of the recorded cycle on S [m].
    krylov : int
        Dimension of the Krylov space.
    rates : (float, float)
        The moduli of the eigenvalues summed: from ``rates[0]`` (faster modes are damped
        by the next cycles anyway) to below ``rates[1]``.

    Returns
    -------
    (m,) array
        The increment on S to add to the state after the recorded cycle [m]; zero where no
        eigenvalue qualifies.
    """
    m = r.size
    beta = float(np.linalg.norm(r))
    k = min(krylov, m)
    if beta == 0.0 or k == 0:
        return np.zeros(m)
    V = np.zeros((m, k + 1))
    H = np.zeros((k + 1, k))
    V[:, 0] = r / beta
    for j in range(k):
        w = _apply_map(jac.U, jac.A, V[:, j].copy())
        for _ in range(2):                      # Gram–Schmidt twice (Giraud et al. 2005)
            h = V[:, :j + 1].T @ w
            H[:j + 1, j] += h
            w -= V[:, :j + 1] @ h
        H[j + 1, j] = np.linalg.norm(w)
        if H[j + 1, j] <= 1e-12 * beta:         # the Krylov space is invariant
            k = j + 1
            break
        V[:, j + 1] = w / H[j + 1, j]
    lam, W = np.linalg.eig(H[:k, :k])
    take = (np.abs(lam) >= rates[0]) & (np.abs(lam) < rates[1])
    if not take.any():
        return np.zeros(m)
    e1 = np.zeros(k, complex)
    e1[0] = beta
    try:
        c = np.linalg.solve(W, e1)              # r in the Ritz basis
    except np.linalg.LinAlgError:
        return np.zeros(m)
    extra = V[:, :k] @ (W[:, take] @ (lam[take] / (1 - lam[take]) * c[take]))
    return extra.real


@dataclass(frozen=True)
class PieceConstraints:
    """The inequalities that keep a cycle on the piece of the cycle map it was recorded on.

    Within each interval between two events every node keeps its mode, and so its
    inequalities: f p ± q ≥ 0 while stuck, p ≥ 0 while slipping, w ≥ 0 while open. On the
    piece, the state at an instant of the cycle started from x + d is the recorded one
    plus M_s d, where M_s is the product of the first s factors of :class:`CycleJacobian`
    (the perturbation changes only at events), so each inequality reads
    g⁰(s) + a_iᵀ M_s d ≥ 0 at the load samples of every interval s, with g⁰(s) its
    smallest recorded value there; at an event, which moves by δt_e, it reads
    g_i(t_e) + ġ_i δt_e + a_iᵀ M_e d ≥ 0. Between those instants each inequality is
    linear in time, so these are all its minima. The nodes that change mode at an event
    are left out at that instant (``Evolution.margin_log``): they sit on an inequality
    there by definition, and the event moving is what :class:`ModeIntervals` checks.

    Attributes
    ----------
    lowest : (E+1, h) array
        g⁰ of the h inequalities at the load samples of the E+1 intervals between the
        factors (+inf where an inequality does not apply) [N or m].
    at_event, event_rate : (E, h) arrays
        Their values at each event (+inf for the nodes that change mode there) and their
        rates ġ_i before it: at the moved event, g_i = g_i(t_e) + ġ_i δt_e + a_iᵀ M_e d
        [N or m, per rad].
    G : (h, m) array
        Their gradients a_i on the moving coordinates S.
    GU : (h, E) array
        a_iᵀ u_e: change of each inequality per unit coefficient of factor e.
    tol : (h,) array
        How far below zero an inequality may go (round-off) [N or m].
    switch_interval, switch_value, switch_G, switch_GU, switch_tol : arrays
        The h_s inequalities on which a node starts to slip, opens or closes at a load
        sample or at another node's event: the interval that begins there, the recorded
        value, gradients (h_s, m), a_iᵀ u_e (h_s, E), and the solver's threshold. Such a
        switch needs the value to stay within [0, threshold] there (less round-off, or as
        recorded): below, the node switches by an event of its own before; above, not at
        all.
    switch_rate, switch_event : arrays
        At another node's event: the inequality's rate before it and the event's index
        (the value is taken at the moved event); 0 and −1 at a load sample.
    """

    lowest: np.ndarray
    at_event: np.ndarray
    event_rate: np.ndarray
    G: np.ndarray
    GU: np.ndarray
    tol: np.ndarray
    switch_interval: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    switch_value: np.ndarray = field(default_factory=lambda: np.zeros(0))
    switch_G: np.ndarray = None
    switch_GU: np.ndarray = None
    switch_tol: np.ndarray = field(default_factory=lambda: np.zeros(0))
    switch_rate: np.ndarray = field(default_factory=lambda: np.zeros(0))
    switch_event: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    def change(self, d: np.ndarray, c: np.ndarray) -> np.ndarray:
        """(E+1, h) change of the inequalities on each interval for a start moved by d
        (m,) whose factor coefficients are c (E,): a_iᵀ M_s d = a_iᵀ d − Σ_{e ≤ s} a_iᵀu_e c_e
        (what the compiled follower evaluates for the inequalities that could fail)."""
        base = self.G @ d
        out = np.empty((c.size + 1, base.size))
        out[0] = base
        np.cumsum(self.GU.T * c[:, None], axis=0, out=out[1:])
        out[1:] = base - out[1:]
        return out

    @classmethod
    def none(cls, E: int, m: int) -> PieceConstraints:
        """No inequalities (to follow the events and mode intervals alone)."""
        return cls(np.zeros((E + 1, 0)), np.zeros((E, 0)), np.zeros((E, 0)),
                   np.zeros((0, m)), np.zeros((0, E)), np.zeros(0))

    def __post_init__(self):
        m, E = self.G.shape[1], self.GU.shape[1]
        if self.switch_G is None:
            object.__setattr__(self, "switch_G", np.zeros((0, m)))
            object.__setattr__(self, "switch_GU", np.zeros((0, E)))
        low = np.min(self.lowest, axis=0, initial=np.inf) + self.tol
        at = np.min(self.at_event, axis=0, initial=np.inf) + self.tol
        object.__setattr__(self, "_slack", (low, at))
        object.__setattr__(self, "_norm", np.sum(np.abs(self.G), axis=1))
        object.__setattr__(self, "_rate_max",
                           np.max(np.abs(self.event_rate), axis=0, initial=0.0))


def piece_constraints(jac: CycleJacobian, log: list, margin_log: list, event_margin_log: list,
                      K: np.ndarray, friction: np.ndarray, force_tol: float,
                      disp_tol: float, switch_log: list = ()) -> PieceConstraints | None:
    """Collect the inequalities of one recorded cycle.

    Parameters
    ----------
    jac : CycleJacobian
        From :func:`cycle_jacobian` on ``log``.
    log : list
        ``Evolution.jacobian_log`` of the cycle.
    margin_log : list of (4, N) arrays
        ``Evolution.margin_log`` of the same cycle (one more entry than ``log``): the
        smallest f p + q, f p − q (stuck), p (slipping) and w (open) at the load
        samples of each interval.
    event_margin_log : list of ((4, N), (4, N)) tuples
        ``Evolution.event_margin_log``: their values at each event and rates before it.
    K : (2N, 2N) array
    friction : (N,) array
    force_tol, disp_tol : float
        Round-off allowances of the force [N] and gap [m] inequalities
        (:data:`ROUND_OFF` times the solver's thresholds).
    switch_log : list of (interval, kind, node, value)
        ``Evolution.switch_log``: nodes that start to slip, open or close at a load
        sample, on an inequality there.

    Returns
    -------
    PieceConstraints or None
        None when the log and the margins do not match.
    """
    E = len(log)
    if len(margin_log) != E + 1 or len(event_margin_log) != E or jac.U.shape[0] != E:
        return None
    S = jac.S
    low = np.array(margin_log)                          # (E+1, 4, N)
    at = np.array([v for v, _ in event_margin_log]).reshape(E, *low.shape[1:])
    rate = np.array([g for _, g in event_margin_log]).reshape(E, *low.shape[1:])
    kind, node = np.nonzero(np.isfinite(low).any(axis=0) | np.isfinite(at).any(axis=0))
    G = _gradients(kind, node, S, K, friction)
    # an inequality that neither the moving coordinates nor the events' moving change
    # cannot fail
    moves = np.isfinite(at[:, kind, node]) & (rate[:, kind, node] != 0.0)
    live = np.any(G != 0.0, axis=1) | np.any(moves, axis=0)
    G = np.ascontiguousarray(G[live])
    tol = np.where(kind == 3, disp_tol, force_tol)[live]
    k, j = kind[live], node[live]
    sw = np.array(switch_log, float).reshape(-1, 6)
    sk, sn = sw[:, 1].astype(int), sw[:, 2].astype(int)
    Gs = _gradients(sk, sn, S, K, friction)
    return PieceConstraints(np.ascontiguousarray(low[:, k, j]),
                            np.ascontiguousarray(at[:, k, j]),
                            np.nan_to_num(rate[:, k, j], posinf=0.0, neginf=0.0), G,
                            np.ascontiguousarray(G @ jac.U.T), tol,
                            sw[:, 0].astype(np.int64), sw[:, 3].copy(), Gs,
                            np.ascontiguousarray(Gs @ jac.U.T),
                            np.where(sk == 3, disp_tol, force_tol) / ROUND_OFF,
                            sw[:, 4].copy(), sw[:, 5].astype(np.int64))


def _gradients(kind: np.ndarray, node: np.ndarray, S: np.ndarray, K: np.ndarray,
               friction: np.ndarray) -> np.ndarray:
    """(len(kind), m) gradients on S (sorted) of f p + q (kind 0), f p − q (1), p (2) and
    w (3) of ``node``: of the events of a cycle and of the inequalities of its modes."""
    return _gradient_rows(np.asarray(kind, np.int64), np.asarray(node, np.int64),
                          np.asarray(S, np.int64), K, np.asarray(friction, float))


@njit(cache=True)
def _gradient_rows(kind, node, S, K, friction):
    """The loop of :func:`_gradients`: rows of K gathered at S, or a unit vector."""
    n, m = K.shape[0] // 2, S.size
    G = np.zeros((kind.size, m))
    for r in range(kind.size):
        k, j = kind[r], node[r]
        if k == 3:                       # w of node j: a unit vector where S holds it
            i = np.searchsorted(S, n + j)
            if i < m and S[i] == n + j:
                G[r, i] = 1.0
            continue
        sq = 1.0 if k == 0 else (-1.0 if k == 1 else 0.0)
        sp = friction[j] if k <= 1 else 1.0
        for i in range(m):
            G[r, i] = sq * K[j, S[i]] + sp * K[n + j, S[i]]
    return G


@njit(cache=True)
def _factor_rows(sizes, idx, vals, S, size):
    """(E, m) rows u_e on S of the factors: ``sizes[e]`` entries ``vals`` at ``idx`` each."""
    pos = np.full(size, -1)
    for i in range(S.size):
        pos[S[i]] = i
    U = np.zeros((sizes.size, S.size))
    k = 0
    for e in range(sizes.size):
        for _ in range(sizes[e]):
            U[e, pos[idx[k]]] = vals[k]
            k += 1
    return U


@njit(cache=True, fastmath={"reassoc", "contract"})
def _apply_map_coefficients(U, A, v, c):
    """M v in place, with the coefficient c_e = a_eᵀ (M_{e−1} v) of every factor in c."""
    E, m = U.shape
    for e in range(E):
        s = 0.0
        for i in range(m):
            s += A[e, i] * v[i]
        c[e] = s
        if s != 0.0:
            for i in range(m):
                v[i] -= U[e, i] * s
    return v



@dataclass(frozen=True)
class ModeIntervals:
    """Every node's intervals of one mode in the recorded cycle that an event begins or
    ends (``Evolution.episode_log``).

    A perturbed start moves the events (:meth:`CycleJacobian.event_shift`); events of
    different nodes may pass each other (a neighbouring piece of the cycle map, which the
    continuity of the map joins to this one), but an interval whose length would go
    below zero means that a node's sequence of modes changes: a slip that shrinks to
    nothing, a stick between two slips that vanishes, an opening that closes.

    Attributes
    ----------
    start, end : (k,) int arrays
        Index of the event that begins / ends each interval, −1 for a load sample or an
        end of the cycle (which do not move).
    length : (k,) array
        Recorded length of each interval [rad].
    tol : (k,) array
        Negative length allowed (round-off) [rad].
    """

    start: np.ndarray
    end: np.ndarray
    length: np.ndarray
    tol: np.ndarray
    #: (k,) int array: the node's mode on each interval (``slipcycle.discrete.model``)
    mode: np.ndarray = None

    @classmethod
    def from_log(cls, episode_log: list, tol: float) -> ModeIntervals:
        """From ``Evolution.episode_log``, with the round-off allowance ``tol`` [rad]."""
        ep = np.array(episode_log, float).reshape(-1, 6)
        return cls(ep[:, 1].astype(int), ep[:, 3].astype(int), ep[:, 4] - ep[:, 2],
                   np.full(ep.shape[0], tol), ep[:, 5].astype(int))

    def change(self, shift: np.ndarray) -> np.ndarray:
        """(k,) change of every interval's length when the events move by ``shift``
        (E,) [rad]."""
        s = np.concatenate([shift, [0.0]])              # index −1: does not move
        return s[self.end] - s[self.start]

    def hold(self, shift: np.ndarray) -> bool:
        """Whether every interval keeps a non-negative length when the events move by
        ``shift`` (E,) [rad]."""
        if self.length.size == 0:
            return True
        return bool(np.all(self.length + self.change(shift) >= -self.tol))


@dataclass(frozen=True)
class PieceRun:
    """Plain cycling from x followed on one sequence of modes (:func:`follow_piece`).

    Attributes
    ----------
    cycles : int
        The cycles started from x + d_1, …, x + d_k all keep the recorded sequence of
        modes (d_1 = r is the increment of the recorded cycle); k = ``cycles``.
    reached : bool
        The increments M^k r fell below the round-off bound within those cycles: the
        step's limit is where plain cycling goes.
    start, after : (m,) arrays
        d_k and d_{k+1} = d_k + M^k r on the moving coordinates S [m].
    """

    cycles: int
    reached: bool
    start: np.ndarray
    after: np.ndarray


def follow_piece(jac: CycleJacobian, r: np.ndarray, constraints: PieceConstraints,
                 intervals: ModeIntervals, tiny: float, max_cycles: int = 5000,
                 max_work: float = 2e9) -> PieceRun:
    """Follow plain cycling from x on the recorded sequence of modes, without running it.

    On the piece, the increments of successive cycles are r, M r, M² r, …, and cycle k
    starts from x + d_k, d_k = r + M r + … + M^{k−1} r. Each of those cycles must keep
    (module docstring)

    - every event in its load segment and in its order, the events moving by
      δt_e = −c_e / ġ_e with c_e = a_eᵀ M_{e−1} d_k;
    - every node's intervals of one mode (:class:`ModeIntervals`): a slip that shrinks to
      nothing stops for good after finitely many cycles, where the piece's periodic state
      would not freeze it;
    - every inequality of the nodes' modes on every interval (:class:`PieceConstraints`):
      a stuck node that touches its friction limit on the way slips and changes the
      memory the history selects (Barber 2012 §3), however firmly the limit would hold it.

    All are linear in d_k, so one product by M per cycle updates them (O(E m), and
    O(E) per inequality that a bound on the state change lets come near its margin).

    Parameters
    ----------
    jac : CycleJacobian
        With the event rates ġ_e, times and load segments.
    r : (2N,) array
        Increment of the recorded cycle [m].
    constraints : PieceConstraints
    intervals : ModeIntervals
    tiny : float
        Increments below this are round-off [m].
    max_cycles, max_work : int, float
        Bounds on k and on the work.

    Returns
    -------
    PieceRun
    """
    S = jac.S
    cost = max(1, 2 * jac.U.size)
    kmax = int(min(max_cycles, max_work / cost))
    k, reached, d, e = _follow(
        jac.U, jac.A, jac.rate, jac.time - jac.lo, jac.hi - jac.time,
        np.concatenate([[False], jac.lo[1:] == jac.lo[:-1]]),
        np.concatenate([[0.0], np.diff(jac.time)]), intervals.start,
        intervals.end, intervals.length, intervals.tol, constraints.G, constraints.GU,
        constraints.lowest, constraints.at_event, constraints.event_rate, constraints.tol,
        constraints._slack[0], constraints._slack[1], constraints._norm,
        constraints._rate_max, constraints.switch_interval, constraints.switch_value,
        constraints.switch_G, constraints.switch_GU, constraints.switch_tol,
        constraints.switch_rate, constraints.switch_event, r[S].copy(), tiny, kmax)
    return PieceRun(k, reached, d, d + e)


@njit(cache=True)
def _follow(U, A, rate, room_before, room_after, same_segment, gap, iv_start, iv_end,
            iv_length, iv_tol, G, GU, lowest, at_event, event_rate, tol, slack_low, slack_at,
            norm, rate_max, sw_interval, sw_value, sw_G, sw_GU, sw_tol, sw_rate, sw_event,
            e, tiny, kmax):
    """The loop of :func:`follow_piece`; returns (k, reached, d_k, M^k r) on S.

    Both checks are linear in (d_k, c(d_k)). The inequalities are checked exactly only
    where a bound on the state change could reach their margin:
    |a_iᵀ M_s d_k| ≤ ‖a_i‖₁ Σ_k (|e_k|∞ + Σ_e |u_e|∞ |c_e(e_k)|)."""
    E, m = U.shape
    h = G.shape[0]
    u_max = np.zeros(E)
    for ev in range(E):
        for i in range(m):
            u_max[ev] = max(u_max[ev], abs(U[ev, i]))
    d = np.zeros(m)
    coef = np.zeros(E)
    shift = np.zeros(E)
    nxt = np.empty(m)
    dn = np.empty(m)
    reach = 0.0
    for k in range(kmax):
        emax = 0.0
        for i in range(m):
            nxt[i] = e[i]
            emax = max(emax, abs(e[i]))
        reach += emax
        for ev in range(E):                     # M e, and the coefficients c_e
            s = 0.0
            for i in range(m):
                s += A[ev, i] * nxt[i]
            coef[ev] += s
            reach += u_max[ev] * abs(s)
            if s != 0.0:
                for i in range(m):
                    nxt[i] -= U[ev, i] * s
        max_shift = 0.0
        for ev in range(E):
            shift[ev] = -coef[ev] / rate[ev]
            max_shift = max(max_shift, abs(shift[ev]))
            # an event that passes a load sample or another event changes the modes the
            # rates after it are solved with: another piece of the map
            if shift[ev] > room_after[ev] + SEGMENT_TOL:
                return k, False, d, e
            # nor before the event before it in its segment, or the segment's start
            if ev > 0 and same_segment[ev]:
                moved = gap[ev] + shift[ev] - shift[ev - 1]
            else:
                moved = room_before[ev] + shift[ev]
            if moved < -SEGMENT_TOL:
                return k, False, d, e
        for t in range(iv_length.size):         # every mode interval keeps its length
            length = iv_length[t]
            if iv_end[t] >= 0:
                length += shift[iv_end[t]]
            if iv_start[t] >= 0:
                length -= shift[iv_start[t]]
            if length < -iv_tol[t]:
                return k, False, d, e
        for i in range(m):
            dn[i] = d[i] + e[i]
        for r in range(h):                      # the inequalities that could fail
            if not (norm[r] * reach >= slack_low[r]
                    or norm[r] * reach + rate_max[r] * max_shift >= slack_at[r]):
                continue
            base = 0.0
            for i in range(m):
                base += G[r, i] * dn[i]
            if lowest[0, r] + base < -tol[r]:
                return k, False, d, e
            change = base
            for ev in range(E):
                if at_event[ev, r] + event_rate[ev, r] * shift[ev] + change < -tol[r]:
                    return k, False, d, e
                change -= GU[r, ev] * coef[ev]
                if lowest[ev + 1, r] + change < -tol[r]:
                    return k, False, d, e
        for r in range(sw_value.size):          # switches at load samples keep happening
            change = 0.0
            for i in range(m):
                change += sw_G[r, i] * dn[i]
            # the switch's interval begins after factor sw_interval − 1; the value before
            # an event uses the product of the factors before it
            last = sw_event[r] if sw_event[r] >= 0 else sw_interval[r]
            for ev in range(last):
                change -= sw_GU[r, ev] * coef[ev]
            value = sw_value[r] + change
            if sw_event[r] >= 0:
                value += sw_rate[r] * shift[sw_event[r]]
            # below zero the node reaches its inequality before that instant, by an
            # event of its own (as recorded, less round-off); above the threshold it does
            # not switch there
            if value > sw_tol[r] or value < min(sw_value[r], 0.0) - 1e-2 * sw_tol[r]:
                return k, False, d, e
        for i in range(m):
            d[i] = dn[i]
            e[i] = nxt[i]
        emax = 0.0
        for i in range(m):
            emax = max(emax, abs(e[i]))
        if emax <= tiny:
            return k + 1, True, d, e
    return kmax, False, d, e
