"""Interface torque laws as beds of Jenkins elements in rotation variables.

Every interface model maps the history of the relative rotation δ = φ2(0) − φ1(0) to the
interface torque T. All of them are written as a *bed* of Jenkins (spring–slider) elements:
element i has torsional stiffness κ_i (N m/rad) and torque capacity c_i = ĉ_i N(t), which
follows the instantaneous normal force N (so the axial motion couples into the torsion), and

    t_i ← clip(t_i + κ_i Δδ, −c_i, c_i),     T = Σ_i t_i.

``distributed``
    The contact disc 0 ≤ ρ ≤ a split into rings. Ring i (ρ_a ≤ ρ ≤ ρ_b) carries the shear
    τ = k_t ρ δ while it sticks and |τ| = f p, p = N/(π a²), while it slips, so
    κ_i = k_t ∫2πρ³ dρ = k_t π(ρ_b⁴ − ρ_a⁴)/2 and ĉ_i = (f/πa²) ∫2πρ² dρ. The sums are exact:
    Σκ_i = k_t J_a (J_a = π a⁴/2), Σ c_i = (2/3) f N a. Rings are independent Coulomb
    sliders with moving limits — the slider bed of the half-space model (docs/halfspace.md) with the
    ring radius in place of the approach level. The outer ring slips first (microslip from
    the rim inwards).
``jenkins``
    One element with the same initial stiffness k_t J_a and capacity (2/3) f N a.
``coulomb``
    Rigid–plastic: T sticks (δ̇ = 0) until |T| = (2/3) f N a.
``iwan``
    Segalman's four-parameter Iwan element (F_S, K_T, χ, β), discretised into Jenkins
    elements; see :func:`segalman_density` and :func:`fit_iwan`.
``welded``
    No slip (rigid, infinite capacity).

References
----------
Segalman, D. J. (2005). A four-parameter Iwan model for lap-type joints. J. Appl. Mech.
72, 752–760. Iwan, W. D. (1966). A distributed-element model for hysteresis and its
steady-state dynamic response. J. Appl. Mech. 33, 893–900. Popov, V. L. & Heß, M. (2015).
Method of Dimensionality Reduction in Contact Mechanics and Friction. Springer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from slipcycle.rods.model import TwoRods, gross_slip_torque

__all__ = ["gross_slip_torque", "InterfaceLaw", "Welded", "DistributedRings", "Coulomb",
           "Jenkins", "Iwan", "INTERFACE_LAWS", "interface_law", "Bed", "make_bed",
           "distributed_bed", "jenkins_bed", "coulomb_bed", "welded_bed",
           "iwan_bed", "SegalmanIwan", "segalman_density", "fit_iwan",
           "distributed_backbone", "distributed_dissipation", "distributed_dissipation_rotation",
           "distributed_torque_to_rotation",
           "jenkins_dissipation", "bed_dissipation", "bed_rotation_at_torque",
           "iwan_discretisation_error", "IWAN_RTOL", "IWAN_T_MIN"]




@dataclass(frozen=True)
class Bed:
    """Interface torque law as a bed of Jenkins elements.

    Attributes
    ----------
    kind : str
        Interface name.
    kappa : (n,) array
        Element stiffnesses κ_i (N m/rad); inf for rigid-plastic.
    cap_unit : (n,) array
        Capacity per unit normal force ĉ_i (N m/N = m): c_i = ĉ_i N.
    rigid : bool
        Single rigid-plastic element (coulomb, welded).
    """

    kind: str
    kappa: np.ndarray
    cap_unit: np.ndarray
    rigid: bool = False

    @property
    def size(self) -> int:
        return int(self.kappa.size)

    @property
    def is_frictional(self) -> bool:
        """Whether the interface can slip (every law but ``welded``)."""
        return INTERFACE_LAWS[self.kind].is_frictional

    @property
    def stiffness(self) -> float:
        """Initial (stuck) torsional stiffness Σκ_i (N m/rad)."""
        return math.inf if self.rigid else float(self.kappa.sum())

    def capacity(self, N: float) -> float:
        """Gross-slip torque Σ ĉ_i N (N m)."""
        return float(self.cap_unit.sum() * N)

    def first_slip_torque(self, N: float) -> float:
        """Interface torque at which the first element slips from the unloaded state (N m)."""
        if self.rigid:
            return self.capacity(N)
        delta = np.min(self.cap_unit * N / self.kappa)
        return float(np.minimum(self.kappa * delta, self.cap_unit * N).sum())

    def initial_state(self, delta0: float, N0: float) -> np.ndarray:
        """Element torques of an interface assembled without slip then rotated by δ0."""
        if self.rigid:
            return np.zeros(1)
        return np.clip(self.kappa * delta0, -self.cap_unit * N0, self.cap_unit * N0)


def distributed_bed(rods: TwoRods, rings: int = 100) -> Bed:
    """Rings of equal width over the contact disc (see module docstring)."""
    if rings < 1:
        raise ValueError(f"rings: must be >= 1, got {rings}")
    a = rods.contact_radius
    e = np.linspace(0.0, a, rings + 1)
    kappa = rods.interface_stiffness * math.pi * (e[1:] ** 4 - e[:-1] ** 4) / 2.0
    cap = rods.friction / (math.pi * a * a) * 2.0 * math.pi * (e[1:] ** 3 - e[:-1] ** 3) / 3.0
    return Bed("distributed", kappa, cap)


def jenkins_bed(rods: TwoRods) -> Bed:
    """One spring–slider with the distributed model's initial stiffness and capacity."""
    return Bed("jenkins", np.array([rods.interface_stiffness * rods.contact_J]),
               np.array([gross_slip_torque(rods.friction, 1.0, rods.contact_radius)]))


def coulomb_bed(rods: TwoRods) -> Bed:
    """Rigid–plastic, capacity (2/3) f N a."""
    return Bed("coulomb", np.array([np.inf]),
               np.array([gross_slip_torque(rods.friction, 1.0, rods.contact_radius)]),
               rigid=True)


def welded_bed(rods: TwoRods) -> Bed:
    """No slip at all."""
    return Bed("welded", np.array([np.inf]), np.array([np.inf]), rigid=True)


# ---------------------------------------------------------------------------------------
# closed forms of the distributed (rings) interface, continuous in ρ
# ---------------------------------------------------------------------------------------
def distributed_backbone(rods: TwoRods, N: float, delta: np.ndarray) -> np.ndarray:
    """Monotonic loading curve T(δ) of the continuous ring model (N m), δ ≥ 0 (rad).

    T = k_t J_a δ until the rim slips at δ_s = f p/(k_t a); beyond, rings outside
    ρ_c = f p/(k_t δ) slip: T = k_t δ π ρ_c⁴/2 + (2π/3) f p (a³ − ρ_c³).
    """
    a, kt, fp = rods.contact_radius, rods.interface_stiffness, rods.friction * rods.pressure(N)
    delta = np.asarray(delta, dtype=float)
    rc = np.minimum(a, fp / (kt * np.maximum(delta, 1e-300)))
    return kt * delta * math.pi * rc**4 / 2.0 + 2.0 * math.pi / 3.0 * fp * (a**3 - rc**3)


def distributed_torque_to_rotation(rods: TwoRods, N: float, T: np.ndarray) -> np.ndarray:
    """Inverse of :func:`distributed_backbone` (rad); inf at or above gross slip.

    On the microslip branch ρ_c³ = 4a³ − 6T/(π f p) and δ = f p/(k_t ρ_c).
    """
    a, kt, fp = rods.contact_radius, rods.interface_stiffness, rods.friction * rods.pressure(N)
    T = np.asarray(T, dtype=float)
    stick = T <= math.pi * fp * a**3 / 2.0
    rc3 = np.maximum(4.0 * a**3 - 6.0 * T / (math.pi * fp), 0.0)
    with np.errstate(divide="ignore"):
        slip = fp / (kt * np.cbrt(rc3))
    return np.where(stick, T / (kt * rods.contact_J), slip)


def distributed_dissipation(rods: TwoRods, N: float, T_amp: np.ndarray) -> np.ndarray:
    """Quasi-static energy loss per cycle of the ring model at torque amplitude T* (J).

    Each ring is a Jenkins element; one with capacity c and yield rotation δ_y driven to ±δ*
    loses 4c(δ* − δ_y). Summed over the slipping rings ρ_c < ρ < a:
    D = 8π f p [δ*(a³ − ρ_c³)/3 − (f p/k_t)(a² − ρ_c²)/2], zero below slip inception
    T_s = π f p a³/2 (the finite first threshold of rim-first microslip).
    """
    fp = rods.friction * rods.pressure(N)
    D = distributed_dissipation_rotation(rods, N, distributed_torque_to_rotation(rods, N, T_amp))
    return np.where(np.asarray(T_amp) <= math.pi * fp * rods.contact_radius**3 / 2.0, 0.0, D)


def distributed_dissipation_rotation(rods: TwoRods, N: float, delta_amp: np.ndarray
                                     ) -> np.ndarray:
    """As :func:`distributed_dissipation`, at interface rotation amplitude δ* (rad) (J)."""
    a, kt, fp = rods.contact_radius, rods.interface_stiffness, rods.friction * rods.pressure(N)
    d = np.asarray(delta_amp, dtype=float)
    rc = np.minimum(a, fp / (kt * np.maximum(d, 1e-300)))
    D = 8.0 * math.pi * fp * (d * (a**3 - rc**3) / 3.0 - fp / kt * (a**2 - rc**2) / 2.0)
    return np.maximum(D, 0.0)


def jenkins_dissipation(capacity: float, stiffness: float, delta_amp: np.ndarray) -> np.ndarray:
    """Energy loss per cycle of one Jenkins element at rotation amplitude δ*: 4c(δ* − c/κ)₊."""
    return 4.0 * capacity * np.maximum(np.asarray(delta_amp) - capacity / stiffness, 0.0)


# ---------------------------------------------------------------------------------------
# Segalman's four-parameter Iwan element
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SegalmanIwan:
    """Segalman (2005) four-parameter Iwan element at a reference normal force.

    The element is a continuum of unit-stiffness Jenkins elements with slip rotations φ
    distributed with density ρ(φ) = R φ^χ H(φ_max − φ) + S δ(φ − φ_max). Parameters:

    Attributes
    ----------
    F_S : float
        Torque of gross slip (N m) = ∫ φ ρ(φ) dφ.
    K_T : float
        Initial stiffness (N m/rad) = ∫ ρ(φ) dφ.
    chi : float
        Exponent, −1 < χ; small-amplitude dissipation ∝ T*^(3+χ).
    beta : float
        Ratio of the lumped S to the continuous part's stiffness, β ≥ 0.
    """

    F_S: float
    K_T: float
    chi: float
    beta: float

    def __post_init__(self):
        if not self.chi > -1.0:
            raise ValueError(f"iwan.chi: must be > -1, got {self.chi}")
        if not self.beta >= 0.0:
            raise ValueError(f"iwan.beta: must be >= 0, got {self.beta}")

    @property
    def phi_max(self) -> float:
        c = self.beta + (self.chi + 1.0) / (self.chi + 2.0)
        return self.F_S * (1.0 + self.beta) / (self.K_T * c)

    @property
    def R(self) -> float:
        c = self.beta + (self.chi + 1.0) / (self.chi + 2.0)
        return self.F_S * (self.chi + 1.0) / (self.phi_max ** (self.chi + 2.0) * c)

    @property
    def S(self) -> float:
        c = self.beta + (self.chi + 1.0) / (self.chi + 2.0)
        return self.F_S / self.phi_max * self.beta / c

    def backbone(self, u: np.ndarray) -> np.ndarray:
        """Monotonic T(u), u ≥ 0 the relative rotation (N m)."""
        chi, R, S, pm = self.chi, self.R, self.S, self.phi_max
        u = np.minimum(np.asarray(u, dtype=float), pm)
        T = R * u ** (chi + 2) / (chi + 2) + u * (R * (pm ** (chi + 1) - u ** (chi + 1))
                                                 / (chi + 1) + S)
        return T

    def dissipation(self, u: np.ndarray) -> np.ndarray:
        """Energy loss per cycle at rotation amplitude u (J): ∫ 4φ(u − φ)₊ ρ(φ) dφ."""
        chi, R, S, pm = self.chi, self.R, self.S, self.phi_max
        u = np.asarray(u, dtype=float)
        ue = np.minimum(u, pm)
        cont = 4.0 * R * (u * ue ** (chi + 2) / (chi + 2) - ue ** (chi + 3) / (chi + 3))
        return cont + 4.0 * S * pm * np.maximum(u - pm, 0.0)

    def rotation_at_torque(self, T_amp: np.ndarray) -> np.ndarray:
        """Rotation amplitude u with backbone(u) = T* (rad), 0 ≤ T* < F_S; φ_max at or above.

        Vectorised bisection to full double precision (the backbone is increasing and
        concave; its slope vanishes at φ_max when β = 0, so Newton's method is not safe).
        """
        T = np.asarray(T_amp, dtype=float)
        lo = np.zeros(T.shape)
        hi = np.full(T.shape, self.phi_max)
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            below = self.backbone(mid) < T
            lo = np.where(below, mid, lo)
            hi = np.where(below, hi, mid)
            if np.all(hi - lo <= 4e-16 * self.phi_max):
                break
        return np.where(T >= self.F_S, self.phi_max, 0.5 * (lo + hi))

    def dissipation_at_torque(self, T_amp: np.ndarray) -> np.ndarray:
        """Energy loss per cycle at torque amplitude T* < F_S (J), closed form.

        D(u(T*)) with u the exact inverse of the backbone (:meth:`rotation_at_torque`).
        """
        return self.dissipation(self.rotation_at_torque(T_amp))


def bed_rotation_at_torque(kappa: np.ndarray, cap: np.ndarray, T_amp: np.ndarray
                           ) -> np.ndarray:
    """Rotation amplitude of a bed of Jenkins elements at torque amplitude T* (rad).

    The monotonic curve T(u) = Σ min(κ_i u, c_i) is piecewise linear with breakpoints at
    the slip rotations y_i = c_i/κ_i; it is inverted exactly. inf at or above Σ c_i.
    """
    kappa, cap = np.asarray(kappa, dtype=float), np.asarray(cap, dtype=float)
    y = cap / kappa
    o = np.argsort(y)
    y, k, c = y[o], kappa[o], cap[o]
    k_left = k.sum() - np.cumsum(k)           # stiffness still sticking beyond y_j
    T_y = np.cumsum(c) + y * k_left            # T at the breakpoints
    T = np.asarray(T_amp, dtype=float)
    j = np.searchsorted(T_y, T)                # first breakpoint with T_y >= T
    jm = np.maximum(j - 1, 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(j == 0, T / k.sum(), y[jm] + (T - T_y[jm]) / k_left[jm])
    return np.where(T >= T_y[-1], np.inf, u)


def bed_dissipation(kappa: np.ndarray, cap: np.ndarray, u_amp: np.ndarray) -> np.ndarray:
    """Energy loss per cycle of a bed of Jenkins elements at rotation amplitude u (J).

    Element i loses 4 c_i (u − c_i/κ_i)₊ per symmetric cycle (Iwan 1966).
    """
    kappa, cap = np.asarray(kappa, dtype=float), np.asarray(cap, dtype=float)
    u = np.asarray(u_amp, dtype=float)[..., None]
    return np.sum(4.0 * cap * np.maximum(u - cap / kappa, 0.0), axis=-1)


#: relative accuracy of the discretised Iwan element's dissipation at torque amplitude
IWAN_RTOL = 2e-3
#: smallest torque amplitude T*/F_S at which that accuracy is guaranteed
IWAN_T_MIN = 1e-6


def _iwan_edges(iw: SegalmanIwan, bins: int, t_min: float) -> np.ndarray:
    """Bin edges 0 = e_0 < … < e_bins = φ_max, equally spaced in logit(φ/φ_max).

    Equal steps in z = ln(φ/(φ_max − φ)) are geometric steps in φ near 0 (the χ power law
    is scale free, so its relative error is the same on every decade) and geometric steps in
    φ_max − φ near the macroslip end (where the backbone flattens and the rotation at a given
    torque is most sensitive). The first interior edge lies two decades below the rotation
    at T* = t_min F_S, the last at φ_max (1 − 1e-6).
    """
    x_lo = 1e-2 * t_min * iw.F_S / (iw.K_T * iw.phi_max)
    x_hi = 1.0 - 1e-6
    z = np.linspace(math.log(x_lo / (1.0 - x_lo)), math.log(x_hi / (1.0 - x_hi)), bins - 1)
    return np.concatenate([[0.0], iw.phi_max / (1.0 + np.exp(-z)), [iw.phi_max]])


def _iwan_check_torques(t_min: float) -> np.ndarray:
    """Torque amplitudes T*/F_S on which the discretisation is verified."""
    return np.concatenate([np.geomspace(t_min, 0.5, 240), 1.0 - np.geomspace(0.5, 1e-9, 120)])


def iwan_discretisation_error(iw: SegalmanIwan, kappa: np.ndarray, cap: np.ndarray,
                              t_min: float = IWAN_T_MIN) -> float:
    """max |D_bed(T*)/D(T*) − 1| over T*/F_S ∈ [t_min, 1 − 1e-9] (dimensionless).

    D_bed from :func:`bed_rotation_at_torque` and :func:`bed_dissipation` (the discrete
    element, exact), D the closed form of the continuous element (:meth:`SegalmanIwan.
    dissipation_at_torque`).
    """
    T = iw.F_S * _iwan_check_torques(t_min)
    exact = iw.dissipation_at_torque(T)
    disc = bed_dissipation(kappa, cap, bed_rotation_at_torque(kappa, cap, T))
    return float(np.max(np.abs(disc / exact - 1.0)))


def segalman_density(iw: SegalmanIwan, elements: int | None = None,
                     t_min: float = IWAN_T_MIN, rtol: float = IWAN_RTOL
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Discretise the Iwan density into Jenkins elements.

    The continuous part R φ^χ on [0, φ_max] is split into bins (:func:`_iwan_edges`), each
    one element whose stiffness ∫ρ dφ and capacity ∫φρ dφ are integrated exactly (so K_T
    and F_S are preserved exactly and the bed's backbone equals the continuous one at every
    bin edge); the lump S at φ_max (β > 0) is one more element.

    A bed of n elements has a piecewise-linear backbone, so its dissipation at a given torque
    amplitude has a relative error O(n⁻²) that no placement of bins removes. With
    ``elements=None`` the count is chosen so that the error is at most ``rtol`` for
    T*/F_S ∈ [t_min, 1 − 1e-9] — verified against the closed form
    (:func:`iwan_discretisation_error`), not predicted; about 360 (χ → −1) to 1250 (χ = 2)
    elements for the defaults. Below t_min F_S the smallest element has not slipped and the
    loss falls below the power law.

    Parameters
    ----------
    iw : SegalmanIwan
    elements : int, optional
        Fixed element count (≥ 3), unverified.
    t_min, rtol : float
        Accuracy target of the automatic count.

    Returns
    -------
    kappa, cap : (n,) arrays
        Stiffnesses (N m/rad) and capacities (N m).

    References
    ----------
    Segalman (2005), J. Appl. Mech. 72, 752–760, eqs. for the four-parameter density and
    its dissipation D ∝ T*^(3+χ); Iwan (1966), J. Appl. Mech. 33, 893–900.
    """

    def build(n: int):
        chi, R, pm = iw.chi, iw.R, iw.phi_max
        e = _iwan_edges(iw, n - 1, t_min)
        kappa = R * (e[1:] ** (chi + 1) - e[:-1] ** (chi + 1)) / (chi + 1)
        cap = R * (e[1:] ** (chi + 2) - e[:-1] ** (chi + 2)) / (chi + 2)
        if iw.S > 0.0:  # the lump at φ_max (β > 0)
            kappa, cap = np.append(kappa, iw.S), np.append(cap, iw.S * pm)
        return kappa, cap

    if elements is not None:
        if elements < 3:
            raise ValueError(f"elements: must be >= 3, got {elements}")
        return build(int(elements))
    n = 128
    for _ in range(8):
        kappa, cap = build(n)
        err = iwan_discretisation_error(iw, kappa, cap, t_min)
        if err <= rtol:
            return kappa, cap
        # the error falls as n^-2: aim 30 % below the target
        n = int(min(max(math.ceil(n * math.sqrt(err / (0.7 * rtol))), n + 16), 8192))
    raise ValueError(f"iwan: cannot discretise chi = {iw.chi:g} to {rtol:g} "
                     f"with {n} elements")  # pragma: no cover - χ is bounded by validation


def fit_iwan(rods: TwoRods, N: float, points: int = 40) -> tuple[SegalmanIwan, float]:
    """Fit Segalman's Iwan element to the distributed (rings) interface at normal force N.

    F_S and K_T are matched exactly (gross-slip torque (2/3) f N a and stuck stiffness
    k_t J_a). χ and β minimise, by nonlinear least squares (``scipy.optimize.least_squares``)

        Σ_k [(D_iwan(T_k) − D_dist(T_k)) / D_dist(T_max)]²
        + Σ_k [(T_iwan(δ_k) − T_dist(δ_k)) / F_S]²

    over torque amplitudes T_k ∈ [0.05, 0.97] F_S (the dissipation curve) and rotations
    δ_k ∈ [0, δ_dist(T_max)] (the stiffness / backbone curve), both with closed forms
    (:func:`distributed_dissipation`, :func:`distributed_backbone`; Segalman's closed
    forms :meth:`SegalmanIwan.dissipation_at_torque`, :meth:`SegalmanIwan.backbone`).
    χ is bounded to [−0.95, 2] and β to [1e-6, 1e3]; the best of three starting points
    is kept.

    Parameters
    ----------
    rods : TwoRods
        Friction f, contact radius a (m) and a finite tangential interface stiffness k_t
        (N/m³) of the rings; ``rods.interface`` is not used.
    N : float
        Normal force (N), > 0, at which the element is fitted (the mean axial force F0).
    points : int
        Number of samples T_k and of samples δ_k (one sum each).

    Returns
    -------
    iwan : SegalmanIwan
        F_S = (2/3) f N a (N m), K_T = k_t J_a = k_t π a⁴/2 (N m/rad), the fitted χ and β
        (dimensionless).
    rms : float
        Root-mean-square of the normalised residuals at the optimum (dimensionless).

    References
    ----------
    Segalman, D. J. (2005). A four-parameter Iwan model for lap-type joints. J. Appl. Mech.
    72, 752–760 (the element's backbone and dissipation). Johnson, K. L. (1985). Contact
    Mechanics, §7.3 (the rings: torsion of a flat circular contact under uniform pressure).
    """
    from scipy.optimize import least_squares

    FS = gross_slip_torque(rods.friction, N, rods.contact_radius)
    KT = rods.interface_stiffness * rods.contact_J
    Tk = np.linspace(0.05, 0.97, points) * FS
    Dd = distributed_dissipation(rods, N, Tk)
    Dref = float(Dd[-1])
    dk = np.linspace(0.0, float(distributed_torque_to_rotation(rods, N, Tk[-1])), points)
    Td = distributed_backbone(rods, N, dk)

    def resid(x):
        iw = SegalmanIwan(FS, KT, x[0], math.exp(x[1]))
        r1 = (iw.dissipation_at_torque(Tk) - Dd) / Dref
        r2 = (iw.backbone(dk) - Td) / FS
        return np.concatenate([r1, r2])

    best = None
    for x0 in ([-0.5, math.log(0.1)], [0.0, 0.0], [0.5, math.log(3.0)]):
        sol = least_squares(resid, x0, bounds=([-0.95, math.log(1e-6)], [2.0, math.log(1e3)]))
        if best is None or sol.cost < best.cost:
            best = sol
    iw = SegalmanIwan(FS, KT, float(best.x[0]), float(math.exp(best.x[1])))
    return iw, float(np.sqrt(2.0 * best.cost / best.fun.size))


def iwan_bed(rods: TwoRods, N_ref: float, elements: int | None = None,
             params: SegalmanIwan | None = None) -> tuple[Bed, SegalmanIwan]:
    """Iwan bed fitted at the mean normal force N_ref (or with given parameters).

    Capacities scale with N(t)/N_ref (Coulomb-like), stiffnesses do not. ``elements=None``
    chooses the count for 0.2 % accuracy of the dissipation (:func:`segalman_density`).
    """
    iw = params if params is not None else fit_iwan(rods, N_ref)[0]
    kappa, cap = segalman_density(iw, elements)
    return Bed("iwan", kappa, cap / N_ref), iw


# ---------------------------------------------------------------------------------------
# interface laws as types
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class InterfaceLaw:
    """One rods interface law: its bed of Jenkins elements and its lumped properties.

    Subclasses (:class:`Welded`, :class:`DistributedRings`, :class:`Coulomb`,
    :class:`Jenkins`, :class:`Iwan`) are small frozen dataclasses holding the law's own
    options; :data:`INTERFACE_LAWS` maps the names of ``TwoRods.interface`` to them and
    :func:`interface_law` builds one from a name, so that no solver compares names.

    Attributes
    ----------
    name : str
        The ``interface`` key (class attribute).
    is_frictional : bool
        Whether the interface can slip (False for ``welded`` only).
    rigid : bool
        Rigid (κ = ∞) single element: ``welded`` and ``coulomb``.
    needs_interface_stiffness : bool
        Whether the law uses the tangential stiffness k_t (N/m³).
    """

    name: ClassVar[str] = ""
    is_frictional: ClassVar[bool] = True
    rigid: ClassVar[bool] = False
    needs_interface_stiffness: ClassVar[bool] = True

    @classmethod
    def from_options(cls, *, rings: int = 100, iwan: SegalmanIwan | None = None
                     ) -> InterfaceLaw:
        """The law with the options that concern it (the others are ignored)."""
        return cls()

    def bed(self, rods: TwoRods, N_ref: float) -> Bed:
        """The law as a bed of Jenkins elements (capacities per unit normal force).

        Parameters
        ----------
        rods : TwoRods
            Contact radius a (m), friction f, tangential stiffness k_t (N/m³).
        N_ref : float
            Reference normal force (N); used by the Iwan element only.
        """
        raise NotImplementedError

    def stiffness(self, rods: TwoRods) -> float:
        """Stuck torsional stiffness k_t J_a (N m/rad), J_a = π a⁴/2; inf if rigid."""
        return math.inf if self.rigid else rods.interface_stiffness * rods.contact_J

    def gross_slip_torque(self, rods: TwoRods, N: float) -> float:
        """Torque capacity (2/3) f N a (N m) (:func:`gross_slip_torque`); inf if welded."""
        return gross_slip_torque(rods.friction, N, rods.contact_radius)

    def slip_inception_torque(self, rods: TwoRods, N: float) -> float:
        """Torque at which slip starts from the unloaded state (N m): the rim's
        τ(a) = f p, T_s = f p J_a/a, for the distributed laws; gross slip for lumped ones."""
        return rods.friction * rods.pressure(N) * rods.contact_J / rods.contact_radius


@dataclass(frozen=True)
class Welded(InterfaceLaw):
    """No slip: rigid, infinite capacity."""

    name: ClassVar[str] = "welded"
    is_frictional: ClassVar[bool] = False
    rigid: ClassVar[bool] = True
    needs_interface_stiffness: ClassVar[bool] = False

    def bed(self, rods: TwoRods, N_ref: float) -> Bed:
        return welded_bed(rods)

    def gross_slip_torque(self, rods: TwoRods, N: float) -> float:
        return math.inf

    def slip_inception_torque(self, rods: TwoRods, N: float) -> float:
        return math.inf


@dataclass(frozen=True)
class DistributedRings(InterfaceLaw):
    """Rings of equal width over the contact disc (module docstring, ``distributed``).

    Attributes
    ----------
    rings : int
        Number of rings, ≥ 1.
    """

    name: ClassVar[str] = "distributed"
    rings: int = 100

    @classmethod
    def from_options(cls, *, rings: int = 100, iwan: SegalmanIwan | None = None
                     ) -> DistributedRings:
        return cls(rings)

    def bed(self, rods: TwoRods, N_ref: float) -> Bed:
        return distributed_bed(rods, self.rings)


@dataclass(frozen=True)
class Coulomb(InterfaceLaw):
    """Rigid–plastic, capacity (2/3) f N a."""

    name: ClassVar[str] = "coulomb"
    rigid: ClassVar[bool] = True
    needs_interface_stiffness: ClassVar[bool] = False

    def bed(self, rods: TwoRods, N_ref: float) -> Bed:
        return coulomb_bed(rods)

    def slip_inception_torque(self, rods: TwoRods, N: float) -> float:
        return self.gross_slip_torque(rods, N)


@dataclass(frozen=True)
class Jenkins(InterfaceLaw):
    """One spring–slider: stiffness k_t J_a, capacity (2/3) f N a."""

    name: ClassVar[str] = "jenkins"

    def bed(self, rods: TwoRods, N_ref: float) -> Bed:
        return jenkins_bed(rods)

    def slip_inception_torque(self, rods: TwoRods, N: float) -> float:
        return self.gross_slip_torque(rods, N)


@dataclass(frozen=True)
class Iwan(InterfaceLaw):
    """Segalman's four-parameter Iwan element, discretised into Jenkins elements.

    Attributes
    ----------
    params : SegalmanIwan, optional
        The element; None: fitted to the rings at the reference normal force
        (:func:`fit_iwan`).
    elements : int, optional
        Fixed element count; None: chosen for the accuracy target (:func:`segalman_density`).
    """

    name: ClassVar[str] = "iwan"
    params: SegalmanIwan | None = None
    elements: int | None = None

    @classmethod
    def from_options(cls, *, rings: int = 100, iwan: SegalmanIwan | None = None) -> Iwan:
        return cls(iwan)

    def fitted(self, rods: TwoRods, N_ref: float) -> Iwan:
        """The same law with its parameters fixed (fitted at N_ref if not given)."""
        if self.params is not None:
            return self
        return Iwan(fit_iwan(rods, N_ref)[0], self.elements)

    def bed(self, rods: TwoRods, N_ref: float) -> Bed:
        return iwan_bed(rods, N_ref, self.elements, self.params)[0]


#: the interface laws by their ``TwoRods.interface`` name
INTERFACE_LAWS: dict[str, type[InterfaceLaw]] = {
    law.name: law for law in (Welded, DistributedRings, Coulomb, Jenkins, Iwan)}


def interface_law(name: str, *, rings: int = 100, iwan: SegalmanIwan | None = None
                  ) -> InterfaceLaw:
    """The :class:`InterfaceLaw` called ``name`` with its options.

    Parameters
    ----------
    name : str
        One of :data:`INTERFACE_LAWS` (``TwoRods.interface``).
    rings : int
        Ring count of ``distributed``.
    iwan : SegalmanIwan, optional
        Parameters of ``iwan`` (None: fitted when the bed is built).

    Returns
    -------
    InterfaceLaw
        The law's frozen object (``Welded``, ``DistributedRings``, ``Coulomb``, ``Jenkins``
        or ``Iwan``).

    Raises
    ------
    ValueError
        An unknown name.
    """
    try:
        law = INTERFACE_LAWS[name]
    except KeyError:
        raise ValueError(f"interface: must be one of {tuple(INTERFACE_LAWS)}, got "
                         f"{name!r}") from None
    return law.from_options(rings=rings, iwan=iwan)


def make_bed(rods: TwoRods, N_ref: float, rings: int = 100, iwan: SegalmanIwan | None = None
             ) -> Bed:
    """The bed of ``rods.interface`` (``rings`` rings for ``distributed``; an Iwan element
    is discretised to its accuracy target, independent of ``rings``):
    ``interface_law(rods.interface, rings=rings, iwan=iwan).bed(rods, N_ref)``.

    Every law is a bed of Jenkins elements, t_i ← clip(t_i + κ_i Δδ, −ĉ_i N, ĉ_i N),
    T = Σ t_i (module docstring): rings κ_i = k_t π(ρ_b⁴ − ρ_a⁴)/2,
    ĉ_i = (2f/3a²)(ρ_b³ − ρ_a³) (``distributed``); one element κ = k_t J_a,
    ĉ = (2/3) f a (``jenkins``); rigid–plastic with ĉ = (2/3) f a (``coulomb``); the
    discretised Segalman element with capacities divided by ``N_ref`` (``iwan``); rigid
    with infinite capacity (``welded``).

    Parameters
    ----------
    rods : TwoRods
        The interface law (``rods.interface``), friction f, contact radius a (m) and
        tangential interface stiffness k_t (N/m³).
    N_ref : float
        Reference normal force (N), > 0 for ``iwan``: the Iwan element is fitted there
        (when ``iwan`` is None) and its capacities scale with N(t)/N_ref. Not used by the
        other laws.
    rings : int
        Number of rings of equal width of ``distributed`` (≥ 1).
    iwan : SegalmanIwan, optional
        Parameters of the ``iwan`` law; None: fitted to the rings at ``N_ref``
        (:func:`fit_iwan`).

    Returns
    -------
    Bed
        ``kind`` (the interface name), ``kappa`` (n,) element stiffnesses (N m/rad; inf
        for a rigid law), ``cap_unit`` (n,) capacities per unit normal force (m), and
        ``rigid``; n = ``rings`` (``distributed``), 1 (``jenkins``, ``coulomb``,
        ``welded``) or the discretised element count (``iwan``, :func:`segalman_density`).

    Raises
    ------
    ValueError
        ``rings`` < 1 for ``distributed``.

    References
    ----------
    Iwan, W. D. (1966). A distributed-element model for hysteresis and its steady-state
    dynamic response. J. Appl. Mech. 33, 893–900. Segalman, D. J. (2005). A four-parameter
    Iwan model for lap-type joints. J. Appl. Mech. 72, 752–760. Johnson, K. L. (1985).
    Contact Mechanics, §7.3.
    """
    return interface_law(rods.interface, rings=rings, iwan=iwan).bed(rods, N_ref)
