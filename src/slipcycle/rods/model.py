"""Two coaxial elastic rods pressed end to end, twisted at one end (docs/rods.md).

Rod 1 occupies x ∈ [−L1, 0] and is clamped at x = −L1; rod 2 occupies [0, L2] and is
driven at x = L2 by a prescribed rotation Θ(t) = Θ_a sin Ωt and an axial compressive force
F(t) = F0 + F_a sin(Ωt + ψ). The rods touch at x = 0 over a disc of radius
a = min(r1, r2). Torsion obeys ρ_j J_j φ_tt = G_j J_j φ_xx and the axial motion
ρ_j A_j u_tt = E_j A_j u_xx.

Sign conventions used throughout the package:

* internal torque T_j(x) = G_j J_j ∂φ_j/∂x; the interface torque is T = T_1(0) = T_2(0);
* the interface relative rotation is δ = φ_2(0) − φ_1(0); a stuck elastic interface gives
  T = k δ with k > 0;
* the normal force N ≥ 0 is compressive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from slipcycle.errors import InputError

__all__ = ["Rod", "TwoRods", "Excitation", "INTERFACES", "gross_slip_torque"]

INTERFACES = ("welded", "distributed", "coulomb", "jenkins", "iwan")


def _check(name: str, value, *, gt: float | None = None, ge: float | None = None,
           le: float | None = None, lt: float | None = None) -> None:
    """Refuse (:class:`~slipcycle.errors.InputError` keyed by the field ``name``) a value
    that is not a finite real number within the bounds."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(name, f"must be a real number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise InputError(name, f"must be finite, got {value}")
    if gt is not None and not value > gt:
        raise InputError(name, f"must be > {gt:g}, got {value:g}")
    if ge is not None and not value >= ge:
        raise InputError(name, f"must be >= {ge:g}, got {value:g}")
    if le is not None and not value <= le:
        raise InputError(name, f"must be <= {le:g}, got {value:g}")
    if lt is not None and not value < lt:
        raise InputError(name, f"must be < {lt:g}, got {value:g}")


def gross_slip_torque(friction: float, normal_force: float, contact_radius: float) -> float:
    """Torque that makes the whole contact disc slip under uniform pressure (N m).

    With the pressure p = N/(π a²) uniform over the disc 0 ≤ ρ ≤ a and the shear at its
    Coulomb limit f p everywhere, T_g = ∫ f p ρ 2πρ dρ = (2/3) π f p a³ = (2/3) f N a.
    This is the capacity of every lumped interface law (``jenkins``, ``coulomb``), the sum
    of the ring capacities of ``distributed``, the F_S of the fitted Iwan element, and the
    scale of the gross-slip amplitude Θ_g; the one place it is written.

    Parameters
    ----------
    friction : float
        Coulomb coefficient f ≥ 0 (dimensionless).
    normal_force : float
        Compressive normal force N (N); 1.0 gives the capacity per unit normal force (m).
    contact_radius : float
        Radius a of the contact disc (m).

    Returns
    -------
    float
        T_g = (2/3) f N a (N m).

    References
    ----------
    Johnson, K. L. (1985). Contact Mechanics, Cambridge University Press, §7.3 (torsion of
    a flat circular contact under uniform pressure).
    """
    return 2.0 / 3.0 * friction * normal_force * contact_radius


@dataclass(frozen=True)
class Rod:
    """One uniform circular elastic rod.

    Parameters
    ----------
    length : float
        L (m).
    radius : float
        r (m).
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio, −1 < ν ≤ 0.5.
    density : float
        ρ (kg/m³).

    Raises
    ------
    slipcycle.errors.InputError
        Keyed by the field name: a length, radius, modulus or density that is not a finite
        positive number, or ν outside (−1, 0.5].
    """

    length: float
    radius: float
    E: float
    nu: float
    density: float

    def __post_init__(self):
        _check("length", self.length, gt=0.0)
        _check("radius", self.radius, gt=0.0)
        _check("E", self.E, gt=0.0)
        _check("nu", self.nu, gt=-1.0, le=0.5)
        _check("density", self.density, gt=0.0)

    @property
    def G(self) -> float:
        """Shear modulus E / 2(1 + ν) (Pa)."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def J(self) -> float:
        """Polar second moment of area π r⁴ / 2 (m⁴)."""
        return 0.5 * math.pi * self.radius**4

    @property
    def area(self) -> float:
        """Cross-section π r² (m²)."""
        return math.pi * self.radius**2

    @property
    def c_torsion(self) -> float:
        """Torsional (shear) wave speed √(G/ρ) (m/s)."""
        return math.sqrt(self.G / self.density)

    @property
    def c_axial(self) -> float:
        """Axial (bar) wave speed √(E/ρ) (m/s)."""
        return math.sqrt(self.E / self.density)

    @property
    def impedance_torsion(self) -> float:
        """Torsional impedance Z = J √(ρ G) (N m s/rad): T = Z × angular velocity of a wave."""
        return self.J * math.sqrt(self.density * self.G)

    @property
    def torsional_stiffness(self) -> float:
        """Static torsional stiffness G J / L (N m/rad)."""
        return self.G * self.J / self.length

    @property
    def polar_inertia(self) -> float:
        """Mass moment of inertia about the axis, ρ J L (kg m²)."""
        return self.density * self.J * self.length


@dataclass(frozen=True)
class TwoRods:
    """The two-rod system with its interface.

    Parameters
    ----------
    rod1, rod2 : Rod
        Clamped rod (x ∈ [−L1, 0]) and driven rod (x ∈ [0, L2]).
    friction : float
        Coulomb coefficient f ≥ 0.
    interface : str
        One of :data:`INTERFACES`.
    interface_stiffness : float
        Tangential interface stiffness per unit area k_t (N/m³); not used by ``welded`` and
        ``coulomb``.
    damping_ratio : float
        Modal damping ratio ζ of every torsional mode (and the loss factor 2ζ of the axial
        frequency response), 0 ≤ ζ ≤ 1.

    Raises
    ------
    slipcycle.errors.InputError
        Keyed by the field name: rods that are not :class:`Rod`, f < 0 or not finite, an
        unknown interface, a missing or non-positive ``interface_stiffness`` for the
        ``distributed``, ``jenkins`` and ``iwan`` interfaces, ζ outside [0, 1].
    """

    rod1: Rod
    rod2: Rod
    friction: float
    interface: str = "distributed"
    interface_stiffness: float = math.inf
    damping_ratio: float = 0.0

    def __post_init__(self):
        for name in ("rod1", "rod2"):
            if not isinstance(getattr(self, name), Rod):
                raise InputError(name, f"must be a Rod, got {type(getattr(self, name)).__name__}")
        _check("friction", self.friction, ge=0.0)
        if self.interface not in INTERFACES:
            raise InputError("interface", f"must be one of {INTERFACES}, got "
                                          f"{self.interface!r}")
        if self.interface in ("distributed", "jenkins", "iwan"):
            if self.interface_stiffness == math.inf:
                raise InputError("interface_stiffness", "required for interface = "
                                                        f"{self.interface!r} (k_t, N/m³)")
            _check("interface_stiffness", self.interface_stiffness, gt=0.0)
        _check("damping_ratio", self.damping_ratio, ge=0.0, le=1.0)

    @property
    def rods(self) -> tuple[Rod, Rod]:
        return (self.rod1, self.rod2)

    @property
    def contact_radius(self) -> float:
        """a = min(r1, r2) (m)."""
        return min(self.rod1.radius, self.rod2.radius)

    @property
    def contact_J(self) -> float:
        """Polar moment of the contact disc π a⁴/2 (m⁴)."""
        return 0.5 * math.pi * self.contact_radius**4

    @property
    def rods_compliance(self) -> float:
        """Static torsional compliance of the rods in series, Σ L_j/(G_j J_j) (rad/(N m))."""
        return sum(r.length / (r.G * r.J) for r in self.rods)

    @property
    def interface_torsional_stiffness(self) -> float:
        """Stuck interface stiffness k_t J_a = k_t π a⁴/2 (N m/rad); inf for rigid interfaces."""
        if self.interface in ("welded", "coulomb"):
            return math.inf
        return self.interface_stiffness * self.contact_J

    def pressure(self, N: float) -> float:
        """Uniform contact pressure p = N/(π a²) (Pa)."""
        return N / (math.pi * self.contact_radius**2)

    def slip_inception_torque(self, N: float) -> float:
        """Torque at which the rim starts to slip, τ(a) = f p: T = f p J_a / a (N m).

        For the lumped ``coulomb`` and ``jenkins`` interfaces slip starts at gross slip.
        """
        if self.interface in ("coulomb", "jenkins"):
            return self.gross_slip_torque(N)
        if self.interface == "welded":
            return math.inf
        return self.friction * self.pressure(N) * self.contact_J / self.contact_radius

    def gross_slip_torque(self, N: float) -> float:
        """Torque capacity of the whole disc, (2/3) π f p a³ = (2/3) f N a (N m)."""
        if self.interface == "welded":
            return math.inf
        return gross_slip_torque(self.friction, N, self.contact_radius)

    def with_(self, **changes) -> TwoRods:
        """A copy with some fields replaced."""
        from dataclasses import replace

        return replace(self, **changes)


@dataclass(frozen=True)
class Excitation:
    """Boundary excitation at x = L2.

    Parameters
    ----------
    rotation_amplitude : float
        Θ_a (rad) of Θ(t) = Θ_a sin Ωt.
    frequency : float
        Ω (rad/s), > 0.
    axial_force : float
        Mean compressive force F0 (N), ≥ 0.
    axial_amplitude : float
        F_a (N) of F(t) = F0 + F_a sin(Ωt + ψ).
    axial_phase : float
        ψ (rad).

    Raises
    ------
    slipcycle.errors.InputError
        Keyed by the field name: a negative or non-finite amplitude, a tensile mean axial
        force (F0 < 0; the interface cannot carry tension), Ω ≤ 0.
    """

    rotation_amplitude: float
    frequency: float
    axial_force: float
    axial_amplitude: float = 0.0
    axial_phase: float = 0.0

    def __post_init__(self):
        _check("rotation_amplitude", self.rotation_amplitude, ge=0.0)
        _check("frequency", self.frequency, gt=0.0)
        _check("axial_force", self.axial_force, ge=0.0)
        _check("axial_amplitude", self.axial_amplitude, ge=0.0)
        _check("axial_phase", self.axial_phase)

    @property
    def period(self) -> float:
        return 2.0 * math.pi / self.frequency

    def with_(self, **changes) -> Excitation:
        from dataclasses import replace

        return replace(self, **changes)

    def rotation(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Θ, Θ̇, Θ̈ at times ``t`` (rad, rad/s, rad/s²)."""
        w = self.frequency
        s, c = np.sin(w * t), np.cos(w * t)
        a = self.rotation_amplitude
        return a * s, a * w * c, -a * w * w * s
