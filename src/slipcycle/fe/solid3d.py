"""Three-dimensional elastic bodies on a rigid flat, reduced to their contact nodes.

A tetrahedral scikit-fem model of body 1 (quadratic ``P2`` by default; P2–P0 mixed near
ν = 0.5, :func:`slipcycle.fe.assembly.stiffness`) rests on a rigid flat z = z₀ with the
initial gap g(x, y) ≥ 0 at each candidate contact node. Its top face is moved rigidly by
the load cases. Every degree of freedom that is neither a contact dof nor prescribed is
condensed out with one sparse factorisation (:func:`slipcycle.condensation.
schur_complement`, Guyan 1965), leaving the reduced stiffness of the N contact nodes in
their local frames (t1 = x, t2 = y, and the flat's normal n = z into body 1):

    q = q^w + A v + Bᵀ w,    p = p^w + B v + C w,

with v the (t1, t2) slip of each node (node-major: node 0 t1, node 0 t2, node 1 t1, …),
w = g + u_z the separation, q the friction force of the flat on the body and p the normal
force, compressive positive (the convention of the 2-D reduction, docs/fe.md, with a second
tangential direction). q^w, p^w are the reactions with every node held at v = w = 0, per
unit of each load case:

=============== ====== ===================================================================
case            unit   what
=============== ====== ===================================================================
``normal``      m      top face moved 1 m towards the flat (−z)
``tangential``  m      top face moved 1 m along +x (t1)
``tangential2`` m      top face moved 1 m along +y (t2)
``gap``         1      the initial gap itself: −[Bᵀ g; C g]
=============== ====== ===================================================================

The result is a :class:`slipcycle.io.matrices.ReducedStiffness` with two tangential
directions, the same object the readers of FE-code exports return.

References
----------
Guyan, R. J. (1965). Reduction of stiffness and mass matrices. AIAA J. 3(2), 380.
Johnson, K. L. (1985). *Contact Mechanics*, Cambridge University Press, §4.2 (Hertz), §7.2
(Cattaneo–Mindlin).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from skfem import MeshTet

from slipcycle.errors import InputError
from slipcycle.fe.contact3d import ELEMENTS_3D, Case3D, mesh_nodes, node_dofs_3d, reduce_contact_3d
from slipcycle.fe.geometry import check_length, check_number, depth_grid, interface_grid
from slipcycle.io.matrices import ReducedStiffness

__all__ = ["Block3D", "block_mesh_3d", "node_dofs_3d", "reduce_on_rigid_flat",
           "block_on_rigid_3d"]

#: the load cases of a body on a rigid flat (name, unit, top-face translation)
TOP_CASES = (("normal", "m", (0.0, 0.0, -1.0)), ("tangential", "m", (1.0, 0.0, 0.0)),
             ("tangential2", "m", (0.0, 1.0, 0.0)))


@dataclass(frozen=True)
class Block3D:
    """A rectangular block of body 1 on a rigid flat, with an optional initial gap.

    Parameters
    ----------
    width_x, width_y, height : float
        Block size (m); the block spans x ∈ [−width_x/2, width_x/2], likewise y, and
        z ∈ [0, height]; the flat is z = 0.
    E, nu : float
        Young's modulus (Pa) and Poisson's ratio of the block.
    contact_x, contact_y : float
        Size (m) of the candidate contact zone |x| ≤ contact_x/2, |y| ≤ contact_y/2,
        meshed uniformly with ``elements`` elements across contact_x.
    elements : int
        Elements across the contact zone along x (the element size h = contact_x/elements
        is used along y too).
    grading : float
        Geometric growth of element size away from the contact zone and with height.
    radius : float or None
        Radius R (m) of a parabolic initial gap g = (x² + y²)/(2R) (the Hertz geometry of a
        sphere of radius R on a flat, Johnson 1985 §4.2); None: a flat punch, g = 0.
    element : str
        ``"P2"`` (quadratic tetrahedra) or ``"P1"``.
    formulation : str
        ``"displacement"``, ``"mixed"`` or ``"auto"`` (mixed for P2 with ν > 0.4).
    """

    width_x: float
    width_y: float
    height: float
    E: float
    nu: float
    contact_x: float
    contact_y: float
    elements: int = 8
    grading: float = 1.4
    radius: float | None = None
    element: str = "P2"
    formulation: str = "auto"

    def __post_init__(self):
        for name in ("width_x", "width_y", "height"):
            check_length(name, getattr(self, name))
        for name in ("E", "contact_x", "contact_y"):
            check_number(name, getattr(self, name), gt=0.0)
        check_number("nu", self.nu, ge=0.0, lt=0.5)
        check_number("contact_x", self.contact_x, le=self.width_x)
        check_number("contact_y", self.contact_y, le=self.width_y)
        check_number("elements", self.elements, ge=1)
        check_number("grading", self.grading, ge=1.0, le=3.0)
        if self.radius is not None:
            check_length("radius", self.radius)
        if self.element not in ELEMENTS_3D:
            raise InputError("element", f"must be one of {', '.join(ELEMENTS_3D)}, "
                             f"got {self.element!r}")
        if self.formulation not in ("displacement", "mixed", "auto"):
            raise InputError("formulation", "must be 'displacement', 'mixed' or 'auto', "
                             f"got {self.formulation!r}")


def block_mesh_3d(block: Block3D) -> MeshTet:
    """Tetrahedral mesh of the block: uniform in the contact zone, graded outside."""
    h = block.contact_x / block.elements
    x = interface_grid(block.width_x, block.contact_x, block.elements, block.grading)
    ny = max(1, int(round(block.contact_y / h)))
    y = interface_grid(block.width_y, block.contact_y, ny, block.grading)
    z = depth_grid(block.height, h, block.grading)
    return MeshTet.init_tensor(x, y, z)


def reduce_on_rigid_flat(mesh: MeshTet, *, E: float, nu: float, contact: Callable,
                         top: Callable, gap: Callable | None = None, element: str = "P2",
                         formulation: str = "auto", source: str = "") -> ReducedStiffness:
    """Reduce a tetrahedral body on a rigid flat z = const to its contact nodes.

    A thin call of :func:`slipcycle.fe.contact3d.reduce_contact_3d` with one body, every
    pair against the rigid flat (outward normal (0, 0, −1), t1 = x, t2 = y), the ``top``
    nodes held and moved by the cases of :data:`TOP_CASES`.

    Parameters
    ----------
    mesh : skfem.MeshTet
        The body, m.
    E, nu : float
        Young's modulus (Pa) and Poisson's ratio.
    contact : callable
        ``contact(xyz) -> bool array``: which nodes (coordinates (3, n), m) are contact
        candidates; they must lie on the plane of the flat.
    top : callable
        ``top(xyz) -> bool array``: the nodes moved rigidly by the load cases.
    gap : callable, optional
        ``gap(xyz) -> (n,)`` initial gap (m, ≥ 0) of the contact nodes; zero if None.
    element, formulation : str
        As :class:`Block3D`.
    source : str
        Provenance text.

    Returns
    -------
    ReducedStiffness
        A (2N, 2N), B (N, 2N), C (N, N) (N/m), ``tangential_dims`` 2, node coordinates
        (N, 3) (m), outward normals (0, 0, −1) and tangents x, y, the load cases of
        :data:`TOP_CASES` and ``gap`` (reactions, N per unit); nodes ordered by y, then x.
    """
    xyz = mesh_nodes(mesh, element).T
    is_contact = np.asarray(contact(xyz), bool)
    is_top = np.asarray(top(xyz), bool)
    if not is_contact.any():
        raise ValueError("no contact candidate nodes")
    if np.any(is_contact & is_top):
        raise ValueError("a contact node is also on the loaded top face")
    order_c = np.lexsort((xyz[0, is_contact], xyz[1, is_contact]))
    cnodes = np.flatnonzero(is_contact)[order_c]
    N = cnodes.size
    g = np.zeros(N) if gap is None else np.asarray(gap(xyz[:, cnodes]), float)
    if np.any(g < 0.0):
        raise ValueError("the initial gap must be ≥ 0")
    fixed = np.zeros((xyz.shape[1], 3), bool)
    fixed[is_top] = True
    cases = []
    for name, unit, move in TOP_CASES:
        u = np.zeros((xyz.shape[1], 3))
        u[is_top] = move
        cases.append(Case3D(name, unit, displacement=u))
    pairs = np.column_stack([cnodes, np.full(N, -1)])
    return reduce_contact_3d(mesh, materials=[(E, nu)], pairs=pairs,
                             normals=(0.0, 0.0, -1.0),
                             tangents=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), fixed=fixed,
                             gap=g, cases=cases, element=element,
                             formulation=formulation, source=source)


def block_on_rigid_3d(block: Block3D) -> ReducedStiffness:
    """Reduce a :class:`Block3D` (contact zone on z = 0, top face z = height moved).

    Parameters
    ----------
    block : Block3D
        Geometry (m), material (Pa) and mesh of the block.

    Returns
    -------
    ReducedStiffness
        As :func:`reduce_on_rigid_flat`; with ``block.radius`` the ``gap`` case holds the
        parabolic gap (x² + y²)/(2R).
    """
    mesh = block_mesh_3d(block)
    eps = 1e-9 * max(block.width_x, block.width_y, block.height)
    hx, hy = block.contact_x / 2 + eps, block.contact_y / 2 + eps

    def contact(xyz):
        return (np.abs(xyz[2]) <= eps) & (np.abs(xyz[0]) <= hx) & (np.abs(xyz[1]) <= hy)

    def top(xyz):
        return np.abs(xyz[2] - block.height) <= eps

    gap = None
    if block.radius is not None:
        R = block.radius

        def gap(xyz):
            return (xyz[0] ** 2 + xyz[1] ** 2) / (2.0 * R)

    return reduce_on_rigid_flat(mesh, E=block.E, nu=block.nu, contact=contact, top=top,
                                gap=gap, element=block.element,
                                formulation=block.formulation,
                                source=f"slipcycle.fe block_on_rigid_3d {block!r}")
