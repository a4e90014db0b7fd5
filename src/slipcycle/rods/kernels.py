"""Compiled inner loops of the rod solvers (Numba).

Every interface model is a *bed* of Jenkins elements in rotation variables (see
:mod:`slipcycle.rods.interfaces`): element i has torsional stiffness κ_i (N m/rad) and
torque capacity c_i = ĉ_i N(t) that follows the normal force. Every solver in this package
(quasi-static, modal, characteristic) reduces one time step to the same problem:

    δ_new = δ_pred − C T_new,        T_new = Σ_i clip(t_i + κ_i (δ_new − δ_old), ±c_i),

i.e. the bed in series with a known compliance C > 0 (the massless rods, the exact modal
step, or the wave impedance). With y = δ_new − δ_old this is

    Σ_i clip(t_i + κ_i y, ±c_i) + y / C = (δ_pred − δ_old) / C,

a force-controlled step of the bed with one extra linear element of stiffness 1/C, which the
Jenkins-bed kernel :func:`slipcycle.kernels.jenkins.solve_tangential_force` (shared with
the half-space slider bed) solves exactly; :func:`slipcycle.kernels.jenkins.apply_increment`
then moves the elements (the same return map as the slider bed's). Rigid-plastic interfaces
(``coulomb``, and ``welded`` with infinite capacity) are the closed-form limit κ → ∞:
T_new = clip((δ_pred − δ_old)/C, ±c).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from slipcycle.kernels.jenkins import apply_increment, solve_tangential_force

__all__ = ["bed_step", "integrate"]


@njit(cache=True)
def bed_step(t, kappa, cap, rigid, target, C, guess, wt, wk, wc, d):
    """One implicit step of a bed in series with compliance C; updates t and d in place.

    Parameters
    ----------
    t : (n,) array
        Element torques (N m), updated.
    kappa, cap : (n,) arrays
        Stiffnesses (N m/rad) and current capacities (N m).
    rigid : bool
        Rigid-plastic single element (κ = ∞).
    target : float
        (δ_pred − δ_old)/C (N m): the torque if the interface did not move.
    C : float
        Series compliance (rad/(N m)), > 0.
    guess : float
        Starting guess for y (rad).
    wt, wk, wc : (n + 1,) work arrays
    d : (n,) array
        Dissipated energy per element (J), incremented by ½(t_old + t_new) × slip.

    Returns
    -------
    T_new : float
    y : float
        δ_new − δ_old (rad).
    """
    n = t.size
    if rigid:
        told = t[0]
        c = cap[0]
        tn = target
        if tn > c:
            tn = c
        elif tn < -c:
            tn = -c
        y = C * (target - tn)
        d[0] += 0.5 * (told + tn) * y
        t[0] = tn
        return tn, y
    capsum = 0.0
    for i in range(n):
        capsum += cap[i]
    if capsum <= 0.0:  # separated: nothing is transmitted
        for i in range(n):
            t[i] = 0.0
        return 0.0, C * target
    for i in range(n):
        wt[i] = t[i]
        wk[i] = kappa[i]
        wc[i] = cap[i]
    wt[n] = 0.0
    wk[n] = 1.0 / C
    wc[n] = 2.0 * (abs(target) + capsum) + 1e-300
    y, _ = solve_tangential_force(wt, wk, wc, target, guess)
    # the slip records of the shared kernel are not needed here: the work arrays take them
    T, _, _ = apply_increment(t, kappa, kappa, cap, y, d, wt[:n], wc[:n], 0.0)
    return T, y


@njit(cache=True)
def integrate(q, v, a11, a12, a21, a22, b0q, b0v, b1q, b1v, b, g, omega, two_zeta_omega,
              C, r_theta, inertia2, h, theta, theta_d, theta_dd, n_scale,
              t, kappa, cap_unit, rigid, d, state, T_out, delta_out, acc):
    """March the modal model (or, with no modes, the quasi-static one) over K steps.

    Modal equations (mass-normalised, m modes of both rods stacked):
    q̈_k + 2ζω_k q̇_k + ω_k² q_k = −b_k T − g_k Θ̈, and the interface relative rotation
    δ = Θ + Σ b_k q_k − R T + r_Θ Θ̈ (R, r_Θ: residual flexibility of the truncated modes).
    Each step is the exact solution of the modal oscillators for forcing linear in time over
    the step (Nigam & Jennings 1969), with the end-of-step torque implicit: the interface
    then sees the compliance C = Σ b_k² B1_k + R and :func:`bed_step` solves it exactly.

    Parameters
    ----------
    q, v : (m,) arrays
        Modal coordinates and velocities, updated.
    a11, a12, a21, a22, b0q, b0v, b1q, b1v : (m,) arrays
        Exact one-step recurrence coefficients.
    b, g : (m,) arrays
        Interface participation ψ(0) (signed) and base-acceleration participation.
    omega, two_zeta_omega : (m,) arrays
    C, r_theta : float
    inertia2 : float
        ρ2 J2 L2, for the drive torque (momentum balance of rod 2).
    h : float
        Time step (s), used for the energy integrals only.
    theta, theta_d, theta_dd : (K + 1,) arrays
        Θ, Θ̇, Θ̈ at the step ends.
    n_scale : (K + 1,) array
        Normal force N ≥ 0 (capacities are cap_unit × N).
    t, kappa, cap_unit : (n,) arrays
        Bed state and parameters; t updated.
    rigid : bool
    d : (n,) array
        Dissipation per element (J), incremented.
    state : (3,) array
        [T, δ, y_prev], updated.
    T_out, delta_out : (K + 1,) arrays
        Interface torque and relative rotation at the step ends.
    acc : (2,) array
        Incremented by the modal damping loss ∫ Σ 2ζω q̇² dt and the input work
        ∫ T_drive Θ̇ dt (J), both by the trapezoidal rule. T_drive = T + ρ2J2L2 Θ̈ +
        Σ g_k q̈_k is the torque at x = L2 from the momentum balance of rod 2.
    """
    m = q.size
    nb = t.size
    cap = np.empty(nb)
    wt = np.empty(nb + 1)
    wk = np.empty(nb + 1)
    wc = np.empty(nb + 1)
    qf = np.empty(m)
    vf = np.empty(m)
    T = state[0]
    delta = state[1]
    yprev = state[2]
    T_out[0] = T
    delta_out[0] = delta
    # power terms at the start
    pd_old = 0.0
    sq = 0.0
    for k in range(m):
        pd_old += two_zeta_omega[k] * v[k] * v[k]
        acc_k = -b[k] * T - g[k] * theta_dd[0] - two_zeta_omega[k] * v[k] - omega[k] ** 2 * q[k]
        sq += g[k] * acc_k
    pin_old = (T + inertia2 * theta_dd[0] + sq) * theta_d[0]
    K = theta.size - 1
    for s in range(K):
        dp = theta[s + 1] + r_theta * theta_dd[s + 1]
        for k in range(m):
            f0 = -b[k] * T - g[k] * theta_dd[s]
            f1 = -g[k] * theta_dd[s + 1]
            qf[k] = a11[k] * q[k] + a12[k] * v[k] + b0q[k] * f0 + b1q[k] * f1
            vf[k] = a21[k] * q[k] + a22[k] * v[k] + b0v[k] * f0 + b1v[k] * f1
            dp += b[k] * qf[k]
        N = n_scale[s + 1]
        if N < 0.0:
            N = 0.0
        for i in range(nb):
            cap[i] = cap_unit[i] * N
        target = (dp - delta) / C
        T, y = bed_step(t, kappa, cap, rigid, target, C, yprev, wt, wk, wc, d)
        delta += y
        yprev = y
        pd = 0.0
        sq = 0.0
        for k in range(m):
            q[k] = qf[k] - b1q[k] * b[k] * T
            v[k] = vf[k] - b1v[k] * b[k] * T
            pd += two_zeta_omega[k] * v[k] * v[k]
            acc_k = (-b[k] * T - g[k] * theta_dd[s + 1] - two_zeta_omega[k] * v[k]
                     - omega[k] ** 2 * q[k])
            sq += g[k] * acc_k
        pin = (T + inertia2 * theta_dd[s + 1] + sq) * theta_d[s + 1]
        acc[0] += 0.5 * h * (pd_old + pd)
        acc[1] += 0.5 * h * (pin_old + pin)
        pin_old = pin
        pd_old = pd
        T_out[s + 1] = T
        delta_out[s + 1] = delta
    state[0] = T
    state[1] = delta
    state[2] = yprev
