"""Normal force–approach laws P(U) of the contact profiles of the case-file format.

A profile is described by its approach U(P) and incremental normal compliance
C(P) = dU/dP, both as functions of the normal load P (N, or N/m for plane problems), and,
where defined, the contact size a(P) (radius, or half-width in 2-D). Everything the slider
bed needs follows from these: the slider density k(s) = d²P/dU² and, for axisymmetric
profiles, the radius at which a slider of level s sits, a(P(s)) (method of dimensionality
reduction, Popov & Heß 2015).

A profile may instead describe itself exactly by a finite set of sliders
(:meth:`Profile.concentrated`): the flat punch (one level) and tabulated P(U) (one slider per
change of slope).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

__all__ = ["Profile", "PowerLaw", "sphere", "Cylinder2D", "FlatPunch", "RoughExponential",
           "Tabulated"]


class Profile(Protocol):
    """What a contact profile must provide (all functions vectorised over P).

    Attributes
    ----------
    plane : bool
        2-D problem: loads are per unit length (N/m) and dissipation in J/m.
    axisymmetric : bool
        Tractions by Abel transform are available (Popov & Heß 2015).
    """

    plane: bool          # 2-D problem: loads per unit length
    axisymmetric: bool   # tractions by Abel transform are available

    def approach(self, P: np.ndarray) -> np.ndarray:
        """Rigid-body approach U(P) in m."""

    def compliance(self, P: np.ndarray) -> np.ndarray:
        """Incremental normal compliance C(P) = dU/dP in m/N."""

    def contact_size(self, P: np.ndarray) -> np.ndarray | None:
        """Contact radius (3-D) or half-width (2-D) a(P) in m; None if undefined."""

    def concentrated(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Exact slider set (levels in m, normal stiffnesses in N/m), or None."""


@dataclass(frozen=True)
class PowerLaw:
    """Axisymmetric power-law profile z = c rⁿ pressed by E* (3-D).

    By the method of dimensionality reduction the equivalent 1-D profile is
    g(x) = κ_n c |x|ⁿ with κ_n = √π Γ(n/2 + 1)/Γ(n/2 + 1/2), so that
    a(U) = (U/(κ_n c))^{1/n} and P(U) = 2E* U a n/(n + 1)  (Popov & Heß 2015, §3).
    The sphere of radius R is n = 2, c = 1/(2R): a² = RU, P = (4/3)E* R^{1/2} U^{3/2}.

    Attributes
    ----------
    c : float
        Profile coefficient, m^(1−n).
    n : float
        Exponent (> 0; 2 for the sphere).
    contact_modulus : float
        E* in Pa.
    plane, axisymmetric : bool
        False, True (see :class:`Profile`).
    """

    c: float
    n: float
    contact_modulus: float
    plane: bool = False
    axisymmetric: bool = True

    @property
    def kappa(self) -> float:
        if self.n == 2.0:  # the sphere (Hertz): sqrt(pi) G(2)/G(3/2) = 2, without SciPy
            return 2.0
        from scipy.special import gamma  # on use: SciPy adds 0.2 s to a start-up

        return math.sqrt(math.pi) * gamma(self.n / 2 + 1) / gamma(self.n / 2 + 0.5)

    def _a_from_P(self, P):
        # P = 2E* κ c a^{n+1} n/(n+1)
        P = np.maximum(np.asarray(P, float), 0.0)
        coef = 2 * self.contact_modulus * self.kappa * self.c * self.n / (self.n + 1)
        return (P / coef) ** (1.0 / (self.n + 1))

    def contact_size(self, P):
        return self._a_from_P(P)

    def edge_slope(self, P):
        """Slope dz/dr = n c a^{n−1} of the profile at the contact edge under load ``P``
        (the half-space theory assumes it small; a/R for the sphere)."""
        return self.n * self.c * self._a_from_P(P) ** (self.n - 1)

    def approach(self, P):
        return self.kappa * self.c * self._a_from_P(P) ** self.n

    def compliance(self, P):
        # dP/dU = 2E* a
        with np.errstate(divide="ignore"):
            return 1.0 / (2 * self.contact_modulus * self._a_from_P(P))

    def concentrated(self):
        return None


def sphere(radius: float, contact_modulus: float) -> PowerLaw:
    """Hertzian sphere: z = r²/(2R) (Hertz 1882; Johnson 1985, §4.2).

    Parameters
    ----------
    radius : float
        R in m.
    contact_modulus : float
        E* in Pa.

    Returns
    -------
    PowerLaw
        n = 2, c = 1/(2R).
    """
    return PowerLaw(c=1.0 / (2.0 * radius), n=2.0, contact_modulus=contact_modulus)


@dataclass(frozen=True)
class Cylinder2D:
    """Plane Hertzian contact of a cylinder of radius R, loads per unit length.

    Half-width a = (4PR/(πE*))^{1/2}. Plane displacements need a reference point; with a
    point at depth d below the surface on the axis of symmetry the approach is
    U = (P/(πE*)) [ln(4d²/a²) − 1] (Johnson 1985, eq. 5.41 form), so the incremental
    compliance C = (ln(4d²/a²) − 2)/(πE*). The dissipation does not depend on d (Barber 2012,
    §4.5); d defaults to R. Valid while C > 0, i.e. a < 2d/e.

    Attributes
    ----------
    radius : float
        R in m.
    contact_modulus : float
        E* in Pa.
    reference_depth : float or None
        d in m (None: d = R).
    plane, axisymmetric : bool
        True, False (see :class:`Profile`).
    """

    radius: float
    contact_modulus: float
    reference_depth: float | None = None
    plane: bool = True
    axisymmetric: bool = False

    @property
    def d(self) -> float:
        return self.reference_depth if self.reference_depth is not None else self.radius

    def contact_size(self, P):
        P = np.maximum(np.asarray(P, float), 0.0)
        return np.sqrt(4 * P * self.radius / (math.pi * self.contact_modulus))

    def edge_slope(self, P):
        """Slope a/R of the profile at the contact edge under load ``P`` (N/m)."""
        return self.contact_size(P) / self.radius

    def approach(self, P):
        P = np.maximum(np.asarray(P, float), 0.0)
        a = self.contact_size(P)
        with np.errstate(divide="ignore", invalid="ignore"):
            U = P / (math.pi * self.contact_modulus) * (np.log(4 * self.d**2 / a**2) - 1)
        return np.where(P > 0, U, 0.0)

    def compliance(self, P):
        a = self.contact_size(P)
        with np.errstate(divide="ignore"):
            return (np.log(4 * self.d**2 / a**2) - 2) / (math.pi * self.contact_modulus)

    def max_load(self) -> float:
        """Largest P with positive compliance (a = 2d/e)."""
        a = 2 * self.d / math.e
        return math.pi * self.contact_modulus * a**2 / (4 * self.radius)

    def concentrated(self):
        return None


@dataclass(frozen=True)
class FlatPunch:
    """Rigid flat circular punch of radius a (3-D): P = 2E* a U (Boussinesq).

    Attributes
    ----------
    radius : float
        a in m.
    contact_modulus : float
        E* in Pa.
    plane, axisymmetric : bool
        False, True (see :class:`Profile`).
    """

    radius: float
    contact_modulus: float
    plane: bool = False
    axisymmetric: bool = True

    def contact_size(self, P):
        return np.full_like(np.asarray(P, float), self.radius)

    def approach(self, P):
        return np.asarray(P, float) / (2 * self.contact_modulus * self.radius)

    def compliance(self, P):
        return np.full_like(np.asarray(P, float), 1 / (2 * self.contact_modulus * self.radius))

    def concentrated(self):
        return np.array([0.0]), np.array([2 * self.contact_modulus * self.radius])


@dataclass(frozen=True)
class RoughExponential:
    """Nominally flat rough contact with dP/dU = P/(γσ) (Barber 2012, eq. 10; Akarapu et al.).

    P = P_ref exp(U/γσ); the approach is measured from the level where P = P_ref (1 N by
    default; the choice does not affect anything physical).

    Attributes
    ----------
    gamma_sigma : float
        γσ in m (the rms roughness σ times γ).
    reference_load : float
        P_ref in N.
    plane, axisymmetric : bool
        False, False (see :class:`Profile`).
    """

    gamma_sigma: float
    reference_load: float = 1.0
    plane: bool = False
    axisymmetric: bool = False

    def contact_size(self, P):
        return None

    def approach(self, P):
        with np.errstate(divide="ignore"):
            return self.gamma_sigma * np.log(np.asarray(P, float) / self.reference_load)

    def compliance(self, P):
        with np.errstate(divide="ignore"):
            return self.gamma_sigma / np.asarray(P, float)

    def concentrated(self):
        return None


@dataclass(frozen=True)
class Tabulated:
    """Measured or computed P(U) pairs, linear between points (and beyond the last one).

    The slider set is exact: one slider at each tabulated approach where the slope
    increases, with stiffness equal to the increase. P(U) must be convex (non-decreasing
    slope), start at P = 0, and increase.

    Attributes
    ----------
    U : (K,) array
        Approaches in m, increasing.
    P : (K,) array
        Normal loads in N (N/m in 2-D), from 0, increasing, convex in U.
    plane, axisymmetric : bool
        Whether the table is per unit length; False.
    """

    U: np.ndarray
    P: np.ndarray
    plane: bool = False
    axisymmetric: bool = False

    def __post_init__(self):
        U, P = np.asarray(self.U, float), np.asarray(self.P, float)
        object.__setattr__(self, "U", U)
        object.__setattr__(self, "P", P)

    @property
    def slopes(self) -> np.ndarray:
        return np.diff(self.P) / np.diff(self.U)

    def contact_size(self, P):
        return None

    def approach(self, P):
        P = np.asarray(P, float)
        U_lin = self.U[-1] + (P - self.P[-1]) / self.slopes[-1]
        return np.where(P <= self.P[-1], np.interp(P, self.P, self.U), U_lin)

    def compliance(self, P):
        idx = np.clip(np.searchsorted(self.P, np.asarray(P, float), side="right") - 1, 0,
                      self.slopes.size - 1)
        return 1.0 / self.slopes[idx]

    def concentrated(self):
        jumps = np.diff(np.concatenate([[0.0], self.slopes]))
        keep = jumps > 0
        return self.U[:-1][keep], jumps[keep]


#: largest profile slope at the contact edge without a warning: the half-space theory
#: (Hertz; Johnson 1985, §4.2) assumes a contact small against the radius, a/R ≪ 1
SLOPE_WARNING = 0.1


def slope_warning(profile, P_max: float) -> str | None:
    """A warning when the contact at the largest load ``P_max`` is too large for the
    half-space theory (slope at its edge above :data:`SLOPE_WARNING`), else None."""
    slope_at = getattr(profile, "edge_slope", None)
    if slope_at is None or not P_max > 0:
        return None
    slope = float(slope_at(P_max))
    if not slope > SLOPE_WARNING:
        return None
    a = float(profile.contact_size(P_max))
    return (f"the contact size {a:.3g} m at the largest load gives a profile slope of "
            f"{slope:.2g} at its edge (a/R for a sphere or cylinder): the half-space theory "
            f"assumes it small (below {SLOPE_WARNING:g}); check the radius, the moduli "
            "(Pa) and the loads")
