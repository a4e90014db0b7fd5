"""Meshes of a bolted lap joint: a gmsh plan-view triangulation extruded into two plates.

The plan view (x along the plates, y across) is one rectangle from the grip of the lower
plate to the grip of the upper plate, cut by the bolt holes, with the overlap edges and the
washer circles as mesh lines, meshed by gmsh (Geuzaine & Remacle 2009) with the size
``h`` in the overlap, growing away from it. Each plate is the extrusion of its part of the
plan triangulation through its thickness, every triangular prism split into three
tetrahedra by the vertex-number rule (each quadrilateral side face gets the diagonal from
the bottom of its higher-numbered vertex to the top of the lower-numbered one, so
neighbouring prisms agree; Dompierre, Labbé, Vallet & Camarero 1999). Both plates are
extruded from the same plan triangles, so their faces on the interface plane z = 0 carry
coincident nodes: a conforming node-to-node interface with the interface nodes duplicated
(one copy per plate).

When the bolt pattern is mirror-symmetric about y = 0 only the half y ≥ 0 is meshed and
reflected, so the mesh itself is exactly mirror-symmetric.

References
----------
Geuzaine, C. & Remacle, J.-F. (2009). Gmsh: a 3-D finite element mesh generator with
built-in pre- and post-processing facilities. Int. J. Numer. Meth. Eng. 79(11), 1309–1331.
Dompierre, J., Labbé, P., Vallet, M.-G. & Camarero, R. (1999). How to subdivide pyramids,
prisms and hexahedra into tetrahedra. Proc. 8th International Meshing Roundtable, 195–204.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plan_mesh", "extrude_tets", "mirror_symmetric"]


def mirror_symmetric(centres: np.ndarray, tol: float) -> bool:
    """True when the set of bolt centres (K, 2) maps onto itself under y → −y."""
    mirrored = centres * np.array([1.0, -1.0])
    d = np.linalg.norm(centres[:, None, :] - mirrored[None, :, :], axis=-1)
    return bool(np.all(d.min(axis=1) <= tol))


def plan_mesh(x_range: tuple[float, float], width: float, overlap: tuple[float, float],
              centres: np.ndarray, hole_radius: float, washer_radius: float, h: float,
              h_far: float) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate the plan view of the joint with gmsh.

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

    Returns
    -------
    points : numpy.ndarray, shape (n, 2)
        Node coordinates, m.
    triangles : numpy.ndarray of int, shape (m, 3)
        Counter-clockwise triangles.
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
        field.setNumber(box, "VIn", 1.0)
        field.setNumber(box, "VOut", h_far * s)
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
        gmsh.option.setNumber("Mesh.Algorithm", 6)          # Frontal-Delaunay
        gmsh.model.mesh.generate(2)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        _, elem_nodes = gmsh.model.mesh.getElementsByType(2)
    finally:
        gmsh.model.remove()
        if started:
            gmsh.finalize()
    index = np.full(int(tags.max()) + 1, -1)
    index[tags.astype(int)] = np.arange(tags.size)
    tri = index[elem_nodes.astype(int)].reshape(-1, 3)
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


def _counter_clockwise(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    d1 = pts[tri[:, 1]] - pts[tri[:, 0]]
    d2 = pts[tri[:, 2]] - pts[tri[:, 0]]
    cw = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0] < 0
    tri = tri.copy()
    tri[cw] = tri[cw][:, ::-1]
    return tri


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
    used = np.unique(tri)
    local = np.full(pts.shape[0], -1)
    local[used] = np.arange(used.size)
    t = np.sort(local[tri], axis=1)          # the vertex-number rule needs sorted triangles
    n = used.size
    levels = len(z)
    p = np.empty((3, n * levels))
    for k, zk in enumerate(z):
        p[:2, k * n:(k + 1) * n] = pts[used].T
        p[2, k * n:(k + 1) * n] = zk
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
