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

__all__ = ["run_scales", "assemble", "CycleHistory", "ratchet_residual"]


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
        F / max diag K [m].
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


@dataclass
class CycleHistory:
    """The start-of-cycle states of a run, with what each cycle run leaves.

    Attributes
    ----------
    disp_scale : float
        Displacement scale [m] (the floor of the residual's scale).
    record : bool
        Keep the sample histories of every cycle.
    starts : list of (M,) arrays
        x_0, x_1, ...: the state at θ = 0 before each cycle and after the last [m].
    dissipation : list of float
        Total dissipation of each cycle [J].
    samples : tuple of lists
        States, reactions and node modes at the samples of each cycle (if recorded).
    """

    disp_scale: float
    record: bool
    starts: list = field(default_factory=list)
    dissipation: list = field(default_factory=list)
    samples: tuple = field(default_factory=lambda: ([], [], []))

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
        """The last increment d = x_c − x_{c−1} [m], its scale max(disp_scale, max |x|)
        over the last two starts [m], and the residual max |d| / scale [1]."""
        xscale = max(self.disp_scale, float(np.max(np.abs(np.array(self.starts[-2:])))))
        d1 = self.starts[-1] - self.starts[-2]
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
