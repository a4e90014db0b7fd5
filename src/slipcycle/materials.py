"""Elastic constants shared by every model (a leaf module: it imports nothing of slipcycle)."""

from __future__ import annotations

__all__ = ["dundurs_beta"]


def dundurs_beta(E1: float, nu1: float, E2: float | None = None, nu2: float | None = None
                 ) -> float:
    """Dundurs' β (plane strain) of body 1 on body 2; body 2 rigid when ``E2`` is None.

    β = [(1 − 2ν₁)/μ₁ − (1 − 2ν₂)/μ₂] / [2 ((1 − ν₁)/μ₁ + (1 − ν₂)/μ₂)]; β = 0 means the
    normal and tangential half-plane problems are uncoupled (the superposition of Ciavarella
    and Jäger is then exact). The one implementation: the half-space contact moduli and the
    FE reduction checks both call it.

    Parameters
    ----------
    E1 : float
        Young's modulus of body 1 (Pa).
    nu1 : float
        Poisson's ratio of body 1.
    E2 : float, optional
        Young's modulus of body 2 (Pa); None: a rigid body 2 (1/μ₂ = 0).
    nu2 : float, optional
        Poisson's ratio of body 2; required with ``E2``.

    Returns
    -------
    float
        β (dimensionless; |β| ≤ 1/2 for 0 ≤ ν ≤ 1/2); on a rigid flat
        β = (1 − 2ν₁)/(2(1 − ν₁)).

    References
    ----------
    Dundurs, J. (1969). Discussion of "Edge-bonded dissimilar orthogonal elastic wedges
    under normal and shear loading". J. Appl. Mech. 36, 650–652. Barber, J. R. (2018).
    Contact Mechanics, Springer, §1.4.
    """
    mu1 = E1 / (2 * (1 + nu1))
    a1, b1 = (1 - 2 * nu1) / mu1, (1 - nu1) / mu1
    if E2 is None:
        return a1 / (2 * b1)
    mu2 = E2 / (2 * (1 + nu2))
    return (a1 - (1 - 2 * nu2) / mu2) / (2 * (b1 + (1 - nu2) / mu2))
