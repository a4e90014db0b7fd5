"""Plane-strain linear-elastic assembly with scikit-fem.

Each body is discretised with vector Lagrange triangles (quadratic ``P2`` by default,
``P1`` optional). Degrees of freedom are numbered per body by scikit-fem; a global
numbering stacks the bodies one after another (block-diagonal stiffness). Nodes are the
points carrying a pair (u_x, u_y) of degrees of freedom: triangle vertices, plus edge
mid-points for P2.

Units: stiffness per unit thickness (N/m per m) times ``thickness`` (m), i.e. N/m;
forces N.

References
----------
Gustafsson, T. & McBain, G. D. (2020). scikit-fem: A Python package for finite element
assembly. Journal of Open Source Software 5(52), 2369.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import (
    Basis,
    BilinearForm,
    ElementTetP0,
    ElementTriP0,
    ElementTriP1,
    ElementTriP2,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshTet,
    asm,
)
from skfem.helpers import ddot, div, sym_grad
from skfem.models.elasticity import lame_parameters, linear_elasticity

from slipcycle.fe.geometry import Body

__all__ = ["BodyDofs", "ELEMENTS", "default_formulation", "body_basis", "stiffness",
           "node_dofs", "traction_load", "assemble"]

ELEMENTS = {"P1": ElementTriP1, "P2": ElementTriP2}


@dataclass
class BodyDofs:
    """Degrees of freedom of one body inside the global numbering.

    Attributes
    ----------
    body : Body
    basis : skfem.Basis
    offset : int
        Index of the body's first DOF in the global vector.
    ux, uy : numpy.ndarray of int, shape (n_nodes,)
        Global DOF indices of the x and y displacement at each node.
    xy : numpy.ndarray, shape (2, n_nodes)
        Node coordinates, m.
    """

    body: Body
    basis: Basis
    offset: int
    ux: np.ndarray
    uy: np.ndarray
    xy: np.ndarray

    @property
    def ndofs(self) -> int:
        return self.basis.N

    def boundary_nodes(self, tag: str) -> np.ndarray:
        """Local node indices (into ux, uy, xy) on the boundary facets named ``tag``."""
        facets = self.body.facets(tag)
        return self.nodes_of_facets(facets)

    def nodes_of_facets(self, facets: np.ndarray) -> np.ndarray:
        """Local node indices of the vertices (and, for P2, mid-points) of ``facets``."""
        facets = np.asarray(facets, dtype=np.int64)
        nodes = np.unique(self.body.mesh.facets[:, facets])
        if self.basis.facet_dofs.size:
            nodes = np.concatenate([nodes, self.body.mesh.nvertices + np.unique(facets)])
        return nodes


def body_basis(body: Body, element: str = "P2") -> Basis:
    """Vector basis of ``element`` ("P1" or "P2") on the body's mesh."""
    return Basis(body.mesh, ElementVector(ELEMENTS[element]()))


def node_dofs(basis: Basis) -> tuple[np.ndarray, np.ndarray]:
    """Local DOF indices (u_x, u_y) of every node: vertices first, then edge mid-points."""
    ux = [basis.nodal_dofs[0]]
    uy = [basis.nodal_dofs[1]]
    if basis.facet_dofs.size:
        ux.append(basis.facet_dofs[0])
        uy.append(basis.facet_dofs[1])
    return np.concatenate(ux), np.concatenate(uy)


def stiffness(basis: Basis, E: float, nu: float, thickness: float = 1.0,
              formulation: str = "displacement") -> sp.csr_matrix:
    """Linear-elastic stiffness matrix, N/m (symmetric positive semi-definite, unsupported).

    Plane strain on a triangle mesh (per ``thickness``), or 3-D on a tetrahedral mesh
    (``thickness`` must then be 1).

    ``formulation="displacement"`` integrates the full strain energy. ``"mixed"`` keeps
    the deviatoric part 2μ ε:ε and replaces the volumetric part λ (div u)² by its
    projection on element-wise constants, λ Dᵀ M₀⁻¹ D with D_ej = ∫_e div φ_j: the
    P2–P0 mixed element with the pressure condensed out, which satisfies the inf-sup
    condition and does not lock as ν → 0.5 (Boffi, Brezzi & Fortin 2013, §8.6).
    """
    lam, mu = lame_parameters(E, nu)  # 3-D Lamé constants = plane-strain constants
    if formulation == "displacement":
        return (thickness * asm(linear_elasticity(lam, mu), basis)).tocsr()
    if formulation != "mixed":
        raise ValueError(f"formulation must be 'displacement' or 'mixed', got {formulation!r}")

    @BilinearForm
    def deviatoric(u, v, w):
        return 2.0 * mu * ddot(sym_grad(u), sym_grad(v))

    @BilinearForm
    def divergence(u, q, w):
        return div(u) * q

    b0 = basis.with_element(ElementTetP0() if isinstance(basis.mesh, MeshTet)
                            else ElementTriP0())
    D = asm(divergence, basis, b0)
    if D.shape[0] != b0.N:
        D = D.T
    area = _element_measures(b0)  # P0 mass matrix is diag(area or volume)
    K = asm(deviatoric, basis) + lam * (D.T @ sp.diags(1.0 / area) @ D)
    return (thickness * K).tocsr()


@LinearForm
def _one(v, w):
    return v


def _element_measures(b0: Basis) -> np.ndarray:
    """Area (triangles) or volume (tetrahedra) of each element: ∫ of its P0 basis function."""
    return asm(_one, b0)


def default_formulation(element: str, nu: float) -> str:
    """``"mixed"`` for quadratic elements of nearly incompressible bodies (ν > 0.4)."""
    return "mixed" if element == "P2" and nu > 0.4 else "displacement"


def traction_load(basis: Basis, facets: np.ndarray, traction: tuple[float, float],
                  thickness: float = 1.0) -> np.ndarray:
    """Consistent nodal forces of a uniform traction (t_x, t_y), Pa, on ``facets``, N."""
    if len(facets) == 0:
        return np.zeros(basis.N)
    fb = FacetBasis(basis.mesh, basis.elem, facets=np.asarray(facets))
    tx, ty = traction

    @LinearForm
    def load(v, w):
        return tx * v[0] + ty * v[1]

    return thickness * asm(load, fb)


def assemble(bodies: list[Body], element: str = "P2", thickness: float = 1.0,
             formulation: str = "auto") -> tuple[sp.csr_matrix, list[BodyDofs]]:
    """Block-diagonal stiffness of all bodies and their DOF bookkeeping.

    ``formulation`` is "displacement", "mixed" or "auto" (:func:`default_formulation`
    per body); the choice is stored in ``body.info["formulation"]``.
    """
    blocks, dofs, offset = [], [], 0
    for body in bodies:
        basis = body_basis(body, element)
        form = default_formulation(element, body.nu) if formulation == "auto" else formulation
        body.info["formulation"] = form
        blocks.append(stiffness(basis, body.E, body.nu, thickness, form))
        ux, uy = node_dofs(basis)
        dofs.append(BodyDofs(body, basis, offset, ux + offset, uy + offset,
                             basis.doflocs[:, ux]))
        offset += basis.N
    return sp.block_diag(blocks, format="csr"), dofs
