"""Meshes of a bolted lap joint: a gmsh plan-view mesh extruded into two plates.

The plan view (x along the plates, y across) is one rectangle from the grip of the lower
plate to the grip of the upper plate, cut by the bolt holes, with the overlap edges and the
washer circles as mesh lines, meshed by gmsh (Geuzaine & Remacle 2009) with the size
``h`` in the overlap, growing away from it: triangles, or quadrilaterals (gmsh's
Frontal-Delaunay for quads with Blossom recombination, Remacle et al. 2012). Each plate is
the extrusion of its part of the plan mesh through its thickness: a quadrilateral gives a
hexahedron; a triangular prism is split into three tetrahedra by the vertex-number rule
(each quadrilateral side face gets the diagonal from the bottom of its higher-numbered
vertex to the top of the lower-numbered one, so neighbouring prisms agree; Dompierre,
Labbé, Vallet & Camarero 1999). Both plates are extruded from the same plan cells, so
their faces on the interface plane z = 0 carry coincident nodes: a conforming node-to-node
interface with the interface nodes duplicated (one copy per plate).

When the bolt pattern is mirror-symmetric about y = 0 only the half y ≥ 0 is meshed and
reflected, so the mesh itself is exactly mirror-symmetric.

References
----------
Geuzaine, C. & Remacle, J.-F. (2009). Gmsh: a 3-D finite element mesh generator with
built-in pre- and post-processing facilities. Int. J. Numer. Meth. Eng. 79(11), 1309–1331.
Remacle, J.-F., Lambrechts, J., Seny, B., Marchandise, E., Johnen, A. & Geuzaine, C.
(2012). Blossom-Quad: a non-uniform quadrilateral mesh generator using a minimum-cost
perfect-matching algorithm. Int. J. Numer. Meth. Eng. 89(9), 1102–1119.
Dompierre, J., Labbé, P., Vallet, M.-G. & Camarero, R. (1999). How to subdivide pyramids,
prisms and hexahedra into tetrahedra. Proc. 8th International Meshing Roundtable, 195–204.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plan_mesh", "extrude_tets", "extrude_hexes", "mirror_symmetric", "cell_weights"]


def mirror_symmetric(centres: np.ndarray, tol: float) -> bool:
    """True when the set of bolt centres (K, 2) maps onto itself under y → −y."""
    mirrored = centres * np.array([1.0, -1.0])
    d = np.linalg.norm(centres[:, None, :] - mirrored[None, :, :], axis=-1)
    return bool(np.all(d.min(axis=1) <= tol))


def plan_mesh(x_range: tuple[float, float], width: float, overlap: tuple[float, float],
              centres: np.ndarray, hole_radius: float, washer_radius: float, h: float,
              h_far: float, quads: bool = False, refine: int = 0
              ) -> tuple[np.ndarray, np.ndarray]:
    """Mesh the plan view of the joint with gmsh, in triangles or quadrilaterals.

    Parameters
    ----------
    x_range : (float, float)
        x of the two grips (plate ends), m.
    width : float
        Plate width W (y ∈ [−W/2, W/2]), m.
    overlap : (float, float)
        x of the overlap edges, m; they become mesh lines.
    centres : numpy.ndarray, shape (K, 2)
        Bolt centres, m.
    hole_radius, washer_radius : float
        Radius of the holes and of the washer circles (mesh lines), m.
    h, h_far : float
        Element size in the overlap and far from it, m.
    quads : bool
        Quadrilaterals instead of triangles: gmsh recombines a mesh of size 2h and splits
        every cell (all-quadrilateral subdivision), so the result has no triangle.
    refine : int
        Uniform refinements of the mesh of size h: each splits every cell into four
        (new nodes on the holes and washer circles lie on the circles), so the meshes
        of one h and refine = 0, 1, 2 … are nested, with spacing h/2^refine.

    Returns
    -------
    points : numpy.ndarray, shape (n, 2)
        Node coordinates, m.
    cells : numpy.ndarray of int, shape (m, 3) or (m, 4)
        Counter-clockwise triangles or quadrilaterals.
    """
    import gmsh

    centres = np.asarray(centres, float)
    s = 1.0 / h                       # gmsh works in units of h (its tolerances are absolute)
    half = mirror_symmetric(centres, 1e-9 * width)
    ylo = 0.0 if half else -width / 2
    started = not gmsh.isInitialized()
    if started:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Verbosity", 0)
        gmsh.model.add("lap_joint_plan")
        occ = gmsh.model.occ
        x0, x1 = x_range
        a, b = overlap
        rects = [occ.addRectangle(x0 * s, ylo * s, 0, (a - x0) * s, (width / 2 - ylo) * s),
                 occ.addRectangle(a * s, ylo * s, 0, (b - a) * s, (width / 2 - ylo) * s),
                 occ.addRectangle(b * s, ylo * s, 0, (x1 - b) * s, (width / 2 - ylo) * s)]
        holes = [(2, occ.addDisk(cx * s, cy * s, 0, hole_radius * s, hole_radius * s))
                 for cx, cy in centres]
        washers = [(2, occ.addDisk(cx * s, cy * s, 0, washer_radius * s,
                                   washer_radius * s)) for cx, cy in centres]
        annuli, _ = occ.cut(washers, holes, removeTool=False)
        cut, _ = occ.cut([(2, rects[1])], holes)
        occ.fragment([(2, rects[0])] + cut + [(2, rects[2])], annuli)
        occ.synchronize()
        if half:                     # the washer parts below y = 0 go
            for dim, tag in gmsh.model.getEntities(2):
                if occ.getCenterOfMass(dim, tag)[1] < 0.0:
                    gmsh.model.removeEntities([(dim, tag)], recursive=True)
        field = gmsh.model.mesh.field
        box = field.add("Box")
        # quadrilaterals: recombine a mesh of size 2h, then split every cell (a quad into
        # four, a triangle into three), which leaves no triangle and halves the size
        grow = 2.0 if quads else 1.0
        field.setNumber(box, "VIn", grow)
        field.setNumber(box, "VOut", grow * h_far * s)
        field.setNumber(box, "XMin", a * s)
        field.setNumber(box, "XMax", b * s)
        field.setNumber(box, "YMin", -width * s)
        field.setNumber(box, "YMax", width * s)
        field.setNumber(box, "ZMin", -1.0)
        field.setNumber(box, "ZMax", 1.0)
        field.setNumber(box, "Thickness", 3.0 * h_far * s)
        field.setAsBackgroundMesh(box)
        for name in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints",
                     "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(name, 0)
        if quads:
            # Frontal-Delaunay for quads, Blossom's perfect matching of the triangles
            gmsh.option.setNumber("Mesh.Algorithm", 8)
            gmsh.option.setNumber("Mesh.RecombineAll", 1)
            gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)
            gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)
        else:
            gmsh.option.setNumber("Mesh.Algorithm", 6)      # Frontal-Delaunay
        gmsh.model.mesh.generate(2)
        for _ in range(refine):
            gmsh.model.mesh.refine()
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        _, elem_nodes = gmsh.model.mesh.getElementsByType(3 if quads else 2)
        left = gmsh.model.mesh.getElementsByType(2)[1].size if quads else 0
    finally:
        gmsh.model.remove()
        if started:
            gmsh.finalize()
    if left:
        raise RuntimeError(f"gmsh left {left // 3} triangles in the quadrilateral plan mesh")
    index = np.full(int(tags.max()) + 1, -1)
    index[tags.astype(int)] = np.arange(tags.size)
    tri = index[elem_nodes.astype(int)].reshape(-1, 4 if quads else 3)
    pts = xyz.reshape(-1, 3)[:, :2] / s
    used = np.unique(tri)
    renumber = np.full(pts.shape[0], -1)
    renumber[used] = np.arange(used.size)
    pts, tri = pts[used], renumber[tri]
    pts[np.abs(pts[:, 1] - ylo) < 1e-9 * width, 1] = ylo
    if half:
        pts, tri = _reflect(pts, tri, width)
    return pts, _counter_clockwise(pts, tri)


def _reflect(pts: np.ndarray, tri: np.ndarray, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Mirror a mesh of y ≥ 0 about y = 0, merging the nodes on y = 0."""
    on_axis = pts[:, 1] == 0.0
    n = pts.shape[0]
    image = np.full(n, -1)
    off = np.flatnonzero(~on_axis)
    image[on_axis] = np.flatnonzero(on_axis)
    image[off] = n + np.arange(off.size)
    new_pts = np.vstack([pts, pts[off] * np.array([1.0, -1.0])])
    return new_pts, np.vstack([tri, image[tri][:, ::-1]])


def _signed_area(pts: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Signed areas (m,) of polygons ``cells`` (m, k) (shoelace formula)."""
    x, y = pts[cells, 0], pts[cells, 1]
    return 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)


def _counter_clockwise(pts: np.ndarray, cells: np.ndarray) -> np.ndarray:
    cw = _signed_area(pts, cells) < 0
    cells = cells.copy()
    cells[cw] = cells[cw][:, ::-1]
    return cells


#: 2×2 Gauss points of the unit square and bilinear shape functions there (4 points × 4)
_G = np.array([-1.0, 1.0]) / np.sqrt(3.0)
_XI, _ETA = (a.ravel() for a in np.meshgrid(_G, _G, indexing="ij"))
_CORNERS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
_N4 = 0.25 * (1 + _XI[:, None] * _CORNERS[:, 0]) * (1 + _ETA[:, None] * _CORNERS[:, 1])
_DN4 = np.stack([0.25 * _CORNERS[:, 0] * (1 + _ETA[:, None] * _CORNERS[:, 1]),
                 0.25 * _CORNERS[:, 1] * (1 + _XI[:, None] * _CORNERS[:, 0])], axis=1)


def cell_weights(pts: np.ndarray, cells: np.ndarray, n: int | None = None) -> np.ndarray:
    """∫ N_a dA of every node a over the plane cells: the consistent nodal forces of a unit
    uniform pressure and the tributary areas of node-to-node contact.

    Parameters
    ----------
    pts : numpy.ndarray, shape (n, 2)
        Node coordinates, m.
    cells : numpy.ndarray of int, shape (m, 3) or (m, 4)
        Triangles (linear shape functions: a third of the area to each corner) or
        quadrilaterals (bilinear, 2×2 Gauss points: exact for any plane quadrilateral).
    n : int, optional
        Length of the result (default ``pts.shape[0]``).

    Returns
    -------
    numpy.ndarray, shape (n,)
        m²; sums to the area of the cells.
    """
    out = np.zeros(pts.shape[0] if n is None else n)
    if cells.shape[1] == 3:
        np.add.at(out, cells.ravel(), np.repeat(np.abs(_signed_area(pts, cells)) / 3, 3))
        return out
    X = pts[cells]                                            # (m, 4, 2)
    J = np.einsum("gdk,mkc->mgdc", _DN4, X)                   # (m, 4 points, 2, 2)
    det = np.abs(J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0])
    np.add.at(out, cells.ravel(), np.einsum("gk,mg->mk", _N4, det).ravel())
    return out


def _levels(pts: np.ndarray, cells: np.ndarray, z: np.ndarray) -> tuple[np.ndarray,
                                                                         np.ndarray]:
    """The plan nodes used by ``cells`` copied to every level of ``z``: points (3,
    n_used len(z)), level-major, and ``cells`` renumbered to the first level."""
    used = np.unique(cells)
    local = np.full(pts.shape[0], -1)
    local[used] = np.arange(used.size)
    n = used.size
    p = np.empty((3, n * len(z)))
    p[:2] = np.tile(pts[used].T, len(z))
    p[2] = np.repeat(np.asarray(z, float), n)
    return p, local[cells]


def extrude_tets(pts: np.ndarray, tri: np.ndarray, z: np.ndarray) -> tuple[np.ndarray,
                                                                           np.ndarray]:
    """Extrude plan triangles through the levels ``z`` into positively oriented tetrahedra.

    Parameters
    ----------
    pts : numpy.ndarray, shape (n, 2)
        Plan nodes, m (only those used by ``tri`` are kept).
    tri : numpy.ndarray of int, shape (m, 3)
        Plan triangles.
    z : numpy.ndarray, shape (L + 1,)
        Increasing levels, m.

    Returns
    -------
    points : numpy.ndarray, shape (3, n_used (L + 1))
        Node coordinates, level-major (level 0 first), nodes in increasing plan number.
    tets : numpy.ndarray of int, shape (4, 3 m L)
    """
    p, local = _levels(pts, tri, z)
    t = np.sort(local, axis=1)               # the vertex-number rule needs sorted triangles
    n, levels = p.shape[1] // len(z), len(z)
    tets = []
    for k in range(levels - 1):
        a, b, c = (t[:, j] + k * n for j in range(3))
        a2, b2, c2 = a + n, b + n, c + n
        tets += [np.stack([a, b, c, a2]), np.stack([b, c, a2, b2]),
                 np.stack([c, a2, b2, c2])]
    tets = np.hstack(tets)
    e1, e2, e3 = (p[:, tets[j]] - p[:, tets[0]] for j in (1, 2, 3))
    vol = np.einsum("ij,ij->j", e1, np.cross(e2, e3, axis=0))
    neg = vol < 0
    tets[1, neg], tets[2, neg] = tets[2, neg].copy(), tets[1, neg].copy()
    return p, tets


def extrude_hexes(pts: np.ndarray, quads: np.ndarray, z: np.ndarray) -> tuple[np.ndarray,
                                                                            np.ndarray]:
    """Extrude plan quadrilaterals through the levels ``z`` into hexahedra.

    Parameters
    ----------
    pts : numpy.ndarray, shape (n, 2)
        Plan nodes, m (only those used by ``quads`` are kept).
    quads : numpy.ndarray of int, shape (m, 4)
        Counter-clockwise plan quadrilaterals.
    z : numpy.ndarray, shape (L + 1,)
        Increasing levels, m.

    Returns
    -------
    points : numpy.ndarray, shape (3, n_used (L + 1))
        Node coordinates, level-major (level 0 first), nodes in increasing plan number.
    hexes : numpy.ndarray of int, shape (8, m L)
        Vertices 0–3 the lower face counter-clockwise seen from +z, 4–7 the upper face
        in the same order (:func:`slipcycle.fe.hex8i.hex8i_stiffness`).
    """
    p, q = _levels(pts, quads, z)
    n, levels = p.shape[1] // len(z), len(z)
    hexes = np.hstack([np.vstack([q.T + k * n, q.T + (k + 1) * n])
                       for k in range(levels - 1)])
    return p, hexes
