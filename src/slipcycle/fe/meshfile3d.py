"""Three-dimensional bodies from mesh files, reduced on a rigid flat (``slipcycle reduce``).

The file (any format meshio reads: Gmsh ``.msh``, ``.vtu``, ``.xdmf``, Abaqus ``.inp``,
...) must hold tetrahedra (``tetra`` or ``tetra10``; only the corner nodes are used,
scikit-fem adds its own mid-points for P2) and triangles (``triangle`` or ``triangle6``)
that carry the named surfaces. Surfaces are named as boundaries are in 2-D
(:mod:`slipcycle.fe.meshfile`): a cell set, a Gmsh physical group of dimension 2, or a
physical number as a string. Each triangle of a named surface must be a face of the
tetrahedra.

The body rests on a rigid flat perpendicular to ``normal`` (the unit normal of the flat
pointing into the body) through the contact node lowest along it; the other contact nodes
start at the gap g_j = n·(x_j − x_lowest); a normal pointing away from the body is refused
(:func:`check_flat_side`). Contact pairs are node-to-rigid-flat, so the
contact model is exact node-to-node for a conforming counter-surface (Wriggers 2006,
§4.1). The reduction itself is :func:`slipcycle.fe.contact3d.reduce_contact_3d`.

References
----------
Wriggers, P. (2006). Computational Contact Mechanics, 2nd ed., Springer.
Gustafsson, T. & McBain, G. D. (2020). scikit-fem: A Python package for finite element
assembly. J. Open Source Softw. 5(52), 2369.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from skfem import Basis, ElementVector, FacetBasis, LinearForm, MeshTet, asm

from slipcycle.errors import InputError
from slipcycle.fe.contact3d import ELEMENTS_3D, Case3D, node_dofs_3d, reduce_contact_3d
from slipcycle.fe.meshfile import cells_of_tag, known_tags, read_meshio, used_cells
from slipcycle.io.case import CaseError
from slipcycle.io.matrices import ReducedStiffness

__all__ = ["MeshSolid", "check_flat_side", "check_reduction_memory", "node_areas",
           "read_mesh_solid", "reduce_mesh_case", "reduce_mesh_solid", "surface_node_count"]

#: node numbers must stay below this for the int64 keys of faces (n³ < 2⁶³)
_MAX_NODES = 2_000_000


@dataclass(frozen=True, eq=False)
class MeshSolid:
    """A tetrahedral body read from a file, with its named surfaces and its loads.

    Attributes
    ----------
    mesh : skfem.MeshTet
        Coordinates in m.
    surfaces : dict of str to numpy.ndarray of int
        Name used by slipcycle (``"contact"``, a clamped or loaded surface) → indices into
        ``mesh.facets``.
    E, nu : float
        Young's modulus (Pa) and Poisson's ratio.
    normal : numpy.ndarray, shape (3,)
        Unit normal of the rigid flat, pointing into the body.
    clamped : tuple of str
        Surfaces held at u = 0 in every case.
    loads : tuple of dict
        Basic load cases ``{"name", "boundary", "traction": (tx, ty, tz)}`` (per unit of
        that traction, Pa) or ``{"name", "boundary", "displacement": (ux, uy, uz)}`` (m; the
        surface is held in every other case).
    element, formulation : str
        ``"P1"``/``"P2"`` and ``"auto"``/``"displacement"``/``"mixed"``.
    info : dict
        ``file`` and anything else for the metadata.
    """

    mesh: MeshTet
    surfaces: dict
    E: float
    nu: float
    normal: np.ndarray
    clamped: tuple = ()
    loads: tuple = ()
    element: str = "P2"
    formulation: str = "auto"
    info: dict = field(default_factory=dict)

    @property
    def n_dofs(self) -> int:
        """Degrees of freedom of the body: 3 per vertex, and per edge mid-point for P2."""
        nodes = self.mesh.p.shape[1] + (self.mesh.edges.shape[1] if self.element == "P2"
                                        else 0)
        return 3 * nodes


def _face_keys(tri: np.ndarray, n: int) -> np.ndarray:
    """One int64 per triangle (3, k) of vertex numbers < n, independent of their order."""
    s = np.sort(tri, axis=0).astype(np.int64)
    return (s[0] * n + s[1]) * n + s[2]


def read_mesh_solid(path: str | Path, tags: dict[str, str], *, key: str = "fe.mesh.file",
                    scale: float = 1.0, data=None) -> tuple[MeshTet, dict]:
    """Read a tetrahedral mesh and name its surfaces.

    Parameters
    ----------
    path : str or pathlib.Path
        Mesh file in any format meshio reads.
    tags : dict of str to str
        Surface name used by slipcycle → tag in the file (module docstring).
    key : str
        Case-file key the errors name (a tag error names ``<table of key>.<surface>``).
    scale : float
        Factor applied to the coordinates to give metres (e.g. 1e-3 for a file in mm).
    data : meshio.Mesh, optional
        The file already read; read from ``path`` if None.

    Returns
    -------
    mesh : skfem.MeshTet
        Positively oriented tetrahedra on the used nodes, m.
    surfaces : dict of str to numpy.ndarray of int
        Indices into ``mesh.facets``, one array per key of ``tags``.

    Raises
    ------
    CaseError
        Unreadable file, no tetrahedra, degenerate tetrahedra, a tag that names no
        triangles, or a triangle that is not a face of the tetrahedra.
    """
    m = read_meshio(path, key) if data is None else data
    t, used, renumber = used_cells(m, ("tetra", "tetra10"), 4, "tetrahedra", path, key)
    if used.size >= _MAX_NODES:
        raise CaseError(key, f"mesh file {path} has {used.size} nodes; at most "
                             f"{_MAX_NODES - 1}")
    pts = np.asarray(m.points, float)
    if pts.shape[1] != 3:
        raise CaseError(key, f"mesh file {path} has {pts.shape[1]}-D points; need x, y, z")
    bad = np.flatnonzero(~np.all(np.isfinite(pts[used]), axis=1))
    if bad.size:
        raise CaseError(key, f"mesh file {path}: {bad.size} node(s) with a non-finite "
                             f"coordinate (first: node {int(used[bad[0]])} at "
                             f"{pts[used[bad[0]]].tolist()})")
    p = pts[used].T * scale
    t = t.T
    e1, e2, e3 = (p[:, t[j]] - p[:, t[0]] for j in (1, 2, 3))
    vol = np.einsum("ij,ij->j", e1, np.cross(e2, e3, axis=0))
    flat = np.abs(vol) <= 1e-12 * np.abs(vol).max()
    if np.any(flat):
        raise CaseError(key, f"mesh file {path} has {int(flat.sum())} degenerate (flat) "
                             "tetrahedra")
    neg = vol < 0
    t[1, neg], t[2, neg] = t[2, neg].copy(), t[1, neg].copy()
    mesh = MeshTet(np.ascontiguousarray(p), np.ascontiguousarray(t))
    n = p.shape[1]
    fkeys = _face_keys(mesh.facets, n)
    order = np.argsort(fkeys)
    surfaces = {}
    where = key.rsplit(".", 1)[0]
    for ours, theirs in tags.items():
        tri = cells_of_tag(m, str(theirs), kind="triangle", corners=3)
        if tri is None:
            raise CaseError(f"{where}.{ours}",
                            f"surface tag {theirs!r} not found in {Path(path).name} "
                            f"(surface tags present: {', '.join(known_tags(m, 2)) or 'none'})")
        tri = renumber[tri]
        if np.any(tri < 0):
            raise CaseError(f"{where}.{ours}", f"a triangle of tag {theirs!r} is not a face "
                                               "of the tetrahedra")
        k = _face_keys(tri, n)
        pos = np.searchsorted(fkeys, k, sorter=order)
        pos = np.minimum(pos, len(order) - 1)
        idx = order[pos]
        if np.any(fkeys[idx] != k):
            raise CaseError(f"{where}.{ours}", f"{int(np.sum(fkeys[idx] != k))} triangle(s) "
                            f"of tag {theirs!r} are not faces of the tetrahedra")
        surfaces[ours] = np.unique(idx)
    return mesh, surfaces


def surface_node_count(mesh: MeshTet, facets: np.ndarray, element: str) -> int:
    """Number of nodes of ``element`` on the triangles ``facets`` (vertices, and the
    mid-points of their edges for P2): those with a tributary area (:func:`node_areas`)."""
    return int(np.count_nonzero(node_areas(mesh, facets, element)))


def check_reduction_memory(solid: MeshSolid, extra=None, contact: str = "contact") -> None:
    """Refuse (:class:`CaseError` naming ``fe.mesh.contact``) a contact surface whose dense
    reduced stiffness (3N)², with the condensation's copies of it, and ``extra(N)`` bytes
    (what solves it, for N contact nodes) exceed the memory budget
    (:func:`slipcycle.io.sizes.check_memory`)."""
    from slipcycle.io.sizes import check_memory

    n = surface_node_count(solid.mesh, solid.surfaces[contact], solid.element)
    more = 0.0 if extra is None else extra(n)
    check_memory("fe.mesh.contact", 4 * 8.0 * (3 * n) ** 2 + more, f"{n} contact nodes",
                 advice="coarsen the mesh on the contact surface")


def _surface_nodes(basis: Basis, dofs: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Rows of ``dofs`` (the nodes of :func:`~slipcycle.fe.contact3d.mesh_nodes`) on
    ``facets``: their vertices and, for P2, the mid-points of their edges."""
    on = basis.get_dofs(facets=np.asarray(facets)).all()
    return np.flatnonzero(np.isin(dofs[:, 0], on))


def _traction_forces(basis: Basis, dofs: np.ndarray, facets: np.ndarray,
                     traction) -> np.ndarray:
    """Consistent nodal forces (n_nodes, 3), N, of a uniform traction (Pa) on ``facets``."""
    fb = FacetBasis(basis.mesh, basis.elem, facets=np.asarray(facets))
    tx, ty, tz = (float(v) for v in traction)

    @LinearForm
    def load(v, w):
        return tx * v[0] + ty * v[1] + tz * v[2]

    return asm(load, fb)[dofs]


def node_areas(mesh: MeshTet, facets: np.ndarray, element: str) -> np.ndarray:
    """Tributary area (m²) of every node of :func:`~slipcycle.fe.contact3d.mesh_nodes` on
    the triangles ``facets`` (zero elsewhere): a third of each triangle to its vertices
    (P1); for P2 a third of each of the four sub-triangles the mid-points cut, so A/12 to
    each vertex and A/4 to each mid-point. They sum to the area of the surface."""
    f = mesh.facets[:, np.asarray(facets)]
    a = 0.5 * np.linalg.norm(np.cross(mesh.p[:, f[1]] - mesh.p[:, f[0]],
                                      mesh.p[:, f[2]] - mesh.p[:, f[0]], axis=0), axis=0)
    nv = mesh.p.shape[1]
    n_nodes = nv + (mesh.edges.shape[1] if element == "P2" else 0)
    out = np.zeros(n_nodes)
    if element == "P1":
        for j in range(3):
            np.add.at(out, f[j], a / 3.0)
        return out
    for j in range(3):
        np.add.at(out, f[j], a / 12.0)
    ekeys = np.sort(mesh.edges, axis=0).astype(np.int64)
    ekeys = ekeys[0] * nv + ekeys[1]
    order = np.argsort(ekeys)
    for i, j in ((0, 1), (1, 2), (0, 2)):
        lo, hi = np.minimum(f[i], f[j]), np.maximum(f[i], f[j])
        edge = order[np.searchsorted(ekeys, lo.astype(np.int64) * nv + hi, sorter=order)]
        np.add.at(out, nv + edge, a / 4.0)
    return out


def check_flat_side(mesh: MeshTet, facets: np.ndarray, normal) -> None:
    """Refuse a rigid flat on the wrong side of the body.

    The contact surface's outward normals (away from the tetrahedron each triangle bounds)
    must, on average over its area, point against ``normal``, the flat's normal into the
    body: a body resting on a flat faces it with −n (Wriggers 2006, §4.1). With n pointing
    away from the body every gap and normal load changes sign and the reduction describes
    a body that never touches the flat.

    Parameters
    ----------
    mesh : skfem.MeshTet
    facets : numpy.ndarray of int
        Indices into ``mesh.facets`` of the contact surface.
    normal : array_like, shape (3,)
        Unit normal of the rigid flat, meant to point into the body.

    Raises
    ------
    slipcycle.errors.InputError
        Key ``normal`` when the area-weighted mean outward normal m̄ of the surface has
        m̄·n ≥ 0.
    """
    facets = np.asarray(facets)
    f = mesh.facets[:, facets]
    t = mesh.t[:, mesh.f2t[0, facets]]
    opposite = t.sum(axis=0) - f.sum(axis=0)  # the vertex of the tetrahedron off the face
    p0 = mesh.p[:, f[0]]
    a2n = np.cross(mesh.p[:, f[1]] - p0, mesh.p[:, f[2]] - p0, axis=0)  # 2·area·normal
    a2n *= np.where(np.einsum("ij,ij->j", a2n, p0 - mesh.p[:, opposite]) < 0, -1.0, 1.0)
    n = np.asarray(normal, float)
    along = float(n @ a2n.sum(axis=1)) / float(np.linalg.norm(a2n, axis=0).sum())
    if along >= 0:
        raise InputError("normal", f"{[float(v) for v in n]} points away from the body: "
                         f"the contact surface's outward normals point along +n (mean "
                         f"n·n_out = {along:+.2f}), so the body lies on the side of −n; "
                         "the flat's normal must point into the body (reverse it)")


def reduce_mesh_solid(solid: MeshSolid, contact: str = "contact"
                      ) -> tuple[ReducedStiffness, np.ndarray]:
    """Reduce a :class:`MeshSolid` on its rigid flat to the contact nodes.

    Parameters
    ----------
    solid : MeshSolid
    contact : str
        Name of the surface whose nodes are the contact candidates.

    Returns
    -------
    reduced : ReducedStiffness
        A (2N, 2N), B (N, 2N), C (N, N) (N/m), ``tangential_dims`` 2, node coordinates
        (N, 3) (m; nodes ordered by z, then y, then x), outward normals −n, tangents t1 =
        x projected on the flat (y where n is nearly along x) and t2 completing the
        right-handed frame (:func:`~slipcycle.io.fe_formats.dofmap.node_frames`), and
        the load cases of ``solid.loads`` then ``gap`` (N per unit of each case).
    area : numpy.ndarray, shape (N,)
        Tributary area of each contact node (:func:`node_areas`), m².

    Raises
    ------
    slipcycle.errors.InputError
        A flat on the wrong side of the body (key ``normal``, :func:`check_flat_side`), a
        contact node that is also clamped or displacement-loaded (key ``clamped`` or the
        case's name), or a surface without nodes.
    slipcycle.condensation.SingularModelError
        The body is not held against rigid motion with the contact nodes held.
    """
    if solid.element not in ELEMENTS_3D:
        raise InputError("element", f"must be one of {', '.join(ELEMENTS_3D)}, got "
                         f"{solid.element!r}")
    basis = Basis(solid.mesh, ElementVector(ELEMENTS_3D[solid.element]()))
    dofs, xyz = node_dofs_3d(basis)
    n = np.asarray(solid.normal, float)
    n = n / np.linalg.norm(n)
    check_flat_side(solid.mesh, solid.surfaces[contact], n)
    cnodes = _surface_nodes(basis, dofs, solid.surfaces[contact])
    cnodes = cnodes[np.lexsort((xyz[0, cnodes], xyz[1, cnodes], xyz[2, cnodes]))]
    height = n @ xyz[:, cnodes]
    gap = height - height.min()
    fixed = np.zeros((xyz.shape[1], 3), bool)
    for name in solid.clamped:
        fixed[_surface_nodes(basis, dofs, solid.surfaces[name])] = True
    if np.any(fixed[cnodes]):
        raise InputError("clamped", f"{int(np.sum(fixed[cnodes].any(axis=1)))} contact "
                         "node(s) lie on a clamped surface; a contact node must be free")
    moved = {}
    for spec in solid.loads:
        if "displacement" in spec and spec["boundary"] not in moved:
            nodes = _surface_nodes(basis, dofs, solid.surfaces[spec["boundary"]])
            if np.any(np.isin(nodes, cnodes)):
                raise InputError(spec["name"], f"surface {spec['boundary']!r} shares nodes "
                                 "with the contact surface; a contact node must be free")
            moved[spec["boundary"]] = nodes
            fixed[nodes] = True
    cases = []
    for spec in solid.loads:
        if "traction" in spec:
            f = _traction_forces(basis, dofs, solid.surfaces[spec["boundary"]],
                                 spec["traction"])
            cases.append(Case3D(spec["name"], "Pa", force=f, description=(
                f"traction {tuple(spec['traction'])} Pa on {spec['boundary']!r}")))
        else:
            u = np.zeros((xyz.shape[1], 3))
            u[moved[spec["boundary"]]] = spec["displacement"]
            cases.append(Case3D(spec["name"], "m", displacement=u, description=(
                f"displacement {tuple(spec['displacement'])} m of {spec['boundary']!r}")))
    pairs = np.column_stack([cnodes, np.full(cnodes.size, -1)])
    source = (f"slipcycle.fe.meshfile3d {solid.info.get('file', '')}: "
              f"{solid.mesh.t.shape[1]} tetrahedra, {3 * xyz.shape[1]} dofs")
    red = reduce_contact_3d(solid.mesh, materials=[(solid.E, solid.nu)], pairs=pairs,
                            normals=-n, fixed=fixed, gap=gap, cases=cases,
                            element=solid.element, formulation=solid.formulation,
                            source=source)
    area = node_areas(solid.mesh, solid.surfaces[contact], solid.element)[cnodes]
    return red, area


def reduce_mesh_case(solid: MeshSolid) -> tuple[ReducedStiffness, np.ndarray]:
    """:func:`reduce_mesh_solid` for a model file: every failure a :class:`CaseError`
    naming the key of the model file (``fe.mesh.normal``, ``fe.mesh.clamped``,
    ``fe.load_case``, ``fe``)."""
    from slipcycle.condensation import SingularModelError
    from slipcycle.io.matrices import StiffnessError

    try:  # the ReducedStiffness checks K symmetric positive definite on construction
        return reduce_mesh_solid(solid)
    except StiffnessError as exc:
        raise CaseError("fe", f"reduced stiffness {exc.problem}") from None
    except InputError as exc:
        key = {"clamped": "fe.mesh.clamped", "normal": "fe.mesh.normal"}
        raise CaseError(key.get(exc.key, "fe.load_case"), exc.problem) from None
    except SingularModelError as exc:
        raise CaseError("fe.mesh.clamped", f"the body is not held against rigid motion "
                        f"with its contact nodes held ({exc}); clamp a surface or "
                        "prescribe the displacement of one") from None
