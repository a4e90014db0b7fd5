"""Cycling the 3-D system to its steady state, and its classification.

The same procedure and classes as the 2-D model: the system is assembled (initial slip
state, or an assembly protocol followed linearly from the unloaded state, or plain
loading to the load at θ = 0), then load cycles are run with
:class:`~slipcycle.discrete3d.evolution.Evolution3D` until the start-of-cycle state
repeats within ``tol`` (``shakedown`` if no node slips in that cycle, else
``cyclic_slip``), or the per-cycle drift repeats (``ratcheting``), or ``cycles`` is
reached (``not_converged``). A node "slips" in the last cycle when its slip length
∮|dv_j| exceeds max(100 tol, 1e-9) × the displacement scale (Barber 2012, §3).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import nnls

from slipcycle.discrete3d.evolution import Evolution3D
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.errors import InadmissibleInitialState
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


def simulate3d(system: FrictionalSystem3D, load: Load3D, *, cycles: int = 40,
               steps_per_cycle: int = 100, initial_slip: np.ndarray | None = None,
               protocol: np.ndarray | None = None, tol: float = 1e-8, min_cycles: int = 1,
               step_tol: float = 1e-7, record: bool = True, adaptive: bool = True,
               substeps: int = 1, extrapolate: bool = True) -> SteadyResult3D:
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
    for c in range(cycles):
        totals = evo.follow(theta, vals, record=record)
        evo.resync()
        unresolved += totals.unresolved
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
        if c + 1 < min_cycles:
            continue
        if residual <= tol:
            state = "steady"
            break
        if len(starts) >= 3:
            d0 = starts[-2] - starts[-3]
            rres = float(np.max(np.abs(d1 - d0))) / xscale
            # a drift that repeats is ratcheting; one shrinking by a constant factor is a
            # slow approach to a periodic state
            if rres <= tol and np.max(np.abs(d1 - d0)) <= 1e-3 * np.max(np.abs(d1)):
                ratchet = d1[:2 * n]
                residual = rres
                state = "ratcheting"
                break
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
        unresolved_steps=unresolved)
