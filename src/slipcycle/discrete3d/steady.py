"""Cycling the 3-D system to its steady state, and its classification.

The same procedure and classes as the 2-D model: the system is assembled (initial slip
state, or an assembly protocol followed linearly from the unloaded state, or plain
loading to the load at θ = 0), then load cycles are run with
:class:`~slipcycle.discrete3d.evolution.Evolution3D` until the start-of-cycle state
repeats within ``tol`` (``shakedown`` if no node slips in that cycle, else
``cyclic_slip``), or the per-cycle drift repeats (``ratcheting``), or ``cycles`` is
reached (``not_converged``). A node "slips" in the last cycle when its slip length
∮|dv_j| exceeds max(100 tol, 1e-9) × the displacement scale (Barber 2012, §3).

Acceleration. Near a periodic state the start-of-cycle states x_c of plain cycling
approach their limit geometrically (a contraction of the cycle map P, x_{c+1} = P(x_c),
whose linearisation about the periodic state has spectral radius < 1); with weak
damping of the slip pattern the ratio is close to 1 and tol is reached only after many
cycles. Once the cycles' pattern (the set of nodes that slip, the set that separate, the
rest stuck) repeats, the limit is extrapolated from the last states by reduced rank
extrapolation (Eddy 1979; Mešina 1977; Sidi, Ford & Smith, SIAM J. Numer. Anal. 1986):
the combination x* = Σ γ_i x_{i+1}, Σ γ_i = 1, that minimises |Σ γ_i (x_{i+1} − x_i)|,
exact for a linear map with k+1 differences when the error lies in k eigen-directions.
The steady state is a set (the stuck nodes' slips are any values their cones admit,
Barber 2012), and the member plain cycling reaches is selected by the history; the
extrapolation keeps it: a node stuck in every cycle of the sequence has exactly the same
slip in all its states, hence the same in x*, and only the components that plain cycling
moves are moved. The jump is tried only in the geometric regime (the last changes
shrink by ratios agreeing within 10 %). x* is then validated by plain cycles from it:
it is accepted only through the ordinary test — a cycle reproduces its start within
``tol`` — and the jump is undone (cycling resumes from the state before it) if the next
cycle's change is not smaller than the last plain change, if in it a node slips or opens
that was stuck and closed in every cycle of the sequence (its memory would change), or
if plain cycling after it stalls (the largest change of 4 cycles above 0.8 × that of the
4 before; acceleration then ends). The accepted state is therefore a fixed point of the
cycle map to the same tolerance as plain cycling's, in the same member of the set.

The cycle map is that of the discretised evolution, whose step control makes it only
piecewise smooth: its refinement decisions change the state by up to about ``step_tol``
× the displacement scale, and below that level plain cycling can settle on a small
periodic orbit (seen with period 4, of amplitude 0.2–0.4 ``step_tol``) instead of a
fixed point, and a ``tol`` well below ``step_tol`` may not be reached.

Frozen subdivision (``replay``). To make the cycle map one fixed function, once the
pattern repeats (the condition of the acceleration: the same slipping / separated / stuck
nodes in two successive cycles) the subdivision of the load intervals that the step
control chose in the last cycle is frozen and replayed in the following cycles
(:class:`~slipcycle.discrete3d.evolution.Evolution3D`, ``plan``): the same sub-steps,
kept as the adaptive method kept them, without the rejected coarser steps and the error
estimates. The replayed map is smooth where the adaptive one has jumps, so plain cycling
and the extrapolation converge to its fixed point; each cycle is cheaper. Every
``replay_check``-th replayed cycle the error estimates are computed as well, and a
sub-step whose end states differ from the recorded ones has its estimate checked too; one
whose estimate fails is redone adaptively, and the subdivision that cycle ended with is
frozen instead. The replayed map equals the adaptive one only where the step control would take
the same decisions, so a fixed point of the replayed map is accepted only after one
adaptive cycle from it reproduces its start within ``tol``; otherwise cycling continues
adaptively (and the subdivision of that cycle may be frozen in turn, at most
``replay_max`` times). The result is therefore a steady state of the adaptive method
within ``tol``, as without replay. Replay is off by default: measured on the FE-like
benchmark chain (1000 and 2000 nodes, ``step_tol`` 1e-4, ``tol`` 1e-6) it removes about
a third of the step solves but the run still does not reach ``tol`` in 50 cycles, and
with the extrapolation near a shakedown it can time a jump so that dying slips stop
elsewhere (another member of the set of steady states).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import nnls

from slipcycle.discrete3d.evolution import Evolution3D
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.errors import InadmissibleInitialState
from slipcycle.kernels.threads import single_threaded
from slipcycle.loading.nodal import force_scale

__all__ = ["SteadyResult3D", "simulate3d", "initial_state_3d", "InadmissibleInitialState3D",
           "STEADY_CLASSES"]

STEADY_CLASSES = ("shakedown", "cyclic_slip", "ratcheting", "not_converged")


class InadmissibleInitialState3D(InadmissibleInitialState):
    """The initial slip violates the cone or contact at θ = 0 (node, margin f p − |q|)."""


@dataclass
class SteadyResult3D:
    """Outcome of :func:`simulate3d` (SI units; nodes numbered from 0).

    Attributes
    ----------
    steady_state : str
        ``shakedown``, ``cyclic_slip``, ``ratcheting`` or ``not_converged``.
    residual : float
        max |x_c − x_{c−1}| of the last two start-of-cycle states / displacement scale.
    cycles_run : int
    dissipation_per_node : (N,) array
        D_j of the last cycle [J].
    work_of_loads : float
        ∮ (vᵀdq^w + wᵀdp^w) of the last cycle [J].
    theta : (n+1,) array
        Sample angles of one cycle [rad].
    x, r : (cycles_run, n+1, 3N) arrays
        States [v, w] (m) and reactions [q, p] (N) at the samples of every cycle.
    modes : (cycles_run, n+1, N) int8 array
        Node state at the end of the step reaching each sample (0 stick, 1 slip,
        2 separated).
    cycle_start_states : (cycles_run + 1, 3N) array
    slip_length : (N,) array
        ∮|dv_j| over the last cycle [m].
    """

    steady_state: str
    residual: float
    cycles_run: int
    dissipation_per_node: np.ndarray
    work_of_loads: float
    slipping_nodes: list
    permanently_stuck_nodes: list
    separating_nodes: list
    theta: np.ndarray
    x: np.ndarray
    r: np.ndarray
    modes: np.ndarray
    cycle_start_states: np.ndarray
    ratchet_per_cycle: np.ndarray
    all_slip_or_separated: bool
    disp_scale: float
    force_scale: float
    slip_length: np.ndarray
    slip_tolerance: float
    steps_per_cycle_taken: list = field(default_factory=list)
    refinements_per_cycle: list = field(default_factory=list)
    dissipation_history: list = field(default_factory=list)
    stored_energy_change: float = 0.0
    normal_work: float = 0.0
    solver_stats: dict = field(default_factory=dict)
    unresolved_steps: int = 0
    #: extrapolation jumps of the start-of-cycle state (accepted, undone)
    jumps: int = 0
    jumps_undone: int = 0
    #: cycles run on a frozen subdivision, subdivisions frozen, and replayed sub-steps
    #: that did not fit (redone adaptively)
    replayed_cycles: int = 0
    replay_freezes: int = 0
    replay_mismatches: int = 0

    @property
    def dissipation_per_cycle(self) -> float:
        """Total dissipation of the last cycle [J]."""
        return float(np.sum(self.dissipation_per_node))

    @property
    def energy_balance_error(self) -> float:
        """|W − ΣD − ΔΠ| of the last cycle / max(|W|, |ΣD|, F·x_scale) (ΔΠ: change of
        ½xᵀKx + r^wᵀx; the normal-work term of opening steps is part of the error)."""
        d = self.dissipation_per_cycle
        ref = max(abs(d), abs(self.work_of_loads), self.force_scale * self.disp_scale)
        return abs(self.work_of_loads - d - self.stored_energy_change) / ref

    @property
    def steady_converged(self) -> bool:
        return self.steady_state != "not_converged"


def initial_state_3d(system: FrictionalSystem3D, r_w: np.ndarray, v0: np.ndarray,
                     force_tol: float) -> np.ndarray:
    """State x = [v0, w] at load r^w for an imposed slip v0 (2N,).

    The separation solves the contact problem w ≥ 0, p = p^w + B v0 + C w ≥ 0, wᵀp = 0,
    the minimum of ½wᵀCw + cᵀw over w ≥ 0 (C positive definite: a non-negative least
    squares problem on the Cholesky factor, unique). Every node must then lie in its cone.

    Raises
    ------
    InadmissibleInitialState3D
        Naming the node with the most negative margin f p − |q|.
    """
    n = system.n_nodes
    v0 = np.asarray(v0, float).reshape(2 * n)
    c = r_w[2 * n:] + system.B @ v0
    L = np.linalg.cholesky(system.C)
    w, _ = nnls(L.T, -np.linalg.solve(L, c))
    x = np.concatenate([v0, w])
    r = r_w + system.K @ x
    q = r[:2 * n].reshape(n, 2)
    p = r[2 * n:]
    margin = system.friction * p - np.linalg.norm(q, axis=1)
    bad = np.flatnonzero(margin < -force_tol)
    if bad.size:
        j = int(bad[np.argmin(margin[bad])])
        what = (f"is separated at θ = 0 but carries a tangential reaction |q| = "
                f"{np.linalg.norm(q[j]):.6g} N") if w[j] > 0 else (
            f"lies outside the friction cone |q| ≤ f p at θ = 0: |q| = "
            f"{np.linalg.norm(q[j]):.6g} N, f p = {system.friction[j] * p[j]:.6g} N")
        raise InadmissibleInitialState3D(j, float(margin[j]), what, bool(w[j] > 0))
    return x


@single_threaded   # small dense solves of the active nodes (kernels.threads)
def simulate3d(system: FrictionalSystem3D, load: Load3D, *, cycles: int = 40,
               steps_per_cycle: int = 100, initial_slip: np.ndarray | None = None,
               protocol: np.ndarray | None = None, tol: float = 1e-8, min_cycles: int = 1,
               step_tol: float = 1e-7, record: bool = True, adaptive: bool = True,
               substeps: int = 1, extrapolate: bool = True, accelerate: bool = True,
               accel_order: int = 3, replay: bool = False, replay_check: int = 5,
               replay_max: int = 20) -> SteadyResult3D:
    """Run load cycles to the steady state.

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
    cycles : int
        Maximum number of cycles.
    steps_per_cycle : int
        Load samples per cycle (path linear between samples).
    initial_slip : (N, 2) or (2N,) array, optional
        Slip at θ = 0 [m] (must be admissible). Excludes ``protocol``.
    protocol : (S, 3N) array, optional
        Assembly: load states [q^w, p^w] visited linearly from the unloaded state, then on
        to the load at θ = 0.
    tol : float
        Relative steady-state tolerance.
    min_cycles : int
    step_tol : float
        Relative tolerance of the step control (:class:`Evolution3D`).
    record : bool
        Keep the sample histories of every cycle.
    adaptive, substeps : bool, int
        Step doubling, or ``substeps`` fixed steps per load interval.
    extrapolate : bool
        Richardson extrapolation of smooth doubled steps.
    accelerate : bool
        Extrapolate the start-of-cycle state to the limit of plain cycling once the
        pattern of slipping / separated / stuck nodes repeats, validated by the next
        cycle (module docstring); False: plain cycling.
    accel_order : int
        Number k of differences (beyond one) the extrapolation combines; it is applied
        after k + 1 cycles with the same pattern.
    replay : bool
        With ``adaptive``: freeze the step control's subdivision once the pattern
        repeats and replay it, verifying the result with an adaptive cycle (module
        docstring); False (default): every cycle adaptive. Off by default: with
        ``accelerate`` near a shakedown (the slip of some nodes dying out) the slightly
        different sequence of the replayed map can time the extrapolation so that those
        nodes stop elsewhere, another member of the set of steady states than plain
        cycling reaches.
    replay_check : int
        Every this many replayed cycles the error estimates are checked as well.
    replay_max : int
        Largest number of times a subdivision is frozen.

    Returns
    -------
    SteadyResult3D
    """
    n = system.n_nodes
    theta, vals = load.cycle_samples(steps_per_cycle)
    F = force_scale(vals if protocol is None else np.vstack([vals, protocol]))
    disp_scale = F / system.stiffness_scale()
    opts = {"step_tol": step_tol, "adaptive": adaptive, "substeps": substeps,
            "extrapolate": extrapolate}
    if initial_slip is not None:
        x0 = initial_state_3d(system, vals[0], initial_slip, 1e-10 * F)
        evo = Evolution3D(system, x0, vals[0], F, **opts)
    else:
        evo = Evolution3D(system, np.zeros(3 * n), np.zeros(3 * n), F, **opts)
        path = [np.zeros(3 * n)]
        if protocol is not None:
            path += list(np.atleast_2d(protocol))
        path.append(vals[0])
        path = np.array(path)
        evo.follow(np.arange(len(path), dtype=float), path)
        evo.resync()
    starts = [evo.x.copy()]
    xs, rs, ms, diss_hist, steps, refs = [], [], [], [], [], []
    state, residual, totals = "not_converged", np.inf, None
    ratchet = np.zeros(2 * n)
    unresolved = 0
    # acceleration: ``seq`` the start states of the current run of plain cycles with one
    # pattern (seq[i+1] = P(seq[i])), ``pattern`` that pattern, ``pending`` the state
    # before an unvalidated jump and the last plain change
    seq, pattern, pending = [evo.x.copy()], None, None
    jumps = undone = 0
    plain_from = 0          # starts[plain_from:] are successive plain cycles
    res_prev = np.inf
    probation = None        # (state before the last jump, residuals since it)
    # frozen subdivision: ``replaying`` the cycles run on evo.plan since it was frozen,
    # ``verify`` the next cycle is the adaptive check of a replayed fixed point
    replay = replay and adaptive
    replaying, verify, freezes, replayed, mismatches = 0, False, 0, 0, 0

    def switch_map():
        # the cycle map changes (frozen ↔ adaptive): the extrapolation's sequence and the
        # ratcheting test restart with cycles of the new map
        nonlocal seq, pattern, plain_from, res_prev
        seq, pattern, plain_from, res_prev = [evo.x.copy()], None, len(starts) - 1, np.inf

    for c in range(cycles):
        was_replay, was_verify = evo.plan is not None, verify
        verify = False
        if was_replay:
            evo.check_plan = replaying % max(replay_check, 1) == replay_check - 1
        totals = evo.follow(theta, vals, record=record)
        evo.resync()
        unresolved += totals.unresolved
        if was_replay:
            replaying += 1
            replayed += 1
            mismatches += totals.replay_mismatches
        starts.append(evo.x.copy())
        diss_hist.append(float(totals.dissipation.sum()))
        steps.append(totals.steps)
        refs.append(totals.refinements)
        if record:
            xs.append(totals.samples["x"])
            rs.append(totals.samples["r"])
            ms.append(totals.samples["modes"])
        xscale = max(disp_scale, float(np.max(np.abs(np.array(starts[-2:])))))
        d1 = starts[-1] - starts[-2]
        residual = float(np.max(np.abs(d1))) / xscale
        cyc_tol = max(100 * tol, 1e-9) * xscale
        pat = np.concatenate([totals.slip_length > cyc_tol, totals.separated])
        stalled = False
        if probation is not None and residual > tol:
            hist = probation[1]
            hist.append(residual)
            # after a jump plain cycling must keep converging: over the last 4 cycles the
            # largest change at most 0.8 × that of the 4 before (a ratio ≤ 0.94 per
            # cycle); a stall (e.g. a small periodic orbit of the discretised cycle map
            # near the jumped state) undoes the jump and ends the acceleration
            stalled = len(hist) >= 8 and max(hist[-4:]) > 0.8 * max(hist[-8:-4])
        if pending is not None or stalled:
            if pending is not None:
                x_before, res_before, pat_before = pending
            else:
                x_before, res_before, pat_before = probation[0], -np.inf, pattern
                accelerate = False
            pending = None
            if stalled or residual > tol and (residual >= res_before
                                              or np.any(pat & ~pat_before)):
                # the jump did not bring the state closer to a periodic one, or a node
                # stuck and closed in every cycle of the sequence slipped or opened (its
                # memory would change: another member of the steady set): undo it and
                # resume plain cycling from the state before it. (A node whose slip per
                # cycle was dying out may stop: plain cycling does the same in the limit.)
                undone += 1
                probation = None
                evo.x = x_before.copy()
                evo.resync()
                starts[-1] = evo.x.copy()
                seq, pattern, plain_from, res_prev = [evo.x.copy()], None, len(starts) - 1, \
                    np.inf
                continue
        if was_replay and totals.replay_mismatches:
            # the frozen subdivision no longer fits the path: freeze the subdivision this
            # cycle ended with (the misfitting steps redone adaptively), or return to
            # adaptive cycles once ``replay_max`` subdivisions have been frozen
            evo.plan, replaying = (totals.plan if freezes < replay_max else None), 0
            freezes += evo.plan is not None
            switch_map()
            continue
        if c + 1 < min_cycles:
            res_prev = residual
            continue
        if residual <= tol:
            if not was_replay:
                state = "steady"
                break
            # a fixed point of the replayed map: accepted only if an adaptive cycle from
            # it reproduces it within tol
            evo.plan, replaying, verify = None, 0, True
            switch_map()
            continue
        if was_verify and freezes < replay_max and pending is None:
            # the adaptive cycle from the replayed fixed point took other decisions:
            # freeze its subdivision and replay that one
            evo.plan, replaying = totals.plan, 0
            freezes += 1
            switch_map()
            continue
        if len(starts) - plain_from >= 3:
            d0 = starts[-2] - starts[-3]
            rres = float(np.max(np.abs(d1 - d0))) / xscale
            # a drift that repeats is ratcheting; one shrinking by a constant factor is a
            # slow approach to a periodic state
            if rres <= tol and np.max(np.abs(d1 - d0)) <= 1e-3 * np.max(np.abs(d1)):
                ratchet = d1[:2 * n]
                residual = rres
                state = "ratcheting"
                break
        if pattern is None or not np.array_equal(pat, pattern):
            seq, pattern = [starts[-2], starts[-1]], pat
        else:
            seq.append(starts[-1])
            if (replay and evo.plan is None and freezes < replay_max and pending is None
                    and not was_verify):
                # the pattern repeats: freeze this cycle's subdivision (the replayed map
                # equals the adaptive one at the states so far, which the extrapolation
                # keeps using)
                evo.plan, replaying = totals.plan, 0
                freezes += 1
        shrinking = residual < res_prev
        res_prev = residual
        # the extrapolation is tried in the geometric regime only (the last changes
        # shrink by a steady ratio); after a jump that had to be undone, a longer run of
        # the pattern is required, and after three no more jumps are tried
        if (accelerate and shrinking and c + 2 < cycles and undone < 3
                and len(seq) >= accel_order + 2 + 3 * undone
                and _geometric(np.array(seq[-(accel_order + 2):]))):
            x_star = _rre(np.array(seq[-(accel_order + 2):]))
            if x_star is not None and np.all(np.isfinite(x_star)):
                pending = (starts[-1].copy(), residual, pattern)
                probation = (starts[-1].copy(), [])
                jumps += 1
                x_star[2 * n:] = np.maximum(x_star[2 * n:], 0.0)   # separations ≥ 0
                evo.x = x_star
                evo.resync()
                starts[-1] = x_star.copy()
                seq, pattern, plain_from, res_prev = [x_star.copy()], None, \
                    len(starts) - 1, np.inf
    slip_tol = max(100 * tol, 1e-9) * max(disp_scale, float(np.max(np.abs(starts[-1]))))
    slipping = np.flatnonzero(totals.slip_length > slip_tol)
    separating = np.flatnonzero(totals.separated)
    stuck = np.flatnonzero((totals.slip_length <= slip_tol) & ~totals.separated)
    if state == "steady":
        state = "shakedown" if slipping.size == 0 else "cyclic_slip"
    if state != "ratcheting":
        ratchet = starts[-1][:2 * n] - starts[-2][:2 * n]
    x0, x1 = starts[-2], starts[-1]
    K = system.K
    d_stored = float(0.5 * (x1 @ K @ x1 - x0 @ K @ x0) + vals[0] @ (x1 - x0))
    if record and xs:
        X, R, Mo = np.array(xs), np.array(rs), np.array(ms)
    else:
        X = R = np.zeros((0, len(theta), 3 * n))
        Mo = np.zeros((0, len(theta), n), np.int8)
    return SteadyResult3D(
        steady_state=state, residual=residual, cycles_run=len(diss_hist),
        dissipation_per_node=totals.dissipation.copy(), work_of_loads=totals.work,
        slipping_nodes=slipping.tolist(), permanently_stuck_nodes=stuck.tolist(),
        separating_nodes=separating.tolist(), theta=theta, x=X, r=R, modes=Mo,
        cycle_start_states=np.array(starts), ratchet_per_cycle=ratchet,
        all_slip_or_separated=totals.all_slip_or_separated, disp_scale=disp_scale,
        force_scale=F, slip_length=totals.slip_length.copy(), slip_tolerance=slip_tol,
        steps_per_cycle_taken=steps, refinements_per_cycle=refs,
        dissipation_history=diss_hist, stored_energy_change=d_stored,
        normal_work=totals.normal_work, solver_stats=dict(evo.solver.stats),
        unresolved_steps=unresolved, jumps=jumps, jumps_undone=undone,
        replayed_cycles=replayed, replay_freezes=freezes, replay_mismatches=mismatches)


def _geometric(states: np.ndarray, spread: float = 1.1) -> bool:
    """The changes u_i = x_{i+1} − x_i of the sequence ``states`` ((k+2, M)) shrink by
    ratios |u_{i+1}|/|u_i| < 1 that agree within the factor ``spread``: the error is then
    dominated by few slowly decaying directions of the cycle map and the extrapolation
    applies; before that (a pattern still settling) it could overshoot."""
    norms = np.linalg.norm(np.diff(states, axis=0), axis=1)
    if np.any(norms == 0.0):
        return False
    ratios = norms[1:] / norms[:-1]
    return bool(ratios.max() < 1.0 and ratios.max() <= spread * ratios.min())


def _rre(states: np.ndarray, max_gain: float = 200.0) -> np.ndarray | None:
    """Reduced rank extrapolation of a fixed-point sequence.

    Parameters
    ----------
    states : (k + 2, M) array
        Successive iterates x_0 … x_{k+1} of x_{i+1} = P(x_i).
    max_gain : float
        The jump from x_{k+1} may be at most this many times the last change (a ratio
        of the sequence up to 1 − 1/max_gain); larger ones are refused.

    Returns
    -------
    (M,) array or None
        x* = Σ γ_i x_{i+1} with Σ γ_i = 1 minimising |Σ γ_i u_i|, u_i = x_{i+1} − x_i
        (Sidi, Ford & Smith, SIAM J. Numer. Anal. 23, 1986); components that did not
        change along the sequence are returned unchanged. None if the problem is
        degenerate or the jump is implausibly large.
    """
    U = np.diff(states, axis=0)                    # (k+1, M)
    moving = np.flatnonzero(np.any(U != 0.0, axis=0))
    last = float(np.max(np.abs(U[-1]))) if moving.size else 0.0
    if last == 0.0:
        return None
    Um = U[:, moving] / last
    # γ_k = 1 − Σ_{i<k} γ_i: min |u_k + Σ_{i<k} γ_i (u_i − u_k)|, a least-squares problem
    # solved by the SVD (minimum norm where the changes are linearly dependent)
    W = (Um[:-1] - Um[-1]).T
    g = np.linalg.lstsq(W, -Um[-1], rcond=1e-12)[0]
    if not np.all(np.isfinite(g)):
        return None
    gamma = np.append(g, 1.0 - g.sum())
    x = states[-1].copy()
    x[moving] = gamma @ states[1:, moving]
    if float(np.max(np.abs(x - states[-1]))) > max_gain * last:
        return None
    return x
