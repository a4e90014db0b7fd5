"""An exported stiffness and its mesh → the reduced contact model A, B, C and its loads.

Each body's export K is read by the readers of :mod:`slipcycle.io.fe_formats` with its
rows labelled ``(node, dof)`` (dof 1, 2, 3: global x, y, z) or, unlabelled, in the order
x, y, z of the mesh nodes. Rows of nodes that are not in the mesh (the internal nodes that
CalculiX adds for ``C3D8I``, 3 per element; rows of more such nodes are the export of
another mesh, refused) and rotations are condensed out with the rest. A mesh node
without rows is held at u = 0: the deck fixes it (``*BOUNDARY`` removes its rows from the
``.sti`` export) or the export does not hold it (a substructure's condensed nodes); a
contact node, a clamped node or a loaded node without rows is refused.

The contact is body 1's surface ``contact``; with one body its counter-surface is rigid,
with two each contact node of body 1 is paired with the node of body 2 at the same place
(within ``tolerance``); two bodies named from one export and mesh (two parts of one deck)
share that one K. Every node of a clamped set and of a set moved by a
``displacement`` case is held (moved in its own case, at rest in the others; a force
case all on held nodes would load nothing and is refused); everything
else is condensed out by :func:`slipcycle.fe.contact3d.condense_contact_3d`, the engine of
slipcycle's own 3-D reductions (one sparse factorisation, Guyan 1965), in the conventions
stated there (Barber 2012, §3): q = q^w + A v + Bᵀ w, p = p^w + B v + C w, with the node
frames of :func:`slipcycle.io.fe_formats.dofmap.node_frames` about each node's outward
normal (:mod:`slipcycle.fe_import.surface`). The initial gap is zero: the counter-surface
conforms to the contact surface.

References
----------
Guyan, R. J. (1965). Reduction of stiffness and mass matrices. AIAA J. 3(2), 380.
Barber, J. R. (2012). Frictional systems under periodic loads — history-dependence,
non-uniqueness and energy dissipation. J. Phys.: Conf. Ser. 382, 012002.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from slipcycle.condensation import SingularModelError
from slipcycle.errors import InputError
from slipcycle.fe.contact3d import Case3D, condense_contact_3d
from slipcycle.fe_import.mesh import ImportedMesh, read_mesh
from slipcycle.fe_import.model import UNITS, BodySpec, ImportModel
from slipcycle.fe_import.surface import (
    face_areas,
    node_areas,
    node_normals,
    pressure_forces,
    surface_nodes,
)
from slipcycle.io.case import CaseError
from slipcycle.io.fe_formats import detect_format, read_raw
from slipcycle.io.fe_formats.common import StiffnessError, check_diagonal, file_error
from slipcycle.io.fe_formats.dofmap import check_symmetric
from slipcycle.io.matrices import ReducedStiffness

__all__ = ["ImportedBody", "ImportedJoint", "read_body", "import_joint"]

_AXES = "xyz"


@dataclass(frozen=True, eq=False)
class ImportedBody:
    """One body ready for the reduction.

    Attributes
    ----------
    mesh : ImportedMesh
    K : scipy.sparse.csr_matrix, shape (n, n)
        The export's stiffness (symmetric part), N/m, with one unit row appended for each
        mesh-node dof it lacks.
    dofs : numpy.ndarray of int, shape (n_nodes, 3)
        Row of K of each mesh node's x, y, z.
    absent : numpy.ndarray of bool, shape (n_nodes, 3)
        The dofs the export lacks (held at 0).
    others : numpy.ndarray of int, shape (k, 3)
        The rows of K that are no mesh node's x, y, z (other nodes, rotations; padded
        with unit rows to whole triples), grouped in threes as nodes of their own that
        the reduction condenses out.
    faces : list of FaceSet
        The contact faces.
    contact : numpy.ndarray of int
        Contact node indices.
    info : dict
        What was read, for the report.
    """

    mesh: ImportedMesh
    K: sp.csr_matrix
    dofs: np.ndarray
    absent: np.ndarray
    others: np.ndarray
    faces: list
    contact: np.ndarray
    info: dict = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class ImportedJoint:
    """The reduced model of an import.

    Attributes
    ----------
    reduced : ReducedStiffness
        A (2N, 2N), B (N, 2N), C (N, N), N/m; coordinates (N, 3), m; outward normals and
        tangents; one load case per ``[[fe_import.load]]``.
    area : numpy.ndarray, shape (N,)
        Tributary area of each contact node, m².
    report : dict
        What was read and checked (written as ``report.txt``).
    """

    reduced: ReducedStiffness
    area: np.ndarray
    report: dict


def _read_export(spec: BodySpec):
    key = f"{spec.key}.stiffness"
    if spec.stiffness.suffix.lower() == ".mas":
        # the same layout as the .sti, so only the name tells it apart
        raise CaseError(key, f"{spec.stiffness.name} is CalculiX's mass matrix "
                        f"(jobname.mas); the stiffness is {spec.stiffness.stem}.sti")
    # a K near the largest float overflows in its norms: refused below in one line, so
    # numpy's RuntimeWarnings would only print around it
    with np.errstate(over="ignore", invalid="ignore"):
        raw, K, fmt = _read_checked(spec, key)
    if K.nnz == 0 or not np.any(K.data):
        raise CaseError(key, f"{spec.stiffness.name}: the stiffness is zero (every entry "
                        "of K is 0)")
    return raw, K, fmt


def _read_checked(spec: BodySpec, key: str):
    """The raw export, its symmetric K (CSR) and format word; errors name ``key``."""
    try:
        fmt = spec.format or detect_format(spec.stiffness)
        if fmt == "npz" or fmt == "matrix-market":
            from slipcycle.io import matrices

            raw = (matrices._raw_npz(spec.stiffness, None) if fmt == "npz"
                   else matrices._raw_mtx(spec.stiffness))
        else:
            raw = read_raw(spec.stiffness, fmt, None)
        if raw.K is None:
            raise file_error(spec.stiffness, "holds reduced blocks A, B, C, not a "
                             "stiffness K of the mesh's nodes")
        if raw.missing_labels is not None:
            # the .dof (.mapping) is the only statement of which node each row belongs
            # to; without it a partial copy or a failed run would be read by guesswork
            raise file_error(spec.stiffness, f"{raw.missing_labels} is missing beside it "
                             "(CalculiX writes jobname.dof with jobname.sti, ANSYS "
                             "HBMAT Fname.mapping with Mapping = YES): it names the node and "
                             "dof of each row, which cannot be matched to the mesh without "
                             "it")
        if not np.any(raw.K.data if sp.issparse(raw.K) else np.asarray(raw.K)):
            raise file_error(spec.stiffness, "the stiffness is zero (every entry of K is 0)")
        # a file cut short at a line boundary leaves rows without their diagonal entry
        check_diagonal(raw.K, raw.labels if raw.transform is None else None,
                       spec.stiffness.name)
        K = check_symmetric(raw.K, spec.stiffness.name)
    except StiffnessError as exc:
        where = spec.stiffness.name
        problem = exc.problem if exc.key == where else f"{exc.key}: {exc.problem}"
        raise CaseError(key, f"{where}: {problem}") from None
    except (ValueError, OSError) as exc:
        raise CaseError(key, f"{spec.stiffness.name}: {exc}") from None
    return raw, sp.csr_matrix(K), fmt


def _rows(raw, K, mesh: ImportedMesh, spec: BodySpec):
    """Row of K of each mesh node's x, y, z (−1 where absent), and the count of others."""
    n_nodes = len(mesh.labels)
    key, name = f"{spec.key}.stiffness", spec.stiffness.name
    dofs = np.full((n_nodes, 3), -1, np.int64)
    if raw.labels is None:
        if K.shape[0] != 3 * n_nodes:
            raise CaseError(key, f"{name}: K has {K.shape[0]} rows without node labels; "
                            f"the mesh has {n_nodes} nodes, 3 × {n_nodes} = {3 * n_nodes} "
                            "rows (x, y, z node by node) expected")
        return np.arange(3 * n_nodes).reshape(n_nodes, 3), 0
    labels = np.asarray(raw.labels, np.int64)
    if len(labels) != K.shape[0]:
        raise CaseError(key, f"{name}: {len(labels)} row labels for {K.shape[0]} rows")
    index = mesh.index_of()
    pos = np.array([index.get(int(n), -1) for n in labels[:, 0]])
    own = (pos >= 0) & (labels[:, 1] >= 1) & (labels[:, 1] <= 3)
    dofs[pos[own], labels[own, 1] - 1] = np.flatnonzero(own)
    if not own.any():
        raise CaseError(key, f"{name}: no row belongs to a node of {mesh.path.name} (first "
                        f"row: node {labels[0, 0]}); is it the export of this mesh?")
    foreign = np.unique(labels[pos < 0, 0])
    # C3D8I elements add 3 internal nodes each, and a few nodes come from the deck's
    # constraints (a rigid body's rotation node); far more are the rows of another mesh,
    # which would be condensed out silently
    allowed = 3 * mesh.incompatible + 8 + len(mesh.labels) // 10
    if foreign.size > allowed:
        raise CaseError(key, f"{name} has rows of {foreign.size} nodes that "
                        f"{mesh.path.name} does not have (first: node {foreign[0]}), more "
                        f"than its elements and constraints can add ({allowed}: 3 internal "
                        "nodes per C3D8I element, and a few); is it the export of this mesh?")
    return dofs, int(np.sum(pos < 0))


#: largest relative residual ‖K u‖ / (max row sum |K| · ‖u‖) of a rigid motion u of a
#: free body's export: the stored K of a free body is round-off (1e-15) from leaving rigid
#: motions free; one of a mesh whose nodes moved since is off by the relative move
RIGID_RTOL = 1e-6


def _check_rigid_modes(K, raw, dofs: np.ndarray, mesh: ImportedMesh, spec: BodySpec) -> None:
    """Refuse a CalculiX stiffness of a free body that does not leave the rigid motions of
    the mesh's nodes free: it is the export of other coordinates (a deck edited after ccx
    ran; the labels alone cannot tell). ccx leaves a fixed dof out of the ``.sti``, so a
    body with every mesh dof in it is free, and K u = 0 for the three translations and the
    three rotations u = ω × x of its nodes (other rows, the internal dofs of C3D8I, at 0:
    they carry no strain in a rigid motion). Exports with rotation rows are not checked."""
    if raw.labels is not None and np.any(np.asarray(raw.labels)[:, 1] > 3):
        return
    x = mesh.points - mesh.points.mean(axis=0)
    U = np.zeros((K.shape[0], 6))
    for a in range(3):
        U[dofs[:, a], a] = 1.0
        U[dofs[:, a], 3:] = np.cross(np.eye(3), x[:, None, :])[:, :, a]
    res = np.linalg.norm(K @ U, axis=0) / (abs(K).sum(axis=1).max() * np.linalg.norm(U, axis=0))
    if not res.max() <= RIGID_RTOL:
        worst = int(np.argmax(res))
        motion = (f"translation along {_AXES[worst]}" if worst < 3
                  else f"rotation about {_AXES[worst - 3]}")
        raise CaseError(f"{spec.key}.stiffness", f"{spec.stiffness.name} is not the stiffness "
                        f"of {mesh.path.name}'s nodes where they are now: a rigid {motion} "
                        f"of the free body is resisted (relative residual {res.max():.1e} > "
                        f"{RIGID_RTOL:g}); was the deck changed after ccx ran? Run ccx again")


def _faces_named(mesh: ImportedMesh, name: str, key: str):
    """Faces of the surface ``name``, or the boundary faces whose nodes are all in the
    node set ``name`` (every node of the set must lie on one)."""
    for table in (mesh.surfaces, mesh.node_sets):
        hit = next((k for k in table if k.upper() == name.upper()), None)
        if hit is not None:
            break
    else:
        known = sorted(set(mesh.surfaces) | set(mesh.node_sets))
        raise CaseError(key, f"no surface or node set {name!r} in {mesh.path.name} "
                        f"(it has: {', '.join(known) or 'none'})")
    if table is mesh.surfaces:
        return _on_boundary(mesh, mesh.surfaces[hit], name, key)
    nodes = mesh.node_sets[hit]
    if nodes.size == 0:
        raise CaseError(key, f"node set {name!r} of {mesh.path.name} is empty")
    inset = np.zeros(len(mesh.labels), bool)
    inset[nodes] = True
    faces = []
    for fs in mesh.boundary_faces():
        sel = inset[fs.nodes].all(axis=1)
        if sel.any():
            faces.append(dataclasses.replace(fs, nodes=fs.nodes[sel], inside=fs.inside[sel]))
    off = np.setdiff1d(nodes, surface_nodes(faces))
    if off.size:
        raise CaseError(key, f"node set {name!r}: {off.size} of its {nodes.size} nodes are "
                        f"not on a face of the body's surface formed by the set (first: "
                        f"node {mesh.labels[off[0]]})")
    return faces


def _on_boundary(mesh: ImportedMesh, faces: list, name: str, key: str) -> list:
    """``faces`` of the surface ``name``, checked: some, each on the body's outer
    boundary (a face of two elements is inside the body, as the node-set route finds)."""
    if not any(len(fs.nodes) for fs in faces):
        raise CaseError(key, f"surface {name!r} of {mesh.path.name} has no faces")
    outer = mesh.boundary_corners()
    for fs in faces:
        inner = [r for r, c in enumerate(map(tuple, fs.corners())) if c not in outer]
        if inner:
            raise CaseError(key, f"surface {name!r}: {fs.name(inner[0], mesh.labels)} is "
                            "inside the body (a face of two elements), not on its surface")
    return faces


def _check_areas(mesh: ImportedMesh, faces: list, name: str, key: str) -> None:
    """Refuse a face of no area (coincident nodes): it has no normal and no area to give
    its nodes."""
    size = float(np.ptp(mesh.points, axis=0).max()) if len(mesh.points) else 0.0
    for fs in faces:
        area = face_areas(mesh.points, fs)
        flat = np.flatnonzero(~(area > 1e-12 * size ** 2))
        if flat.size:
            raise CaseError(key, f"surface {name!r}: {fs.name(flat[0], mesh.labels)} has "
                            f"zero area ({area[flat[0]]:.3g} m²; nodes at one place?)")


def _set_nodes(mesh: ImportedMesh, name: str, key: str) -> np.ndarray:
    """Nodes of the node set (or surface) ``name``; an empty set is refused."""
    hit = next((k for k in mesh.node_sets if k.upper() == name.upper()), None)
    if hit is None:
        return surface_nodes(_faces_named(mesh, name, key))
    if mesh.node_sets[hit].size == 0:
        raise CaseError(key, f"node set {name!r} of {mesh.path.name} is empty")
    return mesh.node_sets[hit]


def read_body(spec: BodySpec, same: ImportedBody | None = None) -> ImportedBody:
    """Read one body's export and mesh, its contact surface and its checks.

    Parameters
    ----------
    spec : BodySpec
        The body's files, sets and units.
    same : ImportedBody, optional
        A body read already from the same export and mesh (two bodies of one deck): its
        mesh and stiffness are taken, and only ``spec``'s contact is read.

    Returns
    -------
    ImportedBody
        The stiffness in N/m on the mesh's nodes (dofs the export lacks held at 0), the
        contact faces and nodes.

    Raises
    ------
    CaseError
        Naming the body's key: an unreadable export or mesh, an export of another mesh,
        a missing set or surface.
    """
    if same is not None:
        faces, contact = _contact(same.mesh, same.absent, spec)
        return dataclasses.replace(same, faces=faces, contact=contact, info={
            **same.info, "contact": spec.contact, "contact_nodes": int(contact.size)})
    length, stiff = UNITS[spec.units]
    mesh = read_mesh(spec.mesh, f"{spec.key}.mesh", length)
    raw, K, fmt = _read_export(spec)
    K = K * stiff
    dofs, foreign = _rows(raw, K, mesh, spec)
    absent = dofs < 0
    extra = int(absent.sum())
    dofs[absent] = K.shape[0] + np.arange(extra)
    unused = np.setdiff1d(np.arange(K.shape[0]), dofs[~absent])
    pad = -unused.size % 3
    others = np.concatenate([unused, K.shape[0] + extra + np.arange(pad)]).reshape(-1, 3)
    if extra + pad:
        K = sp.block_diag([K, sp.identity(extra + pad)], format="csr")
    faces, contact = _contact(mesh, absent, spec)
    if fmt == "calculix" and not absent.any():
        _check_rigid_modes(K, raw, dofs, mesh, spec)
    info = {"stiffness": str(spec.stiffness), "format": fmt,
            # what the deck's numbers were read as; everything written is m, N, Pa
            "units": {"m": "m, N, Pa", "mm": "mm, N, MPa (K in N/mm)"}[spec.units],
            "rows": int(K.shape[0] - extra - pad), "rows_condensed_not_mesh": int(unused.size),
            "mesh": str(spec.mesh), "mesh_nodes": len(mesh.labels),
            "elements": {k: int(len(v)) for k, v in mesh.cells.items()},
            "rows_of_other_nodes": foreign, "mesh_dofs_without_rows": extra,
            "contact": spec.contact, "contact_nodes": int(contact.size)}
    return ImportedBody(mesh, K, dofs, absent, others, faces, contact, info)


def _contact(mesh: ImportedMesh, absent: np.ndarray, spec: BodySpec):
    """The faces and nodes of ``spec``'s contact, checked: faces with an area, every
    node with its rows in the export."""
    faces = _faces_named(mesh, spec.contact, f"{spec.key}.contact")
    _check_areas(mesh, faces, spec.contact, f"{spec.key}.contact")
    contact = surface_nodes(faces)
    if contact.size == 0:
        raise CaseError(f"{spec.key}.contact", f"{spec.contact!r} has no faces")
    bad = np.flatnonzero(absent[contact].any(axis=1))
    if bad.size:
        j = contact[bad[0]]
        raise CaseError(f"{spec.key}.stiffness", f"{spec.stiffness.name} has no row for "
                        f"u_{_AXES[int(np.argmax(absent[j]))]} of contact node "
                        f"{mesh.labels[j]}: the deck fixes it (*BOUNDARY) or constrains "
                        "it (*EQUATION, *TIE, ...), or the export does not hold it")
    return faces, contact


def _same_export(specs) -> bool:
    """Whether two bodies are read from one export and one mesh (two bodies of one deck,
    as CalculiX meshes a *CONTACT PAIR): their stiffness is then one K, not two copies."""
    if len(specs) != 2:
        return False
    a, b = specs
    return (a.stiffness.resolve() == b.stiffness.resolve()
            and a.mesh.resolve() == b.mesh.resolve()
            and (a.units, a.format) == (b.units, b.format))


def _held(body: ImportedBody, names, key: str, what: str,
          contact: np.ndarray | None = None) -> np.ndarray:
    """The nodes of the sets ``names``, none of them a contact node (``contact``; by
    default the body's own) and all with rows in the export."""
    contact = body.contact if contact is None else contact
    nodes = np.unique(np.concatenate([_set_nodes(body.mesh, n, key) for n in names])
                      if names else np.zeros(0, np.int64))
    if np.isin(nodes, contact).any():
        j = nodes[np.isin(nodes, contact)][0]
        raise CaseError(key, f"{what} holds contact node {body.mesh.labels[j]}; a contact "
                        "node must be free")
    lack = nodes[body.absent[nodes].any(axis=1)]
    if lack.size:
        raise CaseError(key, f"{what}: node {body.mesh.labels[lack[0]]} has no row in the "
                        "export (fixed in the deck already, or condensed by the FE code)")
    return nodes


def _pairs(b1: ImportedBody, b2: ImportedBody | None, tolerance: float, key: str
           ) -> tuple[np.ndarray, np.ndarray]:
    """Body-1 contact nodes (ordered by z, y, x) and their partners in body 2 (or −1)."""
    x1 = b1.mesh.points[b1.contact]
    c1 = b1.contact[np.lexsort((x1[:, 0], x1[:, 1], x1[:, 2]))]
    if b2 is None:
        return c1, np.full(c1.size, -1)
    x2 = b2.mesh.points[b2.contact]
    dist, idx = cKDTree(x2).query(b1.mesh.points[c1])
    far = np.flatnonzero(dist > tolerance)
    if far.size:
        j = far[0]
        raise CaseError(key, f"contact node {b1.mesh.labels[c1[j]]} of body 1 has no node "
                        f"of body 2 within {tolerance:g} m (nearest: node "
                        f"{b2.mesh.labels[b2.contact[idx[j]]]} at {dist[j]:.3g} m)")
    if np.unique(idx).size != idx.size or b2.contact.size != c1.size:
        left = np.setdiff1d(np.arange(b2.contact.size), idx)
        j = b2.contact[left[0]] if left.size else b2.contact[idx[0]]
        raise CaseError(key, f"the contact surfaces do not match node to node: node "
                        f"{b2.mesh.labels[j]} of body 2 is not paired once "
                        f"({c1.size} nodes on body 1, {b2.contact.size} on body 2)")
    return c1, b2.contact[idx]


def _cases(model: ImportModel, bodies, offsets, n_all: int, fixed: np.ndarray,
           contacts: list) -> list:
    """The :class:`Case3D` of every load, and the held mask of the moved sets
    (``contacts``: the contact nodes of each body's mesh, that no load may hold)."""
    cases = []
    for ld in model.loads:
        body, off = bodies[ld.body], offsets[ld.body]
        target = f"{ld.key}.{'surface' if ld.kind == 'pressure' else 'nodes'}"
        if ld.kind == "pressure":
            faces = _faces_named(body.mesh, ld.target, target)
            nodes = surface_nodes(faces)
        else:
            nodes = _set_nodes(body.mesh, ld.target, target)
        on = nodes[np.isin(nodes, contacts[ld.body])]
        if on.size:
            raise CaseError(target, f"{ld.target!r} holds contact node "
                            f"{body.mesh.labels[on[0]]}: a load on a contact node is not "
                            "a load on the body (the contact reactions are the unknowns)")
        lack = nodes[body.absent[nodes].any(axis=1)]
        if lack.size:
            raise CaseError(target, f"node {body.mesh.labels[lack[0]]} of {ld.target!r} "
                            "has no row in the export, so it cannot be loaded (the .sti "
                            "route with no *BOUNDARY on it gives every node)")
        arr = np.zeros((n_all, 3))
        if ld.kind == "pressure":
            f = pressure_forces(body.mesh.points, faces, float(ld.value))
            arr[off:off + len(f)] = f
            cases.append(Case3D(ld.name, "1", force=arr, description=(
                f"pressure {float(ld.value):g} Pa on {ld.target}")))
        elif ld.kind == "force":
            arr[off + nodes] = ld.value
            cases.append(Case3D(ld.name, "1", force=arr, description=(
                f"force {ld.value.tolist()} N on each node of {ld.target}")))
        else:
            arr[off + nodes] = ld.value
            fixed[off + nodes] = True
            cases.append(Case3D(ld.name, "1", displacement=arr, description=(
                f"displacement {ld.value.tolist()} m of {ld.target}")))
    return cases


def _check_free_forces(model: ImportModel, cases: list, fixed: np.ndarray) -> None:
    """Refuse a force or pressure case all of whose force lands on held dofs: a grip or
    a clamp takes it, and the case would load nothing (its p^w, q^w exactly 0)."""
    for ld, case in zip(model.loads, cases, strict=True):
        if case.force is not None and not np.any(case.force[~fixed]):
            target = f"{ld.key}.{'surface' if ld.kind == 'pressure' else 'nodes'}"
            raise CaseError(target, f"every node that {ld.target!r} loads is held (clamped, "
                            "or moved by a displacement case): the load goes into the "
                            "support, and this load case puts no force on the free degrees "
                            "of freedom")


def _check_facing(b1: ImportedBody, b2: ImportedBody, specs, key: str) -> None:
    """Refuse a second body whose contact is the first one's, or does not face it: the
    two surfaces' mean outward normals must be opposite."""
    same = (specs[0].mesh.resolve() == specs[1].mesh.resolve()
            and specs[0].contact.upper() == specs[1].contact.upper())
    n1 = node_normals(b1.mesh.points, b1.faces, b1.contact).mean(axis=0)
    n2 = node_normals(b2.mesh.points, b2.faces, b2.contact).mean(axis=0)
    cos = float(n1 @ n2 / (np.linalg.norm(n1) * np.linalg.norm(n2) or 1.0))
    if same or cos > -0.9:
        raise CaseError(key, f"the contact {specs[1].contact!r} of body 2 "
                        + ("is body 1's contact itself" if same else
                           f"does not face body 1's {specs[0].contact!r} (mean outward "
                           f"normals at {np.degrees(np.arccos(np.clip(cos, -1, 1))):.0f}°, "
                           "not opposite)")
                        + ": a pair is two bodies' surfaces that touch")


def import_joint(model: ImportModel) -> ImportedJoint:
    """Reduce the bodies of ``model`` to their contact (module docstring).

    Parameters
    ----------
    model : ImportModel
        A checked model file (:func:`read_import_model`).

    Returns
    -------
    ImportedJoint
        ``reduced``: A (2N, 2N), B (N, 2N), C (N, N), N/m; coordinates (N, 3), m; outward
        normals and tangents; one load case per ``[[fe_import.load]]`` (reactions with the
        contact held, N, for the load as given). ``area`` (N,), m². ``report``: what was
        read and checked.

    Raises
    ------
    CaseError
        Naming the model-file key: a set or surface that is missing or off the surface, a
        load or clamp on a contact node, an export that is unreadable, of another mesh or
        not positive definite, a body not held against rigid motion.
    """
    shared = _same_export(model.bodies)
    bodies = [read_body(model.bodies[0])]
    bodies += [read_body(spec, bodies[0] if shared else None) for spec in model.bodies[1:]]
    b2 = bodies[1] if len(bodies) == 2 else None
    if b2 is not None:
        _check_facing(bodies[0], b2, model.bodies, f"{model.bodies[1].key}.contact")
    c1, c2 = _pairs(bodies[0], b2, model.tolerance, "fe_import.tolerance")
    # two bodies of one deck share one K and one numbering of the nodes: each body's
    # loads and clamps must then keep off both contacts
    blocks = bodies[:1] if shared else bodies
    contacts = ([np.union1d(bodies[0].contact, b2.contact)] * 2 if shared
                else [b.contact for b in bodies])
    if shared and np.intersect1d(bodies[0].contact, b2.contact).size:
        j = np.intersect1d(bodies[0].contact, b2.contact)[0]
        raise CaseError(f"{model.bodies[1].key}.contact", f"node {bodies[0].mesh.labels[j]} "
                        f"lies on both contacts, {model.bodies[0].contact!r} and "
                        f"{model.bodies[1].contact!r}: the two bodies of a pair do not "
                        "share nodes")
    sizes = [len(b.mesh.labels) + len(b.others) for b in blocks]
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(int)
    rows = np.concatenate([[0], np.cumsum([b.K.shape[0] for b in blocks])[:-1]]).astype(int)
    if shared:
        offsets = np.zeros(2, int)
    n_all = int(sum(sizes))
    dofs = np.vstack([np.vstack([b.dofs, b.others]) + r
                      for b, r in zip(blocks, rows, strict=True)])
    xyz = np.vstack([np.vstack([b.mesh.points, np.zeros((len(b.others), 3))])
                     for b in blocks]).T
    fixed = np.vstack([np.vstack([b.absent, np.zeros((len(b.others), 3), bool)])
                       for b in blocks])
    for b, spec, off, busy in zip(bodies, model.bodies, offsets, contacts, strict=True):
        fixed[off + _held(b, spec.clamped, f"{spec.key}.clamped", "clamped", busy)] = True
    cases = _cases(model, bodies, offsets, n_all, fixed, contacts)
    _check_free_forces(model, cases, fixed)
    if b2 is not None and np.isin(c2, b2.contact[fixed[offsets[1] + b2.contact].any(1)]).any():
        raise CaseError("fe_import.body[1].clamped", "a contact node of body 2 is held")
    pairs = np.column_stack([c1, np.where(c2 >= 0, c2 + offsets[-1], -1)])
    normals = node_normals(bodies[0].mesh.points, bodies[0].faces, c1)
    K = sp.block_diag([b.K for b in blocks], format="csr")
    source = "; ".join(f"{b.info['stiffness']} ({b.info['format']}) on {b.info['mesh']}"
                       for b in blocks)
    try:
        red = condense_contact_3d(lambda: (K, "imported"), dofs, xyz, pairs=pairs,
                                  normals=normals, fixed=fixed, cases=cases, source=source)
    except SingularModelError as exc:
        raise CaseError(f"{model.bodies[0].key}.clamped", "the bodies are not held against "
                        f"rigid motion with the contact held ({exc}); clamp a node set or "
                        "prescribe the displacement of one") from None
    except StiffnessError as exc:
        raise CaseError(f"{model.bodies[0].key}.stiffness", f"the reduced stiffness "
                        f"{exc.problem}") from None
    except InputError as exc:
        raise CaseError("fe_import", f"{exc.key}: {exc.problem}") from None
    loads = {k: v for k, v in red.loads.items() if k != "gap"}   # the gap is zero
    red = dataclasses.replace(red, loads=loads)
    area = node_areas(bodies[0].mesh.points, bodies[0].faces, c1)
    report = {"bodies": [b.info for b in bodies], "contact_nodes": int(c1.size),
              "contact_area_m2": float(area.sum()), "load_cases": {
                  c.name: c.description for c in cases},
              "dofs_condensed": int(K.shape[0] - fixed.sum() - 3 * c1.size),
              "dofs_held": int(fixed.sum()), "source": red.source}
    return ImportedJoint(red, area, report)
