"""Compiled inner loops of the slider bed (Numba).

State of slider i: tangential force t_i and accumulated slip z_i of its base. One load
step moves the approach to U and either prescribes the tangential displacement increment
ΔV or the total tangential force Q. Each slider is updated by the return map of a Jenkins
element with a moving limit c_i = f k_i (U − s_i)₊:

    t_i ← clip(t_i + κ_i ΔV, −c_i, c_i),   Δz_i = ΔV − Δt_i/κ_i,   κ_i = k_i/λ_c.

In force control ΔV is the root of the monotone piecewise-linear equation
Σ_i clip(t_i + κ_i ΔV, −c_i, c_i) = Q, solved exactly by
:func:`slipcycle.kernels.jenkins.solve_tangential_force` (shared with the rod solvers).

Dissipation is accumulated per slider as ½(t_old + t_new) Δz, which makes the sum over
sliders equal the trapezoidal ∮Q dV up to the change of stored elastic energy
Σ Δ(t²)/2κ — zero over a closed steady cycle.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# the Jenkins bed's exact force-controlled step is shared with the rod solvers
from slipcycle.kernels.jenkins import (
    _newton,
    apply_increment,
    at_root,
    solve_tangential_force,
)

__all__ = ["drive", "drive_from", "drive_with", "solve_tangential_force", "STATUS_OK", "SLIP_TOL"]

STATUS_OK = -1
#: relative overshoot of a slider's limit below which a step does not count it as slipping
SLIP_TOL = 1e-9


@njit(cache=True)
def drive(t, z, d, level, kn, kt, friction, U_path, T_path, force_control, V0,
          rec_index, rec_t, rec_z, V_out, Q_out, first_slip_out):
    """:func:`drive_from` starting at the approach ``U_path[0]``, without slip accounting.

    Kept for callers of the original signature (benchmarks); new code calls
    :func:`drive_from`, which needs the approach *before* the first step to be exact when
    sliders touch during that step.
    """
    slip = np.zeros(t.size)
    return drive_from(t, z, d, slip, level, kn, kt, friction, U_path, T_path, force_control,
                      V0, U_path[0], rec_index, rec_t, rec_z, V_out, Q_out, first_slip_out)


@njit(cache=True)
def drive_from(t, z, d, slip, level, kn, kt, friction, U_path, T_path, force_control, V0,
               U0, rec_index, rec_t, rec_z, V_out, Q_out, first_slip_out):
    """Drive the bed along a load path, updating the state in place.

    The load path is linear between samples, starting from the state (U0, V0). A slider
    that touches inside a step takes its share of the tangential increment from the moment
    it touches (the approach being linear within the step), which makes a proportional
    path (V = λ (Q/P) U, Ciavarella 1998; Jäger 1998) exact at any step count.

    Parameters
    ----------
    t, z, d, slip : (n,) arrays
        Tangential force (N), base slip (m), accumulated dissipation (J) and accumulated
        absolute slip Σ|Δz| while in contact (m) per slider (updated in place).
    level, kn, kt : (n,) arrays
        Levels s_i (m), normal and tangential stiffnesses (N/m).
    friction : float
    U_path : (K,) array
        Approach at each step.
    T_path : (K,) array
        Tangential force Q (force control) or displacement V (displacement control).
    force_control : bool
    V0, U0 : float
        Tangential displacement and approach before the first step.
    rec_index : (R,) int array
        Ascending step indices whose slider states are copied into rec_t, rec_z (R, n).
    V_out, Q_out : (K,) arrays
        Tangential displacement and force after each step.
    first_slip_out : (K,) int array
        Index of the lowest slider slipping in each step (n if none: full stick). A slider
        counts as slipping when its trial force exceeds its limit by more than
        ``SLIP_TOL`` times the limit: a slider brought back exactly to its limit (a load
        reversal, a proportional path) is not slipping because of rounding.

    Returns
    -------
    status : int
        STATUS_OK, or the step index at which gross slip (|Q| ≥ f P) was reached.
    passes : int
        Total number of sweeps over the sliders (for performance accounting).
    """
    n = t.size
    # reciprocal stiffnesses once per call: the bracket needs (±c − t)/κ for every slider
    # at every step, and a division costs several multiplications
    return drive_with(t, z, d, slip, level, kn, kt, friction, U_path, T_path, force_control,
                      V0, U0, rec_index, rec_t, rec_z, V_out, Q_out, first_slip_out,
                      np.empty(n), np.empty(n), 1.0 / kt)


@njit(cache=True)
def drive_with(t, z, d, slip, level, kn, kt, friction, U_path, T_path, force_control, V0,
               U0, rec_index, rec_t, rec_z, V_out, Q_out, first_slip_out, cap, ke, inv_kt):
    """:func:`drive_from` with its work arrays given: ``cap`` and ``ke`` (n,) (overwritten)
    and ``inv_kt`` = 1/kt (n,), for callers that drive the same bed many times in short
    pieces (the Ŵ map) and would otherwise allocate them every time."""
    n = t.size
    V = V0
    U_old = U0
    r = 0
    passes = 0
    for k in range(U_path.size):
        U = U_path[k]
        # One sweep sets the limits and everything the first Newton step needs at ΔV = 0:
        # Σ clip(t, ±c), the stuck stiffness, and the bracket of the root.
        qmax = 0.0
        q0 = 0.0
        qa0 = 0.0
        s0 = 0.0
        lo = 0.0
        hi = 0.0
        # nearest breakpoints of Σ clip(t + κ ΔV, ±c) on either side of ΔV = 0: between
        # them the sum is linear with slope s0, so one Newton step from 0 is the root
        below = -np.inf
        above = np.inf
        for i in range(n):
            gap = U - level[i]
            c = friction * kn[i] * gap if gap > 0.0 else 0.0
            cap[i] = c
            qmax += c
            # A slider touching during the step carries only the displacement after touch
            # (approach taken linear within the step), so it enters with no force.
            old_gap = U_old - level[i]
            if gap > 0.0 and old_gap < 0.0:
                ke[i] = kt[i] * gap / (gap - old_gap)
                inv = 1.0 / ke[i]
            else:
                ke[i] = kt[i]
                inv = inv_kt[i]
            ti = t[i]
            if ti >= c:
                q0 += c
                qa0 += c
            elif ti <= -c:
                q0 -= c
                qa0 += c
            else:
                q0 += ti
                qa0 += abs(ti)
                s0 += ke[i]
            b_lo = (-c - ti) * inv
            b_hi = (c - ti) * inv
            lo = min(lo, b_lo)
            hi = max(hi, b_hi)
            if c > 0.0:  # a slider out of contact carries nothing: no breakpoint
                # reaching +c ahead, or leaving +c behind (0: at the limit now)
                if b_hi > 0.0:
                    above = min(above, b_hi)
                else:
                    below = max(below, b_hi)
                if b_lo < 0.0:
                    below = max(below, b_lo)
                else:
                    above = min(above, b_lo)
        U_old = U
        passes += 1
        if force_control:
            target = T_path[k]
            if target != 0.0 and abs(target) >= qmax * (1.0 - 1e-12):
                return k, passes
            if qmax > 0.0:
                # the first step of _newton, taken here when it provably lands on the root
                # (no breakpoint between 0 and it): saves the sweep that would confirm it
                r0 = q0 - target
                dv = 0.0 - r0 / s0 if s0 > 0.0 else np.nan
                if at_root(r0, qa0, target):
                    dv = 0.0
                elif not (below < dv < above):
                    dv, p = _newton(t, ke, cap, target, 0.0, r0, s0, lo, hi, qmax, qa0)
                    passes += p
            else:
                dv = 0.0  # nothing in contact and no load: nothing moves
        else:
            dv = T_path[k] - V
        q, n_slip, first = apply_increment(t, kt, ke, cap, dv, d, z, slip, SLIP_TOL)
        passes += 1
        if not force_control and n_slip > 0 and abs(q) >= qmax * (1.0 - 1e-12):
            return k, passes  # every slider in contact slides: gross slip
        V += dv
        V_out[k] = V
        Q_out[k] = q
        first_slip_out[k] = first
        if r < rec_index.size and rec_index[r] == k:
            rec_t[r, :] = t
            rec_z[r, :] = z
            r += 1
    return STATUS_OK, passes
