"""Contact moduli of two elastic bodies and the tangential/normal compliance ratio λ_c."""

from __future__ import annotations

from dataclasses import dataclass

from slipcycle.materials import dundurs_beta

__all__ = ["ContactElasticity", "dundurs_beta"]


@dataclass(frozen=True)
class ContactElasticity:
    """Elastic constants of a contact pair.

    Attributes
    ----------
    contact_modulus : float
        E* = [(1 − ν1²)/E1 + (1 − ν2²)/E2]⁻¹ in Pa.
    compliance_ratio : float
        λ_c = (dV/dQ)/(dU/dP), the ratio of tangential to normal incremental compliance:
        1 for plane problems of similar materials; (2 − ν)/(2(1 − ν)) in 3-D (Barber 2012,
        eq. 9), i.e. E*/(4G*) with G* = [(2 − ν1)/G1 + (2 − ν2)/G2]⁻¹ (Mindlin 1949).
    dundurs_beta : float
        Dundurs' β (0 when the superposition of Ciavarella and Jäger is exact).
    """

    contact_modulus: float
    compliance_ratio: float
    dundurs_beta: float = 0.0

    @classmethod
    def from_materials(cls, E: tuple[float, float], nu: tuple[float, float], *,
                       plane: bool, compliance_ratio: float | None = None
                       ) -> ContactElasticity:
        """From Young's moduli E (Pa) and Poisson's ratios ν of both bodies."""
        (E1, E2), (nu1, nu2) = E, nu
        e_star = 1.0 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
        if compliance_ratio is None:
            if plane:
                compliance_ratio = 1.0
            else:
                G1, G2 = E1 / (2 * (1 + nu1)), E2 / (2 * (1 + nu2))
                g_star = 1.0 / ((2 - nu1) / G1 + (2 - nu2) / G2)
                compliance_ratio = e_star / (4 * g_star)
        return cls(e_star, float(compliance_ratio), dundurs_beta(E1, nu1, E2, nu2))
