"""Driving a slider bed through an assembly protocol and periodic load cycles."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipcycle.halfspace.bed import SliderBed
from slipcycle.halfspace.kernels import STATUS_OK, drive_from

__all__ = ["HistoryResult", "run_history", "GrossSlip"]


@dataclass(frozen=True)
class GrossSlip:
    """Where gross slip (|Q| reaching f P) was met."""

    step: int
    cycle: int          # -1 during assembly
    theta: float        # cycle angle (rad), nan during assembly
    P: float
    Q: float


@dataclass(frozen=True)
class HistoryResult:
    """Histories of one run (K steps in all: assembly then cycles).

    Attributes
    ----------
    U, V, P, Q : (K,) arrays
        Approach (m), tangential displacement (m), normal and tangential load (N).
    theta : (K,) array
        Cycle angle of each step in [0, 2π] (nan during assembly).
    cycle : (K,) int array
        Cycle number of each step (-1 for assembly).
    first_slip : (K,) int array
        Index of the lowest slipping slider in each step (bed.size: full stick).
    slider_dissipation : (C, n) array
        Dissipation of each slider in each cycle run (J).
    slider_slip : (C, n) array
        Σ|Δz| of each slider in each cycle run (m): its total slip over the cycle.
    global_dissipation : (C,) array
        ∮ Q dV per cycle (trapezoidal), J.
    steady : bool
        Whether the slider state at the start of the last cycle repeated at its end.
    state_change : float
        max |Δt| over the last cycle relative to max f·n (the steadiness residual).
    last_t, last_z : (S+1, n) arrays or None
        Slider forces and base slips over the last cycle (θ = 0 … 2π), if recorded.
    gross_slip : GrossSlip or None
    passes : int
        Sweeps over the slider arrays (performance accounting).
    """

    U: np.ndarray
    V: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    theta: np.ndarray
    cycle: np.ndarray
    first_slip: np.ndarray
    slider_dissipation: np.ndarray
    global_dissipation: np.ndarray
    slider_slip: np.ndarray
    steady: bool
    state_change: float
    last_t: np.ndarray | None
    last_z: np.ndarray | None
    gross_slip: GrossSlip | None
    passes: int

    @property
    def cycles_run(self) -> int:
        return self.global_dissipation.size

    @property
    def dissipation_per_cycle(self) -> float:
        """∮ Q dV over the last cycle run (J)."""
        return float(self.global_dissipation[-1]) if self.cycles_run else float("nan")

    @property
    def slider_sum_dissipation(self) -> float:
        """Σ over sliders of their dissipation in the last cycle (J)."""
        return float(self.slider_dissipation[-1].sum()) if self.cycles_run else float("nan")


def _trapezoid_work(Q: np.ndarray, V: np.ndarray, Q0: float, V0: float) -> float:
    Qf = np.concatenate([[Q0], Q])
    Vf = np.concatenate([[V0], V])
    return float(np.sum(0.5 * (Qf[1:] + Qf[:-1]) * np.diff(Vf)))


def run_history(
    bed: SliderBed,
    assembly_normal: np.ndarray,
    assembly_tangential: np.ndarray,
    cycle_normal: np.ndarray,
    cycle_tangential: np.ndarray,
    *,
    normal_control: str = "force",
    tangential_control: str = "force",
    max_cycles: int = 10,
    min_cycles: int = 2,
    steady_tol: float = 1e-9,
    record_last_cycle: bool = True,
    unloaded_approach: float | None = None,
) -> HistoryResult:
    """Run the assembly path, then periodic cycles until the state repeats.

    Parameters
    ----------
    bed : SliderBed
    assembly_normal, assembly_tangential : (Ka,) arrays
        Load states of the assembly protocol, starting from the unloaded state; the last
        one must be the state at θ = 0.
    cycle_normal, cycle_tangential : (S,) arrays
        One cycle sampled at θ_k = 2πk/S, k = 1..S (the last sample closes the cycle).
    normal_control : {"force", "approach"}
        Whether the normal arrays are P (N) or U (m).
    tangential_control : {"force", "displacement"}
        Whether the tangential arrays are Q (N) or V (m).
    max_cycles, min_cycles : int
        Largest and smallest number of cycles run.
    steady_tol : float
        Steady when max|t_end − t_start| ≤ steady_tol · max_i f n_i.
    record_last_cycle : bool
        Keep slider forces and slips over the last cycle (memory n·(S+1)).
    unloaded_approach : float, optional
        Approach of the unloaded state the assembly starts from (m); defaults to the first
        touch of the bed, ``bed.approach(0)``. Sliders touching during a step take their
        share of that step's tangential increment from the moment they touch.

    Returns
    -------
    HistoryResult
        U, V, P, Q per step, slider state, per-cycle dissipation, steady-state flag and,
        if gross slip occurred, where (Ciavarella 1998; Jäger 1998).
    """
    force_control = tangential_control == "force"
    if normal_control == "force":
        to_U = bed.approach
    else:
        def to_U(U):
            return np.asarray(U, float)

    Ua, Uc = to_U(assembly_normal), to_U(cycle_normal)
    S, n = Uc.size, bed.size
    kn, kt, level = bed.normal_stiffness, bed.tangential_stiffness, bed.level
    t, z, d, slip = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    U_last = float(bed.approach(np.zeros(1))[0]) if unloaded_approach is None \
        else float(unloaded_approach)
    empty_idx = np.empty(0, np.int64)
    empty_rec = np.empty((0, n))

    Us, Vs, Qs, firsts, thetas, cyc = [], [], [], [], [], []
    passes = 0
    gross = None

    def run(U_path, T_path, V0, rec):
        nonlocal passes, U_last
        K = U_path.size
        V_out, Q_out = np.zeros(K), np.zeros(K)
        first = np.full(K, n, np.int64)
        if rec:
            idx = np.arange(K, dtype=np.int64)
            rec_t, rec_z = np.empty((K, n)), np.empty((K, n))
        else:
            idx, rec_t, rec_z = empty_idx, empty_rec, empty_rec
        status, p = drive_from(t, z, d, slip, level, kn, kt, bed.friction, U_path, T_path,
                               force_control, V0, U_last, idx, rec_t, rec_z, V_out, Q_out,
                               first)
        passes += p
        U_last = float(U_path[-1]) if U_path.size else U_last
        return status, V_out, Q_out, first, rec_t, rec_z

    def record(U_path, V_out, Q_out, first, theta, cycle, stop):
        """Append the steps actually taken (up to ``stop``) to the histories."""
        Us.append(U_path[:stop])
        Vs.append(V_out[:stop])
        Qs.append(Q_out[:stop])
        firsts.append(first[:stop])
        thetas.append(theta[:stop])
        cyc.append(np.full(min(stop, U_path.size), cycle))

    def gross_slip_at(k, U_path, T_path, V_out, V_start, cycle, theta):
        P_k = float(bed.load(U_path[k]))
        if force_control:
            Q_k = float(T_path[k])
        else:  # the bed slides towards the prescribed displacement at its full capacity
            V_before = V_out[k - 1] if k else V_start
            Q_k = float(np.sign(T_path[k] - V_before)) * bed.friction * P_k
        return GrossSlip(int(sum(u.size for u in Us) + k), cycle, theta, P_k, Q_k)

    # Assembly starts from the unloaded state: V = 0, all forces zero.
    At = np.asarray(assembly_tangential, float)
    status, Va, Qa, fa, _, _ = run(Ua, At, 0.0, False)
    if status != STATUS_OK:
        gross = gross_slip_at(status, Ua, At, Va, 0.0, -1, float("nan"))
    stop = Ua.size if status == STATUS_OK else status
    record(Ua, Va, Qa, fa, np.full(Ua.size, np.nan), -1, stop)
    V_prev, Q_prev = (float(Va[stop - 1]), float(Qa[stop - 1])) if stop else (0.0, 0.0)
    theta_c = 2 * np.pi * np.arange(1, S + 1) / S
    Tc = np.asarray(cycle_tangential, float)
    slider_diss, global_diss, slider_slip = [], [], []
    steady, change = False, np.inf
    last_t = last_z = None
    # largest Coulomb limit of the cycle: the scale of the steadiness residual
    cap_max = bed.friction * float(np.max(kn * np.maximum(Uc.max() - level, 0.0)))
    c = 0
    while gross is None and c < max_cycles:
        t_start, z_start, d_start, s_start = t.copy(), z.copy(), d.copy(), slip.copy()
        status, Vc, Qc, fc, rt, rz = run(Uc, Tc, V_prev, record_last_cycle)
        if status != STATUS_OK:
            gross = gross_slip_at(status, Uc, Tc, Vc, V_prev, c, float(theta_c[status]))
            record(Uc, Vc, Qc, fc, theta_c, c, status)
            break
        record(Uc, Vc, Qc, fc, theta_c, c, S)
        slider_diss.append(d - d_start)
        slider_slip.append(slip - s_start)
        global_diss.append(_trapezoid_work(Qc, Vc, Q_prev, V_prev))
        if record_last_cycle:
            last_t = np.vstack([t_start[None], rt])
            last_z = np.vstack([z_start[None], rz])
        V_prev, Q_prev = float(Vc[-1]), float(Qc[-1])
        change = float(np.max(np.abs(t - t_start))) / cap_max if cap_max > 0 else 0.0
        c += 1
        if change <= steady_tol and c >= min_cycles:
            steady = True
            break

    U = np.concatenate(Us)
    return HistoryResult(
        U=U, V=np.concatenate(Vs), P=bed.load(U), Q=np.concatenate(Qs),
        theta=np.concatenate(thetas), cycle=np.concatenate(cyc),
        first_slip=np.concatenate(firsts),
        slider_dissipation=np.array(slider_diss).reshape(-1, n),
        global_dissipation=np.array(global_diss),
        slider_slip=np.array(slider_slip).reshape(-1, n), steady=steady, state_change=change,
        last_t=last_t, last_z=last_z, gross_slip=gross, passes=passes,
    )
