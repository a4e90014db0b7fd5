"""The rate problem of a discrete frictional system.

At an instant where the state ``x = [v, w]`` and the reactions ``r = [q, p]`` are known and
the load rate ``ṙ^w = [q̇^w, ṗ^w]`` (per radian of θ) is constant, find the node states
(modes) and rates ``ẋ`` such that, with ``ṙ = ṙ^w + K ẋ``,

- ``stick``:           v̇_j = 0, ẇ_j = 0
- ``slip_positive``:   v̇_j ≥ 0, ẇ_j = 0 and q_j = −f p_j is kept: f ṗ_j + q̇_j = 0
- ``slip_negative``:   v̇_j ≤ 0, ẇ_j = 0 and q_j = +f p_j is kept: f ṗ_j − q̇_j = 0
- ``separated``:       p_j = q_j = 0 kept: ṗ_j = q̇_j = 0 (v̇_j, ẇ_j free), ẇ_j ≥ 0 if w_j = 0

and every inequality that is active now stays satisfied to first order: a stuck node at
q = −f p needs f ṗ + q̇ ≥ 0, a node in contact at p = 0 needs ṗ ≥ 0, and so on. This is a
linear complementarity problem (Klarbring 1990); it has a unique solution when the P-matrix
condition of :mod:`~slipcycle.discrete.wellposed` holds.

Method. Only the *critical* nodes (at a friction limit, at p = 0 in contact, or at w = 0
while separated) have a choice. Starting from the previous modes (warm start), the mode
of every node whose condition fails is switched (block principal pivoting, Júdice & Pires
1994), falling back to switching only the first failing node (Murty's least-index
principal pivoting, finite for P-matrices) and, if a mode set repeats, to Lemke's method
on the LCP over the critical nodes.

For a given mode set the rates follow from a linear system in the unknowns of the
non-stuck nodes only (one per slipping node, two per separated node), of size k ≤ 2N.
Its inverse is kept current: when nodes change state it is updated by bordering (a node
starts to slip or separates) or by the Schur-complement removal formula (a node sticks),
O(k²) per changed node, and recomputed from scratch (O(k³)) only after many updates or
when most of the set changes. The rows K[col] of the unknowns (K is symmetric, so they
are its columns, and rows of a C-ordered matrix are contiguous) are kept in a buffer in
the same order: a node that starts to slip appends its rows, one that sticks is replaced
by the last (swap-delete), O(N) per changed unknown, never a gather over all of K. A solve
then costs O(k² + kN) and streams 8(k² + 2kN) bytes once, in a compiled single-threaded
loop (:func:`_mode_rates`); an event with r nodes changing state adds O(k² r + r N) for
the updates (low-rank updates of an inverse: Golub & Van Loan, *Matrix Computations*,
4th ed., §2.1.4). The pivoting, the updates and the rates of one rate problem run in one
compiled call (:func:`_pivot`), which returns to Python only to factorize a mode system
from scratch or to grow the buffers; at a few hundred nodes the per-event cost is then
the O(kN) pass over K rather than the interpreter.

References
----------
A. Klarbring, Ingenieur-Archiv 60 (1990) 529–541. K. G. Murty, *Linear Complementarity,
Linear and Nonlinear Programming*, Heldermann (1988), §4. J. J. Júdice, F. M. Pires, "A
block principal pivoting algorithm for large-scale strictly monotone linear complementarity
problems", Comput. Oper. Res. 21 (1994) 587–596.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from slipcycle.coupled.system import likely_cause
from slipcycle.discrete.lcp import lemke
from slipcycle.discrete.model import SEPARATED, SLIP_NEG, SLIP_POS, STICK, FrictionalSystem
from slipcycle.errors import SolverError

__all__ = ["RateSolver", "RateProblemError"]

#: the dot products of the kernels may be summed in any order (vectorised); no other
#: fast-math licence, so that a zero or non-finite pivot is still seen
_REASSOC = {"reassoc", "contract"}


@njit(cache=True, fastmath=_REASSOC)
def _mode_rates(Minv, Kr, b, rw):
    """Rates of the unknowns ``sol = −Minv b`` and reaction rates ṙ = ṙ^w + K ẋ, with
    K ẋ = Σ_a sol_a K[col_a] over the unknowns' rows of the symmetric K: one streaming
    pass over k rows of 2N (8·k·2N bytes), single-threaded so that a loaded machine
    does not stall in a threaded BLAS call on a vector."""
    k = b.size
    sol = np.zeros(k)
    for a in range(k):
        s = 0.0
        for c in range(k):
            s -= Minv[a, c] * b[c]
        sol[a] = s
    rd = rw.copy()
    for a in range(k):
        s = sol[a]
        if s != 0.0:
            for i in range(rd.size):
                rd[i] += s * Kr[a, i]
    return sol, rd


@njit(cache=True, fastmath=_REASSOC)
def _border_one(P, k, bcol, crow, d):
    """Grow the inverse P[:k, :k] of a mode matrix by one unknown, in place in its buffer:
    new column ``bcol`` (k,), row ``crow`` (k,), diagonal ``d``. With Pb = P bcol,
    cP = crow P and the Schur complement s = d − crow·Pb, the inverse of the bordered
    matrix is [[P + Pb cP / s, −Pb / s], [−cP / s, 1 / s]]. Two matrix–vector products
    and one rank-one update: three passes over k² entries, no allocation of a k × k
    temporary. Returns s (0 or non-finite: the bordered matrix is singular, P is then
    left unchanged)."""
    pb = np.zeros(k)
    cp = np.zeros(k)
    for a in range(k):
        s = 0.0
        ca = crow[a]
        for b in range(k):
            s += P[a, b] * bcol[b]
            cp[b] += ca * P[a, b]
        pb[a] = s
    sch = d
    for a in range(k):
        sch -= crow[a] * pb[a]
    if sch == 0.0 or not np.isfinite(sch):
        return sch
    inv = 1.0 / sch
    for a in range(k):
        fa = pb[a] * inv
        for b in range(k):
            P[a, b] += fa * cp[b]
        P[a, k] = -fa
        P[k, a] = -cp[a] * inv
    P[k, k] = inv
    return sch


@njit(cache=True)
def _remove_one(P, k, i):
    """Drop unknown ``i`` from the inverse P[:k, :k] of a mode matrix, in place: the
    inverse of the matrix without row and column i is P − P[:, i] P[i, :] / P[i, i]
    restricted to the others (Schur-complement removal); the last unknown then moves
    into the hole (swap-delete, the order :func:`_rates_kernel` keeps). One pass
    over k² entries."""
    col = P[:k, i].copy()
    row = P[i, :k].copy()
    inv = 1.0 / P[i, i]
    for a in range(k):
        fa = col[a] * inv
        if fa != 0.0:
            for b in range(k):
                P[a, b] -= fa * row[b]
    last = k - 1
    if i != last:
        for b in range(k):
            P[i, b] = P[last, b]
        for a in range(k):
            P[a, i] = P[a, last]


@njit(cache=True)
def _n_keys(mode):
    """Number of unknowns of a node in ``mode``: 0 stuck, 1 slipping, 2 separated."""
    if mode == STICK:
        return 0
    if mode == SEPARATED:
        return 2
    return 1


@njit(cache=True)
def _node_keys(j, mode, n):
    """The unknowns' keys of node j in ``mode`` (two; −1 where there is none)."""
    if mode == SLIP_POS:
        return (4 * j + 1, -1)
    if mode == SLIP_NEG:
        return (4 * j + 2, -1)
    if mode == SEPARATED:
        return (4 * j + 3, 4 * (n + j) + 3)
    return (-1, -1)


@njit(cache=True)
def _coefficients(key, f, n):
    """(column, node, c_q, c_p) of the unknown ``key``: its equation is
    c_q q̇_j + c_p ṗ_j = 0 and it is the rate of x[column]."""
    col = key // 4
    kind = key % 4
    j = col % n
    if kind == 1:
        return col, j, 1.0, f[j]
    if kind == 2:
        return col, j, -1.0, f[j]
    return col, j, 1.0 if col < n else 0.0, 1.0 if col >= n else 0.0


@njit(cache=True)
def _entry(K, f, key, col):
    """Mode-system entry M[a, b] = c_q K[j_a, col_b] + c_p K[N + j_a, col_b] of the
    equation of unknown ``key`` (row a) and the column ``col`` of unknown b."""
    n = f.size
    _, j, cq, cp = _coefficients(key, f, n)
    return cq * K[j, col] + cp * K[n + j, col]


@njit(cache=True)
def _mode_keys(modes):
    """Sorted keys of the unknowns of a mode set (:func:`_node_keys` of every node)."""
    n = modes.size
    keys = np.empty(2 * n, np.int64)
    k = 0
    for j in range(n):
        for key in _node_keys(j, modes[j], n):
            if key >= 0:
                keys[k] = key
                k += 1
    return np.sort(keys[:k])


@njit(cache=True)
def _mode_matrix(K, f, keys):
    """The mode-system matrix M (k, k) of the unknowns ``keys`` (:func:`_entry`)."""
    k = keys.size
    M = np.empty((k, k))
    for a in range(k):
        for b in range(k):
            M[a, b] = _entry(K, f, keys[a], keys[b] // 4)
    return M


@njit(cache=True)
def _rate_tol(rw):
    """Rate tolerance [N/rad] deciding which inequality rates fail: 1e-9 of the load rate."""
    return 1e-9 * np.max(np.abs(rw)) + 1e-300


@njit(cache=True)
def _rates_kernel(K, f, modes, sysmodes, unk, state, P, Kr, rw, max_updates):
    """Update the inverse of the mode system from the modes it holds (``sysmodes``) to
    ``modes``, node by node (Schur-complement removal of the unknowns that go, bordering
    with the ones that come), and return the rates for the load rate ``rw``.

    ``state`` holds (number of unknowns k, updates since the last factorization, room
    asked for). Returns (status, ẋ, ṙ, unknowns changed): status 0 done; 1 refactorize
    (many changes, many updates, or a zero pivot: the mode matrix is then left invalid);
    2 the buffers need room for ``state[2]`` unknowns (nothing has changed)."""
    n = f.size
    k = state[0]
    xd = np.zeros(2 * n)
    if k < 0:                                   # no valid mode system: factorize
        return 1, xd, rw.copy(), 0
    nchange = 0
    target = k
    for j in range(n):
        if modes[j] != sysmodes[j]:
            a = _n_keys(sysmodes[j])
            b = _n_keys(modes[j])
            nchange += a + b
            target += b - a
    if nchange:
        if nchange > max(8, target // 2) or state[1] > max_updates:
            return 1, xd, rw.copy(), 0
        if target > P.shape[0] or target > Kr.shape[0]:
            state[2] = target
            return 2, xd, rw.copy(), 0
        for j in range(n):
            if modes[j] == sysmodes[j]:
                continue
            old = _node_keys(j, sysmodes[j], n)
            for key in old:
                if key < 0:
                    continue
                i = 0
                while i < k and unk[i] != key:
                    i += 1
                if i == k:                      # not held: rebuild from scratch
                    state[0] = -1
                    return 1, xd, rw.copy(), 0
                _remove_one(P, k, i)
                if i != k - 1:
                    Kr[i, :] = Kr[k - 1, :]
                    unk[i] = unk[k - 1]
                k -= 1
        for j in range(n):
            if modes[j] == sysmodes[j]:
                continue
            for key in _node_keys(j, modes[j], n):
                if key < 0:
                    continue
                col = key // 4
                bcol = np.empty(k)
                crow = np.empty(k)
                for a in range(k):
                    bcol[a] = _entry(K, f, unk[a], col)
                    crow[a] = _entry(K, f, key, unk[a] // 4)
                d = _entry(K, f, key, col)
                sch = _border_one(P, k, bcol, crow, d)
                if sch == 0.0 or not np.isfinite(sch):
                    state[0] = -1
                    return 1, xd, rw.copy(), 0
                Kr[k, :] = K[col, :]
                unk[k] = key
                k += 1
            sysmodes[j] = modes[j]
        state[0] = k
        state[1] += nchange
    b = np.empty(k)
    for a in range(k):
        _, ja, cqa, cpa = _coefficients(unk[a], f, n)
        b[a] = cqa * rw[ja] + cpa * rw[n + ja]
    sol, rd = _mode_rates(P, Kr, b, rw)
    for a in range(k):
        xd[unk[a] // 4] = sol[a]
    return 0, xd, rd, nchange


#: the largest pressure, in force tolerances, that a node at the apex of its friction
#: cone (f p + |q| within the tolerance) may keep when it opens (:func:`_start_modes`)
APEX_P = 1e3


@njit(cache=True)
def friction_tol(f, p, tol):
    """Tolerance [N] within which node j is at a friction limit, g± = f p ± q ≤ it.

    ``tol`` (the force tolerance), but for a node in contact at a real pressure,
    p > :data:`APEX_P` × tol, at most half the width f p of its cone, so that it is
    never at both limits at once (their slacks sum to 2 f p): with ``tol`` alone a cone
    narrower than it (f p ≤ tol: f = 1e-9 at p = 1 N) had both limits active, which the
    solver takes for the apex, and the node was opened with p > 0 held on it while its
    gap grew (or, with that rule confined to p ≈ 0, no mode fitted a load lowering p).
    Near the apex (p ≤ APEX_P × tol) and without friction (f = 0: q = 0, the two limits
    coincide) it is ``tol``.
    """
    if f <= 0.0 or p <= APEX_P * tol:
        return tol
    return min(tol, 0.5 * f * p)


@njit(cache=True)
def _start_modes(f, x, r, guess, tol, disp_tol):
    """Active inequalities at the state (g+, g−, p = 0 in contact, separated), each (N,),
    and the warm start ``guess`` with the modes they no longer allow set to stick
    (:meth:`RateSolver.flags`); also whether any node is critical."""
    n = f.size
    gp = np.zeros(n, np.bool_)
    gm = np.zeros(n, np.bool_)
    p0 = np.zeros(n, np.bool_)
    sep = np.zeros(n, np.bool_)
    modes = guess.astype(np.int8)
    crit = False
    for j in range(n):
        q, p = r[j], r[n + j]
        if x[n + j] > disp_tol:
            sep[j] = True
            modes[j] = SEPARATED
            continue
        ftol = friction_tol(f[j], p, tol)
        gp[j] = f[j] * p + q <= ftol
        gm[j] = f[j] * p - q <= ftol
        # both sides of the friction limit active means f p ≤ tol and, with
        # friction_tol, p ≤ APEX_P tol: the node is at the apex, where it may open too
        # (without that option a load that pulls it open has no rate solution). Not a
        # frictionless node, whose two limits coincide (q = 0) at any p: it slips
        # either way, and opens at p = 0
        p0[j] = p <= tol or (f[j] > 0.0 and gp[j] and gm[j])
        m = modes[j]
        if (m == SLIP_POS and not gp[j]) or (m == SLIP_NEG and not gm[j]) or (
                m == SEPARATED and not p0[j]):
            modes[j] = STICK
        crit = crit or gp[j] or gm[j] or p0[j]
    return gp, gm, p0, sep, modes, crit


@njit(cache=True)
def _violations(modes, gp, gm, p0, sep, f, xd, rd, rate_tol, vtol):
    """Nodes whose active inequalities fail at the rates (ẋ, ṙ), and the mode to try for
    each: (number of them, first of them, the modes with theirs switched)."""
    n = modes.size
    new = modes.copy()
    nbad = 0
    first = -1
    for j in range(n):
        qd, pd = rd[j], rd[n + j]
        vd, wd = xd[j], xd[n + j]
        p_bad = p0[j] and pd < -rate_tol
        gp_bad = gp[j] and f[j] * pd + qd < -rate_tol
        gm_bad = gm[j] and f[j] * pd - qd < -rate_tol
        m = modes[j]
        bad = False
        if m == STICK:
            if p_bad:
                new[j], bad = SEPARATED, True
            elif gp_bad:
                new[j], bad = SLIP_POS, True
            elif gm_bad:
                new[j], bad = SLIP_NEG, True
        elif m == SLIP_POS or m == SLIP_NEG:
            wrong = vd < -vtol if m == SLIP_POS else vd > vtol
            other_bad = gm_bad if m == SLIP_POS else gp_bad
            if p_bad:
                new[j], bad = SEPARATED, True
            elif wrong or other_bad:
                new[j], bad = STICK, True
        elif not sep[j] and wd < -vtol:          # separated at w = 0, closing
            new[j], bad = STICK, True
        if bad:
            nbad += 1
            if first < 0:
                first = j
    return nbad, first, new


@njit(cache=True)
def _modes_hash(modes):
    """64-bit FNV-1a hash of a mode set (the pivoting's record of the sets it tried)."""
    h = np.uint64(14695981039346656037)
    for m in modes:
        h = (h ^ np.uint64(m)) * np.uint64(1099511628211)
    return np.int64(h)


@njit(cache=True)
def _pivot(K, f, x, r, rw, modes, flags, start, force_tol, disp_tol, vtol_scale, sysmodes,
           unk, state, P, Kr, max_updates, loop, seen):
    """Block principal pivoting until no active inequality fails (:meth:`RateSolver.solve`).

    ``start`` 1: begin from the warm start in ``modes`` at the state (x, r), writing the
    active inequalities (:func:`_start_modes`) into ``flags`` (4, N) and the modes they
    allow into ``modes``; 2: rates of ``modes`` as they are (no inequality active);
    0: go on after a return to Python. ``modes`` is changed in place.

    ``loop`` = (iterations left, block switching on, fewest failures so far (−1: none),
    mode sets tried, any node critical, and the running totals of unknowns changed,
    pivots and rate solves) carries the iteration over a return to Python, and ``seen``
    the hashes of the mode sets tried. Returns (status, ẋ, ṙ): 0 solved; 1 factorize the
    mode system of ``modes`` and call again; 2 make room for ``state[2]`` unknowns and
    call again; 3 no solution found by pivoting (a mode set repeats, or the iterations
    run out): Lemke's method."""
    n = f.size
    if start:
        loop[0] = 1 if start == 2 else 4 * n + 20
        loop[1], loop[2], loop[3], loop[4] = 1, -1, 0, 0
        if start == 1:
            gp, gm, p0, sep, m0, crit = _start_modes(f, x, r, modes, force_tol, disp_tol)
            flags[0, :], flags[1, :], flags[2, :], flags[3, :] = gp, gm, p0, sep
            modes[:] = m0
            loop[4] = crit
    rate_tol = _rate_tol(rw)
    vtol = rate_tol * vtol_scale
    while loop[0] > 0:
        status, xd, rd, nchange = _rates_kernel(K, f, modes, sysmodes, unk, state, P, Kr,
                                                rw, max_updates)
        if status != 0:
            return status, xd, rd
        loop[0] -= 1
        loop[5] += nchange
        loop[7] += 1
        if not loop[4]:
            return 0, xd, rd
        nbad, first, new = _violations(modes, flags[0], flags[1], flags[2], flags[3], f,
                                       xd, rd, rate_tol, vtol)
        if nbad == 0:
            return 0, xd, rd
        loop[6] += 1
        h = _modes_hash(modes)
        for i in range(loop[3]):
            if seen[i] == h:
                return 3, xd, rd
        seen[loop[3]] = h
        loop[3] += 1
        if loop[2] >= 0 and nbad >= loop[2]:
            loop[1] = 0                         # no progress: one node at a time (Murty)
        loop[2] = nbad if loop[2] < 0 else min(loop[2], nbad)
        if loop[1]:
            modes[:] = new
        else:
            modes[first] = new[first]
    return 3, np.zeros(2 * n), rw.copy()


class RateProblemError(SolverError):
    """The rate problem has no (unique) solution: the model is ill posed at this state."""


class RateSolver:
    """Solve the rate problem of a :class:`FrictionalSystem`.

    Parameters
    ----------
    system : FrictionalSystem
    force_tol : float
        Absolute tolerance on forces [N] deciding which inequalities are active.
    """

    #: refactorize the mode system after this many updates of its inverse (round-off)
    MAX_UPDATES = 400

    def __init__(self, system: FrictionalSystem, force_tol: float):
        self.sys = system
        self.n = system.n_nodes
        self.K = np.ascontiguousarray(system.K)
        self.f = np.ascontiguousarray(system.friction, dtype=float)
        self.force_tol = float(force_tol)
        self.disp_tol = self.force_tol / float(np.max(np.diag(system.C)))
        self._vtol_scale = 1.0 / float(np.max(np.diag(self.K)))
        # The mode system: the keys of its unknowns (first k entries of ``_unk``), the modes
        # it stands for, and its inverse, kept current by O(k²) updates in place: the
        # leading k × k block of a buffer with room to grow (doubling), so that an event
        # allocates no k × k array. ``_state`` = (k, updates since the last factorization,
        # room asked for); k = −1: no valid mode system.
        self._unk = np.zeros(2 * self.n, np.int64)
        self._sysmodes = np.zeros(self.n, np.int8)
        self._state = np.array([-1, 0, 0], np.int64)
        # the pivoting's state across returns to Python and its running totals
        # (:func:`_pivot`), the hashes of the mode sets it tried, the active inequalities
        self._loop = np.zeros(8, np.int64)
        self._seen = np.zeros(4 * self.n + 20, np.int64)
        self._flags = np.zeros((4, self.n), np.bool_)
        self._factorizations = 0
        self._lemke_calls = 0
        self._P = np.zeros((0, 0))
        # rows K[col_b] of the unknowns, in the order of ``_unk`` (K is symmetric, so these
        # are its columns; rows of a C-ordered matrix are contiguous): kept current row by
        # row, O(N) per unknown added or removed, never gathered from all of K per event
        self._Kr = np.zeros((0, 2 * self.n))

    # -- active inequalities -------------------------------------------------------------
    def flags(self, x: np.ndarray, r: np.ndarray):
        """Active inequalities at state x, reactions r: (g+, g−, p=0 in contact, separated)."""
        gp, gm, p0, sep, _, _ = _start_modes(self.f, x, r, np.zeros(self.n, np.int8),
                                             self.force_tol, self.disp_tol)
        return gp, gm, p0, sep

    # -- rates for a given mode set --------------------------------------------------------
    # Each unknown has an integer key 4*col + kind: col is its index in x = [v, w], kind 1 a
    # positive-slip equation f ṗ_j + q̇_j = 0, kind 2 a negative-slip equation
    # f ṗ_j − q̇_j = 0, kind 3 a separated node (q̇_j = 0 for col = j, ṗ_j = 0 for col = N+j)
    # (:func:`_node_keys`, :func:`_coefficients`).
    def _room(self, k: int) -> None:
        """Make the buffers hold at least k unknowns (doubling, keeping the content)."""
        kk = max(int(self._state[0]), 0)
        if self._P.shape[0] < k:
            cap = min(max(2 * k, 16), 2 * self.n)
            buf = np.empty((cap, cap))
            buf[:kk, :kk] = self._P[:kk, :kk]
            self._P = buf
        if self._Kr.shape[0] < k:
            buf = np.empty((min(max(2 * k, 16), 2 * self.n), 2 * self.n))
            buf[:kk] = self._Kr[:kk]
            self._Kr = buf

    def _rebuild(self, modes: np.ndarray) -> bool:
        """Factorize the mode system of ``modes`` from scratch (O(k³))."""
        self._factorizations += 1
        keys = _mode_keys(modes)
        k = keys.size
        self._state[:] = (-1, 0, 0)
        M = _mode_matrix(self.K, self.f, keys)
        if k:
            try:
                Minv = np.linalg.inv(M)
            except np.linalg.LinAlgError:
                return False
            cond = np.abs(M).sum(axis=0).max() * np.abs(Minv).sum(axis=0).max()
            if not np.isfinite(cond) or cond > 1e13:
                return False
        self._room(k)
        if k:
            self._P[:k, :k] = Minv
            self._Kr[:k] = self.K[keys // 4]
        self._unk[:k] = keys
        self._sysmodes[:] = modes
        self._state[0] = k
        return True

    @property
    def stats(self) -> dict:
        """Counts: rate solves, factorizations of a mode system, unknowns added or removed
        by updates, pivots, Lemke fall-backs."""
        return {"solves": int(self._loop[7]), "factorizations": self._factorizations,
                "updates": int(self._loop[5]), "pivots": int(self._loop[6]),
                "lemke": self._lemke_calls}

    def _iterate(self, x, r, rw, modes, start):
        """Pivot with :func:`_pivot` (``modes`` in place), factorizing the mode system or
        growing its buffers when it asks: (ẋ, ṙ), or None where pivoting finds no
        solution or a mode system is singular."""
        for _ in range(64):
            status, xd, rd = _pivot(self.K, self.f, x, r, rw, modes, self._flags, start,
                                    self.force_tol, self.disp_tol, self._vtol_scale,
                                    self._sysmodes, self._unk, self._state, self._P,
                                    self._Kr, self.MAX_UPDATES, self._loop, self._seen)
            start = 0
            if status == 0:
                return xd, rd
            if status == 1:
                if not self._rebuild(modes):
                    return None
            elif status == 2:
                self._room(int(self._state[2]))
            else:
                return None
        return None

    def rates(self, modes: np.ndarray, rw: np.ndarray):
        """Rates (ẋ, ṙ), both (2N,), for the mode set ``modes`` and load rate ``rw``.

        Returns None if the mode set's system is singular.
        """
        none = np.zeros(2 * self.n)
        return self._iterate(none, none, np.ascontiguousarray(rw, dtype=float),
                             np.array(modes, dtype=np.int8), 2)

    # -- the rate problem -----------------------------------------------------------------
    def solve(self, x: np.ndarray, r: np.ndarray, rw: np.ndarray, guess: np.ndarray):
        """Solve the rate problem at state ``x`` (2N,), reactions ``r`` (2N,), load rate
        ``rw`` (2N,), warm-started from the mode set ``guess`` (N,).

        Returns
        -------
        modes : (N,) int8 array
        xd, rd : (2N,) arrays
            State rates and reaction rates per radian.
        """
        rw = np.ascontiguousarray(rw, dtype=float)
        modes = np.array(guess, dtype=np.int8)
        res = self._iterate(x, r, rw, modes, 1)
        if res is not None:
            return modes, res[0], res[1]
        return self._lemke(x, r, rw, tuple(self._flags.copy()), _rate_tol(rw))

    def _lemke(self, x, r, rw, flags, rate_tol):
        """Fall-back: Lemke's method on the LCP of the critical nodes."""
        self._lemke_calls += 1
        n, K, f = self.n, self.K, self.f
        gp, gm, p0, sep = flags
        U = np.flatnonzero(sep)
        U = np.concatenate([U, n + U])
        zc, zs, rows = [], [], []
        for j in np.flatnonzero(gp | gm | p0):
            if gp[j]:
                zc.append(j)
                zs.append(1.0)
                rows.append((j, 1.0, f[j]))
            if gm[j]:
                zc.append(j)
                zs.append(-1.0)
                rows.append((j, -1.0, f[j]))
            if p0[j]:
                zc.append(n + j)
                zs.append(1.0)
                rows.append((j, 0.0, 1.0))
        zc = np.array(zc, int)
        zs = np.array(zs)
        E = np.zeros((len(rows), 2 * n))
        for i, (j, cq, cp) in enumerate(rows):
            E[i, j] = cq
            E[i, n + j] = cp
        Kt = K[:, zc] * zs[None, :]
        rwt = rw.copy()
        if U.size:
            KUU = K[np.ix_(U, U)]
            sol = np.linalg.solve(KUU, np.column_stack([K[U][:, zc] * zs[None, :], rw[U]]))
            Kt = Kt - K[:, U] @ sol[:, :-1]
            rwt = rwt - K[:, U] @ sol[:, -1]
        M = E @ Kt
        qv = E @ rwt
        z = lemke(M, qv)
        if z is None:
            raise RateProblemError(
                "the rate problem has no solution at this state (Lemke ray termination); "
                + likely_cause(self.sys))
        xd = np.zeros(2 * n)
        np.add.at(xd, zc, zs * z)
        if U.size:
            xd[U] = -np.linalg.solve(KUU, rw[U] + K[np.ix_(U, zc)] @ (zs * z))
        rd = rw + K @ xd
        ztol = rate_tol / float(np.max(np.diag(K)))
        modes = np.full(n, STICK, np.int8)
        modes[sep] = SEPARATED
        # map z back to node modes
        k = 0
        for j in np.flatnonzero(gp | gm | p0):
            zp = zm = zw = 0.0
            if gp[j]:
                zp = z[k]
                k += 1
            if gm[j]:
                zm = z[k]
                k += 1
            if p0[j]:
                zw = z[k]
                k += 1
            if zw > ztol:
                modes[j] = SEPARATED
            elif zp > ztol and zp >= zm:
                modes[j] = SLIP_POS
            elif zm > ztol:
                modes[j] = SLIP_NEG
        return modes, xd, rd
