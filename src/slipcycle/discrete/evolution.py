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
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from slipcycle.discrete.model import SEPARATED, SLIP_NEG, SLIP_POS, STICK, FrictionalSystem
from slipcycle.discrete.rate import RateSolver

__all__ = ["Evolution", "PathTotals"]


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
        At some instant every node slipped or was separated (memory erased, seed §3.1).
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

    @classmethod
    def zeros(cls, n: int) -> PathTotals:
        return cls(np.zeros(n), 0.0, np.zeros(n), np.zeros(n, bool), np.zeros(n, bool),
                   np.zeros(n, bool))


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

    def resync(self) -> None:
        """Recompute the reactions r = r^w + K x exactly (removes round-off drift)."""
        self.r = self.r_w + self.K @ self.x

    def _next_event(self, modes, x, r, xd, rd, remaining):
        n, f, tol = self.n, self.f, self.force_tol
        q, p, w = r[:n], r[n:], x[n:]
        qd, pd, wd = rd[:n], rd[n:], xd[n:]
        stick = modes == STICK
        slip = (modes == SLIP_POS) | (modes == SLIP_NEG)
        sep = modes == SEPARATED
        vals = np.stack([f * p + q, f * p - q, p, w])
        rates = np.stack([f * pd + qd, f * pd - qd, pd, wd])
        use = np.stack([stick, stick, stick | slip, sep])
        thresh = np.array([tol, tol, tol, self.solver.disp_tol])[:, None]
        use &= (vals > thresh) & (rates < 0)
        if not use.any():
            return remaining, None
        t = np.full(vals.shape, np.inf)
        t[use] = vals[use] / -rates[use]
        k = int(np.argmin(t))
        tmin = t.flat[k]
        if tmin >= remaining:
            return remaining, None
        return max(tmin, 0.0), divmod(k, n)

    def advance(self, r_w_end: np.ndarray, dtheta: float, totals: PathTotals) -> None:
        """Follow the linear load segment from the current load to ``r_w_end`` (2N,) over
        ``dtheta`` radians, locating every event, and add to ``totals``."""
        if dtheta <= 0:
            return
        rw = (np.asarray(r_w_end, float) - self.r_w) / dtheta
        n = self.n
        t = 0.0
        count = 0
        guess = self.modes
        while True:
            modes, xd, rd = self.solver.solve(self.x, self.r, rw, guess)
            self.modes = modes
            dt, event = self._next_event(modes, self.x, self.r, xd, rd, dtheta - t)
            if dt > 0:
                x, r = self.x, self.r
                vd = xd[:n]
                # exact integrals of products of linear functions over dt
                totals.dissipation -= (r[:n] + 0.5 * dt * rd[:n]) * vd * dt
                totals.work += float((x + 0.5 * dt * xd) @ rw) * dt
                slipping = (modes == SLIP_POS) | (modes == SLIP_NEG)
                totals.slip_length[slipping] += np.abs(vd[slipping]) * dt
                totals.slipped_positive |= (modes == SLIP_POS) & (vd > 0)
                totals.slipped_negative |= (modes == SLIP_NEG) & (vd < 0)
                sep = modes == SEPARATED
                totals.separated |= sep
                # a node that grazes its friction limit slips a round-off amount: that
                # must not count towards erasing the memory
                moving = np.abs(vd) * dt > self.solver.disp_tol
                if np.all((((modes == SLIP_POS) & (vd > 0)) | ((modes == SLIP_NEG) & (vd < 0)))
                          & moving | sep):
                    totals.all_slip_or_separated = True
                self.x = x + dt * xd
                self.r = r + dt * rd
                self.r_w = self.r_w + dt * rw
                t += dt
            if self.event_log is not None:
                self.event_log.append((self.x.copy(), self.r.copy(), modes.copy()))
            if event is None:
                break
            # warm start: the node that caused the event most likely changes state so
            kind, j = event
            guess = modes.copy()
            guess[j] = (SLIP_POS, SLIP_NEG, SEPARATED, STICK)[kind]
            count += 1
            if count > self.max_events_per_segment:
                raise RuntimeError(
                    f"more than {self.max_events_per_segment} events on one load segment "
                    f"(θ advanced {t:.3g} of {dtheta:.3g} rad): the evolution is stuck; "
                    "check that the model is well posed")
        self.events += count
        totals.events += count
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
        if record:
            xs = np.empty((len(theta), 2 * self.n))
            rs = np.empty((len(theta), 2 * self.n))
            ms = np.empty((len(theta), self.n), np.int8)
            xs[0], rs[0], ms[0] = self.x, self.r, self.modes
        for k in range(len(theta) - 1):
            self.advance(loads[k + 1], theta[k + 1] - theta[k], totals)
            if record:
                xs[k + 1], rs[k + 1], ms[k + 1] = self.x, self.r, self.modes
        if record:
            totals.samples = {"x": xs, "r": rs, "modes": ms}
        return totals
