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
cone's 2×2 linearisation on the slipping rows. Reactions are updated incrementally,
r ← r + K[:, U] δ, so a step costs O(N m + m³) and nothing of size N².

Step control (step doubling, as for ODE integrators): each load interval is solved as one
step and as two half steps; if the end states differ by more than ``step_tol`` × the
displacement scale (or their dissipations by ``step_tol`` × force × displacement scale)
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

Energy bookkeeping per step (trapezoidal): D_j += −½(q_j⁰ + q_j¹)·Δv_j and
W += ½(x⁰ + x¹)·Δr^w; with these the discrete stored energy Π = ½xᵀKx + r^wᵀx changes by
exactly W − ΣD + Σ ½(p⁰ + p¹)Δw (the last term vanishes except in steps where a node
opens or closes).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from slipcycle.discrete3d.cone import node_states, slip_linearisation
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


class StepSolver:
    """Semismooth Newton solver of the incremental problem of one load step.

    Parameters
    ----------
    system : FrictionalSystem3D
    force_scale : float
        Typical load [N]; the Newton residual tolerance is ``rel_tol`` × it.
    rel_tol : float
        Relative residual tolerance of the Newton iteration.
    max_iter : int
        Newton iterations before the step is declared failed (the caller halves it).
    """

    def __init__(self, system: FrictionalSystem3D, force_scale: float,
                 rel_tol: float = 1e-11, max_iter: int = 60):
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
        self.stats = {"solves": 0, "newton_iterations": 0, "failures": 0}
        self._rows_q = np.arange(2 * n).reshape(n, 2)

    def solve(self, x0: np.ndarray, r0: np.ndarray, drw: np.ndarray) -> Step | None:
        """Solve one load step from state ``x0`` (3N,) with reactions ``r0`` (3N,) under the
        load increment ``drw`` (3N,).

        Returns
        -------
        Step or None
            None if the Newton iteration did not converge within ``max_iter``.
        """
        self.stats["solves"] += 1
        n, K, f = self.n, self.K, self.f
        x = x0.copy()
        r = r0 + drw
        v0 = x0[:2 * n].reshape(n, 2)
        for it in range(self.max_iter):
            dv = x[:2 * n].reshape(n, 2) - v0
            w = x[2 * n:]
            q = r[:2 * n].reshape(n, 2)
            p = r[2 * n:]
            modes, z, zn = node_states(q, p, dv, w, f, self.rho_t, self.rho_n)
            stick = modes == STICK
            contact = modes != SEPARATED
            fix_t = np.flatnonzero(stick & np.any(dv != 0.0, axis=1))
            fix_n = np.flatnonzero(contact & (w != 0.0))
            if fix_t.size or fix_n.size:
                # the Newton rows of stuck / closed nodes are the identity: exact
                cols = np.concatenate([self._rows_q[fix_t].ravel(), 2 * n + fix_n])
                delta = -np.concatenate([dv[fix_t].ravel(), w[fix_n]])
                x[cols] += delta
                r += delta @ K[cols]          # K symmetric: rows are contiguous
                dv = x[:2 * n].reshape(n, 2) - v0
                q = r[:2 * n].reshape(n, 2)
                p = r[2 * n:]
            S = np.flatnonzero(modes == SLIP)
            P = np.flatnonzero(modes == SEPARATED)
            zs = q[S] - self.rho_t[S, None] * dv[S]
            zsn = np.linalg.norm(zs, axis=1)
            zsn = np.where(zsn > 0, zsn, 1e-300)
            Rs = q[S] - (f[S] * p[S] / zsn)[:, None] * zs
            Rp = np.concatenate([q[P], p[P, None]], axis=1)
            R = np.concatenate([Rs.ravel(), Rp.ravel()])
            if R.size == 0 or np.max(np.abs(R)) <= self.force_tol:
                if not (fix_t.size or fix_n.size):
                    self.stats["newton_iterations"] += it
                    return Step(x, r, modes, drw, it)
                if R.size == 0:
                    continue
            # condensed Newton system over U = slipping (2 each) + separated (3 each)
            U = np.concatenate([self._rows_q[S].ravel(),
                                np.column_stack([self._rows_q[P], 2 * n + P]).ravel()])
            KUr = K[U]                        # (m, 3N) rows = columns of K (symmetric)
            m = U.size
            ns = S.size
            J = np.empty((m, m))
            if ns:
                phi, nvec = slip_linearisation(zs, zsn, p[S], f[S], self.rho_t[S])
                Kq = KUr[:, self._rows_q[S].ravel()].T.reshape(ns, 2, m)
                Kp = KUr[:, 2 * n + S].T
                Js = (Kq - np.einsum("sab,sbm->sam", phi, Kq)
                      - (f[S][:, None, None] * nvec[:, :, None]) * Kp[:, None, :])
                # + ρ_t Φ on the node's own slip columns (positions 2i, 2i+1 of U)
                i = np.arange(ns)
                Js[i, :, 2 * i] += self.rho_t[S, None] * phi[:, :, 0]
                Js[i, :, 2 * i + 1] += self.rho_t[S, None] * phi[:, :, 1]
                J[:2 * ns] = Js.reshape(2 * ns, m)
            if P.size:
                rows = np.column_stack([self._rows_q[P], 2 * n + P]).ravel()
                J[2 * ns:] = KUr[:, rows].T
            try:
                delta = np.linalg.solve(J, -R)
            except np.linalg.LinAlgError:
                break
            if not np.all(np.isfinite(delta)):
                break
            x[U] += delta
            r += delta @ KUr
        self.stats["failures"] += 1
        return None


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
    samples: dict = field(default_factory=dict)

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
    """

    def __init__(self, system: FrictionalSystem3D, x0: np.ndarray, r_w0: np.ndarray,
                 force_scale: float, *, step_tol: float = 1e-7, max_depth: int = 30,
                 substeps: int = 1, adaptive: bool = True, extrapolate: bool = True):
        self.sys = system
        self.n = system.n_nodes
        self.K = system.K
        self.F = float(force_scale)
        self.disp_scale = self.F / system.stiffness_scale()
        self.solver = StepSolver(system, self.F)
        self.step_tol = float(step_tol)
        self.max_depth = int(max_depth)
        self.substeps = int(substeps)
        self.adaptive = bool(adaptive)
        self.extrapolate = bool(extrapolate)
        self.x = np.array(x0, float)
        self.r_w = np.array(r_w0, float)
        self.r = self.r_w + self.K @ self.x
        disp_tol = 1e-12 * self.disp_scale
        self.modes = np.where(self.x[2 * self.n:] > disp_tol, SEPARATED, STICK).astype(np.int8)
        self._totals: PathTotals3D | None = None
        #: set to a list to record every committed step (x, r, modes, x_before) for checks
        self.step_log: list | None = None

    def resync(self) -> None:
        """Recompute r = r^w + K x exactly (removes round-off drift of the updates)."""
        self.r = self.r_w + self.K @ self.x

    # -- bookkeeping ----------------------------------------------------------------------
    def _step_dissipation(self, x0, r0, step: Step) -> np.ndarray:
        n = self.n
        dv = (step.x[:2 * n] - x0[:2 * n]).reshape(n, 2)
        qm = 0.5 * (r0[:2 * n] + step.r[:2 * n]).reshape(n, 2)
        return -np.einsum("ja,ja->j", qm, dv)

    def _commit(self, step: Step) -> None:
        n, t = self.n, self._totals
        x0, r0 = self.x, self.r
        if t is not None:
            t.dissipation += self._step_dissipation(x0, r0, step)
            t.work += float(0.5 * (x0 + step.x) @ step.drw)
            t.normal_work += float(0.5 * (r0[2 * n:] + step.r[2 * n:])
                                   @ (step.x[2 * n:] - x0[2 * n:]))
            dv = (step.x[:2 * n] - x0[:2 * n]).reshape(n, 2)
            slip = step.modes == SLIP
            t.slip_length[slip] += np.linalg.norm(dv[slip], axis=1)
            t.separated |= step.modes == SEPARATED
            t.slipped |= slip
            t.all_slip_or_separated |= bool(np.all(step.modes != STICK))
            t.steps += 1
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
        exact by a return-map step without load increment."""
        dx = h2.x - full.x
        U = np.flatnonzero(dx)
        x = h2.x.copy()
        x[U] += dx[U]
        r = h2.r + dx[U] @ self.K[U]
        # return to the admissible set: a step with no load increment from the
        # extrapolated state (an O(h⁴) correction) makes the cone and contact exact again
        proj = self.solver.solve(x, r, np.zeros_like(r))
        if proj is None or not np.array_equal(proj.modes, h2.modes):
            return h2
        return Step(proj.x, proj.r, proj.modes, h2.drw, h2.iterations + proj.iterations)

    def _solve(self, x, r, drw):
        return self.solver.solve(x, r, drw)

    def _interval(self, rwa: np.ndarray, rwb: np.ndarray, full: Step | None, depth: int):
        x0, r0 = self.x, self.r
        if full is None:
            full = self._solve(x0, r0, rwb - rwa)
        if full is not None and (not self.adaptive or self._exact(full)):
            self._commit(full)
            return
        mid = 0.5 * (rwa + rwb)
        h1 = self._solve(x0, r0, mid - rwa)
        h2 = None if h1 is None else self._solve(h1.x, h1.r, rwb - mid)
        if full is not None and h2 is not None:
            err = float(np.max(np.abs(full.x - h2.x))) / self.disp_scale
            d_full = float(np.sum(self._step_dissipation(x0, r0, full)))
            d_half = float(np.sum(self._step_dissipation(x0, r0, h1))
                           + np.sum(self._step_dissipation(h1.x, h1.r, h2)))
            err_d = abs(d_full - d_half) / (self.F * self.disp_scale)
            smooth = self._smooth(full, h1, h2)
            # the estimate is that of the half-step (first-order) result; the extrapolated
            # result of a smooth step is O(h³), i.e. about est^(3/2) in scaled units
            tol = self.step_tol ** (2.0 / 3.0) if smooth else self.step_tol
            if max(err, err_d) <= tol:
                self._commit(h1)
                self._commit(self._extrapolate(full, h2) if smooth else h2)
                return
        if depth >= self.max_depth:
            if h2 is None:
                raise IncrementalSolverError(
                    "the incremental problem of a load step has no solution the Newton "
                    "method can find, even on a step 2^-" f"{self.max_depth} of a load "
                    "interval; the friction coefficient is probably above the critical "
                    "value for the current set of slipping and separated nodes")
            if self._totals is not None:
                self._totals.unresolved += 1
            self._commit(h1)
            self._commit(h2)
            return
        if self._totals is not None:
            self._totals.refinements += 1
        self._interval(rwa, mid, h1, depth + 1)
        # h2 was computed from h1: still valid if the first half was kept as h1
        self._interval(mid, rwb, h2 if (h1 is not None and self.x is h1.x) else None,
                       depth + 1)

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
        if record:
            xs = [self.x.copy()]
            rs = [self.r.copy()]
            ms = [self.modes.copy()]
        self.r_w = np.array(vals[0], float)
        for k in range(len(vals) - 1):
            if self.adaptive:
                self._interval(vals[k], vals[k + 1], None, 0)
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
        return t
