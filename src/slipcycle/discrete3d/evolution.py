"""Quasi-static evolution on the Coulomb cone: implicit load steps with step control.

The cone is not piecewise linear, so the exact event location of the 2-D model does not
apply: a slipping node's direction turns continuously. The load path (linear between load
samples, as in 2-D) is followed in *load steps*; each step is the incremental problem of
backward Euler in the load parameter — given the load increment Δr^w, find the slip
increments Δv and the separations w with the cone conditions holding at the end of the
step (the return map of :mod:`~slipcycle.discrete3d.cone`). It is solved exactly (to
round-off) by a semismooth Newton method on the Alart–Curnier equations (Alart & Curnier
1991; Christensen, Klarbring, Pang & Strömberg 1998) with a global–local structure: at
each iterate the nodes are classified from the augmented variables; stuck nodes get
Δv_j = 0 and closed nodes w_j = 0 exactly (their Newton rows are the identity), and the
Newton system is condensed onto the unknowns of the slipping (Δv_j, 2 each) and separated
(Δv_j, w_j, 3 each) nodes, m ≪ 3N: its matrix is the rows of K for those unknowns with the
cone's 2×2 linearisation on the slipping rows. With the active set held fixed the Newton
iteration runs on the m unknowns alone, following only the reactions of their rows
(r_V ← r_V + K[V, U] δ, the block K[V, U] cached per active set); the reactions of all
nodes are then updated once, r ← r + K[:, U] Δ, and every node is classified again, until
no node changes state. The LU factors of the Newton matrix are kept per active set and
reused (chord steps) over the iterations and the following steps while the residual
falls at least fourfold per step, so that most steps need no factorisation; the two half
steps of the step control start from the full step's solution (its midpoint, its end),
a predictor that leaves the solution unchanged. A step costs O(N m) for the reaction
update and O(m²) per iteration, plus O(m³) when the active set is new; with the
separated nodes condensed out (:meth:`StepSolver._separated_block`) an iteration touches
only the slip unknowns and the separations, O((3 ns + npp) 2 ns), and the separated
nodes' slips follow once per round. The rounds and
iterations run compiled (:mod:`~slipcycle.discrete3d._kernels`); Python picks the cached
block of an active set and factorises new Newton matrices.

Step control (step doubling, as for ODE integrators): each load interval is solved as one
step and as two half steps; if the end states differ by more than ``step_tol`` × the
displacement scale (or their dissipations by ``step_tol`` × min(1, 10 f_max) × force ×
displacement scale: below f = 0.1, in proportion to what a step can dissipate)
the interval is halved recursively (at most ``max_depth`` times), else the two half steps
are kept. A step in which no node slips and no node changes between contact and
separation is linear elasticity on a linear load path, hence exact, and is kept without
doubling. Where no node changes state over the interval (smooth slip) the half-step
result is Richardson-extrapolated (:meth:`Evolution3D._extrapolate`), second order, and
accepted at ``step_tol^(2/3)`` (its error is about the estimate to the power 3/2).
With one tangential direction a step is exact unless a node stops or reverses
inside it (the end state depends only on the end modes), so the control refines exactly
around those instants, like the event location of the 2-D model; on the cone the error
per backward-Euler step is O(h²) (the direction turns): first order overall with fixed
steps, second order with the extrapolation (measured orders in ``docs/discrete3d.md``).

Events inside a step. Backward Euler keeps the end state's node modes over the whole
step: a node that closes inside it would keep the slip of the step's start, and a node
that stops because another one starts to slip (or closes) would lose its slip before that
instant; when the instant lies in the first half of the step the full step and the two
half steps agree and step doubling does not see it. So a step whose end state shows a
node closed that was open, or open that was closed (the sign of φ_j = p_j − ρ_n w_j), or,
in a step in which a slipping node stops, a node slipping that was stuck (the sign of
ψ_j = |q_j − ρ_t Δv_j| − f_j φ_j), is split at the first such instant, located by a
secant iteration on steps of a fraction of the step (:meth:`Evolution3D._locate_event`;
exact for one tangential direction, where φ and ψ are affine between events), as the
2-D model's event-driven solver does by construction; the node then takes its state
from that instant. With fixed steps every such event is located (to ``event_tol``); with
step doubling only as far as the step control's tolerance asks: an event whose
neglect moves no node by more than ``step_tol`` × the displacement scale is not located,
and the location stops once the rest to the event is below half that. Each located
event costs a few solves (the secant iterations, and the step split in two).

Energy bookkeeping per step (trapezoidal): D_j += −½(q_j⁰ + q_j¹)·Δv_j and
W += ½(x⁰ + x¹)·Δr^w; with these the discrete stored energy Π = ½xᵀKx + r^wᵀx changes by
exactly W − ΣD + Σ ½(p⁰ + p¹)Δw (the last term vanishes except in steps where a node
opens or closes).

Replay of a recorded subdivision. Every adaptive path records its accepted sub-steps per
load interval (:attr:`PathTotals3D.plan`: the fractions of the interval, the depth, how
the step was kept — exact full step, two half steps, two half steps with the
extrapolation — and the node states at the ends of its steps). With ``plan`` set,
:meth:`Evolution3D.follow` solves the same steps again without the error estimates and
without the rejected coarser steps: only the steps that the adaptive method would keep
(for an extrapolated step also the full step it needs). Where the adaptive decisions on
the new path are the recorded ones, the result equals the adaptive method's to the
Newton tolerance; the path map is then one fixed function instead of a piecewise one
whose refinement decisions may switch from path to path. The Newton tolerance matters
here: the converged step depends on the iteration's path (predictor, chord matrices
kept from earlier steps) through the residual left, and with slipping nodes of small
effective stiffness a residual of 1e-11 × the force scale moved a whole cycle by up to
4e-6 × the displacement scale (the same adaptive cycle repeated from the same state
with other kept matrices; FE-like chain of 60 nodes, ``step_tol`` 1e-5), enough to keep
a ``tol`` of 1e-7 out of reach; with 1e-13 (the default) the repeat agrees within 1e-12.
Where an end state of a sub-step differs from the recorded one, and with ``check_plan``
everywhere, the full step is solved too and the error estimate checked; a recorded step
whose estimate now exceeds the tolerance (or that is no longer exact) is redone
adaptively and counted in :attr:`PathTotals3D.replay_mismatches` (the recorded
subdivision no longer fits). Replay cannot see that the adaptive method would now accept
a coarser step; the caller verifies a result obtained by replay with an adaptive path
(:func:`~slipcycle.discrete3d.steady.simulate3d`).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
from scipy.linalg import LinAlgError, cho_factor, cho_solve
from scipy.linalg.lapack import dgetrf

from slipcycle.coupled.system import likely_cause
from slipcycle.discrete3d._kernels import (
    active_newton,
    active_residual,
    add_at,
    add_rows,
    book_step,
    classify_nodes,
    copy_block,
    doubling_error,
    event_crossings,
    event_values,
    fix_nodes,
    gather_block,
    row_terms,
    slip_jacobian,
    slip_rounds,
)
from slipcycle.discrete3d.cone import slip_linearisation
from slipcycle.discrete3d.model import SEPARATED, SLIP, STICK, FrictionalSystem3D
from slipcycle.errors import SolverError

__all__ = ["StepSolver", "Step", "Evolution3D", "PathTotals3D", "IncrementalSolverError"]


class IncrementalSolverError(SolverError):
    """The incremental problem of a load step could not be solved even on the smallest
    step (ill-posed system, or a friction coefficient above the critical value)."""


@dataclass
class Step:
    """One solved load step.

    Attributes
    ----------
    x, r : (3N,) arrays
        State [v, w] (m) and reactions [q, p] (N) at the end of the step.
    modes : (N,) int8 array
        Node states at the end (STICK, SLIP, SEPARATED).
    drw : (3N,) array
        The load increment [N].
    iterations : int
        Newton iterations.
    """

    x: np.ndarray
    r: np.ndarray
    modes: np.ndarray
    drw: np.ndarray
    iterations: int


def _nbytes(value) -> int:
    if isinstance(value, np.ndarray):
        return value.nbytes
    if isinstance(value, tuple):
        return sum(_nbytes(v) for v in value)
    return 0


class _Cache:
    """Least-recently-used cache of arrays (or tuples of them), bounded in bytes.

    The blocks and factors kept per active set are exact functions of the set, so how
    many are kept changes the cost of a run, never its numbers. A steady cycle revisits
    the same sets every cycle: keeping a whole cycle's worth saves their recomputation.
    """

    def __init__(self, max_bytes: int, max_entries: int = 4096):
        self.max_bytes, self.max_entries = int(max_bytes), int(max_entries)
        self._items: OrderedDict = OrderedDict()
        self.nbytes = 0

    def get(self, key):
        item = self._items.get(key)
        if item is None:
            return None
        self._items.move_to_end(key)
        return item[0]

    def put(self, key, value) -> None:
        size = _nbytes(value)
        if key in self._items:
            self.nbytes -= self._items.pop(key)[1]
        if size > self.max_bytes:
            return
        while self._items and (self.nbytes + size > self.max_bytes
                               or len(self._items) >= self.max_entries):
            self.nbytes -= self._items.popitem(last=False)[1][1]
        self._items[key] = (value, size)
        self.nbytes += size


class StepSolver:
    """Semismooth Newton solver of the incremental problem of one load step.

    The Newton matrix factorised for an active set is reused (chord steps) while each
    step reduces the residual at least by the factor ``chord_rate``.

    Parameters
    ----------
    system : FrictionalSystem3D
    force_scale : float
        Typical load [N]; the Newton residual tolerance is ``rel_tol`` × it.
    rel_tol : float
        Relative residual tolerance of the Newton iteration (module docstring, replay:
        the cycle map is reproducible to about 1e-12 with the default).
    max_iter : int
        Newton iterations before the step is declared failed (the caller halves it).
    cache_bytes : int, optional
        Bound of each cache of per-active-set blocks and factors [bytes] (default
        :attr:`cache_bytes`, and at most 8 × the bytes of K above 256 MiB); the steps do
        not depend on it.
    """

    #: largest residual ratio of a chord step before the Newton matrix is refactorised
    chord_rate = 0.25
    #: condense the separated nodes' rows out of the Newton matrix once per active set
    #: (:meth:`_separated_block`); False: factorise the whole active block every time
    eliminate_separated = True
    #: upper bound of each of the three per-active-set caches [bytes]
    cache_bytes = 2 ** 30
    #: the Newton tolerance of an active set is at least this many units of round-off
    #: of the largest reaction of its rows (:meth:`_tolerance`)
    roundoff_ulps = 4.0

    def __init__(self, system: FrictionalSystem3D, force_scale: float,
                 rel_tol: float = 1e-13, max_iter: int = 60,
                 cache_bytes: int | None = None):
        self.sys = system
        n = self.n = system.n_nodes
        self.K = np.ascontiguousarray(system.K)
        self.f = np.asarray(system.friction, float)
        A, C = system.A, system.C
        # augmentation parameters: the node's own stiffness, so that stick/slip and
        # contact/separation are decided on comparable force scales
        self.rho_t = 0.5 * (np.diag(A)[0::2] + np.diag(A)[1::2])
        self.rho_n = np.diag(C).copy()
        self.force_tol = rel_tol * force_scale
        self.max_iter = max_iter
        self.stats = {"solves": 0, "newton_iterations": 0, "failures": 0,
                      "factorisations": 0}
        self._rows_q = np.arange(2 * n).reshape(n, 2)
        # Σ_j |K_ij| per row, in blocks of rows (no |K| the size of K): the round-off
        # scale of the rows (:meth:`_tolerance`)
        self._row_abs = np.concatenate([np.abs(self.K[i:i + 512]).sum(axis=1)
                                        for i in range(0, self.K.shape[0], 512)])
        # exact per-set blocks and factors: a steady cycle's worth within a memory bound
        limit = self.cache_bytes if cache_bytes is None else cache_bytes
        budget = min(limit, max(2 ** 28, 8 * self.K.nbytes))
        self._blocks = _Cache(budget)
        self._elims = _Cache(budget)
        self._chos = _Cache(budget)
        # the condensed blocks last used per separated set (:meth:`_coupling`): solver
        # state like the chord-step factors (they enter the steps at round-off, so their
        # bound is a function of the system, not of cache_bytes)
        self._condensed = _Cache(max(2 ** 26, 4 * self.K.nbytes))
        # the chord-step factors change the Newton path (not the solution): few are kept
        self._max_blocks = 8
        self._lus: dict = {}
        # the nodes condensed out statically while they stay open (:meth:`condense`)
        self._open: _OpenCondensation | None = None
        self._loads: np.ndarray | None = None
        self._recondense_left = self.recondense_max
        self._condensations: OrderedDict = OrderedDict()

    def solve(self, x0: np.ndarray, r0: np.ndarray, drw: np.ndarray,
              guess: tuple | None = None) -> Step | None:
        """Solve one load step from state ``x0`` (3N,) with reactions ``r0`` (3N,) under the
        load increment ``drw`` (3N,).

        Parameters
        ----------
        x0, r0, drw : (3N,) arrays
            Start state [m], its reactions [N] and the load increment [N].
        guess : (x, r) of (3N,) arrays, optional
            Starting iterate of the Newton method and its reactions
            ``r = r0 + drw + K (x − x0)`` (a predictor; the solution does not depend on
            it). If the iteration fails from it, it is repeated from ``x0``.

        Returns
        -------
        Step or None
            None if the Newton iteration did not converge within ``max_iter``.
        """
        cond = self._open
        while cond is not None:
            step, closing = cond.solve(x0, r0, drw, guess)
            if step is not None:
                return step
            if closing is None:
                break
            # condensed nodes close in the step: the step again with them kept (at most
            # recondense_max times per condensation from outside, then the whole system)
            self.stats["open_fallbacks"] = self.stats.get("open_fallbacks", 0) + 1
            budget = self._recondense_left - 1
            self.condense(cond.nodes[~closing] if budget >= 0 else None, self._loads)
            self._recondense_left = budget
            cond = self._open
        # the condensed Newton iteration failed: this step on the whole system; if that
        # fails too, the caller shortens the step, which may be solved condensed again
        kept, self._open = self._open, None
        step = self._whole(x0, r0, drw, guess)
        self._open = kept
        return step

    def _whole(self, x0, r0, drw, guess) -> Step | None:
        """:meth:`solve` on the whole system."""
        if guess is not None:
            step = self._newton(x0, guess[0].copy(), guess[1].copy(), drw)
            if step is not None:
                return step
        return self._newton(x0, x0.copy(), r0 + drw, drw)

    #: fewest nodes worth a static condensation (:meth:`condense`): below ~100 open
    #: nodes (300 unknowns) a separated block factorises in about a millisecond and the
    #: condensed solver's cold caches cost more than it saves (203-node lap joint:
    #: 70 open nodes, 17.8 s whole, 22.4 s condensed)
    condense_min_nodes = 100
    #: condensations of fewer nodes after condensed nodes closed (:meth:`solve`), per
    #: condensation set from outside (a path, a load interval): each costs about as
    #: much as a few steps on the whole system (751-node lap joint: 7 in its first
    #: cycle, 2 in its assembly)
    recondense_max = 32

    def condense(self, nodes: np.ndarray | None, loads: np.ndarray | None = None) -> None:
        """Solve the following steps with the nodes ``nodes`` (N_o,) condensed out
        statically, or on the whole system (None, or fewer than
        :attr:`condense_min_nodes`). ``loads`` (S, 3N): the samples of the path to be
        followed, whose increments' maps onto the open nodes are computed once
        (:meth:`_OpenCondensation.span`).

        An open node carries no reaction: its three rows are linear, K_OC Δx_C +
        K_OO Δx_O + Δr^w_O = 0, so while the nodes stay open the step is the same
        incremental problem on the other nodes with the stiffness
        K* = K_CC − K_CO K_OO⁻¹ K_OC and the load increment Δr^w_C − K_CO K_OO⁻¹ Δr^w_O
        (static condensation), and Δx_O follows. The per-active-set work of the Newton
        iteration (the separated block, :meth:`_separated_block`, factorised for every
        new separated set) then covers only the nodes that open and close. A step whose
        end leaves condensed nodes closed (p_j − ρ_n w_j > 0) is solved again with those
        nodes kept (the others condensed: a condensation of fewer nodes, used by the
        following steps too); a step whose condensed Newton iteration fails, on the
        whole system. The condensed K* (and its caches) is kept for the two latest node
        sets.
        """
        self._loads = loads
        self._recondense_left = self.recondense_max
        if nodes is None or len(nodes) < self.condense_min_nodes:
            self._open = None
            return
        nodes = np.asarray(nodes, np.int64)
        key = nodes.tobytes()
        cond = self._condensations.get(key)
        if cond is None:
            cond = _OpenCondensation(self, nodes)
            if len(self._condensations) >= 2:
                self._condensations.popitem(last=False)
            self._condensations[key] = cond
        cond.span(loads, 0.01 * self.force_tol)
        self._open = cond

    @property
    def condensing(self) -> bool:
        """A static condensation is active (:meth:`condense`)."""
        return self._open is not None

    def chord_state(self):
        """The kept chord-step factors (of the condensed solver too), to restore."""
        sub = None if self._open is None else dict(self._open.solver._lus)
        return dict(self._lus), self._open, sub

    def restore_chords(self, state) -> None:
        self._lus = state[0]
        # the condensed solver's factors only to the same condensation (a fallback may
        # have replaced it: its active sets are numbered otherwise)
        if self._open is not None and self._open is state[1]:
            self._open.solver._lus = state[2]

    def _newton(self, x0, x, r, drw) -> Step | None:
        """The semismooth Newton iteration from the iterate (x, r) (both modified)."""
        self.stats["solves"] += 1
        n, K, f = self.n, self.K, self.f
        xmax = float(np.max(np.abs(x0)))     # the rows' round-off scale (:meth:`_tolerance`)
        modes = np.empty(n, np.int8)
        fix_t = np.empty(n, np.bool_)
        fix_n = np.empty(n, np.bool_)
        slip = np.empty(n, np.int64)
        sep = np.empty(n, np.int64)
        it = rounds = 0
        pending = False       # the next round's classification is at hand (slip_rounds)
        while pending or (it < self.max_iter and rounds < self.max_iter):
            if not pending:
                rounds += 1
                # node states from the augmented variables (cone.node_states, one pass)
                count, ns, npp = classify_nodes(x, r, x0, f, self.rho_t, self.rho_n, modes,
                                                fix_t, fix_n, slip, sep)
                fixed = count > 0
                if fixed:
                    # the Newton rows of stuck / closed nodes are the identity: exact
                    fix_nodes(K, x, x0, r, fix_t, fix_n)
            pending = False
            if ns + npp == 0:
                if not fixed:
                    self.stats["newton_iterations"] += it
                    return Step(x, r, modes.copy(), drw, it)
                continue
            block = self._active_block(slip[:ns], sep[:npp])
            if npp == 0:
                # slipping nodes only: the rounds on this set run compiled
                code, it, rounds, count, ns, npp = self._slip_rounds(
                    block, x, r, x0, it, rounds, fixed, modes, fix_t, fix_n, slip, sep,
                    xmax)
                if code == 5:
                    self.stats["newton_iterations"] += it
                    return Step(x, r, modes.copy(), drw, it)
                if code == 4:
                    break
                fixed, pending = count > 0, True
                continue
            # x[U] and the reactions r are updated in place unless the round failed
            status, moved, it = self._local_newton(block, x, r, x0, it, xmax)
            if status == 0 and not fixed and not moved:
                self.stats["newton_iterations"] += it
                return Step(x, r, modes.copy(), drw, it)
            if status == 4:
                break
        self.stats["failures"] += 1
        return None

    def _tolerance(self, r: np.ndarray, V: np.ndarray, xmax: float) -> float:
        """The residual tolerance [N] of the Newton iteration on the active rows ``V``:
        ``force_tol`` (relative to the service cycle's force scale), but not below
        :attr:`roundoff_ulps` units of round-off of the terms of those rows,
        |r_i| + Σ_j |K_ij| ``xmax`` (r = r^w + K x, ``xmax`` = max |x| of the step's
        start), which no residual resolves: a service load 1e-8 of the preload asked for
        one under the preload's round-off, and the step ended in "no solution the
        Newton method can find". Rows not in the set do not count: a node clamped by a
        large force that stays stuck does not coarsen the others' tolerance."""
        floor = self.roundoff_ulps * _EPS * row_terms(r, V, self._row_abs, xmax)
        return max(self.force_tol, floor)

    def _slip_rounds(self, block, x, r, x0, it, rounds, fixed, modes, fix_t, fix_n, slip,
                     sep, xmax):
        """The rounds of :meth:`_newton` on an active set of slipping nodes only, compiled
        (:func:`~slipcycle.discrete3d._kernels.slip_rounds`) until the set changes (code
        6, its classification done), the step converges (5) or fails (4); the Newton
        matrices are factorised here (:meth:`_factorise`) and kept per set as in
        :meth:`_local_newton`; ``xmax`` (max |x| at the step's start) sets the floor of
        the residual tolerance (:meth:`_tolerance`).

        Returns
        -------
        code, it, rounds, count, ns, npp
        """
        key, U, V, KVU, fS, rhoS, rhoP = block
        m = U.size
        xU, rV, D = np.empty(m), np.empty(V.size), np.zeros(m)
        R, zs, zsn = np.empty(m), np.empty((fS.size, 2)), np.empty(fS.size)
        lu = self._lus.get(key)
        first, fresh, res_prev, stepped = True, False, np.inf, False
        tol = self._tolerance(r, V, xmax)
        while True:
            f_lu, piv = (lu[0], lu[1]) if lu is not None else (_NO_LU, _NO_PIV)
            code, it, rounds, res_prev, stepped, count, ns, npp = slip_rounds(
                self.K, x, r, x0, self.f, self.rho_t, self.rho_n, modes, fix_t, fix_n, slip,
                sep, U, V, first, fixed, xU, rV, D, fS, rhoS, KVU, f_lu, piv,
                lu is not None, fresh, it, rounds, self.max_iter, res_prev, stepped,
                tol, self.chord_rate, R, zs, zsn)
            if code != 3:
                return code, it, rounds, count, ns, npp
            lu = self._factorise(0, block, None, zs, zsn, rV[m:])
            if lu is None:
                return 4, it + 1, rounds, 0, 0, 0
            first, fresh = False, True

    def _active_block(self, S: np.ndarray, P: np.ndarray):
        """Unknowns U of the slipping (t1, t2) and separated (t1, t2, n) nodes, the rows
        V = U ∪ normal rows of the slipping nodes, the block K[V, U] and the nodes'
        friction coefficients and augmentation parameters (cached: the active set repeats
        over the Newton iterations and consecutive steps)."""
        key = (S.tobytes(), P.tobytes())
        hit = self._blocks.get(key)
        if hit is None:
            n = self.n
            S, P = S.copy(), P.copy()
            U = np.concatenate([self._rows_q[S].ravel(),
                                np.column_stack([self._rows_q[P], 2 * n + P]).ravel()])
            V = np.concatenate([U, 2 * n + S])
            hit = (key, U, V, gather_block(self.K, V, U), self.f[S].copy(),
                   self.rho_t[S].copy(), self.rho_n[P].copy())
            self._blocks.put(key, hit)
        return hit

    def _separated_block(self, key, KVU, ns, npp):
        """The separated nodes' rows condensed per active set (block elimination).

        With s = 2 ns slip unknowns and the separated ones P, the Newton matrix is
        [[J_SS, J_SP], [K_PS, K_PP]], where K_PP (a principal block of the positive
        definite K) does not depend on the iterate and the slip rows are a node-wise
        linear map L of the rows of K: J_S· = L(K_{VS,·}) (+ ρΦ on the own columns).
        Hence the Schur complement is the slip Jacobian of K̃ = K_{VS,S} − K_{VS,P} W,
        W = K_PP⁻¹ K_PS, a system of 2 ns unknowns instead of 2 ns + 3 npp: the lap
        joint's open nodes (most of its interface) cost one Cholesky per separated set.

        Returns
        -------
        tuple or None
            (Cholesky factor of K_PP, W (p, s), K̃ (s + ns, s), K_{VS,P} (s + ns, p));
            None when K_PP does not factorise (then the full matrix is used).
        """
        last = self._condensed.get(key[1])
        if last is not None and last[0] == key[0]:
            return last[1]
        s, m = 2 * ns, 2 * ns + 3 * npp
        # K_PP depends on the separated set only, which changes far less often than
        # the slipping one: its factor is kept per separated set
        cho = self._chos.get(key[1])
        if cho is None:
            try:
                cho = cho_factor(KVU[s:m, s:m], lower=True, check_finite=False)
            except LinAlgError:
                return None
            self._chos.put(key[1], cho)
        KSP = self._elims.get(key)
        if KSP is None:
            KSP = np.vstack([KVU[:s, s:m], KVU[m:, s:m]])
            self._elims.put(key, KSP)
        S = np.frombuffer(key[0], np.int64)
        W, Kt = self._coupling(S, cho, KVU, KSP, ns, last)
        hit = (cho, W, Kt, KSP)
        self._condensed.put(key[1], (key[0], hit, S))
        return hit

    @staticmethod
    def _coupling(S, cho, KVU, KSP, ns, last):
        """W = K_PP⁻¹ K_PS (p, s) and K̃ = K_{VS,S} − K_{VS,P} W (s + ns, s) of the
        slipping nodes ``S`` (:meth:`_separated_block`).

        The slipping set changes more often than the separated one, and a column of W
        depends only on the separated set and its own slip unknown, an entry of K̃ only
        on the separated set and its two nodes: what W and K̃ of the slipping set
        ``last`` (the one last used with this separated set, or None) hold for the nodes
        slipping in both is copied, and only the new nodes' columns of W (p² each
        instead of p² per column) and rows and columns of K̃ are computed. Each entry is
        computed once, so copies do not accumulate round-off.
        """
        s = 2 * ns
        m = KVU.shape[1]
        if last is None:
            W = np.ascontiguousarray(cho_solve(cho, KVU[s:m, :s], check_finite=False))
            return W, np.vstack([KVU[:s, :s], KVU[m:, :s]]) - KSP @ W
        S_last, (_, W_last, Kt_last, _) = last[2], last[1]
        pos = np.searchsorted(S_last, S)
        old = (pos < S_last.size) & (S_last[np.minimum(pos, S_last.size - 1)] == S)
        # the slip unknowns (the columns, the tangential rows of K̃), the normal rows
        cols_old, cols_new = np.flatnonzero(np.repeat(old, 2)), np.flatnonzero(
            np.repeat(~old, 2))
        src = (2 * pos[old, None] + np.arange(2)).ravel()
        rows_old = np.concatenate([cols_old, s + np.flatnonzero(old)])
        rows_src = np.concatenate([src, 2 * S_last.size + pos[old]])
        rows_new = np.concatenate([cols_new, s + np.flatnonzero(~old)])
        all_p = np.arange(m - s)
        W = np.empty((m - s, s))
        copy_block(W, all_p, cols_old, W_last, all_p, src)
        Kt = np.empty((s + ns, s))
        copy_block(Kt, rows_old, cols_old, Kt_last, rows_src, src)
        if cols_new.size:
            Wn = cho_solve(cho, KVU[s:m, cols_new], check_finite=False)
            W[:, cols_new] = Wn
            # row k of K̃'s base [K_{S,S}; K_{N,S}] is row k (tangential) or m + k − s
            # (normal) of KVU
            base = np.concatenate([np.arange(s), np.arange(m, m + ns)])
            Kt[:, cols_new] = gather_block(KVU, base, cols_new) - KSP @ Wn
            Kt[rows_new[:, None], cols_old] = (gather_block(KVU, base[rows_new], cols_old)
                                               - KSP[rows_new] @ W[:, cols_old])
        return W, Kt

    def _keep(self, key, lu) -> None:
        """Keep the factorised Newton matrix of an active set for chord steps."""
        if len(self._lus) >= self._max_blocks:
            self._lus.pop(next(iter(self._lus)))
        self._lus[key] = lu

    def _factorise(self, kind, block, elim, zs, zsn, pS):
        """The Newton matrix of an active set with slipping nodes at the current iterate,
        factorised: (lu, piv, phi, nvec) for
        :func:`~slipcycle.discrete3d._kernels.chord_newton` (``kind`` as there), or None
        if it is singular."""
        key, U, V, KVU, fS, rhoS, rhoP = block
        ns, npp = fS.size, rhoP.size
        self.stats["factorisations"] += 1
        phi, nvec = slip_linearisation(zs, zsn, pS, fS, rhoS)
        phi, nvec = np.ascontiguousarray(phi), np.ascontiguousarray(nvec)
        if kind == 2:
            J = slip_jacobian(elim[2], ns, 0, phi, nvec, fS, rhoS)
        else:
            J = slip_jacobian(KVU, ns, npp, phi, nvec, fS, rhoS)
        f_lu, piv, info = dgetrf(J, overwrite_a=True)
        if info != 0:           # singular Newton matrix
            return None
        lu = (np.asfortranarray(f_lu), piv, phi, nvec)
        self._keep(key, lu)
        return lu

    def _local_newton(self, block, x, r, x0, it, xmax):
        """Newton iterations on the active unknowns U with the active set held fixed
        (compiled: :func:`~slipcycle.discrete3d._kernels.active_newton`), then x[U] and
        the reactions r (both modified) updated by the change D of x[U].

        Only the reactions of the rows V are followed in the iterations
        (r_V += K[V, U] δ): the stuck and closed nodes do not enter the Newton system,
        and their reactions are updated once at the end (r += K[:, U] D), after which
        the caller re-classifies every node. The Newton matrix last factorised for this
        active set is reused (chord steps) while the residual falls at least fourfold
        per step; the converged solution is that of the Newton method with a fresh
        matrix, only the path differs. ``xmax`` (max |x| at the step's start) sets the
        floor of the residual tolerance (:meth:`_tolerance`).

        Returns
        -------
        status : int
            0 the residual of the active rows is within tolerance, 1 a node of the
            active set changed state, 2 ``max_iter`` reached, 4 a singular or
            non-finite Newton step (nothing applied).
        moved : bool
            D ≠ 0.
        it : int
            Iteration count after these iterations.
        """
        key, U, V, KVU, fS, rhoS, rhoP = block
        ns, npp, m = fS.size, rhoP.size, U.size
        tol = self._tolerance(r, V, xmax)
        if ns == 0:
            D, done, it = self._separated_newton(block, x[U], r[V], it, tol)
            if D is None:
                return 4, False, it
            moved = bool(np.any(D))
            if moved:
                add_at(self.K, U, D, x, r)
            return (0 if done else 1), moved, it
        xU, rV, D = np.empty(m), np.empty(V.size), np.zeros(m)
        R, zs, zsn = np.empty(m), np.empty((ns, 2)), np.empty(ns)
        # separated nodes beside slipping ones: eliminated (:meth:`_separated_block`)
        elim = (self._separated_block(key, KVU, ns, npp)
                if npp and self.eliminate_separated else None)
        kind, W, KSP, Kt, y = 0, _NO_W, _NO_W, _NO_W, _NO_Y
        ya = np.zeros(1, np.int64)
        if elim is not None:
            kind, W, Kt, KSP = 2, elim[1], elim[2], elim[3]
            rP = r[V[2 * ns:m]]
            if np.max(np.abs(rP)) > tol:
                # K_PP⁻¹ R_P of the separated rows, linear: zero after the first step. A
                # residual already within the Newton tolerance (the round-off the last
                # round left, in most rounds) is kept as it is, the steps solve
                # K_PS dS + K_PP dP = 0 and do not change it: a p² solve saved
                y = cho_solve(elim[0], rP, check_finite=False)
        lu = self._lus.get(key)
        res_prev, stepped, fresh, first = np.inf, False, False, True
        while True:
            f_lu, piv, phi, nvec = lu if lu is not None else _NO_FACTORS
            status, it, res_prev, stepped, moved = active_newton(
                kind, self.K, x, r, x0, U, V, first, xU, rV, D, fS, rhoS, rhoP, KVU, f_lu,
                piv, W, KSP, Kt, phi, nvec, y, ya, lu is not None, fresh, it, self.max_iter,
                res_prev, stepped, tol, self.chord_rate, R, zs, zsn)
            first = False
            if status == 3:
                lu = self._factorise(kind, block, elim, zs, zsn, rV[m:])
                if lu is None:
                    return 4, False, it + 1
                fresh = True
                continue
            return status, moved, it

    def _separated_newton(self, block, xU, rV, it, tol):
        """:meth:`_local_newton` of an active set of separated nodes only: the rows are
        linear, the Newton matrix is K_PP itself (its Cholesky factor kept); ``tol`` the
        residual tolerance (:meth:`_tolerance`)."""
        key, U, V, KVU, fS, rhoS, rhoP = block
        m = U.size
        D = np.zeros(m)
        R = np.empty(m)
        cho = self._lus.get(key)
        res_prev, stepped = np.inf, False
        while True:
            res, changed = active_residual(xU, rV, _NO_NVEC, fS, rhoS, rhoP, 0, rhoP.size,
                                           R, _NO_NVEC, _NO_Y)
            if stepped and changed:
                return D, False, it
            if res <= tol:
                return D, True, it
            if it >= self.max_iter:
                return D, False, it
            it += 1
            if cho is None or res > self.chord_rate * res_prev:
                self.stats["factorisations"] += 1
                try:
                    cho = cho_factor(KVU, lower=True, check_finite=False)
                except LinAlgError:
                    return None, False, it
                self._keep(key, cho)
            delta = cho_solve(cho, -R, check_finite=False)
            if not np.all(np.isfinite(delta)):
                return None, False, it
            res_prev, stepped = res, True
            D += delta
            xU += delta
            rV += KVU @ delta


class _OpenCondensation:
    """A set of open nodes condensed out of the incremental problem
    (:meth:`StepSolver.condense`): the condensed solver, and the maps back.

    Parameters
    ----------
    parent : StepSolver
    nodes : (N_o,) int array
        The condensed nodes, ascending.
    """

    def __init__(self, parent: StepSolver, nodes: np.ndarray):
        n = self.n = parent.n
        self.nodes = nodes
        kept = np.setdiff1d(np.arange(n), nodes)
        self.kept = kept
        # dofs in the layout [t1 t2 of each node, then n of each node]
        self.c = np.concatenate([parent._rows_q[kept].ravel(), 2 * n + kept])
        self.o = np.concatenate([parent._rows_q[nodes].ravel(), 2 * n + nodes])
        K = parent.K
        cho = cho_factor(K[np.ix_(self.o, self.o)], lower=True, check_finite=False)
        KOC = K[np.ix_(self.o, self.c)]
        # T = K_OO⁻¹ K_OC: Δx_O = −K_OO⁻¹ Δr^w_O − T Δx_C; kept transposed (c, o), so
        # that the rows of the unknowns a step changed are contiguous
        T = cho_solve(cho, KOC, check_finite=False)
        self.cho, self.Tt = cho, np.ascontiguousarray(T.T)
        Ks = K[np.ix_(self.c, self.c)] - KOC.T @ T
        Ks = 0.5 * (Ks + Ks.T)
        nc = kept.size
        sub = SimpleNamespace(n_nodes=nc, K=Ks, friction=parent.f[kept],
                              A=Ks[:2 * nc, :2 * nc], C=Ks[2 * nc:, 2 * nc:])
        solver = StepSolver(sub, 1.0, max_iter=parent.max_iter)
        # the whole system's tolerance and augmentation parameters: the same Newton path
        solver.force_tol = parent.force_tol
        solver.rho_t, solver.rho_n = parent.rho_t[kept], parent.rho_n[kept]
        solver.stats = parent.stats
        self.solver = solver
        self.rho_o = parent.rho_n[nodes]
        self._span = None

    #: largest dimension of a path's load increments whose maps are kept (:meth:`span`)
    max_span = 8

    def span(self, loads: np.ndarray | None, tol: float) -> None:
        """Compute the maps K_OO⁻¹ Δr^w_O and T^T Δr^w_O of the load increments of a
        path through the samples ``loads`` (S, 3N) once, on an orthonormal basis Q of
        the span of loads[k]_O − loads[0]_O (every increment of the path lies in it: a
        cycle's increments are multiples of one or two load vectors). A step's
        increment is then mapped through its coordinates Qᵀ Δr^w_O when its part
        outside the span (round-off of the difference of two loads) is below ``tol``
        [N], a hundredth of the Newton tolerance, else directly."""
        self._span = None
        if loads is None or len(loads) < 2:
            return
        d = (loads[1:, self.o] - loads[0, self.o]).T
        if not np.any(d):
            return
        u, sv, _ = np.linalg.svd(d, full_matrices=False)
        Q = u[:, sv > 1e-12 * sv[0]]
        if Q.shape[1] > self.max_span:
            return
        self._span = (np.ascontiguousarray(Q.T), cho_solve(self.cho, Q, check_finite=False),
                      self.Tt @ Q, tol)

    def _maps(self, dro: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(K_OO⁻¹ Δr^w_O, Tᵀ Δr^w_O) of the open nodes' load increment ``dro``."""
        if self._span is not None:
            Qt, G, H, tol = self._span
            coef = Qt @ dro
            if np.max(np.abs(dro - coef @ Qt)) <= tol:
                return G @ coef, H @ coef
        if not np.any(dro):
            return np.zeros(self.o.size), np.zeros(self.c.size)
        return cho_solve(self.cho, dro, check_finite=False), self.Tt @ dro

    def solve(self, x0, r0, drw, guess):
        """The step on the condensed system, mapped back to the whole one.

        Returns
        -------
        step : Step or None
            None if the condensed Newton iteration failed or a condensed node closes.
        closing : (N_o,) bool array or None
            The condensed nodes the step leaves closed (p_j − ρ_n w_j > 0), when it does.
        """
        c, o = self.c, self.o
        g, h = self._maps(drw[o])
        step = self.solver.solve(x0[c], r0[c], drw[c] - h,
                                 None if guess is None else (guess[0][c], guess[1][c]))
        if step is None:
            return None, None
        n, m = self.n, self.nodes.size
        dx = step.x - x0[c]
        nz = np.flatnonzero(dx)
        dx_o = -g
        add_rows(self.Tt, nz, -dx[nz], dx_o)    # − Tᵀ Δx_C, the rows read in place
        w = x0[o[2 * m:]] + dx_o[2 * m:]
        # p_j − ρ_n w_j ≤ 0: each condensed node stays open (classify_nodes' test)
        closing = r0[o[2 * m:]] - self.rho_o * w > 0.0
        if np.any(closing):
            return None, closing
        stats = self.solver.stats                   # the parent's (shared)
        stats["condensed_steps"] = stats.get("condensed_steps", 0) + 1
        x, r = x0.copy(), r0.copy()
        x[c], r[c] = step.x, step.r
        x[o] += dx_o
        modes = np.full(n, SEPARATED, np.int8)
        modes[self.kept] = step.modes
        return Step(x, r, modes, drw, step.iterations), None


#: unit round-off of float64
_EPS = float(np.finfo(float).eps)

# placeholders of the arrays chord_newton does not read for a kind of active set (typed
# as the real ones, so that one compiled version serves)
_NO_LU = np.empty((0, 0), order="F")
_NO_PIV = np.empty(0, np.int32)
_NO_PHI = np.empty((0, 2, 2))
_NO_NVEC = np.empty((0, 2))
_NO_W = np.empty((0, 0))
_NO_Y = np.empty(0)
_NO_FACTORS = (_NO_LU, _NO_PIV, _NO_PHI, _NO_NVEC)


@dataclass
class PathTotals3D:
    """Accumulated quantities over a load path (one cycle, or the assembly).

    Attributes
    ----------
    dissipation : (N,) array
        D_j = −∫ q_j·dv_j [J].
    work : float
        ∫ (vᵀdq^w + wᵀdp^w) [J].
    normal_work : float
        Σ ½(p⁰ + p¹)Δw of the steps (zero in the continuous problem) [J].
    slip_length : (N,) array
        ∫ |dv_j| while node j slips in contact [m].
    separated, slipped : (N,) bool arrays
        Node j was separated / slipped at some step end.
    all_slip_or_separated : bool
        At some step end every node slipped or was separated (memory erased).
    steps, refinements : int
        Load steps taken and intervals halved by the step control.
    unresolved : int
        Steps kept at the largest depth without passing the error test.
    events : int
        Steps split where a node closes or opens inside them.
    plan : list
        The accepted sub-steps of each load interval (module docstring, replay); it can
        be passed as :attr:`Evolution3D.plan` to solve the same subdivision again.
    replay_mismatches : int
        Recorded sub-steps that did not fit the path when replayed (redone adaptively).
    closed : (N,) bool array
        Node j was closed at the start or at some step end (the others stayed open over
        the whole path and are condensed out of the next one, :meth:`StepSolver.condense`).
    samples : dict
        ``x``, ``r`` ((n+1, 3N)) and ``modes`` ((n+1, N)) at the load samples (if recorded).
    """

    dissipation: np.ndarray
    work: float = 0.0
    normal_work: float = 0.0
    slip_length: np.ndarray = None
    separated: np.ndarray = None
    slipped: np.ndarray = None
    all_slip_or_separated: bool = False
    steps: int = 0
    refinements: int = 0
    unresolved: int = 0
    events: int = 0
    samples: dict = field(default_factory=dict)
    #: accepted sub-steps per load interval, a list per interval of
    #: (fraction start, fraction end, depth, kind, node states at the step ends)
    plan: list = field(default_factory=list)
    replay_mismatches: int = 0
    closed: np.ndarray = None

    @classmethod
    def zeros(cls, n: int) -> PathTotals3D:
        return cls(np.zeros(n), 0.0, 0.0, np.zeros(n), np.zeros(n, bool), np.zeros(n, bool))


class Evolution3D:
    """Quasi-static evolution of a :class:`FrictionalSystem3D` along a piecewise-linear
    load path, with step-doubling control (module docstring).

    Parameters
    ----------
    system : FrictionalSystem3D
    x0 : (3N,) array
        Initial state [v, w] [m].
    r_w0 : (3N,) array
        Load [q^w, p^w] at the initial state [N].
    force_scale : float
        Typical load [N].
    step_tol : float
        Relative tolerance of the step control (state error / displacement scale).
    max_depth : int
        Largest number of halvings of one load interval.
    substeps : int
        Equal steps per load interval when ``adaptive`` is False (convergence studies).
    adaptive : bool
        Step doubling (default) or fixed steps.
    extrapolate : bool
        Richardson extrapolation of smooth doubled steps (default True).

    Attributes
    ----------
    disp_scale : float
        Displacement scale [m] of the step control: state errors relative to it, energy
        errors to max diag K × its square. ``force_scale`` / max diag K at first; the
        steady-state driver sets the service cycle's once the assembly is done
        (:func:`~slipcycle.discrete3d.steady.simulate3d`).
    """

    #: split a step at the instant a node closes or opens inside it, or starts to slip
    #: inside a step in which another one stops (:meth:`_locate_event`); False: backward
    #: Euler over the whole step (a closing node keeps the slip of the step's start)
    locate_events = True

    #: an event function (:meth:`_event_values`) at a located event, relative to the force scale
    event_tol = 1e-11
    #: condense the nodes open over the whole last path out of the next one, else those
    #: open over a load interval out of it (:meth:`StepSolver.condense`,
    #: :meth:`_condense_interval`; False: every step on the whole system)
    condense_open = True
    #: secant iterations of one event location at most
    event_iterations = 40
    #: an event within this fraction of a load interval from a step's end is taken
    #: at that end (no steps shorter than this are made for events)
    event_min = 1e-8

    def __init__(self, system: FrictionalSystem3D, x0: np.ndarray, r_w0: np.ndarray,
                 force_scale: float, *, step_tol: float = 1e-7, max_depth: int = 30,
                 substeps: int = 1, adaptive: bool = True, extrapolate: bool = True):
        self.sys = system
        self.n = system.n_nodes
        self.K = system.K
        self.F = float(force_scale)
        self.stiffness = system.stiffness_scale()
        self.disp_scale = self.F / self.stiffness
        #: min(1, 10 f_max): the energy a step can dissipate is f p |Δv| ≤ f_max × the
        #: elastic energy scale; the D test follows it below f = 0.1 (:meth:`_accept`)
        self._friction = min(1.0, 10.0 * float(np.max(system.friction, initial=0.0)))
        self.solver = StepSolver(system, self.F)
        self.step_tol = float(step_tol)
        self.max_depth = int(max_depth)
        self.substeps = int(substeps)
        self.adaptive = bool(adaptive)
        self.extrapolate = bool(extrapolate)
        self.x = np.array(x0, float)
        self.r_w = np.array(r_w0, float)
        self.r = self.r_w + self.K @ self.x
        disp_tol = 1e-12 * self.F / self.stiffness
        self.modes = np.where(self.x[2 * self.n:] > disp_tol, SEPARATED, STICK).astype(np.int8)
        self._totals: PathTotals3D | None = None
        #: set to a list to record every committed step (x, r, modes, x_before) for checks
        self.step_log: list | None = None
        #: a recorded subdivision (:attr:`PathTotals3D.plan`) to replay, or None: adaptive
        self.plan: list | None = None
        #: while replaying, also solve the full steps and check the error estimates
        self.check_plan = False
        self._leaves: list = []
        self._always_open: np.ndarray | None = None
        self._path_condensed = False

    def resync(self) -> None:
        """Recompute r = r^w + K x exactly (removes round-off drift of the updates)."""
        self.r = self.r_w + self.K @ self.x

    # -- bookkeeping ----------------------------------------------------------------------
    def _commit(self, step: Step) -> None:
        t = self._totals
        x0, r0 = self.x, self.r
        if t is not None:
            # a node open at both ends of the step carries q = 0 over it (contact law):
            # it books no dissipation, as a frictionless one (its q is round-off, which
            # booked D_j of ±1e-17, a negative D of a node open all cycle)
            f = self.solver.f
            open_ = (self.modes == SEPARATED) & (step.modes == SEPARATED)
            if open_.any():
                f = np.where(open_, 0.0, f)
            work, normal_work, none_stuck = book_step(
                x0, r0, step.x, step.r, step.drw, step.modes, f, t.dissipation,
                t.slip_length, t.separated, t.slipped)
            t.work += work
            t.normal_work += normal_work
            t.all_slip_or_separated |= none_stuck
            t.steps += 1
            t.closed |= step.modes != SEPARATED
        if self.step_log is not None:
            self.step_log.append((step.x.copy(), step.r.copy(), step.modes.copy(), x0.copy()))
        self.x, self.r, self.modes = step.x, step.r, step.modes
        self.r_w = self.r_w + step.drw

    def _exact(self, step: Step) -> bool:
        """No node slips and none opens or closes: linear elasticity, exact."""
        return not np.any(step.modes == SLIP) and np.array_equal(
            step.modes == SEPARATED, self.modes == SEPARATED)

    def _smooth(self, full: Step, h1: Step, h2: Step) -> bool:
        """Some node slips and no node changes state over the interval."""
        return (self.extrapolate and np.array_equal(full.modes, h2.modes)
                and np.array_equal(h1.modes, h2.modes)
                and np.array_equal(self.modes, h2.modes) and bool(np.any(h2.modes == SLIP)))

    def _extrapolate(self, full: Step, h2: Step) -> Step:
        """Richardson extrapolation 2·x_{h/2} − x_h of a smooth step (no node changes state
        within the interval), raising backward Euler's local error from O(h²) to O(h³):
        the turning slip direction is then integrated to second order. The cone holds to
        O(h⁴) (the two end reactions lie on the same circle within O(h²)) and is then made
        exact by a return-map step without load increment. Called with the first half
        step committed (the state is h1's): a node whose correction would take back more
        than half of its slip over the second half step (outside the asymptotic range,
        e.g. a slip of 1e-6 of the displacement scale that nearly stops inside the step,
        where the full step slipped 60 % more than the two halves) gets that much of it
        only (:meth:`_limit`), else its slip would run backwards along q, a negative
        dissipation."""
        dx = self._limit(h2.x - full.x, h2)
        U = np.flatnonzero(dx)
        x = h2.x.copy()
        x[U] += dx[U]
        r = h2.r.copy()
        add_rows(self.solver.K, U, dx[U], r)
        # return to the admissible set: a step with no load increment from the
        # extrapolated state (an O(h⁴) correction) makes the cone and contact exact again.
        # A node the correction leaves inside its cone (a slip ending within O(h²) of the
        # step's end) sticks there: keeping the step for all nodes, instead of falling
        # back to the half steps, keeps the path map continuous (a fall-back switched the
        # extrapolation off for every node at once, a jump of the size of the error
        # estimate that Anderson mixing of the cycle starts could not get past)
        proj = self.solver.solve(x, r, np.zeros_like(r))
        if proj is None:
            return h2
        # such a node slipped in the step: it is booked as slipping (slip length, state)
        modes = np.where((proj.modes == STICK) & (h2.modes == SLIP), SLIP, proj.modes)
        return Step(proj.x, proj.r, modes.astype(proj.modes.dtype), h2.drw,
                    h2.iterations + proj.iterations)

    def _limit(self, dx: np.ndarray, h2: Step) -> np.ndarray:
        """The Richardson correction ``dx`` (3N,) with each slipping node's tangential part
        c_j scaled so that the second half step's slip a_j (from the committed first half
        to h2) stays at least half of itself along a_j: (a_j + s c_j)·a_j ≥ ½|a_j|², s ≤ 1.
        Continuous in the states (no switch), and s = 1 in the asymptotic range, where
        |c_j| = O(h²) ≪ |a_j| = O(h)."""
        n = self.n
        slip = h2.modes == SLIP
        if not slip.any():
            return dx
        a = (h2.x[:2 * n] - self.x[:2 * n]).reshape(n, 2)
        c = dx[:2 * n].reshape(n, 2)
        back, aa = -np.sum(c * a, axis=1), np.sum(a * a, axis=1)
        over = slip & (back > 0.5 * aa)
        if over.any():
            dx = dx.copy()
            scale = 0.5 * aa[over] / back[over]
            dx[:2 * n].reshape(n, 2)[over] *= scale[:, None]
        return dx

    def _solve(self, x, r, drw, guess=None):
        return self.solver.solve(x, r, drw, guess)

    def _accept(self, x0, r0, full: Step, h1: Step, h2: Step,
                smooth: bool | None = None) -> tuple[bool, bool]:
        """(accepted, smooth): the step-doubling test of an interval solved as ``full``
        and as the half steps ``h1``, ``h2`` from (x0, r0); ``smooth`` given: the test
        of a step kept with (True) or without (False) the extrapolation."""
        err, d_full, d_half = doubling_error(x0, r0, full.x, full.r, h1.x, h1.r, h2.x,
                                             h2.r, self.n)
        err /= self.disp_scale
        # energy errors relative to max diag K × disp_scale² (F × disp_scale at first),
        # times min(1, 10 f_max): a step dissipates at most f_max × that, so D's relative
        # error is bounded by about 10 step_tol for every f (with the energy scale alone a
        # small f, 1e-6, left D off by 1.3 %: a node reversing inside a step moves D by
        # O(f), below that scale); from f = 0.1 up the test is the energy scale's (a
        # stricter one cost the 751-node lap joint 24 % more time for the same D to five
        # digits); a model without friction dissipates nothing and has no energy error
        err_d = 0.0 if self._friction <= 0.0 else abs(d_full - d_half) / (
            self._friction * self.stiffness * self.disp_scale ** 2)
        if smooth is None:
            smooth = self._smooth(full, h1, h2)
        # the estimate is that of the half-step (first-order) result; the extrapolated
        # result of a smooth step is O(h³), i.e. about est^(3/2) in scaled units
        tol = self.step_tol ** (2.0 / 3.0) if smooth else self.step_tol
        return max(err, err_d) <= tol, smooth

    # -- events inside a step ---------------------------------------------------------------
    def _event_values(self, x0: np.ndarray, x: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Event functions (2N,) [N] of the end state (x, r) of a step from ``x0``.

        φ_j = p_j − ρ_n w_j (the first N): negative while node j is separated (p = 0,
        w > 0), positive while it is closed; its zero is the instant the node closes or
        opens. ψ_j = |q_j − ρ_t Δv_j| − f_j φ_j (the last N): negative while a closed
        node sticks, zero at the start of a step while it slips, positive once it slipped
        in the step; its zero, for a node stuck at the step's start, is the instant it
        starts to slip. Both are continuous along the path and affine in the load
        parameter while no node changes state (one tangential direction).
        """
        sv = self.solver
        return event_values(x0, x, r, sv.f, sv.rho_t, sv.rho_n)

    def _crossings(self, g0: np.ndarray, g1: np.ndarray, stops: bool) -> np.ndarray:
        """Events (indices into the event functions) crossed between two states: a sign
        change of φ_j (a node closes or opens) and, if ``stops``, of ψ_j from below for a
        node closed at both ends (it starts to slip); functions within the event
        tolerance at either end are at their event already."""
        return event_crossings(g0, g1, stops, self.event_tol * self.F)

    @staticmethod
    def _first(idx: np.ndarray, g0: np.ndarray, g1: np.ndarray) -> int:
        """The event of ``idx`` crossed first on the straight line between g0 and g1."""
        return int(idx[np.argmin(g0[idx] / (g0[idx] - g1[idx]))])

    def _locate_event(self, drw: np.ndarray, full: Step, width: float = 1.0):
        """The first instant inside a step at which a node closes or opens, or, in a step
        in which a slipping node stops, starts to slip.

        Backward Euler keeps the end state's modes over the whole step: a node that
        closes inside it keeps the slip of the step's start, and a node that stops
        because another one starts to slip (or closes) loses its slip before that
        instant; step doubling does not see this when the instant lies in the first
        half (the full step and the half steps then agree). The step ended in ``full``
        under the load increment ``drw`` (3N,); the fraction s ∈ (0, 1) at which the
        first event function (:meth:`_event_values`) that changed sign vanishes is found
        by a safeguarded secant iteration on steps of fraction s from the start: the
        function is affine on each side of the event while no other node changes state,
        so the secant through two points on one side lands on it exactly (one tangential
        direction), regula falsi inside the bracket otherwise. An event crossed before
        the current estimate becomes the one followed. ``width`` is the step's fraction
        of its load interval: an event closer than ``event_min`` × the interval to either
        end of the step is taken at that end.

        Returns
        -------
        (s, Step) or None
            The fraction and the step to it (the event function within ``event_tol`` ×
            the force scale), or None when no event is crossed strictly inside the step.
        """
        x0, r0 = self.x, self.r
        stops = bool(np.any((self.modes == SLIP) & (full.modes == STICK)))
        g0, g1 = self._event_values(x0, x0, r0), self._event_values(x0, full.x, full.r)
        cross = self._crossings(g0, g1, stops)
        if cross.size == 0:
            return None
        tol = self.event_tol * self.F
        lo, hi, best = 0.0, 1.0, (1.0, full)
        j = self._first(cross, g0, g1)
        pts = {True: [(0.0, g0[j])], False: [(1.0, g1[j])]}   # start's side / other
        for _ in range(self.event_iterations):
            s = self._secant_guess(pts, lo, hi, tol)
            step = self._solve(x0, r0, s * drw,
                               (x0 + s * (full.x - x0), r0 + s * (full.r - r0)))
            if step is None:
                return None
            g = self._event_values(x0, step.x, step.r)
            early = self._crossings(g0, g, stops)
            early = early[early != j]
            if early.size:
                # another event is crossed before s: follow it on [lo, s]
                hi, best = s, (s, step)
                j = self._first(early, g0, g)
                pts = {True: [(0.0, g0[j])], False: [(s, g[j])]}
                continue
            same = (g[j] > 0) == (g0[j] > 0)
            if same and abs(g[j]) <= tol:
                best = (s, step)
                break
            first = len(pts[True]) == 1
            pts[same].append((s, g[j]))
            if same:
                lo = s
            else:
                hi, best = s, (s, step)
            if hi - lo <= 1e-15:
                break
            if same and self.adaptive:
                # with step doubling the event needs locating only as far as the step
                # control's tolerance: the movement the whole step would not book
                # (:meth:`_moved`) up to the estimated event, or from s to it
                rate = self._moved(step, full) / s
                s_event = self._secant_guess(pts, lo, hi, 0.0)
                if first and rate * s_event <= self.step_tol * self.disp_scale:
                    return None
                if rate * (s_event - s) <= 0.5 * self.step_tol * self.disp_scale:
                    best = (s, step)
                    break
        s, step = best
        edge = self.event_min / width
        return (s, step) if edge < s < 1.0 - edge else None

    def _moved(self, step: Step, full: Step) -> float:
        """Largest slip increment [m] up to the end of ``step`` (before the event) of
        the nodes whose state differs between the start and the end of ``full``: they
        slipped, or moved freely while open, and the whole step, keeping its end
        state's modes, books none of it (about the error of not locating the event)."""
        nodes = np.flatnonzero(self.modes != full.modes)
        dofs = self.solver._rows_q[nodes].ravel()
        return float(np.max(np.abs(step.x[dofs] - self.x[dofs]), initial=0.0))

    @staticmethod
    def _secant_guess(pts: dict, lo: float, hi: float, tol: float) -> float:
        """Next fraction: the secant through the last two points of one side of the
        event (exact where the function is affine there), else regula falsi between the
        bracket's ends, moved toward the start by half the event tolerance (so that the
        located step ends just before the event: a node that starts to slip there has
        not slipped yet), else the bracket's midpoint."""
        lines = [pts[side][-2:] for side in (True, False) if len(pts[side]) >= 2]
        lines.append([pts[True][-1], pts[False][-1]])
        for (sa, ga), (sb, gb) in lines:
            if gb != ga and sb != sa:
                slope = (gb - ga) / (sb - sa)
                s = sb - gb / slope - 0.5 * tol / abs(slope)
                if lo < s < hi:
                    return s
        return 0.5 * (lo + hi)

    def _interval(self, rwa: np.ndarray, rwb: np.ndarray, full: Step | None, depth: int,
                  guess: tuple | None = None, fa: float = 0.0, fb: float = 1.0,
                  at_event: bool = False):
        # at_event: the interval ends at a located event, where the path is not smooth:
        # no Richardson extrapolation onto it (its cone projection could close the node)
        x0, r0 = self.x, self.r
        if full is None:
            full = self._solve(x0, r0, rwb - rwa, guess)
        event = None if full is None or not self.locate_events else self._locate_event(
            rwb - rwa, full, fb - fa)
        if event is not None:
            # a node closes or opens inside: split the step at that instant, so that
            # the node takes its state from it (not from the start of the step)
            s, step = event
            rws, fs = rwa + s * (rwb - rwa), fa + s * (fb - fa)
            if self._totals is not None:
                self._totals.events += 1
            self._leaves.append((fa, fb, depth, "L", ()))
            self._interval(rwa, rws, step, depth, fa=fa, fb=fs, at_event=True)
            # the whole step's end (same end load, so its reactions are consistent) is
            # the predictor of the rest: the solution does not depend on it
            self._interval(rws, rwb, None, depth, (full.x, full.r), fa=fs, fb=fb,
                           at_event=at_event)
            return
        if full is not None and (not self.adaptive or self._exact(full)):
            self._leaves.append((fa, fb, depth, "E", (full.modes,)))
            self._commit(full)
            return
        mid = 0.5 * (rwa + rwb)
        # predictors from the full step (r is affine in x and the load, so the guesses'
        # reactions need no product with K): the middle of the full step for the first
        # half, the end of the full step (same end load) for the second
        g1 = None if full is None else (0.5 * (x0 + full.x), 0.5 * (r0 + full.r))
        h1 = self._solve(x0, r0, mid - rwa, g1)
        g2 = None if full is None else (full.x, full.r)
        h2 = None if h1 is None else self._solve(h1.x, h1.r, rwb - mid, g2)
        if full is not None and h2 is not None:
            ok, smooth = self._accept(x0, r0, full, h1, h2, False if at_event else None)
            if ok:
                self._leaves.append((fa, fb, depth, "X" if smooth else "H",
                                     (h1.modes, h2.modes)))
                self._commit(h1)
                self._commit(self._extrapolate(full, h2) if smooth else h2)
                return
        if depth >= self.max_depth:
            if h2 is None:
                raise IncrementalSolverError(
                    "the incremental problem of a load step has no solution the Newton "
                    "method can find, even on a step 2^-" f"{self.max_depth} of a load "
                    f"interval; {self._likely_cause()}")
            if self._totals is not None:
                self._totals.unresolved += 1
            self._leaves.append((fa, fb, depth, "U", (h1.modes, h2.modes)))
            self._commit(h1)
            self._commit(h2)
            return
        if self._totals is not None:
            self._totals.refinements += 1
        fm = 0.5 * (fa + fb)
        self._interval(rwa, mid, h1, depth + 1, fa=fa, fb=fm)
        # h2 was computed from h1: still valid if the first half was kept as h1; else a
        # predictor for the second half (same end load, so its reactions are consistent)
        if h1 is not None and self.x is h1.x:
            self._interval(mid, rwb, h2, depth + 1, fa=fm, fb=fb, at_event=at_event)
        else:
            self._interval(mid, rwb, None, depth + 1, None if h2 is None else (h2.x, h2.r),
                           fa=fm, fb=fb, at_event=at_event)

    def _likely_cause(self) -> str:
        """Why a step may have no solution (:func:`~slipcycle.coupled.system.likely_cause`)."""
        return likely_cause(self.sys)

    def _condense_interval(self, rwa: np.ndarray, rwb: np.ndarray) -> Step | None:
        """Where no condensation is active (the first path, or one that fell back),
        condense the nodes open at the start of the load interval from ``rwa`` to
        ``rwb`` (3N,) and at the end of its whole step out of the interval's steps
        (:meth:`StepSolver.condense`): such a node rarely closes in between (on the
        751-node lap joint 15 of 5600 node-intervals in the assembly and the first
        cycle), and one that does is kept in its step and after it
        (:meth:`StepSolver.solve`).

        Returns
        -------
        Step or None
            The interval's whole step (solved on the whole system), or None.
        """
        if not self.condense_open or (self._path_condensed and self.solver.condensing):
            return None
        full = self._solve(self.x, self.r, rwb - rwa)
        if full is not None:
            nodes = np.flatnonzero((self.modes == SEPARATED) & (full.modes == SEPARATED))
            self.solver.condense(nodes, np.array([rwa, rwb]))
        return full

    def _replay_step(self, rwa, rwb, kind: str, modes: tuple) -> bool:
        """Solve one recorded sub-step as the adaptive method kept it and commit it;
        False (nothing committed) if it does not fit: an end state of a sub-step differs
        from the recorded one, or (``check_plan``) the error estimate fails."""
        x0, r0 = self.x, self.r
        if kind == "E":
            full = self._solve(x0, r0, rwb - rwa)
            if (full is None or not self._exact(full)
                    or not np.array_equal(full.modes, modes[0])):
                return False
            self._commit(full)
            return True
        full = None
        if kind == "X":
            full = self._solve(x0, r0, rwb - rwa)
            if full is None:
                return False
        mid = 0.5 * (rwa + rwb)
        # the predictors of the half steps are those of the cycles that skip the check
        # (the full step's only for an extrapolated step): a check does not change them
        pred = full if kind == "X" else None
        g1 = None if pred is None else (0.5 * (x0 + pred.x), 0.5 * (r0 + pred.r))
        h1 = self._solve(x0, r0, mid - rwa, g1)
        if h1 is None:
            return False
        h2 = self._solve(h1.x, h1.r, rwb - mid, None if pred is None else (pred.x, pred.r))
        if h2 is None:
            return False
        # another active set than recorded: the step is kept only if its error estimate
        # still passes
        check = self.check_plan or not (np.array_equal(h1.modes, modes[0])
                                        and np.array_equal(h2.modes, modes[1]))
        if check and full is None:
            # the Newton matrices kept for the chord steps are restored after this
            # extra solve: the converged steps depend on them within the Newton
            # tolerance, and a check must not perturb the replayed map
            lus = self.solver.chord_state()
            full = self._solve(x0, r0, rwb - rwa)
            self.solver.restore_chords(lus)
            if full is None:
                return False
        if check and not self._accept(x0, r0, full, h1, h2, kind == "X")[0]:
            return False
        self._commit(h1)
        self._commit(self._extrapolate(full, h2) if kind == "X" else h2)
        return True

    def _replay(self, rwa_k: np.ndarray, rwb_k: np.ndarray, leaves: list) -> None:
        """Replay the recorded sub-steps of one load interval (module docstring); a
        sub-step that does not fit is redone adaptively from its start. An interval in
        which a node closed or opened is solved adaptively again: the instant of the
        event moves with the path, a recorded fraction would miss it."""
        if any(leaf[3] == "L" for leaf in leaves):
            self._interval(rwa_k, rwb_k, None, 0)
            return
        d = rwb_k - rwa_k
        for fa, fb, depth, kind, modes in leaves:
            rwa = rwa_k + fa * d
            rwb = rwb_k if fb == 1.0 else rwa_k + fb * d
            n0 = len(self._leaves)
            if self._replay_step(rwa, rwb, kind, modes):
                self._leaves.append((fa, fb, depth, kind, modes))
            else:
                del self._leaves[n0:]
                if self._totals is not None:
                    self._totals.replay_mismatches += 1
                self._interval(rwa, rwb, None, depth, fa=fa, fb=fb)

    def follow(self, theta: np.ndarray, vals: np.ndarray, record: bool = False
               ) -> PathTotals3D:
        """Follow the load path linearly through ``vals`` ((S, 3N) loads [q^w, p^w] at
        angles ``theta`` (S,)), starting from the current state.

        Returns
        -------
        PathTotals3D
            Totals over the path; with ``record`` the states at every sample.
        """
        n = self.n
        t = self._totals = PathTotals3D.zeros(n)
        t.closed = self.modes != SEPARATED
        # the nodes open over the whole last path are condensed out while they stay open
        self.solver.condense(self._always_open if self.condense_open else None,
                             np.asarray(vals, float))
        # else (or once it falls back) the open nodes are condensed per load interval
        self._path_condensed = self.solver.condensing
        if record:
            xs = [self.x.copy()]
            rs = [self.r.copy()]
            ms = [self.modes.copy()]
        self.r_w = np.array(vals[0], float)
        plan = self.plan if self.adaptive else None
        if plan is not None and len(plan) != len(vals) - 1:
            raise ValueError("the recorded subdivision has "
                             f"{len(plan)} load intervals, the path {len(vals) - 1}")
        for k in range(len(vals) - 1):
            self._leaves = []
            if plan is not None:
                self._replay(vals[k], vals[k + 1], plan[k])
                t.plan.append(self._leaves)
            elif self.adaptive or self.substeps == 1:
                full = self._condense_interval(vals[k], vals[k + 1])
                self._interval(vals[k], vals[k + 1], full, 0)
                if self.adaptive:
                    t.plan.append(self._leaves)
            else:
                s = np.linspace(0.0, 1.0, self.substeps + 1)
                for a, b in zip(s[:-1], s[1:], strict=True):
                    rwa = vals[k] + a * (vals[k + 1] - vals[k])
                    rwb = vals[k] + b * (vals[k + 1] - vals[k])
                    self._interval(rwa, rwb, None, 0)
            if record:
                xs.append(self.x.copy())
                rs.append(self.r.copy())
                ms.append(self.modes.copy())
        self.r_w = np.array(vals[-1], float)
        if record:
            t.samples = {"x": np.array(xs), "r": np.array(rs), "modes": np.array(ms)}
        self._totals = None
        self.solver.condense(None)
        self._always_open = np.flatnonzero(~t.closed)
        return t
