"""Event-driven exact quasi-static evolution along a piecewise-linear load path.

On a linear segment of the load path the load rate ṙ^w is constant, so the solution of
the rate problem (:class:`~slipcycle.discrete.rate.RateSolver`) stays constant until an
*event*: a stuck node reaches q = ±f p, a node in contact reaches p = 0, a separated
node's gap w closes. These are roots of linear functions of θ on the segment, located in
closed form; the rate problem is then solved again at the event. Between events the state
is exactly linear in θ, so the result is exact for the piecewise-linear load path; the
only discretisation error is the sampling of a smooth load. A slipping node whose slip
rate would change sign is found by re-solving the rate problem at every load sample, where
the load rate changes.

Energy bookkeeping is exact on every linear piece: the dissipation of node j,
D_j = −∫ q_j dv_j, and the work of the loads W = ∫ (vᵀ dq^w + wᵀ dp^w), which must equal
Σ D_j over a closed (steady) cycle because the stored energy ½ xᵀKx + r^wᵀx returns.

Linearisation of the cycle map. The rates of a piece depend on the modes and the load rate
only, not on the state, so a perturbation δx of the state passes every load sample
unchanged and is changed only at events: an event of the function g(x, θ) = aᵀx + b(θ)
(rate ġ before it) moves by δt = −aᵀδx / ġ, so that afterwards δx ← (I − u aᵀ) δx with
u = (ẋ_before − ẋ_after) / ġ. With ``jacobian_log`` set to a list the evolution records
(event kind, node, u, ġ, θ and its load segment) for every event;
:mod:`~slipcycle.discrete.periodic` composes them into the cycle map's Jacobian and, with
δt, follows plain cycling on that piece of the map. ``signature`` (a hash) records the
sequence of modes and events, so that two cycles with the same sequence are known to
share one affine map.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from slipcycle.discrete.model import SEPARATED, SLIP_NEG, SLIP_POS, STICK, FrictionalSystem
from slipcycle.discrete.rate import RateSolver, friction_tol

__all__ = ["Evolution", "PathTotals"]


@njit(cache=True)
def _scan_events(f, q, p, w, qd, pd, wd, modes, tol, disp_tol, remaining):
    """First event on the piece: (dt, kind, node, rate of its function); kind −1: none
    before ``remaining``. Kinds: 0 a stuck node reaches q = −f p (g = f p + q), 1 q = +f p
    (g = f p − q), 2 a node in contact reaches p = 0, 3 a separated node closes (w = 0).
    Ties go to the lowest (kind, node), O(N) with no temporaries."""
    best, bkind, bnode, brate = remaining, -1, -1, 0.0
    for j in range(f.size):
        m = modes[j]
        for kind in range(4):
            if kind <= 1:
                if m != STICK:
                    continue
                s = 1.0 if kind == 0 else -1.0
                g = f[j] * p[j] + s * q[j]
                gd = f[j] * pd[j] + s * qd[j]
                thr = friction_tol(f[j], p[j], tol)   # the activity test's own
            elif kind == 2:
                if m == SEPARATED:
                    continue
                g, gd, thr = p[j], pd[j], tol
            else:
                if m != SEPARATED:
                    continue
                g, gd, thr = w[j], wd[j], disp_tol
            if g > thr and gd < 0.0:
                t = g / -gd
                if t < best or (t == best and bkind >= 0 and
                                (kind < bkind or (kind == bkind and j < bnode))):
                    best, bkind, bnode, brate = t, kind, j, gd
    return max(best, 0.0), bkind, bnode, brate


@njit(cache=True)
def _accumulate(modes, x, r, xd, rd, rw, dt, diss, slip_len, spos, sneg, sep, disp_tol, f,
                margin):
    """Exact integrals over a piece of length dt (products of linear functions) into the
    totals, in place; returns (work of the loads, every node slipped or was open, x, r at
    the end of the piece)."""
    n = modes.size
    erased = True
    for j in range(n):
        vd = xd[j]
        m = modes[j]
        # an open node carries q = 0 and a frictionless one q = ∓f p = 0 (contact and
        # friction laws): their q is round-off, which booked D_j of ±1e-17 (negative D
        # of a shakedown with a node open all cycle)
        if m != SEPARATED and f[j] > 0.0:
            diss[j] -= (r[j] + 0.5 * dt * rd[j]) * vd * dt
        if m == SLIP_POS or m == SLIP_NEG:
            slip_len[j] += abs(vd) * dt
        if m == SLIP_POS and vd > 0:
            spos[j] = True
        if m == SLIP_NEG and vd < 0:
            sneg[j] = True
        if m == SEPARATED:
            sep[j] = True
        # a node that grazes its friction limit slips a round-off amount: that must not
        # count towards erasing the memory
        moving = abs(vd) * dt > disp_tol
        if not (m == SEPARATED or (moving and ((m == SLIP_POS and vd > 0) or
                                               (m == SLIP_NEG and vd < 0)))):
            erased = False
    work = 0.0
    for i in range(x.size):
        work += (x[i] + 0.5 * dt * xd[i]) * rw[i]
    x1 = x + dt * xd
    r1 = r + dt * rd
    for j in range(n):
        if modes[j] == SEPARATED:
            mg = 0.0
        else:
            p = r1[n + j]
            mg = min(f[j] * p - abs(r1[j]), p)
        if mg < margin[j]:
            margin[j] = mg
    return work * dt, erased, x1, r1


@njit(cache=True)
def _margin_rows(modes, f, x, r, out, lowest):
    """Per node the inequalities of its mode into ``out`` (4, N), or their minimum with
    ``out`` when ``lowest``: f p + q and f p − q while stuck, p while slipping, w while
    open, +inf where one does not apply (``Evolution.margin_log``)."""
    n = modes.size
    for j in range(n):
        m = modes[j]
        p = r[n + j]
        a = b = c = d = np.inf
        if m == STICK:
            a = f[j] * p + r[j]
            b = f[j] * p - r[j]
        elif m == SEPARATED:
            d = x[n + j]
        else:
            c = p
        if lowest:
            out[0, j] = min(out[0, j], a)
            out[1, j] = min(out[1, j], b)
            out[2, j] = min(out[2, j], c)
            out[3, j] = min(out[3, j], d)
        else:
            out[0, j], out[1, j], out[2, j], out[3, j] = a, b, c, d


@dataclass
class PathTotals:
    """Accumulated quantities over a load path (one cycle, or the assembly).

    Attributes
    ----------
    dissipation : (N,) array
        D_j = −∫ q_j dv_j over the path [J].
    work : float
        ∫ (vᵀ dq^w + wᵀ dp^w) over the path [J].
    slip_length : (N,) array
        ∫ |dv_j| while node j slips in contact [m].
    separated : (N,) bool array
        Node j was separated at some instant.
    slipped_positive, slipped_negative : (N,) bool arrays
        Node j slipped in that direction at some instant.
    all_slip_or_separated : bool
        At some instant every node slipped or was separated (memory erased, Barber 2012, §3.1).
    events : int
        Number of events located (state changes inside load segments).
    """

    dissipation: np.ndarray
    work: float = 0.0
    slip_length: np.ndarray = None
    separated: np.ndarray = None
    slipped_positive: np.ndarray = None
    slipped_negative: np.ndarray = None
    all_slip_or_separated: bool = False
    events: int = 0
    samples: dict = field(default_factory=dict)
    #: smallest margin min(f p − |q|, p) of each node at the ends of the pieces [N]
    #: (0 while separated): how close a node that did not slip came to slipping
    min_margin: np.ndarray = None

    @classmethod
    def zeros(cls, n: int) -> PathTotals:
        return cls(np.zeros(n), 0.0, np.zeros(n), np.zeros(n, bool), np.zeros(n, bool),
                   np.zeros(n, bool), min_margin=np.full(n, np.inf))


class Evolution:
    """Exact quasi-static evolution of a :class:`FrictionalSystem`.

    Parameters
    ----------
    system : FrictionalSystem
    x0 : (2N,) array
        Initial state [v, w] in m.
    r_w0 : (2N,) array
        Load r^w = [q^w, p^w] at the initial state, N.
    force_scale : float
        Typical load magnitude [N]; tolerances are relative to it (``rel_tol``).
    rel_tol : float
        Relative tolerance deciding when an inequality is active.
    """

    def __init__(self, system: FrictionalSystem, x0: np.ndarray, r_w0: np.ndarray,
                 force_scale: float, rel_tol: float = 1e-10):
        self.sys = system
        self.n = system.n_nodes
        self.K = system.K
        self.f = np.asarray(system.friction)
        self.force_tol = rel_tol * force_scale
        self.solver = RateSolver(system, self.force_tol)
        self.x = np.array(x0, float)
        self.r_w = np.array(r_w0, float)
        self.r = self.r_w + self.K @ self.x
        self.modes = np.where(self.x[self.n:] > self.solver.disp_tol, SEPARATED,
                              STICK).astype(np.int8)
        self.events = 0
        #: set to a list to record (x, r, modes) after every event piece (for checks)
        self.event_log: list | None = None
        self.max_events_per_segment = 20 * self.n + 200
        #: set to a list to record the rank-one factors (kind, node, idx, u[idx]) of the
        #: cycle map's Jacobian, one per event (module docstring)
        self.jacobian_log: list | None = None
        #: set to a list to record, for every interval between two events of
        #: ``jacobian_log``, the smallest value at its load samples of the inequalities each
        #: node's mode must keep (4, N): f p + q ≥ 0 and f p − q ≥ 0 while stuck, p ≥ 0
        #: while slipping, w ≥ 0 while open, +inf where one does not apply (:meth:`follow`
        #: adds the last interval; :func:`~slipcycle.discrete.periodic.piece_constraints`)
        self.margin_log: list | None = None
        #: with ``jacobian_log``: every node's maximal intervals of one mode that begin or
        #: end at an event, as (node, first event, start θ, last event, end θ, mode) with event
        #: indices into ``jacobian_log`` (−1: a load sample or the end of the path, which
        #: do not move) — a perturbed start moves the events, and an interval whose length
        #: would go negative means that the sequence of modes changes
        self.episode_log: list = []
        #: with ``margin_log``: at every event, the inequalities of the nodes that keep
        #: their mode there and their rates before it, ((4, N), (4, N))
        self.event_margin_log: list = []
        #: with ``margin_log``: the nodes that start to slip, open or close at a load
        #: sample (:meth:`_record_switches`)
        self.switch_log: list = []
        self._lowest = None
        self._tracking = False
        self._clock = 0.0
        #: set to ``hashlib.blake2b()`` to hash the sequence of modes and events
        self.signature = None

    def resync(self) -> None:
        """Recompute the reactions r = r^w + K x exactly (removes round-off drift)."""
        self.r = self.r_w + self.K @ self.x

    def _record_margins(self, modes: np.ndarray, after_event: bool, theta: float,
                        event_node: int = -1) -> None:
        """Add the start of a piece with ``modes`` to the records of ``margin_log``.

        At a load sample (which a perturbed start does not move) the values go into the
        interval's minima. After an event they were recorded at the event with the rates
        before it (``event_margin_log``), since a perturbed start moves the event; the
        nodes whose mode changes there sit on an inequality of both modes at that instant
        (f p ± q = 0 when a node starts or stops slipping, p = 0 or w = 0 when it opens or
        closes) and are left out: that the interval of each mode keeps its length is what
        ``episode_log`` checks."""
        changed = modes != self.modes
        nodes = changed.nonzero()[0]        # (cheaper than np.flatnonzero, per event)
        if nodes.size:
            self._close_episodes(nodes, len(self.jacobian_log) if after_event else -1,
                                 theta)
        if self._lowest is None:            # mode intervals only
            return
        if not after_event:
            if nodes.size:
                self._record_switches(nodes, modes)
            _margin_rows(modes, self.f, self.x, self.r, self._lowest, True)
            return
        value, rate = self._at_event
        others = changed.copy()
        others[event_node] = False
        if others.any():
            self._record_switches(np.flatnonzero(others), modes, (value, rate))
        value[:, changed] = np.inf
        self.event_margin_log.append((value, rate))
        self.margin_log.append(self._lowest)
        self._lowest = np.full((4, self.n), np.inf)

    def _record_switches(self, nodes: np.ndarray, modes: np.ndarray,
                         at_event: tuple | None = None) -> None:
        """Record the nodes that start to slip, open or close at a load sample, or at the
        event of another node: each sits on an inequality there (f p ± q, p or w within
        the tolerance), and a perturbed start moves it off, to an event of its own before
        that instant or to no switch at all (``switch_log``: interval index, inequality
        kind as in ``margin_log``, node, value, its rate before an event (0 at a sample),
        and the event's index, −1 at a sample). A node that stops slipping does so because
        of the rates alone."""
        n = self.n
        q, p, w = self.r[:n], self.r[n:], self.x[n:]
        interval = len(self.jacobian_log)
        event = interval if at_event is not None else -1
        for j in nodes:
            new, old = modes[j], self.modes[j]
            if new == SLIP_POS and old != SLIP_POS:
                kind, value = 0, self.f[j] * p[j] + q[j]
            elif new == SLIP_NEG and old != SLIP_NEG:
                kind, value = 1, self.f[j] * p[j] - q[j]
            elif new == SEPARATED:
                kind, value = 2, p[j]
            elif old == SEPARATED:
                kind, value = 3, w[j]
            else:
                continue
            rate = 0.0
            if at_event is not None and np.isfinite(at_event[0][kind, j]):
                rate = float(at_event[1][kind, j])
            self.switch_log.append((interval, kind, int(j), float(value), rate, event))

    def _close_episodes(self, nodes: np.ndarray, event: int, theta: float) -> None:
        """End the current mode interval of ``nodes`` at ``theta`` (by ``event``, or −1)."""
        s_ev, s_th, log = self._episode_event, self._episode_theta, self.episode_log
        for j in nodes.tolist():          # one or two nodes at an event: plain ints
            if s_ev[j] >= 0 or event >= 0:
                log.append((j, int(s_ev[j]), float(s_th[j]), event, theta,
                            int(self.modes[j])))
            s_ev[j] = event
            s_th[j] = theta

    def _margins(self, m: np.ndarray, x: np.ndarray, r: np.ndarray) -> np.ndarray:
        """The inequalities the modes ``m`` must keep, per node (4, N): f p + q and
        f p − q while stuck, p while slipping, w while open, +inf where they do not apply;
        of the state (x, r), or their rates from the rates (ẋ, ṙ)."""
        out = np.empty((4, self.n))
        _margin_rows(m, self.f, x, r, out, False)
        return out

    def _next_event(self, modes, x, r, xd, rd, remaining):
        n = self.n
        dt, kind, j, rate = _scan_events(self.f, r[:n], r[n:], x[n:], rd[:n], rd[n:], xd[n:],
                                         modes, self.force_tol, self.solver.disp_tol,
                                         remaining)
        if kind < 0:
            return remaining, None
        self._event_rate = rate
        return dt, (kind, j)

    def advance(self, r_w_end: np.ndarray, dtheta: float, totals: PathTotals) -> None:
        """Follow the linear load segment from the current load to ``r_w_end`` (2N,) over
        ``dtheta`` radians, locating every event, and add to ``totals``."""
        if dtheta <= 0:
            return
        rw = (np.asarray(r_w_end, float) - self.r_w) / dtheta
        t = 0.0
        count = 0
        guess = self.modes
        jlog, sig = self.jacobian_log, self.signature
        pending = None
        while True:
            modes, xd, rd = self.solver.solve(self.x, self.r, rw, guess)
            if self._tracking:
                self._record_margins(modes, pending is not None, self._clock + t,
                                     pending[1] if pending is not None else -1)
            self.modes = modes
            if pending is not None:
                # rank-one factor I − u aᵀ of the event just passed (module docstring),
                # ġ, which says how far the event moves, and where it happened: θ and
                # the load segment [θ_lo, θ_hi] it must not leave
                kind, j, gdot, xd_b, t_event = pending
                diff = xd_b - xd
                idx = diff.nonzero()[0]
                jlog.append((kind, j, idx, diff[idx] / gdot, gdot, self._clock + t_event,
                             self._clock, self._clock + dtheta))
                pending = None
            if sig is not None:
                sig.update(modes.tobytes())
            dt, event = self._next_event(modes, self.x, self.r, xd, rd, dtheta - t)
            if dt > 0:
                work, erased, self.x, self.r = _accumulate(
                    modes, self.x, self.r, xd, rd, rw, dt, totals.dissipation,
                    totals.slip_length, totals.slipped_positive, totals.slipped_negative,
                    totals.separated, self.solver.disp_tol, self.f, totals.min_margin)
                totals.work += work
                if erased:
                    totals.all_slip_or_separated = True
                self.r_w = self.r_w + dt * rw
                t += dt
            if self.event_log is not None:
                self.event_log.append((self.x.copy(), self.r.copy(), modes.copy()))
            if self._lowest is not None:
                if event is None:
                    _margin_rows(modes, self.f, self.x, self.r, self._lowest, True)
                else:                       # the interval ends at this event
                    self._at_event = (self._margins(modes, self.x, self.r),
                                      self._margins(modes, xd, rd))
            if event is None:
                break
            # warm start: the node that caused the event most likely changes state so
            kind, j = event
            if jlog is not None:
                pending = (kind, j, self._event_rate, xd, t)
            if sig is not None:
                sig.update(bytes((kind,)) + int(j).to_bytes(4, "little"))
            guess = modes.copy()
            guess[j] = (SLIP_POS, SLIP_NEG, SEPARATED, STICK)[kind]
            count += 1
            if count > self.max_events_per_segment:
                raise RuntimeError(
                    f"more than {self.max_events_per_segment} events on one load segment "
                    f"(θ advanced {t:.3g} of {dtheta:.3g} rad): the evolution is stuck; "
                    "check that the model is well posed")
        if sig is not None:
            sig.update(b"|")
        self.events += count
        totals.events += count
        self._clock += dtheta
        self.r_w = np.asarray(r_w_end, float).copy()

    def follow(self, theta: np.ndarray, loads: np.ndarray, totals: PathTotals | None = None,
               record: bool = False):
        """Follow the piecewise-linear load path through samples (θ_k, r^w_k).

        Parameters
        ----------
        theta : (n+1,) array
            Path parameter at the samples (rad; any increasing parameter for assembly).
        loads : (n+1, 2N) array
            r^w at the samples; ``loads[0]`` must be the current load.
        totals : PathTotals, optional
            Accumulator (new one if None).
        record : bool
            Store x, r and modes at every sample in ``totals.samples``.

        Returns
        -------
        PathTotals
        """
        totals = totals or PathTotals.zeros(self.n)
        # mode intervals with the Jacobian, inequalities with ``margin_log`` as well
        self._tracking = self.jacobian_log is not None
        if self._tracking:
            self.episode_log = []
            self._episode_event = np.full(self.n, -1)
            self._episode_theta = np.zeros(self.n)
            self._clock = 0.0
        if self._tracking and self.margin_log is not None:
            self._lowest = np.full((4, self.n), np.inf)
            self.event_margin_log = []
            self.switch_log = []
        if record:
            xs = np.empty((len(theta), 2 * self.n))
            rs = np.empty((len(theta), 2 * self.n))
            ms = np.empty((len(theta), self.n), np.int8)
            xs[0], rs[0], ms[0] = self.x, self.r, self.modes
        for k in range(len(theta) - 1):
            self.advance(loads[k + 1], theta[k + 1] - theta[k], totals)
            if record:
                xs[k + 1], rs[k + 1], ms[k + 1] = self.x, self.r, self.modes
        if self._lowest is not None:
            self.margin_log.append(self._lowest)
            self._lowest = None
        if self._tracking:
            self._close_episodes(np.arange(self.n), -1, self._clock)
            self._tracking = False
        if record:
            totals.samples = {"x": xs, "r": rs, "modes": ms}
        return totals
