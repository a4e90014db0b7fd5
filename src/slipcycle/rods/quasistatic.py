"""Quasi-static solution: massless rods in series with the interface (docs/rods.md).

With inertia neglected the rods are torsional springs G_j J_j/L_j in series, so
δ = Θ − C_r T with C_r = L1/(G1J1) + L2/(G2J2), and the normal force equals the applied
axial force, N = F(t). For the distributed interface the stick shear is τ(ρ) = T ρ/J_a
(J_a = π a⁴/2), slip starts at the rim when τ(a) = f p0, i.e. at T_s = f p0 J_a/a, and gross
slip occurs at T_g = (2/3) π f p0 a³. The hysteresis loop is computed by the same exact
step as the dynamic model (:func:`slipcycle.rods.modal.steady_state` with no modes and the
full static compliance), so quasi-static and dynamic answers differ only by inertia.
"""

from __future__ import annotations

import math

import numpy as np

from slipcycle.rods.interfaces import Bed, gross_slip_torque
from slipcycle.rods.modal import DynamicResult, ModalBasis, steady_state
from slipcycle.rods.model import Excitation, TwoRods

__all__ = ["quasi_static_basis", "quasi_static_loop", "qs_normal_force",
           "slip_inception_torque_qs", "gross_slip_torque_qs", "slip_inception_amplitude"]


def slip_inception_torque_qs(rods: TwoRods, N: float) -> float:
    """T_s = f p0 J_a / a with p0 = N/(π a²) (N m): the rim starts to slip."""
    a = rods.contact_radius
    return rods.friction * N / (math.pi * a * a) * rods.contact_J / a


def gross_slip_torque_qs(rods: TwoRods, N: float) -> float:
    """T_g = (2/3) π f p0 a³ = (2/3) f N a (N m): :func:`~slipcycle.rods.interfaces.
    gross_slip_torque` of the rods' friction and contact radius."""
    return gross_slip_torque(rods.friction, N, rods.contact_radius)


def quasi_static_basis(rods: TwoRods) -> ModalBasis:
    """A modal model with no modes whose residual compliance is the whole rods' compliance."""
    e = np.zeros(0)
    return ModalBasis(e, e, e, rods.rods_compliance, 0.0, 0.0, 0.0, 0, True)


def qs_normal_force(exc: Excitation, t: np.ndarray) -> np.ndarray:
    """N(t) = F0 + F_a sin(Ωt + ψ) (N): no axial inertia."""
    return exc.axial_force + exc.axial_amplitude * np.sin(exc.frequency * t + exc.axial_phase)


def quasi_static_loop(rods: TwoRods, exc: Excitation, bed: Bed, steps_per_cycle: int = 400,
                      max_cycles: int = 10) -> DynamicResult:
    """Steady quasi-static hysteresis loop, starting from the unloaded, unslipped state.

    The excitation frequency only labels time; the answer does not depend on it.
    Inertia is neglected: the rods are torsional springs in series with the interface,
    δ = Θ − C_r T, C_r = L1/(G1 J1) + L2/(G2 J2), and the normal force is the applied
    axial force, N(t) = F0 + F_a sin(Ωt + ψ) (clipped at 0 by the bed). The loop is run
    by the dynamic solver's exact step with no modes and the full static compliance
    (:func:`quasi_static_basis`, :func:`slipcycle.rods.modal.steady_state` with
    tolerance 1e-9 and no acceleration), so quasi-static and dynamic answers differ only
    by inertia.

    Parameters
    ----------
    rods : TwoRods
        The rods (their static torsional compliance C_r, rad/(N m)).
    exc : Excitation
        Drive amplitude Θ_a (rad), axial force F0, F_a (N) and phase ψ (rad); Ω (rad/s)
        only sets the time axis.
    bed : Bed
        The interface law (:func:`slipcycle.rods.interfaces.make_bed`).
    steps_per_cycle : int
        K, steps per period.
    max_cycles : int
        Upper limit of cycles; reaching it is reported (``converged=False``).

    Returns
    -------
    DynamicResult
        The last cycle: ``t``, ``theta``, ``T``, ``delta``, ``N`` of shape (K + 1,) (s, rad,
        N m, rad, N), friction ``dissipation`` per cycle (J), ``damping_loss`` (0),
        ``input_work`` (J), ``cycles``, ``converged``, ``residual`` and
        ``element_dissipation`` (n,) (J).

    References
    ----------
    Iwan, W. D. (1966). A distributed-element model for hysteresis and its steady-state
    dynamic response. J. Appl. Mech. 33, 893–900 (the loop of a bed of Jenkins elements).
    Johnson, K. L. (1985). Contact Mechanics, §7.3 (torsion of a flat circular contact).
    """
    K = int(steps_per_cycle)
    tt = np.arange(K + 1) * exc.period / K
    return steady_state(rods, exc, bed, quasi_static_basis(rods), steps_per_cycle=K,
                        max_cycles=max_cycles, tol=1e-9, accelerate=False,
                        N_history=qs_normal_force(exc, tt))


def slip_inception_amplitude(torque_per_rotation: np.ndarray, first_slip_torque: np.ndarray
                             ) -> float:
    """Smallest drive amplitude Θ_a at which the interface starts to slip (rad).

    Parameters
    ----------
    torque_per_rotation : (K,) array
        Stuck interface torque over the cycle per unit Θ_a (N m/rad).
    first_slip_torque : (K,) array
        Torque at which the first element slips at each instant (N m), ∝ N(t).

    Returns
    -------
    float
        min_t first_slip_torque/|torque_per_rotation| (inf if it never slips).
    """
    a = np.abs(np.asarray(torque_per_rotation))
    with np.errstate(divide="ignore"):
        r = np.where(a > 0, np.asarray(first_slip_torque) / a, np.inf)
    return float(np.min(r))
