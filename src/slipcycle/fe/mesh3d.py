"""Tetrahedral meshes of several bodies: from gmsh, and split along a contact interface.

Two bodies meshed together in one gmsh model (volumes fragmented so that they share the
interface surface) give a conforming mesh: the interface vertices are shared.
:func:`split_interface` duplicates them for body 2, leaving two bodies that touch only
through the returned node pairs (body-1 vertex, coincident body-2 vertex), with the
outward normal of body 1 and the tributary area of each pair: the input of
:func:`slipcycle.fe.contact3d.reduce_contact_3d` for node-to-node contact with linear
(P1) elements.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
from skfem import MeshTet

from slipcycle.errors import InputError

__all__ = ["Interface3D", "mesh_from_gmsh", "split_interface", "tet_faces"]

#: the four faces of a tetrahedron (local vertex indices) and the opposite vertex
_FACES = ((1, 2, 3, 0), (0, 2, 3, 1), (0, 1, 3, 2), (0, 1, 2, 3))


@dataclass(frozen=True)
class Interface3D:
    """A mesh split along a contact interface.

    Attributes
    ----------
    mesh : skfem.MeshTet
        The mesh with the body-2 interface vertices duplicated (new vertices appended).
    element_body : numpy.ndarray of int, shape (n_elements,)
        Body label of each tetrahedron (unchanged).
    pairs : numpy.ndarray of int, shape (N, 2)
        Body-1 vertex and its body-2 copy, ordered by y, then x, then z of the vertex.
    normals : numpy.ndarray, shape (N, 3)
        Outward unit normal of body 1 (area-weighted mean of the interface faces).
    area : numpy.ndarray, shape (N,)
        Tributary area (a third of each adjacent interface face), m².
    """

    mesh: MeshTet
    element_body: np.ndarray
    pairs: np.ndarray
    normals: np.ndarray
    area: np.ndarray


def mesh_from_gmsh(volumes: dict[int, int] | None = None, model=None
                   ) -> tuple[MeshTet, np.ndarray]:
    """The linear tetrahedra of the current gmsh model as a scikit-fem mesh.

    Parameters
    ----------
    volumes : dict, optional
        gmsh volume entity tag → body label. Default: each 3-D physical group, in order
        of its tag, is one body (labels 0, 1, …); without physical groups every volume
        is body 0.
    model : gmsh.model, optional
        Default ``gmsh.model`` (``gmsh.initialize()`` and meshing are the caller's).

    Returns
    -------
    mesh : skfem.MeshTet
        Vertices renumbered 0…n−1 (unused gmsh nodes dropped), m.
    element_body : numpy.ndarray of int, shape (n_elements,)
    """
    if model is None:
        import gmsh

        model = gmsh.model
    if volumes is None:
        groups = sorted(model.getPhysicalGroups(3), key=lambda g: g[1])
        volumes = {}
        for label, (_, tag) in enumerate(groups):
            for ent in model.getEntitiesForPhysicalGroup(3, tag):
                volumes[int(ent)] = label
        if not volumes:
            volumes = {int(t): 0 for _, t in model.getEntities(3)}
    tags, coords, _ = model.mesh.getNodes()
    coords = np.asarray(coords).reshape(-1, 3)
    index = np.full(int(np.max(tags)) + 1, -1)
    index[np.asarray(tags, int)] = np.arange(len(tags))
    cells, labels = [], []
    for ent, label in volumes.items():
        etypes, _, enodes = model.mesh.getElements(3, ent)
        for et, nodes in zip(etypes, enodes, strict=True):
            if et != 4:
                raise InputError("mesh", f"volume {ent}: element type {et} (only linear "
                                 "tetrahedra, gmsh type 4, are read; mesh with order 1)")
            t = index[np.asarray(nodes, int).reshape(-1, 4)]
            cells.append(t)
            labels.append(np.full(len(t), label))
    if not cells:
        raise InputError("mesh", "the gmsh model has no tetrahedra (call mesh.generate(3))")
    t = np.concatenate(cells)
    used, t = np.unique(t, return_inverse=True)
    t = t.reshape(-1, 4)
    return MeshTet(coords[used].T.copy(), t.T.copy()), np.concatenate(labels)


def tet_faces(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All element faces: sorted vertex triples (4 n_el, 3), element, opposite vertex."""
    nel = t.shape[1]
    faces = np.concatenate([np.sort(t[list(f[:3])].T, axis=1) for f in _FACES])
    elem = np.tile(np.arange(nel), 4)
    opp = np.concatenate([t[f[3]] for f in _FACES])
    return faces, elem, opp


def split_interface(mesh: MeshTet, element_body, body1: int, body2: int, *,
                    side2: Iterable[int] | None = None,
                    select: Callable | None = None) -> Interface3D:
    """Duplicate the vertices of the faces shared by bodies ``body1`` and ``body2``.

    Parameters
    ----------
    mesh : skfem.MeshTet
        Conforming mesh of all bodies (interface vertices shared), m.
    element_body : array_like of int, shape (n_elements,)
        Body label of each tetrahedron.
    body1, body2 : int
        Labels of the two bodies in contact.
    side2 : iterable of int, optional
        Labels of the elements that take the duplicated vertices (default ``{body2}``:
        e.g. add a body bonded to body 2 that touches the interface).
    select : callable, optional
        ``select(centroids (3, n_faces)) -> bool``: which shared faces form the contact
        interface (default all); the others stay bonded except at vertices they share
        with selected faces.

    Returns
    -------
    Interface3D
    """
    eb = np.asarray(element_body)
    if eb.shape != (mesh.t.shape[1],):
        raise InputError("element_body", f"must have one label per element "
                         f"({mesh.t.shape[1]})")
    side2 = {body2} if side2 is None else set(side2)
    if body1 in side2:
        raise InputError("side2", "must not contain body 1")
    faces, elem, opp = tet_faces(mesh.t)
    order = np.lexsort(faces.T[::-1])
    fs = faces[order]
    same = np.all(fs[1:] == fs[:-1], axis=1)
    i, j = order[:-1][same], order[1:][same]            # the two elements of a shared face
    bi, bj = eb[elem[i]], eb[elem[j]]
    one_two = (bi == body1) & (bj == body2)
    two_one = (bi == body2) & (bj == body1)
    k1 = np.concatenate([i[one_two], j[two_one]])        # face entries on the body-1 side
    if k1.size == 0:
        raise InputError("element_body", f"bodies {body1} and {body2} share no face")
    p = mesh.p
    tri = faces[k1]
    cent = p[:, tri].mean(axis=2)
    if select is not None:
        keep = np.asarray(select(cent), bool)
        tri, cent, k1 = tri[keep], cent[:, keep], k1[keep]
        if tri.size == 0:
            raise InputError("select", "no shared face selected")
    nrm = np.cross(p[:, tri[:, 1]] - p[:, tri[:, 0]], p[:, tri[:, 2]] - p[:, tri[:, 0]],
                   axis=0)
    outward = np.sum(nrm * (cent - p[:, opp[k1]]), axis=0) > 0   # away from body 1
    nrm = np.where(outward, nrm, -nrm)                  # |nrm| = 2 × face area
    verts, inv = np.unique(tri, return_inverse=True)
    inv = inv.reshape(-1, 3)
    vn = np.zeros((verts.size, 3))
    area = np.zeros(verts.size)
    for c in range(3):
        np.add.at(vn, inv[:, c], nrm.T)
        np.add.at(area, inv[:, c], np.linalg.norm(nrm, axis=0) / 6.0)
    vn /= np.linalg.norm(vn, axis=1, keepdims=True)
    xyz = p[:, verts]
    srt = np.lexsort((xyz[2], xyz[0], xyz[1]))
    verts, vn, area = verts[srt], vn[srt], area[srt]
    n0 = p.shape[1]
    copy = np.full(n0, -1)
    copy[verts] = n0 + np.arange(verts.size)
    t = mesh.t.copy()
    on2 = np.isin(eb, list(side2))
    sub = t[:, on2]
    hit = copy[sub] >= 0
    sub[hit] = copy[sub[hit]]
    t[:, on2] = sub
    pnew = np.concatenate([p, p[:, verts]], axis=1)
    pairs = np.column_stack([verts, n0 + np.arange(verts.size)])
    return Interface3D(MeshTet(pnew, t), eb.copy(), pairs, vn, area)
