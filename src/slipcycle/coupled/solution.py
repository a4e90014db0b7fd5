"""The outcome of a steady-state run of a coupled discrete model, and the classification of
its last cycle (shared by the 2-D and 3-D models).

A steady cycle is ``shakedown`` when no node slips in it (nodes may still separate and
close), ``cyclic_slip`` when some nodes slip every cycle and the others stay permanently
stuck, ``ratcheting`` when the state drifts by the same amount every cycle, and
``not_converged`` when the cycles ran out first (J. R. Barber, J. Phys.: Conf. Ser. 382
(2012) 012002, §3; :class:`~slipcycle.result.SteadyState`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from slipcycle.coupled.settings import SolverStats
from slipcycle.loading.service import service_slip_tolerance, slips_in_cycle
from slipcycle.result import SteadyState

__all__ = ["CycleSolution", "CYCLE_CLASSES", "last_cycle", "slip_tolerance"]

#: the classes a steady-state run of a discrete model ends in (those of
#: :class:`~slipcycle.result.SteadyState` it can reach, in its order): the words of the
#: ``steady_state`` summary entry
CYCLE_CLASSES: tuple[str, ...] = tuple(
    s.value for s in SteadyState if s.converged or s is SteadyState.NOT_CONVERGED)


@dataclass(kw_only=True)
class CycleSolution:
    """Fields and properties of a steady-state run shared by both discrete models (SI
    units; nodes numbered from 0; M = 2N degrees of freedom in 2-D, 3N in 3-D, and T the
    tangential ones, N in 2-D, 2N in 3-D).

    Attributes
    ----------
    steady_state : str
        ``shakedown``, ``cyclic_slip``, ``ratcheting`` or ``not_converged``
        (:class:`~slipcycle.result.SteadyState` words).
    residual : float
        max |x_c − x_{c−1}| of the start-of-cycle states of the last two cycles (for
        ratcheting: of their differences), relative to the service cycle's displacement
        scale with its round-off floor
        (:class:`~slipcycle.coupled.cycles.ResidualScale`) [1].
    cycles_run : int
    dissipation_per_node : (N,) array
        D_j = −∮ q_j · dv_j of the last cycle run [J].
    work_of_loads : float
        ∮ (vᵀdq^w + wᵀdp^w) over the last cycle run [J].
    slipping_nodes, permanently_stuck_nodes, separating_nodes : list of int
        Nodes that slip, stay stuck, or separate in the last cycle.
    theta : (S,) array
        Load sample angles of one cycle [rad].
    x, r : (cycles_run, S, M) arrays
        States [v, w] [m] and reactions [q, p] [N] at the samples of every cycle run
        (empty first axis when not recorded).
    modes : (cycles_run, S, N) int8 array
        Node state at each sample (the model's ``STATE_NAMES``).
    cycle_start_states : (cycles_run + 1, M) array
    ratchet_per_cycle : (T,) array
        Slip increment per cycle of the last cycle [m].
    all_slip_or_separated : bool
        Every node slipped or separated at some instant of the last cycle (memory erased).
    disp_scale : float
        Displacement scale F / max diag K of the whole load [m].
    force_scale : float
        Force scale F of the loads [N].
    slip_length : (N,) array
        ∮ |dv_j| over the last cycle [m].
    slip_tolerance : float
        Slip length [m] at or below which a node counts as stuck in the last cycle:
        max(100 tol, 1e-9) × the elastic displacement of the service load's variation
        over the cycle (:func:`slip_tolerance`): the class follows the service load, not
        the preload or the state the assembly left.
    dissipation_history : list of float
        Total dissipation of each cycle [J].
    stored_energy_change : float
        Change of ½ xᵀKx + r^wᵀx over the last cycle [J].
    solver_stats : SolverStats
        What the run did (accelerators, step solver).
    certificate : Certificate or None
        The method that shaped the state, its certified residual and the estimated
        distances of the state and of D from plain cycling's limit
        (:class:`~slipcycle.coupled.driver.Certificate`).
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
    force_scale: float = 1.0
    slip_length: np.ndarray | None = None
    slip_tolerance: float = 0.0
    dissipation_history: list = field(default_factory=list)
    stored_energy_change: float = 0.0
    solver_stats: SolverStats = field(default_factory=SolverStats)
    certificate: Any = None

    @property
    def dissipation_per_cycle(self) -> float:
        """Total dissipation of the last (steady) cycle [J]."""
        return float(np.sum(self.dissipation_per_node))

    @property
    def energy_balance_error(self) -> float:
        """|W − Σ D_j − ΔΠ| over the last cycle, relative to max(|W|, |Σ D_j|, F·x_scale).

        ΔΠ is the change of the stored energy Π = ½ xᵀKx + r^wᵀx over the cycle (zero once
        the cycle is steady, so that Σ D_j = W)."""
        d = self.dissipation_per_cycle
        ref = max(abs(d), abs(self.work_of_loads), self.force_scale * self.disp_scale)
        return abs(self.work_of_loads - d - self.stored_energy_change) / ref

    @property
    def steady_converged(self) -> bool:
        """Whether a periodic (or ratcheting) state was reached."""
        return SteadyState(self.steady_state).converged


def slip_tolerance(tol: float, disp_scale: float, samples: np.ndarray,
                   stiffness_scale: float) -> float:
    """Slip length [m] at or below which a node counts as stuck over a steady cycle:
    max(100 tol, 1e-9) × the elastic displacement of the service load's variation over
    the cycle (:func:`~slipcycle.loading.service.service_slip_tolerance`), at least
    1e-12 × the displacement scale."""
    return service_slip_tolerance(tol, samples, stiffness_scale, disp_scale)


def last_cycle(system, state: str, ratchet: np.ndarray, totals, starts: list, tol: float,
               disp_scale: float, samples: np.ndarray, records: tuple | None,
               n_theta: int) -> dict:
    """Classify the last cycle run and gather the fields of :class:`CycleSolution`.

    Parameters
    ----------
    system : FrictionalSystem or FrictionalSystem3D
    state : str
        ``"steady"``, ``"ratcheting"`` or ``"not_converged"`` (the driver's verdict);
        ``"steady"`` becomes ``shakedown`` or ``cyclic_slip``.
    ratchet : (T,) array
        Drift per cycle of a ratcheting state (else replaced by the last increment) [m].
    totals
        The last cycle's totals (``slip_length``, ``separated``, ``dissipation``, ``work``,
        ``all_slip_or_separated``).
    starts : list of (M,) arrays
        Start-of-cycle states [m].
    tol, disp_scale : float
        Steady-state tolerance [1] and displacement scale [m].
    samples : (S, M) array
        Load r^w at the samples of one cycle [N], the first at θ = 0.
    records : (xs, rs, ms) lists or None
        Sample histories of every cycle, if recorded.
    n_theta : int
        Samples per cycle S.

    Returns
    -------
    dict
        Keyword arguments of :class:`CycleSolution` but ``residual``, ``cycles_run``,
        ``theta``, ``dissipation_history``, ``force_scale`` and ``solver_stats``.
    """
    n, m = system.n_nodes, starts[-1].size
    slip_tol = slip_tolerance(tol, disp_scale, samples, system.stiffness_scale())
    r_w0 = samples[0]
    # each node's net tangential movement over the cycle (2-D: one slip, 3-D: two)
    drift = np.abs(starts[-1][:m - n] - starts[-2][:m - n]).reshape(n, -1)
    moves = slips_in_cycle(totals.slip_length, np.linalg.norm(drift, axis=1), slip_tol,
                           state == "ratcheting")
    slipping = np.flatnonzero(moves)
    separating = np.flatnonzero(totals.separated)
    stuck = np.flatnonzero(~moves & ~totals.separated)
    if state == "steady":
        state = "shakedown" if slipping.size == 0 else "cyclic_slip"
    if state != "ratcheting":
        ratchet = starts[-1][:m - n] - starts[-2][:m - n]
    x0, x1 = starts[-2], starts[-1]
    K = system.K
    d_stored = float(0.5 * (x1 @ K @ x1 - x0 @ K @ x0) + r_w0 @ (x1 - x0))
    if records is not None and records[0]:
        X, R, Mo = (np.array(a) for a in records)
    else:
        X = R = np.zeros((0, n_theta, m))
        Mo = np.zeros((0, n_theta, n), np.int8)
    return dict(steady_state=state, dissipation_per_node=totals.dissipation.copy(),
                work_of_loads=totals.work, slipping_nodes=slipping.tolist(),
                permanently_stuck_nodes=stuck.tolist(), separating_nodes=separating.tolist(),
                x=X, r=R, modes=Mo, cycle_start_states=np.array(starts),
                ratchet_per_cycle=ratchet, all_slip_or_separated=totals.all_slip_or_separated,
                disp_scale=disp_scale, slip_length=totals.slip_length.copy(),
                slip_tolerance=slip_tol, stored_energy_change=d_stored)
