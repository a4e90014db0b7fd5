"""A sphere pressed on a flat block, both elastic: the Hertz–Cattaneo–Mindlin model in 3-D.

Two coaxial cylinders of radius ``radius_body`` share the disk z = 0: the cap
(body 1, 0 ≤ z ≤ cap_height) and the block (body 2, −block_height ≤ z ≤ 0), meshed
together by gmsh with linear tetrahedra of size ``h_contact`` within ``refine`` of the
origin, growing to ``h_far``. The interface vertices are duplicated
(:func:`slipcycle.fe.mesh3d.split_interface`); the pairs within ``contact_radius`` of
the axis are the contact candidates, the others are free surface. The curvature of the
sphere of radius R enters through the initial gap g = R − √(R² − r²) ≈ r²/(2R) of each
pair, as in Hertz's theory, which treats both bodies as half-spaces (Johnson 1985,
§4.2); with bodies of one material the Dundurs constant β = 0 and the normal and
tangential problems uncouple (Johnson 1985, §7.2).

Load cases (the cap top z = cap_height held and moved rigidly; the block bottom held):

=============== ====== ======================================================
case            unit   what
=============== ====== ======================================================
``normal``      m      cap top moved 1 m towards the block (−z)
``tangential``  m      cap top moved 1 m along +x (t1)
``tangential2`` m      cap top moved 1 m along +y (t2)
``gap``         1      the initial gap: −[Bᵀ g; C g]
=============== ====== ======================================================

References
----------
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge University Press.
Geuzaine, C. & Remacle, J.-F. (2009). Gmsh: a 3-D finite element mesh generator with
built-in pre- and post-processing facilities. Int. J. Numer. Meth. Engng 79, 1309–1331.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipcycle.errors import InputError
from slipcycle.fe.contact3d import Case3D, mesh_nodes, reduce_contact_3d
from slipcycle.fe.geometry import check_number
from slipcycle.fe.mesh3d import Interface3D, mesh_from_gmsh, split_interface
from slipcycle.io.matrices import ReducedStiffness

__all__ = ["SphereOnBlock", "sphere_mesh", "sphere_on_block"]


@dataclass(frozen=True)
class SphereOnBlock:
    """A spherical cap of radius R on a flat block, same material.

    Parameters
    ----------
    R : float
        Sphere radius (m).
    E, nu : float
        Young's modulus (Pa) and Poisson's ratio of both bodies.
    contact_radius : float
        Pairs with r ≤ contact_radius are contact candidates (m); must exceed the largest
        contact radius of the loads applied.
    h_contact : float
        Element size within ``refine`` (default 1.25 contact_radius) of the origin (m).
    h_far : float
        Element size far from the contact (m).
    radius_body, cap_height, block_height : float
        Radius of both cylinders and their heights (m).
    refine : float or None
        Radius of the uniformly refined zone (m).
    """

    R: float
    E: float
    nu: float
    contact_radius: float
    h_contact: float
    h_far: float
    radius_body: float
    cap_height: float
    block_height: float
    refine: float | None = None

    def __post_init__(self):
        for name in ("R", "E", "contact_radius", "h_contact", "h_far", "radius_body",
                     "cap_height", "block_height"):
            check_number(name, getattr(self, name), gt=0.0)
        check_number("nu", self.nu, ge=0.0, lt=0.5)
        check_number("contact_radius", self.contact_radius, lt=0.5 * self.radius_body)
        check_number("h_contact", self.h_contact, le=self.h_far)
        if self.contact_radius >= self.R:
            raise InputError("contact_radius", "must be smaller than the sphere radius R")
        if self.refine is not None:
            check_number("refine", self.refine, ge=self.contact_radius,
                         lt=self.radius_body)

    @property
    def refine_radius(self) -> float:
        return 1.25 * self.contact_radius if self.refine is None else self.refine


def sphere_mesh(model: SphereOnBlock) -> Interface3D:
    """gmsh mesh of cap (body 0) and block (body 1), split at z = 0 (all shared faces)."""
    import gmsh

    own = not gmsh.isInitialized()
    if own:
        gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("sphere_on_block")
        occ = gmsh.model.occ
        rb = model.radius_body
        cap = occ.addCylinder(0, 0, 0, 0, 0, model.cap_height, rb)
        block = occ.addCylinder(0, 0, -model.block_height, 0, 0, model.block_height, rb)
        occ.fragment([(3, cap)], [(3, block)])
        occ.synchronize()
        vols = {}
        for _, tag in gmsh.model.getEntities(3):
            zc = gmsh.model.occ.getCenterOfMass(3, tag)[2]
            vols[tag] = 0 if zc > 0 else 1
        centre = occ.addPoint(0, 0, 0)
        occ.synchronize()
        faces = [t for _, t in gmsh.model.getEntities(2)
                 if abs(gmsh.model.occ.getCenterOfMass(2, t)[2]) < 1e-12 * rb]
        gmsh.model.mesh.embed(0, [centre], 2, faces[0])
        f = gmsh.model.mesh.field
        dist = f.add("Distance")
        f.setNumbers(dist, "PointsList", [centre])
        thr = f.add("Threshold")
        f.setNumber(thr, "InField", dist)
        f.setNumber(thr, "SizeMin", model.h_contact)
        f.setNumber(thr, "SizeMax", model.h_far)
        f.setNumber(thr, "DistMin", model.refine_radius)
        grow = model.refine_radius + 4.0 * (model.h_far - model.h_contact)
        f.setNumber(thr, "DistMax", min(grow, rb))
        f.setAsBackgroundMesh(thr)
        for key in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints",
                    "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(key, 0)
        gmsh.option.setNumber("Mesh.Algorithm3D", 10)            # HXT, deterministic
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.mesh.generate(3)
        mesh, eb = mesh_from_gmsh(vols)
    finally:
        gmsh.model.remove()
        if own:
            gmsh.finalize()
    return split_interface(mesh, eb, 0, 1)


def sphere_on_block(model: SphereOnBlock, *, source: str = ""
                    ) -> tuple[ReducedStiffness, np.ndarray]:
    """Reduce a :class:`SphereOnBlock` onto its contact candidates.

    Returns
    -------
    red : ReducedStiffness
        The cases of the module docstring (N per unit), nodes ordered by y then x, normals
        (0, 0, −1) (outward of the cap), tangents x, y.
    area : numpy.ndarray, shape (N,)
        Tributary area of each pair, m².
    """
    it = sphere_mesh(model)
    xyz = mesh_nodes(it.mesh)
    p1 = xyz[it.pairs[:, 0]]
    r = np.hypot(p1[:, 0], p1[:, 1])
    keep = r <= model.contact_radius * (1 + 1e-9)
    pairs, area = it.pairs[keep], it.area[keep]
    R = model.R
    gap = R - np.sqrt(R**2 - r[keep] ** 2)
    eps = 1e-9 * max(model.cap_height, model.block_height)
    top = np.abs(xyz[:, 2] - model.cap_height) <= eps
    bottom = np.abs(xyz[:, 2] + model.block_height) <= eps
    fixed = np.zeros_like(xyz, dtype=bool)
    fixed[top | bottom] = True
    cases = []
    for name, move in (("normal", (0, 0, -1.0)), ("tangential", (1.0, 0, 0)),
                       ("tangential2", (0, 1.0, 0))):
        u = np.zeros_like(xyz)
        u[top] = move
        cases.append(Case3D(name, "m", displacement=u))
    red = reduce_contact_3d(it.mesh, materials=[(model.E, model.nu)] * 2,
                            element_body=it.element_body, pairs=pairs,
                            normals=(0.0, 0.0, -1.0),
                            tangents=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), fixed=fixed,
                            gap=gap, cases=cases, element="P1",
                            source=source or f"slipcycle.fe sphere_on_block {model!r}")
    return red, area
