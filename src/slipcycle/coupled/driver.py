"""The steady-state driver of the discrete models: one cycle loop, with its accelerators
behind one small interface.

Plain cycling runs load cycles x_{c+1} = Φ(x_c) from the assembled state until the start
of a cycle repeats within the tolerance (the last increment and, where the increments
shrink geometrically, the rest of the creep:
:func:`~slipcycle.kernels.creep.creep_distance`), the state ratchets (the increment
repeats), or the cycles run out (J. R. Barber, J. Phys.: Conf. Ser. 382 (2012) 012002,
§3). An :class:`Accelerator` judges each cycle run and may replace the next start by a
step towards the limit; :class:`PlainCycling` takes none. The 2-D model's periodic
follower and slow-mode steps (:class:`slipcycle.discrete.steady.PieceSteps`) and the 3-D
model's Anderson mixing with replay (:class:`slipcycle.discrete3d.steady.Mixing`) are
the others.

Certificate. A state reached with an accelerator's steps is accepted only after plain
cycles from it: the loop goes on cycling without steps until a cycle reproduces its start
within the tolerance (:func:`certify`). The run then reports the method whose steps
shaped the state (:data:`ACCELERATIONS`), the certified residual, and estimates of how far
the state (the stuck nodes' memory among it) and D still are from the limit of plain
cycling continued from there: the rest of the geometric creep of the last two plain
increments, ρ/(1 − ρ) times the last one (:func:`~slipcycle.kernels.creep.creep_distance`;
plain cycling's own runs report the same estimate). Where the accelerator took the state
to another member of the set of steady states (Barber 2012, §3: the stuck nodes' memory is
set by the history) no cycle can tell. An accelerator whose steps can do that says so
with its :attr:`Accelerator.distance_bound`: the largest distances measured between its
results and plain cycling's limit on the benchmark systems; the certificate of a state
its steps shaped then reports at least that bound, never the (much smaller) creep of the
certifying cycles (the 3-D Anderson mixing: docs/discrete3d.md). The 2-D steps follow
plain cycling's own trajectory on the piecewise-affine cycle map; their distances are
measured by the tests and bounded in docs/discrete.md.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from slipcycle.coupled.cycles import CycleHistory, ratchet_residual
from slipcycle.coupled.settings import RunSettings
from slipcycle.kernels.creep import creep_distance

__all__ = ["CycleState", "Accelerator", "PlainCycling", "BackOff", "run_cycles", "STEADY",
           "SKIP", "ACCELERATIONS", "Certificate", "certify", "certificate"]

#: the words of the ``acceleration`` summary entry: the method whose steps shaped the
#: steady state (none: plain cycling; periodic: the 2-D periodic follower; slow_modes:
#: also the 2-D slow-mode steps; anderson: the 3-D Anderson mixing)
ACCELERATIONS = ("none", "periodic", "slow_modes", "anderson")

#: verdicts of :meth:`Accelerator.judge` and :meth:`Accelerator.step`: the state is
#: steady (the loop ends), or the rest of this cycle's tests is skipped
STEADY = "steady"
SKIP = "skip"


@dataclass
class CycleState:
    """What the loop knows after each cycle, shared with the accelerator.

    Attributes
    ----------
    system
        The frictional system (``K``, ``friction``, ``n_nodes``).
    evo
        The evolution engine (``x``, ``follow``, ``resync``).
    settings : RunSettings
    history : CycleHistory
        The start-of-cycle states and the cycles' records.
    r_w0 : (M,) array
        Load at θ = 0 [N].
    F : float
        Force scale [N].
    c : int
        Index of the cycle just run (from 0).
    totals
        What the last cycle left (dissipation, slip lengths, events, ...).
    d1 : (M,) array
        The last increment x_c − x_{c−1} [m].
    xscale : float
        The residual's scale [m].
    residual : float
        max |d1| / xscale [1] (np.inf for a refused step).
    increment_steady : bool
        The last increment alone is below the tolerance (steady if the cycles run out).
    state : str
        ``"not_converged"``, ``"steady"`` or ``"ratcheting"``.
    ratchet : (T,) array or None
        The drift per cycle of a ratcheting state [m].
    """

    system: Any
    evo: Any
    settings: RunSettings
    history: CycleHistory
    r_w0: np.ndarray
    F: float
    c: int = -1
    totals: Any = None
    d1: np.ndarray | None = None
    xscale: float = 1.0
    residual: float = np.inf
    increment_steady: bool = False
    state: str = "not_converged"
    ratchet: np.ndarray | None = None

    @property
    def starts(self) -> list:
        """The start-of-cycle states x_0, ..., x_c [m]."""
        return self.history.starts

    @property
    def last(self) -> bool:
        """Whether the cycle just run is the last one allowed."""
        return self.c + 1 >= self.settings.cycles

    @property
    def counted(self) -> bool:
        """Whether at least ``min_cycles`` cycles have been run."""
        return self.c + 1 >= self.settings.min_cycles

    def restart(self, x: np.ndarray) -> None:
        """Go on cycling from the state x (the start of the next cycle) [m]."""
        self.evo.x = x.copy()
        self.evo.resync()


class Accelerator:
    """The interface of the driver's strategies (all methods optional but :meth:`judge`).

    The loop calls, each cycle: :meth:`before_cycle`, runs the cycle, :meth:`after_cycle`,
    then :meth:`judge` (may end the run, :data:`STEADY`, or skip the rest, :data:`SKIP`),
    the ratcheting test where :meth:`ratchet_test` allows it, and :meth:`step` (may end
    the run, or replace the next start).
    """

    def before_cycle(self, run: CycleState) -> None:
        """Set up what the next cycle must record."""

    def after_cycle(self, run: CycleState) -> None:
        """Book what the cycle just run did (counts, events)."""

    def judge(self, run: CycleState) -> str | None:
        """Judge the cycle just run: :data:`STEADY`, :data:`SKIP` or None (go on)."""
        raise NotImplementedError

    def ratchet_test(self, run: CycleState) -> bool:
        """Whether the last three starts are successive plain cycles (the ratcheting
        test applies)."""
        return len(run.starts) >= 3

    def step(self, run: CycleState) -> str | None:
        """Take a step towards the limit (or not); :data:`STEADY` ends the run."""
        return None

    @property
    def method(self) -> str:
        """The word (:data:`ACCELERATIONS`) of the steps that shaped the current state."""
        return "none"

    #: (memory, D): the largest distances of the state (relative to the slip scale) and
    #: of D (relative) from plain cycling's limit measured on the benchmark systems for
    #: the states this accelerator's steps shape, reported by their certificate instead of
    #: the creep estimate where larger (:func:`certificate`); None: the steps follow plain
    #: cycling's trajectory and the creep estimate applies
    distance_bound: tuple[float, float] | None = None

    def certifying(self, run: CycleState) -> None:
        """The plain cycles of the certificate follow (:func:`certify`): record nothing
        for steps."""


class PlainCycling(Accelerator):
    """No acceleration: steady when the increment and the rest of the creep of the plain
    cycles since :attr:`plain_from` are below the tolerance."""

    def __init__(self):
        #: starts[plain_from:] are successive plain cycles
        self.plain_from = 0

    def judge(self, run: CycleState) -> str | None:
        if not run.counted:
            return SKIP
        tol = run.settings.tol
        run.increment_steady = run.residual <= tol
        near = creep_distance(run.starts[self.plain_from:], run.residual, run.xscale)
        return STEADY if near <= tol else None

    def ratchet_test(self, run: CycleState) -> bool:
        return len(run.starts) - self.plain_from >= 3


class BackOff:
    """When an accelerator that keeps finding no step tries again.

    An attempt costs about a cycle (it records the cycle's events and gathers its
    Jacobian); where the piece of the cycle map changes every cycle it never finds a step.
    After ``attempts`` fruitless attempts in a row the next one waits
    min(2^(k − attempts), ``max_wait``) cycles (k the fruitless attempts so far): 1, 2, 4, 8,
    8, ... A step found resets the count; a refused step holds the attempts for a while.

    Parameters
    ----------
    attempts : int
        Fruitless attempts in a row before waiting.
    max_wait : int
        Most cycles between two attempts.
    """

    def __init__(self, attempts: int, max_wait: int):
        self.attempts, self.max_wait = attempts, max_wait
        self.wait = 0          # cycles until the next attempt
        self.fruitless = 0     # attempts in a row that found no step

    @property
    def ready(self) -> bool:
        """Whether the next cycle may attempt a step."""
        return self.wait == 0

    def hold(self, cycles: int) -> None:
        """No attempt for the next ``cycles`` - 1 cycles (after a refused step)."""
        self.wait = cycles

    def outcome(self, found: bool | None, may_wait: bool = True) -> None:
        """Book an attempt: a step ``found`` (True), none (False), or undecided (None: the
        attempt goes on in the next cycle). ``may_wait``: waiting is allowed."""
        if found:
            self.fruitless = 0
        elif found is not None:
            self.fruitless += 1
            if may_wait and self.fruitless >= self.attempts:
                self.wait = max(self.wait, min(2 ** (self.fruitless - self.attempts),
                                               self.max_wait))

    def tick(self) -> None:
        """One cycle has passed."""
        self.wait = max(self.wait - 1, 0)


def run_cycles(run: CycleState, theta: np.ndarray, vals: np.ndarray,
               accelerator: Accelerator,
               progress: Callable[[float, float], None] | None = None) -> CycleState:
    """Cycle to the steady state.

    Parameters
    ----------
    run : CycleState
        The assembled run (history holding the start x_0).
    theta, vals : arrays
        Sample angles [rad] and loads [N] of one cycle.
    accelerator : Accelerator
    progress : callable, optional
        ``progress(cycles_done, cycles)`` after each cycle.

    Returns
    -------
    CycleState
        With ``state`` ``"steady"`` (not yet classified), ``"ratcheting"`` or
        ``"not_converged"``.
    """
    evo, history, cycles = run.evo, run.history, run.settings.cycles
    for c in range(cycles):
        run.c, run.increment_steady = c, False
        accelerator.before_cycle(run)
        run.totals = evo.follow(theta, vals, record=history.record)
        evo.resync()
        if progress is not None:
            progress(c + 1, cycles)
        history.add(evo.x, run.totals)
        accelerator.after_cycle(run)
        run.d1, run.xscale, run.residual = history.increment()
        verdict = accelerator.judge(run)
        if verdict is STEADY:
            run.state = "steady"
            break
        if verdict is SKIP:
            continue
        if accelerator.ratchet_test(run):
            rres = ratchet_residual(run.starts, run.d1, run.xscale, run.settings.tol)
            if rres is not None:
                run.ratchet = run.d1[:run.d1.size - run.system.n_nodes]
                run.residual, run.state = rres, "ratcheting"
                break
        if accelerator.step(run) is STEADY:
            run.state = "steady"
            break
    if run.state == "not_converged" and run.increment_steady:
        run.state = "steady"      # the cycles ran out after the increment test
    if run.state == "steady" and accelerator.method != "none":
        certify(run, theta, vals, accelerator, progress)
    return run


def certify(run: CycleState, theta: np.ndarray, vals: np.ndarray, accelerator: Accelerator,
            progress: Callable[[float, float], None] | None = None) -> CycleState:
    """Plain cycles from an accelerated steady state until one reproduces its start within
    the tolerance (at least one; within the cycles left): the state stays ``"steady"``,
    else becomes ``"not_converged"`` with the last plain residual. The accelerator books
    each cycle (:meth:`Accelerator.after_cycle`) but takes no step."""
    evo, history, cycles = run.evo, run.history, run.settings.cycles
    accelerator.certifying(run)
    run.state = "not_converged"
    for c in range(run.c + 1, cycles + 1):
        # one cycle beyond ``cycles`` at most: the certificate of a state reached in the
        # last cycle allowed
        run.c = c
        run.totals = evo.follow(theta, vals, record=history.record)
        evo.resync()
        if progress is not None:
            progress(min(c + 1, cycles), cycles)
        history.add(evo.x, run.totals)
        accelerator.after_cycle(run)
        run.d1, run.xscale, run.residual = history.increment()
        if run.residual <= run.settings.tol:
            run.state = "steady"
            break
    return run


@dataclass(frozen=True)
class Certificate:
    """What a steady-state run reports on how its state was reached (module docstring).

    Attributes
    ----------
    acceleration : str
        The method whose steps shaped the state (:data:`ACCELERATIONS`).
    certified_residual : float
        max |Φ(x) − x| / scale of the last (plain) cycle [1].
    memory_distance : float
        Estimated distance of the state (the stuck nodes' slips among it) from the limit
        of plain cycling continued from it, relative to the displacement scale [1]:
        ρ/(1 − ρ) times the last increment (ρ the ratio of the last two plain increments;
        the last increment where they do not shrink). For a state shaped by the steps of
        an accelerator with a :attr:`Accelerator.distance_bound`, at least its first entry:
        the distance from plain cycling's limit from the *start* is not estimated by any
        cycle, only bounded by measurements on the benchmark systems.
    dissipation_distance : float
        Estimated distance of D from that limit [1]: the last change of D times max(1,
        ρ/(1 − ρ)), relative to |D|, or to ``tol`` × F × displacement scale (the energy
        the cycling resolves) where |D| is below that; inf with fewer than three cycles
        run (the first cycle from an assembled or imposed state says nothing about D's
        convergence). At least the second entry
        of the accelerator's :attr:`Accelerator.distance_bound`, as above.
    """

    acceleration: str
    certified_residual: float
    memory_distance: float
    dissipation_distance: float


def certificate(run: CycleState, accelerator: Accelerator) -> Certificate:
    """The :class:`Certificate` of a finished run (its last three starts and D's)."""
    starts, dis = run.history.starts, run.history.dissipation
    res = run.residual
    if not np.isfinite(res) or len(starts) < 2 or run.state == "ratcheting":
        # a ratcheting state has no limit to be distant from
        return Certificate(accelerator.method, float(res), np.inf, np.inf)
    near = creep_distance(starts[-3:], res, run.xscale)
    factor = near / res if res > 0 else 1.0
    d_dist = np.inf
    if len(dis) >= 3:
        # relative to |D|, but not below the energy the cycling resolves (tol × F × x):
        # a shakedown's D of round-off or creep size would make any distance look huge
        floor = run.F * run.xscale * max(run.settings.tol, 1e-12)
        scale = max(abs(dis[-1]), floor) or run.F * run.xscale
        d_dist = abs(dis[-1] - dis[-2]) * factor / scale
    bound = accelerator.distance_bound
    if bound is not None and accelerator.method != "none":
        # the steps may have moved the memory: what was measured, not the creep
        near, d_dist = max(near, bound[0]), max(d_dist, bound[1])
    return Certificate(accelerator.method, float(res), float(near), float(d_dist))
