"""Cycling the 3-D system to its steady state, and its classification.

The same procedure and classes as the 2-D model: the system is assembled (initial slip
state, or an assembly protocol followed linearly from the unloaded state, or plain
loading to the load at θ = 0), then load cycles are run with
:class:`~slipcycle.discrete3d.evolution.Evolution3D` until the start-of-cycle state
repeats within ``tol`` and, where its increments shrink geometrically, the rest of the
creep is within ``tol`` too (:func:`~slipcycle.kernels.creep.creep_distance`)
(``shakedown`` if no node slips in that cycle, else ``cyclic_slip``), or the per-cycle
drift repeats (``ratcheting``), or ``cycles`` is reached (``not_converged``; steady if the
last increment alone was below ``tol``). A node "slips" in the last cycle when its slip length
∮|dv_j| exceeds max(100 tol, 1e-9) × the displacement scale (Barber 2012, §3).

Acceleration (opt-in, ``accelerate=True``; the default is plain cycling). Near a periodic
state the start-of-cycle states x_c of plain cycling approach their limit geometrically
(a contraction of the cycle map P, x_{c+1} = P(x_c), whose linearisation about the
periodic state has spectral radius < 1); with weak damping of the slip pattern the ratio
is close to 1 and tol is reached only after many cycles (on the 2000-node benchmark
chain, 0.987 per cycle: the nodes at the edge of the slip zones, whose slip per cycle is
small, creep toward their limit). Once the cycles' pattern (the set of nodes that slip,
the set that separate, the rest stuck) repeats and its changes shrink by a steady ratio,
the limit is extrapolated by reduced rank extrapolation (Eddy 1979; Mešina 1977; Sidi,
Ford & Smith, SIAM J. Numer. Anal. 1986): the combination x* = Σ γ_i x_{i+1}, Σ γ_i = 1,
that minimises |Σ γ_i (x_{i+1} − x_i)|, exact for a linear map with k+1 differences when
the error lies in k eigen-directions. From then on every cycle of the run jumps: the
pairs (x_i, P(x_i)) of its cycles, the jumped ones included, are combined by Anderson
mixing (Anderson, J. ACM 1965; Walker & Ni, SIAM J. Numer. Anal. 2011; equivalent to
GMRES on a linear map), x* = Σ α_i P(x_i) with Σ α_i = 1 minimising |Σ α_i (P(x_i) −
x_i)|, over the last ``ANDERSON_WINDOW`` pairs. The steady state is a set (the stuck
nodes' slips are any values their cones admit, Barber 2012), and the member plain cycling
reaches is selected by the history; the mixing keeps it: a node stuck in every cycle of
the run has exactly the same slip in all its states, hence the same in x*, and only the
components that the cycles move are moved. Mixing is not monotone; the jumps fail, and
cycling resumes from the end of the best cycle of the run, if a node stuck and closed in
every cycle of the run slips or opens (its memory would change), or if the change of a
cycle rises above ``ANDERSON_GROWTH`` times the best one or does not improve on it for
``ANDERSON_PATIENCE`` jumps (twice the mixing goes on with the failed pair among its
secants, then a longer plain run is required; three failures end the jumps). After the
jumps, plain cycling must keep converging: if it stalls (the largest change of 4 cycles
above 0.8 × that of the 4 before) the state before the first jump is restored and
acceleration ends. A state is accepted only through the ordinary test — a cycle
reproduces its start within ``tol`` — so it is a fixed point of the cycle map to the same
tolerance as plain cycling's. It keeps the memory of every node stuck throughout the run;
a node whose slip is still dying out when the jumps start may stop a little elsewhere
than plain cycling would stop it, i.e. on another member of the set (the tests compare
with plain cycling to a tight tolerance on random coupled systems and FE-like chains of
50 and 200 nodes: equal within the cycling tolerance, D within 1e-9. On the benchmark
chain of 500 nodes, whose slip-zone edge node creeps for 2290 plain cycles, 40
accelerated cycles end with that node 1.7e-3 of the largest slip elsewhere and D 4.1e-5
above plain cycling's limit — a hundredth of the step control's error of D at
``step_tol`` 1e-4, 0.5 % (both measured once; the plain run takes five minutes). On the
2-D FE-reduced block of 401 nodes, whose creeping nodes stop one by one over 2000 cycles,
the same mixing moved the dissipation by up to 3e-4, which is why the 2-D model follows
its exact piecewise-affine map instead, :mod:`slipcycle.discrete.periodic`). On the
CalculiX C3D8I block of 121 contact nodes (``benchmarks/bench_accelerated.py``) the
mixing ends after 62 cycles with D 8.7e-5 and the state 8.0e-4 of the slip scale off
plain cycling's limit, while the creep of its certifying cycles reads about 1e-9: no
cycle sees a jump to another member of the set. Nor does a gentler extrapolation follow
the trajectory: reduced rank extrapolation of that block's plain sequence (windows 3–12)
leaves an error of 6–19 d² (d the plain sequence's distance to its limit, relative to the
slip scale: the sequence is no sum of a few geometric terms), and plain cycling from the
extrapolated state keeps much of that error on the set of steady states (jumps that
landed 1.3e-3, 4.2e-5 and 2.9e-6 off end 7.2e-5, 4.2e-5 and 2.9e-6 from plain cycling's
limit; ``bench_accelerated.extrapolation_rows``): within 1e-6 of that limit a jump saves
few cycles. Plain cycling is the default (``accelerate`` None or False); an Anderson
run's certificate reports :data:`ANDERSON_DISTANCE`, the largest distances measured on
the benchmark systems, as its distance from plain cycling's limit
(:class:`~slipcycle.coupled.driver.Certificate`).

The cycle map is that of the discretised evolution, whose step control makes it only
piecewise smooth: its refinement decisions change the state by up to about ``step_tol``
× the displacement scale, and below that level plain cycling can settle on a small
periodic orbit (seen with period 4, of amplitude 0.2–0.4 ``step_tol``) instead of a
fixed point, and the mixing, which needs one smooth map, stalls: a ``tol`` well below
``step_tol`` may not be reached.

Frozen subdivision (``replay``). To make the cycle map one fixed function, once the
pattern repeats (the same slipping / separated / stuck nodes in two successive cycles)
the subdivision of the load intervals that the step control chose in the last cycle is
frozen and replayed in the following cycles
(:class:`~slipcycle.discrete3d.evolution.Evolution3D`, ``plan``): the same sub-steps,
kept as the adaptive method kept them (with or without the extrapolation), without the
rejected coarser steps and the error estimates. The replayed map is smooth where the
adaptive one has jumps, so plain cycling and the mixing converge to its fixed point;
each cycle is cheaper. Outside the jumps every ``replay_check``-th replayed cycle
computes the error estimates as well; in every cycle a sub-step whose end states differ
from the recorded ones has its estimate checked too, and one whose estimate fails is
redone adaptively (outside the jumps the subdivision that cycle ended with is then frozen
instead, at most ``replay_max`` times; during the jumps the map stays the replay of one
subdivision). A fixed point of the replayed map is accepted only after a verifying
replay from it with every sub-step's error estimate checked fits the subdivision (no
sub-step redone) and reproduces its start within ``tol``; otherwise the corrected
subdivision is frozen and cycling goes on. The result is therefore a periodic state of a
discretisation every step of which passes the step control's error test, within ``tol``:
the adaptive method itself, which may take coarser steps where the test allows, moves it
by the step control's error level (about ``step_tol`` × the displacement scale; 3e-5 at
``step_tol`` 1e-5 on a 60-node chain, tested), and the two dissipate the same energy to
that level. Replay is off by default: near a shakedown (the slip of some nodes dying
out) the slightly different sequence of the replayed map can time a jump so that those
nodes stop elsewhere, another member of the set of steady states than plain cycling
reaches.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import nnls

from slipcycle.coupled.anderson import anderson as _anderson
from slipcycle.coupled.anderson import geometric as _geometric
from slipcycle.coupled.cycles import CycleHistory, assemble, for_cycles, run_scales
from slipcycle.coupled.driver import (
    SKIP,
    STEADY,
    CycleState,
    PlainCycling,
    certificate,
    run_cycles,
)
from slipcycle.coupled.settings import RunSettings, SolverStats
from slipcycle.coupled.solution import CYCLE_CLASSES, CycleSolution, last_cycle
from slipcycle.discrete3d.evolution import Evolution3D
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.errors import InadmissibleInitialState
from slipcycle.kernels.creep import creep_distance
from slipcycle.kernels.threads import single_threaded

__all__ = ["SteadyResult3D", "simulate3d", "initial_state_3d", "InadmissibleInitialState3D",
           "STEADY_CLASSES"]

#: the classes :func:`simulate3d` ends in (:data:`slipcycle.coupled.solution.CYCLE_CLASSES`)
STEADY_CLASSES = CYCLE_CLASSES

#: Anderson mixing of the cycle starts: secant pairs used, largest rise of the residual
#: over the best one of the run, and jumps allowed without improving on it
ANDERSON_WINDOW = 16
ANDERSON_GROWTH = 10.0
ANDERSON_PATIENCE = 8

#: (state, D): the distances of an Anderson-mixed steady state from plain cycling's
#: limit that its certificate reports at least (relative to the slip scale, and to D),
#: the largest measured on the benchmark systems rounded up: the CalculiX block 8.0e-4
#: and 8.7e-5 (``benchmarks/bench_accelerated.py``), the FE-like chain of 500 nodes
#: 1.7e-3 and 4.1e-5 (module docstring). Measured, not a bound for every system.
ANDERSON_DISTANCE = (2e-3, 1e-4)


class InadmissibleInitialState3D(InadmissibleInitialState):
    """The initial slip violates the cone or contact at θ = 0 (node, margin f p − |q|)."""


@dataclass(kw_only=True)
class SteadyResult3D(CycleSolution):
    """Outcome of :func:`simulate3d`: the fields of
    :class:`~slipcycle.coupled.solution.CycleSolution` (M = 3N: ``x = [v, w]`` with
    node-major (t1, t2) slips; ``modes`` 0 stick, 1 slip, 2 separated at the end of the
    step reaching each sample) and those of the step-controlled 3-D engine.

    Attributes
    ----------
    steps_per_cycle_taken, refinements_per_cycle : list of int
        Load steps taken and step refinements of each cycle.
    normal_work : float
        Work of the normal loads on opening steps of the last cycle [J] (part of the
        energy balance error).
    unresolved_steps : int
        Steps whose error estimate stayed above the tolerance at the smallest step.
    """

    steps_per_cycle_taken: list = field(default_factory=list)
    refinements_per_cycle: list = field(default_factory=list)
    normal_work: float = 0.0
    unresolved_steps: int = 0

    # the accelerators' counts (:class:`~slipcycle.coupled.settings.SolverStats`)
    @property
    def jumps(self) -> int:
        """Extrapolation jumps of the start-of-cycle state accepted."""
        return self.solver_stats.jumps

    @property
    def jumps_undone(self) -> int:
        """Extrapolation jumps undone."""
        return self.solver_stats.jumps_undone

    @property
    def replayed_cycles(self) -> int:
        """Cycles run on a frozen subdivision."""
        return self.solver_stats.replayed_cycles

    @property
    def replay_freezes(self) -> int:
        """Subdivisions frozen."""
        return self.solver_stats.replay_freezes

    @property
    def replay_mismatches(self) -> int:
        """Replayed sub-steps that did not fit (redone adaptively)."""
        return self.solver_stats.replay_mismatches


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
               substeps: int = 1, extrapolate: bool = True, accelerate: bool | None = None,
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
    accelerate : bool or None
        True: extrapolate the start-of-cycle state to the limit of plain cycling once the
        pattern of slipping / separated / stuck nodes repeats, then mix every following
        cycle of the pattern (Anderson), each validated by the next cycle; the state may
        end on another member of the set of steady states than plain cycling's, and the
        certificate reports :data:`ANDERSON_DISTANCE` (module docstring). None (default)
        or False: plain cycling.
    accel_order : int
        Number k of differences (beyond one) the first extrapolation combines; it is
        applied after k + 1 cycles with the same pattern.
    replay : bool
        With ``adaptive``: freeze the step control's subdivision once the pattern
        repeats and replay it; the result is a periodic state of a subdivision whose
        every step passes the error test (module docstring). False (default): every
        cycle adaptive. Recommended for large systems with ``tol`` below ``step_tol``,
        where the adaptive map's switching decisions stall the mixing; off by default
        because near a shakedown (the slip of some nodes dying out) the replayed map can
        time a jump so that those nodes stop elsewhere, another member of the set of
        steady states than plain cycling reaches.
    replay_check : int
        Every this many replayed cycles the error estimates are checked as well.
    replay_max : int
        Largest number of times a subdivision is frozen.

    Returns
    -------
    SteadyResult3D
    """
    settings = RunSettings(cycles=cycles, steps_per_cycle=steps_per_cycle, tol=tol,
                           min_cycles=min_cycles, step_tol=step_tol, replay=replay)
    theta, vals, F, disp_scale = run_scales(system, load, steps_per_cycle, protocol)
    opts = {"step_tol": step_tol, "adaptive": adaptive, "substeps": substeps,
            "extrapolate": extrapolate}
    def evolution(x0, rw, scale):
        return Evolution3D(system, x0, rw, scale, **opts)

    evo = assemble(lambda x0, rw: evolution(x0, rw, F), system, vals[0], F, initial_slip,
                   protocol, initial_state_3d)
    # the cycles' force tolerances, step control and steady-state residual follow the
    # service cycle, not the whole load the assembly was stepped on
    evo = for_cycles(evolution, evo, vals, F)
    history = CycleHistory.of_run(system, vals, disp_scale, tol, evo.x, record)
    evo.disp_scale = history.scale.step_scale(evo.x, step_tol)
    run = CycleState(system, evo, settings, history, vals[0], F)
    mix = Mixing(bool(accelerate), accel_order, replay and adaptive, replay_check,
                 replay_max)
    run_cycles(run, theta, vals, mix)
    history, totals = run.history, run.totals
    stats = SolverStats(solver=dict(evo.solver.stats), jumps=mix.jumps,
                        jumps_undone=mix.undone, replayed_cycles=mix.replay.replayed,
                        replay_freezes=mix.replay.freezes,
                        replay_mismatches=mix.replay.mismatches)
    return SteadyResult3D(
        residual=run.residual, cycles_run=len(history.dissipation), theta=theta,
        force_scale=F, steps_per_cycle_taken=mix.steps, refinements_per_cycle=mix.refs,
        dissipation_history=history.dissipation, normal_work=totals.normal_work,
        solver_stats=stats, unresolved_steps=mix.unresolved,
        certificate=certificate(run, mix),
        **last_cycle(system, run.state, run.ratchet, totals, run.starts, tol, disp_scale,
                     vals, history.records(), len(theta)))


class Mixing(PlainCycling):
    """The accelerator of the 3-D engine: Anderson mixing of the start-of-cycle states,
    with the replay of a frozen subdivision of the step control (:class:`Replay`; module
    docstring).

    Once the pattern of slipping / separated / stuck nodes repeats and the changes of the
    plain cycles shrink geometrically, the start is extrapolated to the limit
    (:func:`~slipcycle.coupled.anderson.anderson`), then every following cycle of the
    pattern is mixed; jumps that fail (a stuck node's memory changes, the residual grows
    or stalls) are undone. With ``replay`` the subdivision of a repeating pattern is
    frozen and replayed, and a fixed point of the replayed map is verified by a replay
    with every error estimate checked.

    Parameters
    ----------
    accelerate : bool
        The Anderson jumps (False: plain cycling, with replay if asked).
    accel_order : int
        Differences (beyond one) the first jump combines.
    replay : bool
        Freeze and replay the step control's subdivision.
    replay_check : int
        Every this many replayed cycles the error estimates are checked as well.
    replay_max : int
        Most subdivisions frozen.
    """

    def __init__(self, accelerate: bool, accel_order: int, replay: bool, replay_check: int,
                 replay_max: int):
        super().__init__()
        self.accelerate, self.accel_order = accelerate, accel_order
        self.replay = Replay(replay, replay_check, replay_max)
        self.steps, self.refs, self.unresolved = [], [], 0
        # ``pairs`` the (start, end) states (x_i, P(x_i)) of the cycles of the current run
        # with one pattern, ``run_jumps`` the jumps made in it, ``pattern`` that pattern;
        # ``best`` (end state, residual, cycles since) the best cycle since the run's
        # first jump, the state cycling resumes from if the jumps fail
        self.pairs, self.pattern, self.run_jumps, self.best = [], None, 0, None
        self.jumps = self.undone = 0
        self.res_prev = np.inf
        self.probation = None   # (state before the last jump, residuals since it)
        self.pat = None
        self.jumped = False     # the current state comes from a jump

    #: a jump can take the memory elsewhere: the measured distances (module docstring)
    distance_bound = ANDERSON_DISTANCE

    @property
    def method(self) -> str:
        return "anderson" if self.jumped else "none"

    def before_cycle(self, run: CycleState) -> None:
        self.replay.before_cycle(run.evo, jumping=self.best is not None)

    def after_cycle(self, run: CycleState) -> None:
        totals = run.totals
        self.unresolved += totals.unresolved
        self.replay.after_cycle(totals)
        self.steps.append(totals.steps)
        self.refs.append(totals.refinements)

    def _switch_map(self, run: CycleState) -> None:
        # the cycle map changes (frozen ↔ adaptive): the extrapolation's sequence and the
        # ratcheting test restart with cycles of the new map
        self.pairs, self.pattern, self.plain_from, self.res_prev, self.run_jumps, \
            self.best = [], None, len(run.starts) - 1, np.inf, 0, None

    def judge(self, run: CycleState) -> str | None:
        tol, residual, starts = run.settings.tol, run.residual, run.starts
        cyc_tol = max(100 * tol, 1e-9) * run.xscale
        self.pat = np.concatenate([run.totals.slip_length > cyc_tol, run.totals.separated])
        verdict = self._jumps_failed(run)
        if verdict is not None:
            return verdict
        if self.replay.misfit(run, jumping=self.best is not None):
            self._switch_map(run)
            return SKIP
        if not run.counted:
            self.res_prev = residual
            return SKIP
        # the last increment, and the rest of a geometric creep of this map's plain
        # cycles (not the check of a replayed fixed point; never below the increment),
        # below the tolerance
        run.increment_steady = residual <= tol and self.replay.checked
        near = residual if self.replay.was_verify else creep_distance(
            starts[self.plain_from:], residual, run.xscale)
        return self.replay.fixed_point() if near <= tol else None

    def _jumps_failed(self, run: CycleState) -> str | None:
        """Undo the jumps where they fail (:data:`SKIP`), else None."""
        tol, residual, starts, evo = run.settings.tol, run.residual, run.starts, run.evo
        stalled = False
        if self.probation is not None and residual > tol and self.best is None:
            since = self.probation[1]
            since.append(residual)
            # after the jumps plain cycling must keep converging: over the last 4 cycles
            # the largest change at most 0.8 × that of the 4 before (a ratio ≤ 0.94 per
            # cycle); a stall (e.g. a small periodic orbit of the discretised cycle map
            # near the jumped state) undoes the jumps and ends the acceleration
            stalled = len(since) >= 8 and max(since[-4:]) > 0.8 * max(since[-8:-4])
        failed = stalled
        memory = False
        best = self.best
        if best is not None and residual > tol:
            # a jumped cycle: Anderson mixing is not monotone, so the residual may rise
            # for a while; the jumps fail if a node stuck and closed in every cycle of the
            # run slipped or opened (its memory would change: another member of the
            # steady set), or if the residual rose above GROWTH × the best one, or did
            # not improve on it for PATIENCE jumps. (A node whose slip per cycle was
            # dying out may stop, where the mixing takes it: module docstring.)
            if residual < best[1]:
                best = (starts[-1].copy(), residual, 0)
            else:
                best = (best[0], best[1], best[2] + 1)
            self.best = best
            memory = bool(np.any(self.pat & ~self.pattern))
            failed = (memory or residual > ANDERSON_GROWTH * best[1]
                      or best[2] > ANDERSON_PATIENCE)
        if failed and not (memory or stalled) and self.undone < 2:
            # the jump overshot (the map is not linear at its scale): go on from the end of
            # the best cycle with the secants gathered so far, this one's included
            self.undone += 1
            self.pairs.append((starts[-2], starts[-1]))
            run.restart(best[0])
            starts[-1] = evo.x.copy()
            self.best = (best[0], best[1], 0)
            return SKIP
        if failed:
            # resume plain cycling from the end of the best cycle (before the first jump
            # if cycling stalled after them)
            self.undone += 1
            run.restart(self.probation[0] if stalled else best[0])
            self.jumped = self.jumped and not stalled
            self.accelerate = self.accelerate and not stalled
            self.probation = self.best = None
            starts[-1] = evo.x.copy()
            self.pairs, self.pattern, self.plain_from, self.res_prev, self.run_jumps = \
                [], None, len(starts) - 1, np.inf, 0
            return SKIP
        return None

    def step(self, run: CycleState) -> str | None:
        starts, pat = run.starts, self.pat
        if self.pattern is None or not np.array_equal(pat, self.pattern):
            self.pairs, self.pattern, self.run_jumps, self.best = \
                [(starts[-2], starts[-1])], pat, 0, None
        else:
            self.pairs.append((starts[-2], starts[-1]))
            # the pattern repeats: freeze this cycle's subdivision (the replayed map equals
            # the adaptive one at the states so far, which the extrapolation keeps using)
            self.replay.freeze(run, jumping=self.best is not None)
        shrinking = run.residual < self.res_prev
        self.res_prev = run.residual
        # the first jump of a run is tried in the geometric regime only (the changes of its
        # plain cycles shrink by a steady ratio); after jumps that had to be undone, a
        # longer run of the pattern is required, and after three no more jumps are tried.
        # Then every cycle of the run jumps, with the secants of the jumped cycles
        # (Anderson mixing), until the run ends or the jumps fail
        window = self.accel_order + 1
        pairs = self.pairs
        if self.run_jumps:
            ready = True
        else:
            ready = (shrinking and len(pairs) >= window + 3 * self.undone
                     and _geometric(np.array([pairs[-window][0]]
                                             + [end for _, end in pairs[-window:]])))
        if (self.accelerate and run.c + 2 < run.settings.cycles and self.undone < 3
                and ready):
            self._jump(run, window)
        return None

    def _jump(self, run: CycleState, window: int) -> None:
        """Replace the next start by the Anderson extrapolation of the run's pairs."""
        starts, n = run.starts, run.system.n_nodes
        m = window if not self.run_jumps else ANDERSON_WINDOW
        X = np.array([start for start, _ in self.pairs[-m:]])
        x_star = _anderson(X, np.array([end for _, end in self.pairs[-m:]]))
        if x_star is not None and np.all(np.isfinite(x_star)):
            if self.best is None:
                self.best = (starts[-1].copy(), run.residual, 0)
            if self.probation is None:
                self.probation = (starts[-1].copy(), [])
            self.jumps += 1
            self.run_jumps += 1
            self.jumped = True
            x_star[2 * n:] = np.maximum(x_star[2 * n:], 0.0)   # separations ≥ 0
            run.restart(x_star)
            starts[-1] = x_star.copy()
            self.plain_from = len(starts) - 1


class Replay:
    """The replay of a frozen subdivision of the step control (module docstring): the
    cycle map of a repeating pattern is made one fixed map, and a fixed point of it is
    accepted only once a replay with every sub-step's error estimate checked fits the
    subdivision and reproduces it.

    Parameters
    ----------
    on : bool
        Freeze subdivisions at all.
    check : int
        Every this many replayed cycles (outside the jumps) the error estimates are
        checked as well.
    most : int
        Most subdivisions frozen.
    """

    def __init__(self, on: bool, check: int, most: int):
        self.on, self.check, self.most = on, check, most
        self.replaying = 0       # cycles run on the plan since it was frozen
        self.verify = False      # the next cycle is the checked replay of a fixed point
        self.freezes = self.replayed = self.mismatches = 0
        self.was_replay = self.was_verify = False

    def before_cycle(self, evo, jumping: bool) -> None:
        """Note whether the next cycle replays (or verifies); set its error checks (in
        the verifying cycle, and every ``check``-th cycle outside the jumps, which need
        one fixed map)."""
        self.was_replay, self.was_verify = evo.plan is not None, self.verify
        self.verify = False
        if self.was_replay:
            evo.check_plan = self.was_verify or (not jumping and self.replaying % max(
                self.check, 1) == self.check - 1)

    def after_cycle(self, totals) -> None:
        """Count the replayed cycle and its sub-steps that did not fit."""
        if self.was_replay:
            self.replaying += 1
            self.replayed += 1
            self.mismatches += totals.replay_mismatches

    def misfit(self, run: CycleState, jumping: bool) -> bool:
        """Where the frozen subdivision no longer fits the path, freeze the one this cycle
        ended with (the misfitting steps redone adaptively), or return to adaptive cycles
        once ``most`` have been frozen; True: the cycle map changed. (During the jumps
        the map stays the replay of the one subdivision, whose misfitting steps are redone
        adaptively in each cycle.)"""
        if not (self.was_replay and run.totals.replay_mismatches
                and (not jumping or self.was_verify)):
            return False
        run.evo.plan = run.totals.plan if self.freezes < self.most else None
        self.replaying = 0
        self.freezes += run.evo.plan is not None
        return True

    @property
    def checked(self) -> bool:
        """Whether the cycle just run may end the run (adaptive, or the verifying
        replay)."""
        return not self.was_replay or self.was_verify

    def fixed_point(self) -> str:
        """At a fixed point of the cycle just run: steady if it may end the run, else
        verify it by one more replay with every error estimate checked."""
        if self.checked:
            return STEADY
        self.verify = True
        return SKIP

    def freeze(self, run: CycleState, jumping: bool) -> None:
        """Freeze the subdivision of the cycle just run (its pattern repeats)."""
        if (self.on and run.evo.plan is None and self.freezes < self.most and not jumping
                and not self.was_verify):
            run.evo.plan, self.replaying = run.totals.plan, 0
            self.freezes += 1
