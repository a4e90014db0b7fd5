"""The pieces of the steady-state drivers shared by the 2-D and 3-D discrete models: the
scales and the assembly of a run, the record of its cycles, and the tests on the
start-of-cycle states x_c (steadiness, ratcheting).

Plain cycling maps the state at θ = 0 of one cycle to that of the next, x_{c+1} = Φ(x_c);
a steady cycle is a fixed point of Φ, a ratcheting one a fixed point up to a constant drift
(J. R. Barber, J. Phys.: Conf. Ser. 382 (2012) 012002, §3).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from slipcycle.loading.nodal import force_scale
from slipcycle.loading.service import service_force_scale

__all__ = ["run_scales", "assemble", "for_cycles", "CycleHistory", "ResidualScale",
           "ratchet_residual", "ROUNDOFF", "STEP_ROUNDOFF"]

#: round-offs (units of the machine epsilon) of a term that a cycle-to-cycle change of a
#: state component must exceed to be told from the round-off of the state (the updates of
#: one cycle accumulate a few hundred at most)
ROUNDOFF = 1e3
#: round-offs of the state by which the full step and the two half steps of a step-doubling
#: control can differ with no discretisation error (:meth:`ResidualScale.step_scale`)
STEP_ROUNDOFF = 4.0


def run_scales(system, load, steps_per_cycle: int, protocol: np.ndarray | None):
    """Sample angles and loads of one cycle, the force scale and the displacement scale.

    Returns
    -------
    theta : (S,) array
        Sample angles [rad].
    vals : (S, M) array
        Loads r^w = [q^w, p^w] at the samples [N].
    F : float
        Force scale of the loads and the assembly protocol [N].
    disp_scale : float
        F / max diag K [m] (the whole load's: the tolerances of forces and of the
        admissibility of a state; the steady-state residual follows the service cycle,
        :class:`ResidualScale`).
    """
    theta, vals = load.cycle_samples(steps_per_cycle)
    F = force_scale(vals if protocol is None else np.vstack([vals, protocol]))
    return theta, vals, F, F / system.stiffness_scale()


def assemble(evolution: Callable, system, r0: np.ndarray, F: float,
             initial_slip: np.ndarray | None, protocol: np.ndarray | None,
             initial_state: Callable):
    """The evolution at θ = 0: from an admissible initial slip, or assembled from the
    unloaded state along the protocol's load states (linearly) to the load at θ = 0.

    Parameters
    ----------
    evolution : callable
        ``evolution(x0, r0)``: the model's evolution engine at state x0 [m], load r0 [N].
    system : FrictionalSystem or FrictionalSystem3D
    r0 : (M,) array
        Load at θ = 0 [N].
    F : float
        Force scale [N] (the admissibility threshold of an initial slip is 1e-10 F).
    initial_slip : array or None
        Slip at θ = 0 [m]; excludes ``protocol``.
    protocol : (P, M) array or None
        Assembly load states [N].
    initial_state : callable
        ``initial_state(system, r0, slip, force_tol)``: the model's admissible state.
    """
    m = system.K.shape[0]
    if initial_slip is not None:
        return evolution(initial_state(system, r0, initial_slip, 1e-10 * F), r0)
    evo = evolution(np.zeros(m), np.zeros(m))
    path = [np.zeros(m)]
    if protocol is not None:
        path += list(np.atleast_2d(protocol))
    path.append(r0)
    path = np.array(path)
    evo.follow(np.arange(len(path), dtype=float), path)
    evo.resync()
    return evo


def for_cycles(evolution: Callable, evo, samples: np.ndarray, F: float):
    """The evolution the cycles run on: ``evo`` (assembled with tolerances relative to
    the whole load F [N]) continued from its state with tolerances relative to the
    service cycle's force scale (:func:`~slipcycle.loading.service.service_force_scale`;
    a preload would hide the service slip); ``evo`` itself where the two coincide.

    Parameters
    ----------
    evolution : callable
        ``evolution(x0, r0, force_scale)``: the model's evolution engine.
    evo : the assembled evolution, at θ = 0.
    samples : (S, M) array
        Load samples of one cycle [N] (the first at θ = 0).
    F : float
        Force scale of the whole load [N].
    """
    F_cycles = service_force_scale(samples, F)
    return evo if F_cycles == F else evolution(evo.x, samples[0], F_cycles)


@dataclass(frozen=True, eq=False)
class ResidualScale:
    """The scale of the steady-state residual: the service cycle's displacement, floored
    by the round-off of the state.

    The change x_c − x_{c−1} of the start of a cycle is measured against u_s, the elastic
    displacement of the service load's variation over the cycle
    (:func:`~slipcycle.loading.service.service_force_scale` / max diag K: at most the
    whole load's displacement scale, which a constant load keeps), not against the whole
    load: a preload 1e7 times the service load would otherwise pass the transient of the
    first cycles as steady. A component changes by round-off alone at the level of
    the terms that set it: its own value and, through r = r^w + K x, the terms of its
    node's equilibrium, ``ROUNDOFF`` ε (|x_i| + (s_i + f s_n)/K_ii) with
    s = max_θ |r^w| + |K| |x| (s_n the node's normal row, f its friction coefficient,
    for the slip condition |q| = f p). (The 3-D Newton solves end far below their force
    tolerance: a random 5-node system with a node clamped by 1e8 N, whose tolerance is
    3.9e-6 m as a displacement, converges to cycle changes of 3e-12 m; that tolerance
    is no floor.) Only components that changed count: a
    clamped node keeps its state bit for bit, however large its load. The residual's
    scale is max(u_s, δ / tol) with δ the largest such floor, so that tol × scale is
    never below the round-off of the components that moved.

    Attributes
    ----------
    service : float
        u_s [m].
    K : (M, M) array
        Reduced stiffness [N/m].
    load : (M,) array
        max over the cycle's samples of |r^w| [N].
    normal : (M,) int array
        The normal row of each component's node.
    friction : (M,) array
        f of the node of each tangential component, 0 for the normal ones.
    """

    service: float
    K: np.ndarray
    load: np.ndarray
    normal: np.ndarray
    friction: np.ndarray

    @classmethod
    def of(cls, system, samples: np.ndarray, disp_scale: float) -> ResidualScale:
        """The residual scale of ``system`` (2-D or 3-D) under the load ``samples``
        ((S, M) [N], the first at θ = 0); ``disp_scale`` the whole load's [m]."""
        n, m = system.n_nodes, system.K.shape[0]
        t = m // n - 1                       # tangential components per node
        node = np.concatenate([np.arange(t * n) // t, np.arange(n)])
        f = np.concatenate([np.asarray(system.friction, float)[node[:t * n]], np.zeros(n)])
        k = system.stiffness_scale()
        u = service_force_scale(samples, disp_scale * k) / k
        return cls(u, system.K, np.max(np.abs(np.asarray(samples, float)), axis=0),
                   t * n + node, f)

    def roundoff(self, xa: np.ndarray, xb: np.ndarray) -> float:
        """Largest round-off [m] of the components that differ between two states."""
        moved = np.flatnonzero(xa != xb)
        if moved.size == 0:
            return 0.0
        x = np.maximum(np.abs(xa), np.abs(xb))
        rows = np.unique(np.concatenate([moved, self.normal[moved]]))
        s = np.zeros(x.size)
        s[rows] = self.load[rows] + np.abs(self.K[rows]) @ x
        kii = np.diag(self.K)[moved]
        terms = x[moved] + (s[moved] + self.friction[moved] * s[self.normal[moved]]) / kii
        return float(ROUNDOFF * np.finfo(float).eps * np.max(terms))

    def step_scale(self, x: np.ndarray, step_tol: float) -> float:
        """Displacement scale [m] of a step-doubling control over the service cycles
        from the state x: max(u_s, ``STEP_ROUNDOFF`` ε max |x| / step_tol), so that
        step_tol × scale stays above the round-off of the difference of the full step
        and the two half steps (x0 + Δ rounded once and twice: at most 3 ε |x| apart with
        no error at all), or every step would be halved to the deepest level. The whole
        state's max |x|: which components will move is not known before the steps."""
        big = STEP_ROUNDOFF * np.finfo(float).eps * float(np.max(np.abs(x), initial=0.0))
        return max(self.service, big / step_tol)

    def scale(self, xa: np.ndarray, xb: np.ndarray, tol: float) -> float:
        """max(u_s, δ / tol) [m], δ the :meth:`roundoff` of the change from xa to xb."""
        return max(self.service, self.roundoff(xa, xb) / max(tol, np.finfo(float).tiny))


@dataclass
class CycleHistory:
    """The start-of-cycle states of a run, with what each cycle run leaves.

    Attributes
    ----------
    disp_scale : float
        Displacement scale [m]: the residual's scale where no ``scale`` is given.
    record : bool
        Keep the sample histories of every cycle.
    starts : list of (M,) arrays
        x_0, x_1, ...: the state at θ = 0 before each cycle and after the last [m].
    dissipation : list of float
        Total dissipation of each cycle [J].
    samples : tuple of lists
        States, reactions and node modes at the samples of each cycle (if recorded).
    scale : ResidualScale or None
        The service cycle's residual scale with its round-off floor.
    tol : float
        Steady-state tolerance [1] (the round-off floor is δ / tol).
    """

    disp_scale: float
    record: bool
    starts: list = field(default_factory=list)
    dissipation: list = field(default_factory=list)
    samples: tuple = field(default_factory=lambda: ([], [], []))
    scale: ResidualScale | None = None
    tol: float = 1e-8

    @classmethod
    def of_run(cls, system, samples: np.ndarray, disp_scale: float, tol: float,
               x0: np.ndarray, record: bool) -> CycleHistory:
        """The history of a steady-state run from the start x0 [m] under the load
        ``samples`` ((S, M) [N]), its residual measured against the service cycle
        (:class:`ResidualScale`) at the tolerance ``tol``."""
        return cls(disp_scale, record, [np.array(x0, float)],
                   scale=ResidualScale.of(system, samples, disp_scale), tol=tol)

    def add(self, x: np.ndarray, totals) -> None:
        """Append the cycle just run (its end state x, its ``totals``)."""
        self.starts.append(x.copy())
        self.dissipation.append(float(totals.dissipation.sum()))
        if self.record:
            for lst, key in zip(self.samples, ("x", "r", "modes"), strict=True):
                lst.append(totals.samples[key])

    def drop_last(self) -> None:
        """Forget the last cycle run (a checking cycle whose step was refused)."""
        for lst in (self.starts, self.dissipation) + (self.samples if self.record else ()):
            lst.pop()

    def increment(self):
        """The last increment d = x_c − x_{c−1} [m], its scale [m] and the residual
        max |d| / scale [1]. The scale is that of the service cycle with the round-off
        floor of the components that changed (:meth:`ResidualScale.scale`); without a
        ``scale``, max(disp_scale, max |x|) over the last two starts."""
        xa, xb = self.starts[-2], self.starts[-1]
        if self.scale is not None:
            xscale = self.scale.scale(xa, xb, self.tol)
        else:
            xscale = max(self.disp_scale, float(np.max(np.abs(np.array(self.starts[-2:])))))
        d1 = xb - xa
        return d1, xscale, float(np.max(np.abs(d1))) / xscale

    def records(self) -> tuple | None:
        """The sample histories (states, reactions, modes), or None if not recorded."""
        return self.samples if self.record else None


def ratchet_residual(starts: list, d1: np.ndarray, xscale: float, tol: float) -> float | None:
    """The residual of a ratcheting state, or None if the last two increments do not
    repeat: max |d_c − d_{c−1}| / scale ≤ tol, and the change at most 1e-3 of the drift
    (a drift that shrinks by a constant factor each cycle is a slow approach to a periodic
    state, not ratcheting)."""
    d0 = starts[-2] - starts[-3]
    rres = float(np.max(np.abs(d1 - d0))) / xscale
    if rres <= tol and np.max(np.abs(d1 - d0)) <= 1e-3 * np.max(np.abs(d1)):
        return rres
    return None
