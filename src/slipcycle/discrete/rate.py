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
4th ed., §2.1.4).

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

from slipcycle.discrete.lcp import lemke
from slipcycle.discrete.model import SEPARATED, SLIP_NEG, SLIP_POS, STICK, FrictionalSystem
from slipcycle.errors import SolverError

__all__ = ["RateSolver", "RateProblemError"]


@njit(cache=True)
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


@njit(cache=True)
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
    into the hole (swap-delete, the order :meth:`RateSolver._remove` keeps). One pass
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

    def __init__(self, system: FrictionalSystem, force_tol: float):
        self.sys = system
        self.n = system.n_nodes
        self.K = np.ascontiguousarray(system.K)
        self.f = np.asarray(system.friction)
        self.force_tol = float(force_tol)
        self.disp_tol = self.force_tol / float(np.max(np.diag(system.C)))
        self._unk: np.ndarray | None = None   # keys of the current mode system's unknowns
        # its inverse, kept current by O(k²) updates in place: the leading k × k block of
        # a buffer with room to grow (doubling), so that an event allocates no k × k array
        self._P = np.zeros((0, 0))
        self._updates = 0
        self._modes_key = None
        self._arrays = None
        # rows K[col_b] of the unknowns, in the order of ``_unk`` (K is symmetric, so these
        # are its columns; rows of a C-ordered matrix are contiguous): kept current row by
        # row, O(N) per unknown added or removed, never gathered from all of K per event
        self._Kr = np.zeros((0, 2 * self.n))
        self._mark = np.zeros(8 * self.n + 4, bool)   # scratch for key-set differences
        self.stats = {"solves": 0, "factorizations": 0, "updates": 0, "pivots": 0,
                      "lemke": 0}

    # -- active inequalities -------------------------------------------------------------
    def flags(self, x: np.ndarray, r: np.ndarray):
        """Active inequalities at state x, reactions r: (g+, g−, p=0 in contact, separated)."""
        n, f, tol = self.n, self.f, self.force_tol
        q, p, w = r[:n], r[n:], x[n:]
        sep = w > self.disp_tol
        gp = (f * p + q <= tol) & ~sep
        gm = (f * p - q <= tol) & ~sep
        # both sides of the friction limit active means f p ≤ tol: the node is at the
        # apex, where it may open too (without that option a load that pulls it open has
        # no rate solution)
        p0 = ((p <= tol) | (gp & gm)) & ~sep
        return gp, gm, p0, sep

    @property
    def _Minv(self) -> np.ndarray:
        """The inverse of the current mode matrix (k, k): a view into its buffer."""
        k = 0 if self._unk is None else self._unk.size
        return self._P[:k, :k]

    def _room(self, k: int) -> None:
        """Make the inverse's buffer hold at least k × k (doubling, keeping the content)."""
        if self._P.shape[0] < k:
            cap = min(max(2 * k, 16), 2 * self.n)
            buf = np.empty((cap, cap))
            kk = 0 if self._unk is None else min(self._unk.size, self._P.shape[0])
            buf[:kk, :kk] = self._P[:kk, :kk]
            self._P = buf

    def _store(self, Minv: np.ndarray) -> None:
        k = Minv.shape[0]
        if self._P.shape[0] < k:
            cap = min(max(2 * k, 16), 2 * self.n)
            self._P = np.empty((cap, cap))
        self._P[:k, :k] = Minv

    # -- rates for a given mode set --------------------------------------------------------
    # Each unknown has an integer key 4*col + kind: col is its index in x = [v, w], kind 1 a
    # positive-slip equation f ṗ_j + q̇_j = 0, kind 2 a negative-slip equation
    # f ṗ_j − q̇_j = 0, kind 3 a separated node (q̇_j = 0 for col = j, ṗ_j = 0 for col = N+j).
    def _keys(self, modes: np.ndarray) -> np.ndarray:
        n = self.n
        slip_p = np.flatnonzero(modes == SLIP_POS)
        slip_n = np.flatnonzero(modes == SLIP_NEG)
        sep = np.flatnonzero(modes == SEPARATED)
        return np.sort(np.concatenate([4 * slip_p + 1, 4 * slip_n + 2, 4 * sep + 3,
                                       4 * (n + sep) + 3]))

    def _decode(self, keys: np.ndarray):
        n, f = self.n, self.f
        cols = keys // 4
        kind = keys % 4
        j = cols % n
        cq = np.where(kind == 1, 1.0, np.where(kind == 2, -1.0, (cols < n).astype(float)))
        cp = np.where(kind == 3, (cols >= n).astype(float), f[j])
        return cols, j, cq, cp

    def _entries(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Mode-system entries M[a, b] = c_q K[j_a, col_b] + c_p K[N + j_a, col_b]."""
        _, j, cq, cp = self._decode(rows)
        c = cols // 4
        K = self.K
        return cq[:, None] * K[j[:, None], c[None, :]] + cp[:, None] * K[(self.n + j)[:, None],
                                                                          c[None, :]]

    def _rebuild(self, keys: np.ndarray) -> bool:
        self.stats["factorizations"] += 1
        self._updates = 0
        self._unk = keys
        self._Kr = self._grow(keys.size)
        self._Kr[:keys.size] = self.K[keys // 4]
        if keys.size == 0:
            return True
        M = self._entries(keys, keys)
        try:
            Minv = np.linalg.inv(M)
        except np.linalg.LinAlgError:
            self._unk = None
            return False
        cond = np.abs(M).sum(axis=0).max() * np.abs(Minv).sum(axis=0).max()
        if not np.isfinite(cond) or cond > 1e13:
            self._unk = None
            return False
        self._store(Minv)
        return True

    def _grow(self, k: int) -> np.ndarray:
        """The row buffer with room for ``k`` unknowns (doubling: amortised O(N) per row)."""
        if self._Kr.shape[0] < k:
            buf = np.empty((max(2 * k, 16), 2 * self.n))
            kk = 0 if self._unk is None else min(self._Kr.shape[0], self._unk.size)
            buf[:kk] = self._Kr[:kk]
            self._Kr = buf
        return self._Kr

    def _remove(self, idx: np.ndarray) -> None:
        """Drop unknowns at positions ``idx``: Schur-complement formula on the inverse.

        The last unknowns move into the holes (swap-delete), so that only the rows of K
        that change place are copied: O(r N + k² r) for r removed of k unknowns."""
        buf = self._Kr
        if idx.size == 1:
            # one unknown leaves (the usual event): in place, one pass over k² entries
            i, k = int(idx[0]), self._unk.size
            _remove_one(self._P, k, i)
            if i != k - 1:
                buf[i] = buf[k - 1]
                self._unk[i] = self._unk[k - 1]
            self._unk = self._unk[:k - 1].copy()
            return
        P = self._Minv
        order = np.arange(P.shape[0])
        size = order.size
        for i in np.sort(idx)[::-1]:
            size -= 1
            if i != size:
                order[i] = order[size]
                buf[i] = buf[size]
        keep = order[:size]
        Pkr = P[np.ix_(keep, idx)]
        Prk = P[np.ix_(idx, keep)]
        Prr = P[np.ix_(idx, idx)]
        self._store(P[np.ix_(keep, keep)] - Pkr @ np.linalg.solve(Prr, Prk))
        self._unk = self._unk[keep]

    def _add(self, new: np.ndarray) -> bool:
        """Add unknowns ``new`` by block bordering of the inverse."""
        old = self._unk
        if new.size == 1:
            # one node changes state (the usual event): bordering in place, O(k²)
            k = old.size
            self._room(k + 1)
            bcol = self._entries(old, new)[:, 0]
            crow = self._entries(new, old)[0]
            d = float(self._entries(new, new)[0, 0])
            sch = _border_one(self._P, k, np.ascontiguousarray(bcol),
                              np.ascontiguousarray(crow), d)
            if not (np.isfinite(sch) and sch != 0.0):
                return False
            buf = self._grow(k + 1)
            buf[k] = self.K[new[0] // 4]
            self._unk = np.concatenate([old, new])
            return True
        P = self._Minv
        Bm = self._entries(old, new)          # (k, r) new columns, old rows
        Cm = self._entries(new, old)          # (r, k) new rows, old columns
        Dm = self._entries(new, new)          # (r, r)
        PB = P @ Bm
        CP = Cm @ P
        S = Dm - Cm @ PB
        if S.shape == (1, 1):
            # one node changes state (the usual event): a scalar pivot, no LAPACK call
            if not (np.isfinite(S[0, 0]) and S[0, 0] != 0.0):
                return False
            Sinv = 1.0 / S
        else:
            try:
                Sinv = np.linalg.inv(S)
            except np.linalg.LinAlgError:
                return False
        if not np.all(np.isfinite(Sinv)) or (
                np.abs(S).sum(axis=0).max() * np.abs(Sinv).sum(axis=0).max() > 1e13):
            return False
        k, r = P.shape[0], S.shape[0]
        Q = np.empty((k + r, k + r))
        PBS = PB @ Sinv
        Q[:k, :k] = P + PBS @ CP
        Q[:k, k:] = -PBS
        Q[k:, :k] = -Sinv @ CP
        Q[k:, k:] = Sinv
        buf = self._grow(k + r)
        buf[k:k + r] = self.K[new // 4]
        self._store(Q)
        self._unk = np.concatenate([old, new])
        return True

    def _set_modes(self, modes: np.ndarray) -> bool:
        """Make the inverse of the mode system current for ``modes`` by block bordering
        (nodes that start to slip or separate) and Schur-complement removal (nodes that
        stick), O(k² r) for r changed unknowns."""
        key = modes.tobytes()
        if key == self._modes_key and self._unk is not None:
            return True
        self._arrays = None
        target = self._keys(modes)
        if self._unk is None:
            ok = self._rebuild(target)
        else:
            mark, unk = self._mark, self._unk
            mark[target] = True
            drop = np.flatnonzero(~mark[unk])
            mark[target] = False
            mark[unk] = True
            add = target[~mark[target]]
            mark[unk] = False
            nchange = drop.size + add.size
            if nchange == 0:
                ok = True
            elif nchange > max(8, target.size // 2) or self._updates > 400:
                ok = self._rebuild(target)
            else:
                if drop.size:
                    self._remove(drop)
                ok = True
                if add.size:
                    ok = self._add(add)
                    if not ok:
                        self._unk = None
                self._updates += nchange
                self.stats["updates"] += nchange
        self._modes_key = key if ok else None
        return ok

    def rates(self, modes: np.ndarray, rw: np.ndarray):
        """Rates (ẋ, ṙ), both (2N,), for the mode set ``modes`` and load rate ``rw``.

        Returns None if the mode set's system is singular.
        """
        self.stats["solves"] += 1
        if not self._set_modes(modes):
            return None
        xd = np.zeros(2 * self.n)
        if self._unk.size == 0:
            return xd, rw.copy()
        if self._arrays is None:
            self._arrays = self._decode(self._unk)
        cols, j, cq, cp = self._arrays
        sol, rd = _mode_rates(self._Minv, self._Kr, cq * rw[j] + cp * rw[self.n + j], rw)
        xd[cols] = sol
        return xd, rd

    # -- consistency --------------------------------------------------------------------
    def violations(self, modes, flags, xd, rd, rate_tol):
        """Boolean (N,) array: nodes whose active inequalities fail, and the mode to try."""
        n, f = self.n, self.f
        gp, gm, p0, sep = flags
        vd, wd = xd[:n], xd[n:]
        qd, pd = rd[:n], rd[n:]
        gpd = f * pd + qd
        gmd = f * pd - qd
        vtol = rate_tol / float(np.max(np.diag(self.K)))
        stick = modes == STICK
        spos = modes == SLIP_POS
        sneg = modes == SLIP_NEG
        smode = modes == SEPARATED
        p_bad = p0 & (pd < -rate_tol)
        gp_bad = gp & (gpd < -rate_tol)
        gm_bad = gm & (gmd < -rate_tol)
        new = modes.copy()
        bad = np.zeros(n, bool)
        # stick
        b = stick & (p_bad | gp_bad | gm_bad)
        new[b & gm_bad] = SLIP_NEG
        new[b & gp_bad] = SLIP_POS
        new[b & p_bad] = SEPARATED
        bad |= b
        # slip positive / negative
        for m, wrong, other_bad in ((spos, vd < -vtol, gm_bad), (sneg, vd > vtol, gp_bad)):
            b = m & (p_bad | wrong | other_bad)
            new[b] = STICK
            new[b & p_bad] = SEPARATED
            bad |= b
        # separated at w = 0
        b = smode & ~sep & (wd < -vtol)
        new[b] = STICK
        bad |= b
        return bad, new

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
        flags = self.flags(x, r)
        gp, gm, p0, sep = flags
        modes = guess.astype(np.int8, copy=True)
        modes[(modes == SLIP_POS) & ~gp] = STICK
        modes[(modes == SLIP_NEG) & ~gm] = STICK
        modes[(modes == SEPARATED) & ~p0] = STICK
        modes[sep] = SEPARATED
        rate_tol = 1e-9 * float(np.max(np.abs(rw), initial=0.0)) + 1e-300
        crit = gp | gm | p0
        seen = set()
        block = True
        best = None
        for _ in range(4 * self.n + 20):
            res = self.rates(modes, rw)
            if res is None:
                break
            xd, rd = res
            if not crit.any():
                return modes, xd, rd
            bad, new = self.violations(modes, flags, xd, rd, rate_tol)
            nbad = int(bad.sum())
            if nbad == 0:
                return modes, xd, rd
            self.stats["pivots"] += 1
            key = modes.tobytes()
            if key in seen:
                break
            seen.add(key)
            if best is not None and nbad >= best:
                block = False
            best = nbad if best is None else min(best, nbad)
            if block:
                modes = new
            else:
                j = int(np.flatnonzero(bad)[0])
                modes = modes.copy()
                modes[j] = new[j]
        return self._lemke(x, r, rw, flags, rate_tol)

    def _lemke(self, x, r, rw, flags, rate_tol):
        """Fall-back: Lemke's method on the LCP of the critical nodes."""
        self.stats["lemke"] += 1
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
                "the friction coefficient is probably above f_crit for the current set of "
                "slipping and separated nodes")
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
