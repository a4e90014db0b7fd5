"""Cycling to the steady state and its classification.

:func:`simulate` assembles the system (initial slip state or assembly protocol), then runs
load cycles with the exact evolution of :mod:`~slipcycle.discrete.evolution` until the
state at the start of a cycle repeats within a tolerance, or the maximum number of cycles
is reached. A state that creeps geometrically, by ρ of its last increment per cycle, is
still ρ/(1 − ρ) increments from its limit: that distance must be within the tolerance
too (plain cycling of an FE-reduced block of 41 contact nodes creeping at ρ = 0.95 at
tolerance 1e-8: the increment test alone stops with D 4.9e-6 off its limit, the
distance 3.7e-7). Both are measured against the service cycle's displacement, with a
round-off floor (:class:`~slipcycle.coupled.cycles.ResidualScale`), not the whole
load's: a preload would pass the transient of the first cycles as steady. The steady
cycle is classified as

- ``shakedown``: no node slips (nodes may still separate and close: ``separation``),
- ``cyclic_slip``: some nodes slip every cycle, the others stay permanently stuck,
- ``ratcheting``: the state drifts by the same amount every cycle (slip accumulates),
- ``not_converged``: no repetition within the cycles allowed; the residual is reported
  together with the dissipation of the last cycle run.

Dissipation per node D_j = −∮ q_j dv_j and in total are those of the last cycle run; the
energy balance Σ D_j = ∮ (vᵀdq^w + wᵀdp^w) is checked on it.

Where the state creeps geometrically towards its periodic orbit, :func:`simulate` follows
plain cycling on the current piece of the piecewise-affine cycle map without running its
cycles (:mod:`~slipcycle.discrete.periodic`), skips to where it leaves the piece or to its
limit, with the memory of the stuck nodes that plain cycling gives them, and checks every
skip by an exact cycle; ``accelerate=False`` is plain cycling.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from slipcycle.coupled.cycles import CycleHistory, assemble, for_cycles, run_scales
from slipcycle.coupled.driver import (
    SKIP,
    STEADY,
    BackOff,
    CycleState,
    PlainCycling,
    certificate,
    run_cycles,
)
from slipcycle.coupled.settings import RunSettings, SolverStats
from slipcycle.coupled.solution import CYCLE_CLASSES, CycleSolution, last_cycle
from slipcycle.discrete.evolution import Evolution
from slipcycle.discrete.lcp import lemke
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import SEPARATED, SLIP_NEG, SLIP_POS, FrictionalSystem
from slipcycle.discrete.periodic import (
    ROUND_OFF,
    SEGMENT_TOL,
    CycleJacobian,
    ModeIntervals,
    PieceConstraints,
    cycle_jacobian,
    follow_piece,
    piece_constraints,
    slow_mode_sum,
)
from slipcycle.errors import InadmissibleInitialState
from slipcycle.kernels.creep import creep_distance
from slipcycle.result import STEADY_STATES

__all__ = ["SteadyResult", "simulate", "initial_state", "InadmissibleInitialState",
           "STEADY_CLASSES", "STEADY_CODES", "ACCELERATE_MIN_NODES", "SLOW_MIN_NODES"]

#: the classes :func:`simulate` ends in (:data:`slipcycle.coupled.solution.CYCLE_CLASSES`)
STEADY_CLASSES = CYCLE_CLASSES

#: deprecated alias (for one release) of :data:`slipcycle.result.STEADY_STATES`, the one
#: list of steady-state words with their integer codes
STEADY_CODES = STEADY_STATES

#: smallest system stepped to its periodic state by default (``simulate(accelerate=None)``);
#: smaller ones cycle plainly: a cycle costs them little, and their cycle counts are the
#: reference numbers quoted for the examples
ACCELERATE_MIN_NODES = 16

#: smallest system whose accelerated run takes slow-mode steps by default
#: (``simulate(slow_modes=None)``): FE-reduced blocks of hundreds of nodes creep over
#: thousands of cycles that the follower cannot skip (their piece of the cycle map changes
#: every cycle), while on small random systems a step may carry a node past its stop
#: (``test_discrete_slow_modes.py``) and a cycle costs little
SLOW_MIN_NODES = 100

#: periodic-state steps refused by their checking cycle before a run stops trying
MAX_PERIODIC_REJECTIONS = 5

#: a node's interval of one mode may shrink this far below zero [rad] before a step
#: counts as changing its sequence of modes (round-off of simultaneous events)
INTERVAL_TOL = 1e-9

#: fewest cycles on one sequence of modes worth skipping (a skip costs a checking cycle)
MIN_SKIP = 3

#: a skip's checking cycle must land on the predicted start to this fraction of the skip's
#: length, or to the cycling tolerance (round-off of the products by M, and the changes
#: below the cycling tolerance that the follower lets pass)
SKIP_MATCH = 1e-6

#: most cycles followed on one piece at once (a longer path is skipped in parts)
MAX_FOLLOW = 1000

#: what :func:`_periodic_target` answers when a step looks possible on the events and
#: mode intervals of a cycle recorded without its inequalities
RECORD = "record the inequalities"

#: fruitless attempts of the follower in a row after which it backs off: after k ≥ this
#: many, the next attempt waits min(2^(k − this), :data:`MAX_ATTEMPT_WAIT`) cycles. An
#: attempt records the cycle's events and gathers its Jacobian, which costs about as much
#: as the cycle itself; where the piece of the cycle map changes every cycle (large
#: FE-reduced blocks, slip fronts of many nodes) it never finds a step
ATTEMPTS_BEFORE_WAIT = 4

#: most cycles between two attempts of a follower that keeps finding no step: a step
#: found that much later costs at most as many plain cycles
MAX_ATTEMPT_WAIT = 8

#: slow-mode steps (:func:`_slow_mode_target`) refused by their checking cycle before a run
#: stops trying them
MAX_SLOW_REJECTIONS = 10

#: a slow-mode step is refused when the cycle from it has a residual this many times that
#: of the cycle before it (the step wakes faster modes that the next cycles damp, so some
#: growth of the residual is not a failure; a step off its piece is one)
SLOW_GROWTH = 10.0

#: fewest ratio |Φ(x_k) − x_k| / |x_k − x_{k−1}| of a creep worth a slow-mode step: a
#: faster creep reaches the tolerance in a few more cycles anyway, and a step that
#: extrapolates it lands elsewhere more often (``test_discrete_slow_modes.py``)
SLOW_CREEP = 0.8

#: consecutive cycles in which the follower found no step before a slow-mode step is tried
#: (the follower keeps plain cycling's memory exactly and skips more at once where it can)
SLOW_AFTER = 3

#: what a slow-mode step's checking cycle is compared with (``predicted`` of a step)
SLOW = "slow"

#: a steady state reached with steps is polished by one more step down to this fraction
#: of the steady-state tolerance
POLISH = 1e-3

#: the slow-mode steps go on until their remaining distance is below
#: max(POLISH·tol, min(tol, this)) of the state's scale, tighter than the tolerance: D of
#: an FE-reduced block is small against its elastic energy, so D to 1e-6 needs the state to
#: about 1e-11, and a step skips the rest of a creep that plain cycling would take
#: thousands of cycles for (401-node block at tol 1e-8: 134 cycles and D 1.8e-7 off plain
#: cycling's limit, against 114 cycles and 9.0e-7 when the steps stop at the tolerance;
#: ``benchmarks/bench_accelerated.py``)
SLOW_SETTLED = 1e-11


def _same_piece(moving: frozenset, moving_step: frozenset, totals, force_tol: float) -> bool:
    """Whether the cycle from a step's target stayed on the piece of the cycle map the step
    was computed on, up to its boundary: no node moves that did not move then, and a node
    that moved then and no longer does came within ``force_tol`` of slipping or opening —
    the limit of a slip that shrank to nothing, not a node the step froze short of it."""
    if not moving <= moving_step:
        return False
    gone = np.array(sorted(moving_step - moving), dtype=int)
    return bool(np.all(totals.min_margin[gone] <= force_tol)) if gone.size else True


def _cycle_piece(evo: Evolution, system: FrictionalSystem, increment: np.ndarray,
                 drift_tol: float) -> CycleJacobian | None:
    """The Jacobian of the cycle just run (increment Φ(x) − x), with its event rates and
    segments, or None where the cycle is not on one piece of the map: a coordinate
    changed that no event of the cycle moves (a drift)."""
    jac = cycle_jacobian(evo.jacobian_log, system.K, system.friction)
    if jac is None or jac.rate is None:
        return None
    outside = np.ones(increment.size, bool)
    outside[jac.S] = False
    if np.any(np.abs(increment[outside]) > 1e-3 * drift_tol):
        return None
    return jac


def _periodic_target(evo: Evolution, system: FrictionalSystem, jac: CycleJacobian,
                     x: np.ndarray, increment: np.ndarray, r_w0: np.ndarray,
                     drift_tol: float):
    """Where plain cycling from ``x`` goes, found without running its cycles (the cycle
    map is piecewise affine: :mod:`~slipcycle.discrete.periodic`).

    ``increment`` = Φ(x) − x of the cycle just run, whose Jacobian ``jac``
    (:func:`_cycle_piece`), mode intervals and inequalities ``evo`` recorded. Plain
    cycling is followed on that piece of the map, one product by the cycle's Jacobian per
    cycle (:func:`~slipcycle.discrete.periodic.follow_piece`):

    - if it stays on the piece until its increments fall below a thousandth of the
      cycling tolerance, the answer is where it arrives: the periodic state of the piece
      with the memory plain cycling gives it (refused when it violates a friction or
      contact inequality at θ = 0);
    - if it leaves the piece after k ≥ :data:`MIN_SKIP` cycles (or after the most cycles
      followed at once), the answer is the start of the last cycle on the piece, x + d_k,
      with the start that cycle leads to, x + d_{k+1}, which the next cycle run must
      reproduce.

    The inequalities cost O(N) per event to record and O(E N) to gather, so a cycle
    records the events and mode intervals only, and the inequalities only when the cycle
    before found a step possible on those alone.

    Returns
    -------
    (target, predicted) : ((2N,) array, (2N,) array or None), :data:`RECORD` or None
        ``predicted`` is None for a periodic state; :data:`RECORD` asks for the
        inequalities in the next cycle.
    """
    intervals = ModeIntervals.from_log(evo.episode_log, INTERVAL_TOL)
    tiny = 1e-3 * drift_tol
    # the events and mode intervals alone first (O(E) per cycle followed): most refusals
    # happen there, before the inequalities are gathered (O(E N)); they only decide
    # whether a skip of MIN_SKIP cycles is possible, so they follow no further
    run = follow_piece(jac, increment, PieceConstraints.none(*jac.U.shape), intervals, tiny,
                       max_cycles=MIN_SKIP)
    if not run.reached and run.cycles < MIN_SKIP:
        return None
    if evo.margin_log is None:
        return RECORD          # worth a look: record the inequalities in the next cycle
    cons = piece_constraints(jac, evo.jacobian_log, evo.margin_log, evo.event_margin_log,
                             system.K, system.friction, ROUND_OFF * evo.force_tol,
                             ROUND_OFF * evo.solver.disp_tol, evo.switch_log)
    if cons is None:
        return None
    run = follow_piece(jac, increment, cons, intervals, tiny, max_cycles=MAX_FOLLOW)
    target = x.copy()
    if not run.reached:
        if run.cycles < MIN_SKIP:
            return None
        target[jac.S] += run.start
        predicted = x.copy()
        predicted[jac.S] += run.after
        return target, predicted
    target[jac.S] += run.after
    return (target, None) if _admissible(evo, system, target, r_w0) else None


def _admissible(evo: Evolution, system: FrictionalSystem, x: np.ndarray,
                r_w0: np.ndarray) -> bool:
    """Whether the state x (2N,) satisfies the friction and contact inequalities at θ = 0
    (load r_w0), within ten times the solver's thresholds."""
    n = system.n_nodes
    r = r_w0 + system.K @ x
    q, p, w = r[:n], r[n:], x[n:]
    ftol, dtol = 10 * evo.force_tol, 10 * evo.solver.disp_tol
    open_ = w > evo.solver.disp_tol
    bad = np.where(open_, (np.abs(q) > ftol) | (np.abs(p) > ftol),
                   (np.abs(q) > system.friction * p + ftol) | (p < -ftol)) | (w < -dtol)
    return not bad.any()


def _slow_mode_target(evo: Evolution, system: FrictionalSystem, jac: CycleJacobian,
                      x_next: np.ndarray, increment: np.ndarray, r_w0: np.ndarray,
                      drift_tol: float):
    """Where plain cycling creeps to along the slow eigenvectors of the cycle's Jacobian
    (:func:`~slipcycle.discrete.periodic.slow_mode_sum`), when the piece of the cycle map
    changes every cycle and cannot be followed. Events of different nodes may pass each
    other on the way (the map is continuous across such changes of piece), but the step
    ends where the first node's slip or opening shrinks to nothing (:func:`_before_a_stop`):
    that node stops there for good, with the slip plain cycling leaves it.

    ``x_next`` = Φ(x) is the start after the cycle just run, ``increment`` = Φ(x) − x and
    ``jac`` its Jacobian (:func:`_cycle_piece`).
    The step is further shortened (halved, at most three times) until its target
    satisfies the friction and contact inequalities at θ = 0. It is a guess: the next
    cycle checks it. Steps below ``drift_tol``/1000 [m] are not taken.

    Returns
    -------
    target : (2N,) array or None
    remaining : float
        The slow modes' whole remaining distance, max |Σ_{k≥1} λᵏ z| [m] (before any
        shortening): a state whose residual is below the tolerance is steady only when
        this is too.
    """
    extra = slow_mode_sum(jac, increment[jac.S])
    if not np.all(np.isfinite(extra)):
        return None, 0.0
    remaining = float(np.max(np.abs(extra), initial=0.0))
    extra = extra * _before_a_stop(jac, evo.episode_log, increment[jac.S], extra)
    if np.max(np.abs(extra), initial=0.0) <= 1e-3 * drift_tol:
        return None, remaining
    for alpha in (1.0, 0.5, 0.25, 0.125):
        target = x_next.copy()
        target[jac.S] += alpha * extra
        if _admissible(evo, system, target, r_w0):
            return target, remaining
    return None, remaining


def _before_a_stop(jac: CycleJacobian, episode_log: list, d: np.ndarray,
                   extra: np.ndarray) -> float:
    """The largest fraction α ≤ 1 of a slow-mode step before which no node stops: no
    node's interval of slip or separation shrinks to nothing, and no event leaves its load
    segment (a node that slipped on through a load sample may stop there instead). A node
    that stops keeps for good the slip plain cycling leaves it, which a longer step would
    move on (the piece's continuation past the stop slips it back, and the other nodes
    with it).

    On the piece, the events of the cycle from x + p move by δt = −c(p)/ġ
    (:meth:`~slipcycle.discrete.periodic.CycleJacobian.events_moved_by`), linear in p: the
    start after the recorded cycle is p = d, the step's target p = d + α·extra. Limits
    that the next cycle crosses already (α = 0) are plain cycling's own and do not bind.
    """
    iv = ModeIntervals.from_log(episode_log, INTERVAL_TOL)
    s0, s1 = jac.events_moved_by(d), jac.events_moved_by(extra)
    # a stick between two slips that vanishes joins them: the node slips on, and its
    # slip is set by its friction limit, not by its memory
    frees = np.isin(iv.mode, (SLIP_POS, SLIP_NEG, SEPARATED))
    room = np.concatenate([(iv.length + iv.change(s0))[frees] + iv.tol[frees],
                           (jac.hi - jac.time - s0) + SEGMENT_TOL,     # to the segment's end
                           (jac.time + s0 - jac.lo) + SEGMENT_TOL])    # to its start
    use = np.concatenate([iv.change(s1)[frees], s1, -s1])
    hit = np.isfinite(room) & (room >= 0) & (room + use < 0)
    if not hit.any():
        return 1.0
    return max(min(1.0, float(np.min(room[hit] / -use[hit]))), 0.0)


@dataclass(kw_only=True)
class SteadyResult(CycleSolution):
    """Outcome of :func:`simulate`: the fields of
    :class:`~slipcycle.coupled.solution.CycleSolution` (M = 2N: ``x = [v, w]``; ``modes``
    0 stick, 1 slip_positive, 2 slip_negative, 3 separated, on the last piece before each
    sample) and those of the exact 2-D engine.

    Attributes
    ----------
    events_per_cycle : list of int
        Events located in each cycle.
    initial_state : (2N,) array or None
        The state at θ = 0 before the first cycle [m].
    """

    events_per_cycle: list = field(default_factory=list)
    initial_state: np.ndarray | None = None


def initial_state(system: FrictionalSystem, r_w: np.ndarray, v0: np.ndarray,
                  force_tol: float) -> np.ndarray:
    """State x = [v0, w] at load r^w for an imposed slip v0.

    The separation w solves the contact LCP  w ≥ 0, p = p^w + B v0 + C w ≥ 0, wᵀp = 0
    (unique, C positive definite). Then every node must satisfy |q_j| ≤ f_j p_j.

    Raises
    ------
    InadmissibleInitialState
        Naming the first offending node and its margin f p − |q| < 0.
    """
    n = system.n_nodes
    v0 = np.asarray(v0, float)
    p_w = r_w[n:]
    w = lemke(system.C, p_w + system.B @ v0)
    if w is None:  # pragma: no cover - C is SPD, Lemke always succeeds
        raise RuntimeError("contact problem for the initial state has no solution")
    x = np.concatenate([v0, w])
    r = r_w + system.K @ x
    q, p = r[:n], r[n:]
    margin = system.friction * p - np.abs(q)
    bad = np.flatnonzero(margin < -force_tol)
    if bad.size:
        j = int(bad[np.argmin(margin[bad])])
        what = ("is separated at θ = 0 but carries a tangential reaction q = "
                f"{q[j]:.6g} N") if w[j] > 0 else (
            f"violates the friction inequality |q| ≤ f p at θ = 0: q = {q[j]:.6g} N, "
            f"f p = {system.friction[j] * p[j]:.6g} N")
        raise InadmissibleInitialState(j, float(margin[j]), what, bool(w[j] > 0))
    return x


def simulate(system: FrictionalSystem, load: DiscreteLoad, *, cycles: int = 40,
             steps_per_cycle: int = 100, initial_slip: np.ndarray | None = None,
             protocol: np.ndarray | None = None, tol: float = 1e-8, min_cycles: int = 1,
             record: bool = True, accelerate: bool | None = None,
             slow_modes: bool | None = None,
             progress: Callable[[float, float], None] | None = None) -> SteadyResult:
    """Run load cycles to the steady state.

    Parameters
    ----------
    system : FrictionalSystem
    load : DiscreteLoad
    cycles : int
        Maximum number of cycles.
    steps_per_cycle : int
        Load samples per cycle (the path is linear between samples; breakpoints of
        tabulated loads are added).
    initial_slip : (N,) array, optional
        Slip v0 at θ = 0 (must be admissible). Excludes ``protocol``.
    protocol : (S, 2N) array, optional
        Assembly protocol: load states r^w = [q^w, p^w] visited in order, linearly, from
        the unloaded undeformed state before the first cycle; the path then goes on
        linearly to the load at θ = 0. Without either, the system is loaded linearly from
        the unloaded state to the load at θ = 0.
    tol : float
        Relative tolerance of the steady-state test: the last increment of the
        start-of-cycle state, and, where the increments shrink geometrically by ρ per
        cycle, the rest of the creep, ρ/(1 − ρ) times the last increment
        (:func:`~slipcycle.kernels.creep.creep_distance`), must both be below it. If
        the cycles run out with only the increment below it, the run is classified as
        steady all the same.
    min_cycles : int
        Run at least this many cycles.
    record : bool
        Keep the sample histories of every cycle.
    accelerate : bool, optional
        Step to the periodic state once two consecutive cycles share one sequence of modes
        and events (:mod:`~slipcycle.discrete.periodic`), then check it by an exact cycle;
        a state reached with steps is certified by plain cycles from it that reproduce
        their start within ``tol`` (:func:`~slipcycle.coupled.driver.certify`; the result's
        ``certificate``). ``False``: plain cycling. Default (None): on for N ≥
        :data:`ACCELERATE_MIN_NODES`. Where the attempts keep finding no step they back
        off (:data:`ATTEMPTS_BEFORE_WAIT`, :data:`MAX_ATTEMPT_WAIT`).
    slow_modes : bool, optional
        With the steps on: where no step has been found for :data:`SLOW_AFTER` cycles
        (the piece of the cycle map changes every cycle), also step along the slow modes
        of the cycle's Jacobian, each step ending where the first node stops
        (:func:`_slow_mode_target`); a residual below ``tol`` is then steady only when
        the slow modes' remaining distance is below max(1e-3 ``tol``, min(``tol``,
        :data:`SLOW_SETTLED`)). Steps are taken only where the
        last increment kept at least :data:`SLOW_CREEP` of the one before. Default
        (None): on for N ≥ :data:`SLOW_MIN_NODES`. A node that stops or starts to slip
        during such a step is not seen, so the stuck nodes' memory is plain cycling's
        only approximately (on the 401-node FE block at ``tol`` 1e-11, to 1e-6 of the
        state, and D to 1e-6; on a random 4-node system with steps allowed after the
        first cycle, D 7.3e-4 off): small systems take none by default.
    progress : callable, optional
        ``progress(cycles_done, cycles)``, called after each cycle (a progress bar); the run
        may stop before ``cycles`` at its steady state.

    Returns
    -------
    SteadyResult
    """
    settings = RunSettings(cycles=cycles, steps_per_cycle=steps_per_cycle, tol=tol,
                           min_cycles=min_cycles)
    theta, vals, F, disp_scale = run_scales(system, load, steps_per_cycle, protocol)
    evo = _assembled(system, vals, F, initial_slip, protocol)
    x_init = evo.x.copy()
    history = CycleHistory.of_run(system, vals, disp_scale, tol, evo.x, record)
    run = CycleState(system, evo, settings, history, vals[0], F)
    accel = (system.n_nodes >= ACCELERATE_MIN_NODES) if accelerate is None else bool(accelerate)
    slow = system.n_nodes >= SLOW_MIN_NODES if slow_modes is None else bool(slow_modes)
    steps = PieceSteps(accel, accel and slow)
    run_cycles(run, theta, vals, steps, progress)
    res = _steady_result(system, evo, run.state, run.residual, run.ratchet, run.totals,
                         run.starts, steps.events, run.history.dissipation,
                         run.history.records(), theta, vals, tol, disp_scale, F, x_init,
                         steps.stats)
    res.certificate = certificate(run, steps)
    return res


class PieceSteps(PlainCycling):
    """The accelerator of the exact 2-D engine: steps on the piecewise-affine cycle map.

    Where the same nodes moved in the last two cycles, the periodic follower
    (:func:`_periodic_target`) follows plain cycling on the current piece of the map and
    skips to where it leaves the piece or to its limit; where it keeps finding no step
    it backs off (:data:`ATTEMPTS_BEFORE_WAIT`, :data:`MAX_ATTEMPT_WAIT`). With
    ``slow_modes``, where it found none for :data:`SLOW_AFTER` cycles, a step along the
    slow modes of the cycle's Jacobian (:func:`_slow_mode_target`). Every step is checked
    by the next, exact, cycle and undone when that cycle refuses it. With ``accel`` off
    this is plain cycling (the exact engine's events are still counted).

    Parameters
    ----------
    accel : bool
        Take steps at all.
    slow_modes : bool
        Also the slow-mode steps.
    """

    def __init__(self, accel: bool, slow_modes: bool):
        super().__init__()
        self.accel = accel
        self.events = []               # events located in each cycle kept
        self.stats = {"periodic_attempts": 0, "periodic_steps": 0,
                      "periodic_steps_rejected": 0, "cycles_discarded": 0,
                      "slow_mode_steps": 0, "slow_mode_steps_rejected": 0}
        self.targets = set()           # indices into ``starts`` that are targets of a step
        self.saved = None              # what to restore if the checking cycle refuses
        self.follower = Follower()
        self.slow = SlowModes(slow_modes)
        self.backoff = BackOff(ATTEMPTS_BEFORE_WAIT, MAX_ATTEMPT_WAIT)
        self.no_step = 0               # cycles in a row in which the follower found no step
        self.moving_prev = None        # nodes the events of the last kept cycle moved
        self.attempt = False
        self.checking = self.moving = None
        self.near, self.same = np.inf, False

    def before_cycle(self, run: CycleState) -> None:
        # record what a step needs only in a cycle that may attempt one
        self.attempt = (self.accel and (self.follower.active or self.slow.active)
                        and self.backoff.ready)
        self.follower.record(run.evo, self.attempt)

    def after_cycle(self, run: CycleState) -> None:
        self.events.append(run.totals.events)

    def ratchet_test(self, run: CycleState) -> bool:
        return len(run.starts) >= 3 and len(run.starts) - 2 not in self.targets

    @property
    def method(self) -> str:
        st = self.stats
        if st["slow_mode_steps"] > st["slow_mode_steps_rejected"]:
            return "slow_modes"
        return "periodic" if st["periodic_steps"] > st["periodic_steps_rejected"] else "none"

    def certifying(self, run: CycleState) -> None:
        self.follower.record(run.evo, False)

    def judge(self, run: CycleState) -> str | None:
        starts, tol, totals = run.starts, run.settings.tol, run.totals
        checking, self.saved = self.saved, None
        # the rest of a geometric creep must be below the tolerance too (not after a step)
        self.near = run.residual if checking is not None or len(starts) - 2 in self.targets \
            else creep_distance(starts, run.residual, run.xscale)
        # nodes that slipped (beyond round-off) or opened in this cycle
        moving = frozenset(np.flatnonzero((totals.slip_length > 1e-3 * tol * run.xscale)
                                          | totals.separated).tolist()) if self.accel else None
        refuse = checking is not None and self._refused(run, checking, moving)
        if refuse:
            run.residual = np.inf
        # the last increment alone below the tolerance: steady if the cycles run out
        # before the creep's distance is too (the test before that estimate)
        run.increment_steady = run.residual <= tol and run.counted
        if not run.counted and checking is None:
            self.moving_prev = moving
            return SKIP
        # a steady state that plain cycling would accept is polished by one more step
        # (when the last two cycles allow one) to POLISH·tol, closer to the true limit
        same = self.moving_prev is not None and moving == self.moving_prev
        polish = (self.attempt and self.follower.active and not run.last and same
                  and checking is None and run.residual > POLISH * tol)
        # where slow-mode steps are on, a residual below the tolerance is not yet steady:
        # the creep's remaining distance is about residual / (1 − λ), and the next slow-mode
        # step says whether it is below the tolerance (else it takes the step)
        polish = polish or (self.slow.active and not run.last
                            and self.no_step >= SLOW_AFTER and self.attempt
                            and run.residual > POLISH * tol)
        if self.near <= tol and run.counted and not polish:
            return STEADY
        if refuse:
            return self._undo(run, checking)
        self.moving, self.same = moving, same
        return None

    def _refused(self, run: CycleState, checking: tuple, moving: frozenset) -> bool:
        """Whether the cycle run from a step's target refuses the step."""
        starts, tol = run.starts, run.settings.tol
        if checking[5] is SLOW:
            # a slow-mode step: the cycle from it must not creep off (a step off its
            # piece lands where the residual grows)
            return run.residual > SLOW_GROWTH * checking[3]
        if checking[5] is not None:
            # a skip: the checking cycle must land where plain cycling goes
            skip = float(np.max(np.abs(starts[-2] - checking[0])))
            return bool(np.max(np.abs(starts[-1] - checking[5]))
                        > SKIP_MATCH * skip + 1e-3 * tol * run.xscale)
        # a periodic state: the cycle from it stays on its piece and gets closer
        return (not _same_piece(moving, checking[4], run.totals, 10 * tol * run.F)
                or run.residual > 0.5 * checking[3])

    def _undo(self, run: CycleState, checking: tuple) -> str:
        """Discard the checking cycle of a refused step (it left the piece of the cycle
        map it was computed on) and go on cycling from where the step was taken."""
        starts = run.starts
        run.history.drop_last()
        self.events.pop()
        self.targets.discard(len(starts) - 1)
        starts[-1], run.evo.modes, run.totals, run.residual, self.moving_prev = checking[:5]
        run.restart(starts[-1])
        slow = checking[5] is SLOW
        self.stats["periodic_steps_rejected"] += 1
        self.stats["slow_mode_steps_rejected"] += slow
        self.stats["cycles_discarded"] += 1
        (self.slow if slow else self.follower).left -= 1
        self.backoff.hold(1 if slow else 2)
        if run.residual <= run.settings.tol and run.counted:
            return STEADY      # the state the refused polishing step started from
        return SKIP

    def step(self, run: CycleState) -> str | None:
        if self.attempt and not run.last:
            target, predicted, settled = self._target(run)
            # a slow-mode step still possible (above round-off) does not keep a state
            # from being steady once the slow modes' whole remaining distance is below the
            # tolerance: the steps would only chase the round-off of the cycle
            if (self.near <= run.settings.tol and run.counted and settled
                    and (target is None or predicted is SLOW)):
                return STEADY
            if target is not None:
                self.stats["periodic_steps"] += 1
                self.stats["slow_mode_steps"] += predicted is SLOW
                self.saved = (run.starts[-1].copy(), run.evo.modes.copy(), run.totals,
                              run.residual, self.moving, predicted)
                run.starts[-1] = target
                self.targets.add(len(run.starts) - 1)
                run.restart(target)
        self.backoff.tick()
        self.moving_prev = self.moving
        return None

    def _target(self, run: CycleState):
        """The follower's step, else a slow-mode step: (target, predicted, settled)."""
        self.stats["periodic_attempts"] += 1
        # the follower where the same nodes moved in the last two cycles (the cycle
        # map on one piece), then the slow modes where it found no step for a while
        follow = self.same and self.follower.active
        jac = (_cycle_piece(run.evo, run.system, run.d1, run.settings.tol * run.xscale)
               if follow or self.slow.wants_jacobian(self.no_step) else None)
        step = self.follower.propose(run, jac if follow else None)
        target, predicted = (None, None) if step is None or step is RECORD else step
        self.no_step = self.no_step + 1 if target is None else 0
        # back off where the follower keeps finding nothing (not while slow-mode
        # steps, which need every cycle's Jacobian, are on; a cycle that asks for
        # the inequalities is part of the same attempt)
        self.backoff.outcome(None if step is RECORD else step is not None,
                             may_wait=not self.slow.active)
        settled = True     # no slow mode says the state is still far from periodic
        if target is None and jac is not None and self.slow.due(self.no_step):
            target, settled = self.slow.propose(run, jac, self.targets)
            predicted = SLOW
        return target, predicted, settled


class Follower:
    """The periodic follower: plain cycling followed on the current piece of the
    piecewise-affine cycle map without running its cycles (:func:`_periodic_target`).

    It stops trying after :data:`MAX_PERIODIC_REJECTIONS` refused steps (:attr:`left`);
    a cycle that found a step possible on the events and mode intervals alone asks the
    next cycle to record the inequalities too.
    """

    def __init__(self):
        self.left = MAX_PERIODIC_REJECTIONS    # refusals before the follower stops
        self.inequalities = False              # the next cycle records the inequalities

    @property
    def active(self) -> bool:
        """Whether the follower still tries."""
        return self.left > 0

    def record(self, evo: Evolution, attempt: bool) -> None:
        """Have the next cycle record what an attempt needs."""
        evo.jacobian_log = [] if attempt else None
        evo.margin_log = [] if attempt and self.inequalities else None
        self.inequalities = False

    def propose(self, run: CycleState, jac: CycleJacobian | None):
        """The step on the piece of the cycle just run (``jac``; None: no attempt):
        ``(target, predicted)``, :data:`RECORD` or None (:func:`_periodic_target`)."""
        step = None
        if jac is not None:
            step = _periodic_target(run.evo, run.system, jac, run.starts[-2], run.d1,
                                    run.r_w0, run.settings.tol * run.xscale)
        self.inequalities = step is RECORD
        return step


class SlowModes:
    """The slow-mode steps: where the piece of the cycle map changes every cycle, a step
    along the slow eigenvectors of the cycle's Jacobian, ending where the first node stops
    (:func:`_slow_mode_target`), taken where the state creeps slowly (the last increment
    kept :data:`SLOW_CREEP` of the one before) after :data:`SLOW_AFTER` cycles without a
    step of the follower. Off after :data:`MAX_SLOW_REJECTIONS` refused steps.

    Parameters
    ----------
    on : bool
        Take slow-mode steps at all.
    """

    def __init__(self, on: bool):
        self.left = MAX_SLOW_REJECTIONS if on else 0   # refusals before they stop

    @property
    def active(self) -> bool:
        """Whether slow-mode steps are still tried."""
        return self.left > 0

    def wants_jacobian(self, no_step: int) -> bool:
        """Whether the next attempt needs the cycle's Jacobian for a slow-mode step."""
        return self.active and no_step + 1 >= SLOW_AFTER

    def due(self, no_step: int) -> bool:
        """Whether a slow-mode step is tried after ``no_step`` cycles without a step."""
        return self.active and no_step >= SLOW_AFTER

    def propose(self, run: CycleState, jac: CycleJacobian, targets: set):
        """``(target, settled)``: the step (None: none) and whether the slow modes'
        whole remaining distance is below max(POLISH·tol, min(tol, SLOW_SETTLED))."""
        starts, d1 = run.starts, run.d1
        # a step from the first cycles, before a slow creep shows, extrapolates a
        # transient and lands on another periodic state
        creep = len(starts) >= 3 and (
            len(starts) - 2 in targets
            or np.max(np.abs(d1)) >= SLOW_CREEP * np.max(np.abs(starts[-2] - starts[-3])))
        if not creep:
            return None, True
        tol = run.settings.tol
        target, remaining = _slow_mode_target(run.evo, run.system, jac, starts[-1], d1,
                                              run.r_w0, tol * run.xscale)
        return target, remaining <= max(POLISH * tol, min(tol, SLOW_SETTLED)) * run.xscale


def _assembled(system: FrictionalSystem, vals: np.ndarray, F: float,
               initial_slip: np.ndarray | None, protocol: np.ndarray | None) -> Evolution:
    """The evolution at θ = 0 (:func:`~slipcycle.coupled.cycles.assemble`), assembled
    with tolerances relative to the whole load F [N], continued for the cycles with the
    service cycle's (:func:`~slipcycle.coupled.cycles.for_cycles`); ``vals`` the (S, M)
    load samples [N]."""
    def evolution(x0, rw, scale):
        return Evolution(system, x0, rw, scale)

    evo = assemble(lambda x0, rw: evolution(x0, rw, F), system, vals[0], F, initial_slip,
                   protocol, initial_state)
    return for_cycles(evolution, evo, vals, F)


def _steady_result(system, evo, state, residual, ratchet, totals, starts, events, diss_hist,
                   records, theta, vals, tol, disp_scale, F, x_init, jstats) -> SteadyResult:
    """Classify the last cycle (stuck, slipping and separating nodes) and pack the run."""
    return SteadyResult(
        residual=residual, cycles_run=len(events), theta=theta, events_per_cycle=events,
        solver_stats=SolverStats(solver=dict(evo.solver.stats), **jstats),
        dissipation_history=diss_hist, initial_state=x_init, force_scale=F,
        **last_cycle(system, state, ratchet, totals, starts, tol, disp_scale, vals,
                     records, len(theta)))
