"""Periodic steady-state solver of the rods (Newton on the cycle, rods/periodic.py).

Every check is against an independent reference: the scheme's own time stepping (the
periodic operator must reproduce one cycle of the recurrence exactly), finite differences
(the Newton tangent) and plain cycling to a tight tolerance (the steady state reached).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import slipcycle.rods.modal as modal
from slipcycle.rods.interfaces import distributed_bed, jenkins_bed
from slipcycle.rods.limits import Study, gross_slip_amplitude, regime_map
from slipcycle.rods.modal import (
    Propagator,
    condense_unresolved,
    modal_basis,
    steady_state,
    step_coefficients,
)
from slipcycle.rods.model import Excitation, Rod, TwoRods
from slipcycle.rods.periodic import _bed_periodic, _jacobian, periodic_operator
from slipcycle.rods.welded import omega1

N0 = 1.0e4
K = 200


def rods_system(zeta=0.01, interface="distributed"):
    r = Rod(0.5, 0.01, 200e9, 0.3, 7850.0)
    rods = TwoRods(r, r, 0.3, interface, 1e13, zeta)
    bed = distributed_bed(rods, 30) if interface == "distributed" else jenkins_bed(rods)
    return rods, bed, modal_basis(rods, 12), omega1(rods)


#: The periodic states form a family: rings that slip during the transient but not in the
#: steady cycle keep offsets that depend on the transient, which shift the mean torque.
#: The dissipation and the ranges ptp(T), ptp(δ) are the same for every member (agree to
#: 1e-11); the peak max|T| = mean + amplitude is not: at Ω/ω1 = 2.19, Θa = 0.1 Θg,
#: ζ = 0.003 projected cycling, plain physical cycling and Newton after 20 cycles give
#: peaks differing by up to 4e-4 with equal ranges and losses.
T_MAX_RTOL = 1e-3
AMPLITUDE_RTOL = 1e-8


def _same_cycle(new, ref):
    """Dissipation, torque range and rotation range equal; peak torque to the family."""
    floor = 1e-12 * ref.T_max * np.ptp(ref.delta)
    assert abs(new.dissipation - ref.dissipation) <= 1e-7 * ref.dissipation + floor
    assert _rel(np.ptp(new.T), np.ptp(ref.T)) <= AMPLITUDE_RTOL
    assert _rel(np.ptp(new.delta), np.ptp(ref.delta)) <= AMPLITUDE_RTOL
    assert _rel(new.T_max, ref.T_max) <= T_MAX_RTOL


@pytest.fixture
def newton_early(monkeypatch):
    """Make every run that has not converged after 20 cycles go through Newton."""
    monkeypatch.setattr(modal, "NEWTON_AFTER", 20)
    monkeypatch.setattr(modal, "NEWTON_WORTH", 0.0)


def _rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


# --- the periodic operator is the scheme's periodic response ----------------------------
@pytest.mark.parametrize("ratio", [0.05, 0.9, 2.9])
def test_periodic_operator_reproduces_one_cycle_of_the_recurrence(ratio):
    rods, bed, basis, w1 = rods_system()
    W = ratio * w1
    h = 2 * math.pi / W / K
    b = condense_unresolved(basis, h)
    coef = step_coefficients(b.omega, b.zeta, h)
    op = periodic_operator(b, coef, K)
    rng = np.random.default_rng(1)
    T = rng.normal(size=K) * 10.0
    tt = np.arange(K + 1) * h
    theta, _, theta_dd = Excitation(0.01, W, N0).rotation(tt)
    q, v = op.modal_state(T, theta_dd[:K])
    q0, v0 = q.copy(), v.copy()
    a11, a12, a21, a22, b0q, b0v, b1q, b1v = coef
    delta = np.empty(K)
    for s in range(K):  # the recurrence of rods.kernels.integrate with T given
        f0 = -b.b * T[s] - b.g * theta_dd[s]
        f1 = -b.b * T[(s + 1) % K] - b.g * theta_dd[s + 1]
        q, v = (a11 * q + a12 * v + b0q * f0 + b1q * f1,
                a21 * q + a22 * v + b0v * f0 + b1v * f1)
        s1 = (s + 1) % K
        delta[s1] = theta[s + 1] + b.r_theta * theta_dd[s + 1] + b.b @ q - b.R * T[s1]
    scale = np.max(np.abs(delta))
    assert np.max(np.abs(q - q0)) <= 1e-9 * max(np.max(np.abs(q0)), 1e-300)
    assert np.max(np.abs(v - v0)) <= 1e-9 * max(np.max(np.abs(v0)), 1e-300)
    ref = op.drive(theta[:K], theta_dd[:K]) - op.convolve(T)
    assert np.max(np.abs(delta - ref)) <= 1e-10 * scale


@pytest.mark.parametrize("ratio", [0.05, 0.9, 2.9])
@pytest.mark.parametrize("k_factor", [1.0, 0.1, math.inf])
def test_fourier_projection_equals_dense_monodromy(ratio, k_factor):
    """(I − S(k)^K)⁻¹ e from the periodic operator (O(K m)) equals the dense solve with
    the K-th power of the one-step matrix of the stuck interface."""
    rods, bed, basis, w1 = rods_system()
    prop = Propagator.build(modal_basis(rods, 40), ratio * w1, 400, bed.stiffness)
    k = k_factor * bed.stiffness
    k_used, lu = prop.monodromy_lu(k)
    e = np.random.default_rng(3).normal(size=2 * prop.basis.size)
    dense = modal._lu_solve(lu, e)
    fourier = prop.periodic().project(k_used, e)
    assert np.max(np.abs(fourier - dense)) <= 1e-10 * np.max(np.abs(dense))


def test_newton_tangent_matches_finite_differences():
    rods, bed, basis, w1 = rods_system()
    prop = Propagator.build(basis, 0.9 * w1, K, bed.stiffness)
    op = prop.periodic()
    rng = np.random.default_rng(2)
    c = bed.cap_unit * N0 / bed.kappa
    delta = 3 * c.min() * np.sin(2 * np.pi * np.arange(K) / K) + 1e-3 * c.min() * rng.normal(
        size=K)
    N = np.full(K, N0)
    n = bed.size

    def resid(d):
        T, t_end, kd = np.empty(K), np.empty(n), np.empty(K)
        ref, kref = np.empty((K, 64), dtype=np.int64), np.empty((K, 64))
        assert _bed_periodic(d, np.zeros(n), 0.0, bed.kappa, bed.cap_unit, N, T, t_end, kd,
                             ref, kref) >= 0
        return d + op.convolve(T), kd, ref, kref

    r0, kd, ref, kref = resid(delta)
    J = np.empty((K, K))
    _jacobian(op.h, kd, ref, kref, J)
    agree = 0
    for _ in range(6):
        u = rng.normal(size=K)
        eps = 1e-9 * c.min()
        fd = (resid(delta + eps * u)[0] - r0) / eps
        agree += np.max(np.abs(fd - J @ u)) <= 1e-5 * np.max(np.abs(J @ u))
    assert agree >= 5  # a direction may cross a stick/slip kink within eps


# --- the steady state reached: Newton against plain cycling -----------------------------
GRID = [(r, f) for r in (0.3, 0.9, 1.6, 2.9) for f in (0.3, 0.9, 2.5)]


@pytest.mark.parametrize("ratio,factor", GRID)
def test_newton_returns_the_steady_state_of_cycling(ratio, factor, newton_early):
    """Stuck (0.3 Θg), microslip and gross slip, below, near and above resonance (the
    stuck system's second natural frequency is 3 ω1): dissipation and amplitude equal
    those of cycling converged to 1e-11."""
    rods, bed, basis, w1 = rods_system()
    exc = Excitation(factor * gross_slip_amplitude(rods, N0), ratio * w1, N0)
    new = steady_state(rods, exc, bed, basis, K, 2000, 1e-10, method="newton")
    ref = steady_state(rods, exc, bed, basis, K, 3000, 1e-11, method="cycling")
    assert ref.converged and new.converged
    assert new.cycles <= max(ref.cycles, 22)
    _same_cycle(new, ref)


@pytest.mark.parametrize("ratio,factor", [(0.3, 0.9), (1.6, 0.3), (0.9, 2.5)])
def test_zero_damping_points_are_marked_never_wrong(ratio, factor, newton_early):
    """ζ = 0: where cycling converges both agree; where it does not, Newton's point is
    marked converged only if an ordinary cycle from it repeats to the tolerance."""
    rods, bed, basis, w1 = rods_system(zeta=0.0)
    exc = Excitation(factor * gross_slip_amplitude(rods, N0), ratio * w1, N0)
    new = steady_state(rods, exc, bed, basis, K, 400, 1e-9, method="newton")
    ref = steady_state(rods, exc, bed, basis, K, 400, 1e-9, method="cycling")
    if ref.converged:
        assert new.converged
        assert _rel(new.dissipation, ref.dissipation) <= 1e-6
    if new.converged:
        assert new.residual <= 1e-9  # the verifying cycle passed the cycling test
        again = steady_state(rods, exc, bed, basis, K, 400, 1e-9, method="newton")
        assert again.dissipation == new.dissipation  # deterministic
    else:
        assert not ref.converged  # Newton never loses a point that cycling gets


def test_near_resonance_branch_is_the_one_cycling_reaches(newton_early):
    """Near the stuck system's resonance friction gives several periodic states; the
    solver continues the cycling run from its start (the stuck linear steady state), so
    it returns the branch that cycling reaches: same loss and amplitude on a sweep
    through the resonance."""
    rods, bed, basis, w1 = rods_system()
    amp = 0.6 * gross_slip_amplitude(rods, N0)
    for ratio in (2.7, 2.85, 2.95, 3.0, 3.05, 3.2):
        exc = Excitation(amp, ratio * w1, N0)
        new = steady_state(rods, exc, bed, basis, K, 2000, 1e-10, method="newton")
        ref = steady_state(rods, exc, bed, basis, K, 3000, 1e-11, method="cycling")
        assert new.converged and ref.converged
        _same_cycle(new, ref)


@settings(max_examples=12, deadline=None)
@given(ratio=st.floats(0.02, 3.2), factor=st.floats(0.1, 4.0),
       zeta=st.sampled_from([0.003, 0.01, 0.05]),
       interface=st.sampled_from(["distributed", "jenkins"]))
def test_newton_agrees_with_cycling_over_the_domain(ratio, factor, zeta, interface):
    rods, bed, basis, w1 = rods_system(zeta, interface)
    exc = Excitation(factor * gross_slip_amplitude(rods, N0), ratio * w1, N0)
    old = (modal.NEWTON_AFTER, modal.NEWTON_WORTH)
    modal.NEWTON_AFTER, modal.NEWTON_WORTH = 20, 0.0  # Newton wherever cycling is not done
    try:
        new = steady_state(rods, exc, bed, basis, K, 3000, 1e-10, method="newton")
    finally:
        modal.NEWTON_AFTER, modal.NEWTON_WORTH = old
    ref = steady_state(rods, exc, bed, basis, K, 4000, 1e-11, method="cycling")
    if not ref.converged:
        assert not new.converged or new.residual <= 1e-10
        return
    assert new.converged
    _same_cycle(new, ref)


def test_method_is_checked():
    rods, bed, basis, w1 = rods_system()
    with pytest.raises(ValueError, match="method"):
        steady_state(rods, Excitation(0.01, w1, N0), bed, basis, K, method="shooting")


def test_map_points_without_a_verified_periodic_state_are_flagged():
    """A cycle limit too small for the steady state: every point of the map that has not
    passed the cycling test is flagged, and the converged ones equal the full solution."""
    rods, bed, basis, w1 = rods_system()
    exc = Excitation(0.01, w1, N0)
    ratios, factors = np.array([0.3, 1.6, 2.9]), np.array([0.3, 1.5])
    short = regime_map(Study(rods, exc, bed, basis, K, 4, 1e-6), ratios, factors, False)
    full = regime_map(Study(rods, exc, bed, basis, K, 2000, 1e-8), ratios, factors, False)
    assert full["converged"].all()
    assert (~short["converged"]).any()
    ok = short["converged"]
    assert np.allclose(short["torque_ratio"][ok], full["torque_ratio"][ok], rtol=1e-5)
