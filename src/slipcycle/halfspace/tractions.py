"""Traction, slip and dissipation-density distributions of axisymmetric contacts.

In the method of dimensionality reduction (Popov & Heß 2015, ch. 3 and 7) the sliders of
an axisymmetric contact sit on a line at x = a(P(s)) (two per level, at ±x), so slider i
spreads over the cell [a_i, a_{i+1}] with line load f_i/(2Δx_i). The 3-D surface fields
follow by Abel-type transforms of the 1-D line loads q₁(x) and slips z₁(x):

    τ(r) = −(1/π) ∫_r^a q₁′(x) / √(x² − r²) dx          (tractions; likewise p from n₁)
    s(r) =  (2/π) ∫_0^r z₁(x)  / √(r² − x²) dx          (local slip of the surfaces)

and the local dissipation density over a cycle is W(r) = ∮ τ(r) ds(r).

The 1-D fields are taken piecewise linear between cell centres, constant over the first
and last half-cells, and dropping to zero at the outer edge of the bed (which gives the
square-root singularity of the flat punch). The transforms are then exact integrals of
those interpolants, assembled once as matrices so that whole histories transform by a
matrix product.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipcycle.halfspace.bed import SliderBed

__all__ = ["AbelOperators", "abel_operators", "dissipation_density"]


@dataclass(frozen=True)
class AbelOperators:
    """Linear maps from slider quantities (n,) to radial distributions (m,).

    Attributes
    ----------
    radius : (m,) array
        Radii (m) at which distributions are evaluated.
    traction : (m, n) array
        Maps slider forces (N) to surface traction (Pa); applies to normal and tangential.
    slip : (m, n) array
        Maps slider base slips (m) to local surface slip (m).
    """

    radius: np.ndarray
    traction: np.ndarray
    slip: np.ndarray


def abel_operators(bed: SliderBed, n_radii: int = 200) -> AbelOperators:
    """Assemble the traction and slip transforms for an axisymmetric bed."""
    if bed.edge_size is None:
        raise ValueError("tractions need a profile with a contact radius (axisymmetric)")
    edges = np.asarray(bed.edge_size, float)
    width = np.diff(edges)
    n = bed.size
    centre = 0.5 * (edges[:-1] + edges[1:])
    # Nodes: cell centres plus the outer edge X carrying the last cell's value.
    X = edges[-1]
    nodes = np.concatenate([centre, [X]])
    h = np.diff(nodes)
    h = np.where(h > 0, h, np.inf)  # coincident nodes (zero-width cells) carry no gradient
    radius = X * (np.arange(n_radii) + 0.5) / n_radii
    r = radius[:, None]

    # per-unit-length density: value at node j is force_j / (2 width_j)
    scale = np.where(width > 0, 1.0 / (2.0 * np.where(width > 0, width, 1.0)), 0.0)

    # traction: -(1/π) Σ_j (q_{j+1} − q_j)/h_j ∫ dx/√(x²−r²) + q_last/(π √(X²−r²))
    F = np.arccosh(np.maximum(nodes[None, :], r) / r)          # (m, n+1)
    I2 = np.diff(F, axis=1) / h[None, :]                         # (m, n)
    T = np.zeros((n_radii, n + 1))
    T[:, 1:] += I2
    T[:, :-1] -= I2
    T *= -1.0 / np.pi
    T[:, -1] += 1.0 / (np.pi * np.sqrt(np.maximum(X**2 - radius**2, 1e-300)))
    T[:, n - 1] += T[:, n]       # node n carries slider n-1's value
    traction = T[:, :n] * scale[None, :]

    # slip: (2/π) ∫_0^r z(x)/√(r²−x²) dx, z linear on segments, constant on [0, x_0]
    xc = np.minimum(nodes[None, :], r)
    G0 = np.arcsin(xc / r)
    G1 = -np.sqrt(r**2 - xc**2)
    I0, I1 = np.diff(G0, axis=1), np.diff(G1, axis=1)            # (m, n)
    S = np.zeros((n_radii, n + 1))
    with np.errstate(invalid="ignore"):
        S[:, :-1] += np.where(np.isfinite(h), (nodes[None, 1:] * I0 - I1) / h, I0)
        S[:, 1:] += np.where(np.isfinite(h), (I1 - nodes[None, :-1] * I0) / h, 0.0)
    S[:, 0] += G0[:, 0]                                          # constant part on [0, x_0]
    S *= 2.0 / np.pi
    S[:, n - 1] += S[:, n]
    return AbelOperators(radius, traction, S[:, :n])


def dissipation_density(ops: AbelOperators, forces: np.ndarray, slips: np.ndarray
                        ) -> np.ndarray:
    """W(r) = ∮ τ ds over a closed cycle (J/m²).

    Parameters
    ----------
    forces, slips : (K, n) arrays
        Slider tangential forces and base slips at the samples of one closed cycle.
    """
    tau = forces @ ops.traction.T       # (K, m)
    s = slips @ ops.slip.T
    return np.sum(0.5 * (tau[1:] + tau[:-1]) * np.diff(s, axis=0), axis=0)
