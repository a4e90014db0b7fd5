"""Three-dimensional contact reduction: tetrahedral elastic bodies condensed onto N pairs.

One tetrahedral mesh holds every body (each element tagged with its body and material);
bodies in contact do not share nodes on the contact surface: each contact pair j is a node
of body 1 and the coincident node of body 2 (or −1: a rigid counter-surface that does not
move). Every degree of freedom that is neither held (prescribed) nor a body-1 contact dof
is condensed out with one sparse factorisation (:func:`slipcycle.condensation.
schur_complement`, Guyan 1965).

Sign conventions (those of :mod:`slipcycle.io.matrices` and the 2-D reduction
:mod:`slipcycle.fe.reduction`; Barber 2012, §3). Pair j has the outward unit normal n_j
of body 1 (out of body 1, towards body 2), the inward direction e_j = −n_j and two unit
tangents t1_j, t2_j with (t1, t2, e) right-handed orthonormal (by default those of
:func:`slipcycle.io.fe_formats.dofmap.node_frames`: t1 = x projected on the plane, or y
when e is nearly along x). With u¹, u² the displacements of the two nodes (u² = 0 for a
rigid counter-surface),

    v_ja = t_a · (u¹_j − u²_j)          slip of body 1 relative to body 2 (a = 1, 2)
    w_j  = g_j − n_j · (u¹_j − u²_j)    separation; w > 0 opens the gap

(body 1 moves as u¹ = u² + t1 v1 + t2 v2 + e (w − g)); q_ja, p_j are the forces of body
2 on body 1 along t_a and e (p > 0 compressive); body 2 receives −(q t + p e). Then

    q = q^w + A v + Bᵀ w,      p = p^w + B v + C w,

A (2N × 2N) node-major (node 0 t1, node 0 t2, node 1 t1, …), B (N × 2N), C (N × N); q^w,
p^w are the reactions with every pair held at v = w = 0, per unit of each load case,
and the case ``gap`` is −[Bᵀ g; C g] (N).

References
----------
Guyan, R. J. (1965). Reduction of stiffness and mass matrices. AIAA J. 3(2), 380.
Barber, J. R. (2012). Frictional systems under periodic loads — history-dependence,
non-uniqueness and energy dissipation. J. Phys.: Conf. Ser. 382, 012002.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, MeshTet

from slipcycle.condensation import schur_complement
from slipcycle.errors import InputError
from slipcycle.fe.assembly import default_formulation, stiffness
from slipcycle.io.fe_formats.dofmap import node_frames
from slipcycle.io.matrices import ReducedStiffness

__all__ = ["Case3D", "ELEMENTS_3D", "mesh_nodes", "node_dofs_3d", "reduce_contact_3d",
           "condense_contact_3d"]

ELEMENTS_3D = {"P1": ElementTetP1, "P2": ElementTetP2}


@dataclass(frozen=True)
class Case3D:
    """One basic load case of a 3-D reduction, applied with unit magnitude.

    Parameters
    ----------
    name : str
        e.g. ``"normal"``, ``"tangential"`` (not ``"gap"``: added by the reduction).
    unit : str
        What one unit of the case is: ``"N"`` (force), ``"m"`` (displacement), ``"Pa"``.
    force : numpy.ndarray, shape (n_nodes, 3), optional
        Nodal forces (x, y, z) at every node of :func:`mesh_nodes`, N.
    displacement : numpy.ndarray, shape (n_nodes, 3), optional
        Prescribed displacements (x, y, z), m; only the entries of held components
        (``fixed``) are used, the others are ignored.
    description : str
    """

    name: str
    unit: str
    force: np.ndarray | None = None
    displacement: np.ndarray | None = None
    description: str = ""


def node_dofs_3d(basis: Basis) -> tuple[np.ndarray, np.ndarray]:
    """DOF indices (n_nodes, 3) of (u_x, u_y, u_z) at every node and its coordinates (3, n).

    Nodes are the vertices, then (P2) the edge mid-points in the order of ``mesh.edges``.
    """
    parts = [basis.nodal_dofs]
    if basis.edge_dofs.size:
        parts.append(basis.edge_dofs)
    dofs = np.concatenate(parts, axis=1).T
    return dofs, basis.doflocs[:, dofs[:, 0]]


def mesh_nodes(mesh: MeshTet, element: str = "P1") -> np.ndarray:
    """Coordinates (n_nodes, 3) of the nodes of ``element`` on ``mesh``, m.

    P1: the vertices (``mesh.p.T``); P2: the vertices, then the mid-points of
    ``mesh.edges``. These are the rows of ``fixed``, :class:`Case3D` arrays and the node
    indices of ``pairs`` in :func:`reduce_contact_3d`.
    """
    if element == "P1":
        return mesh.p.T.copy()
    _check_element(element)
    mid = 0.5 * (mesh.p[:, mesh.edges[0]] + mesh.p[:, mesh.edges[1]])
    return np.concatenate([mesh.p, mid], axis=1).T.copy()


def _check_element(element):
    if element not in ELEMENTS_3D:
        raise InputError("element", f"must be one of {', '.join(ELEMENTS_3D)}, got "
                         f"{element!r}")


def _per_pair(name, value, N, shape):
    a = np.asarray(value, float)
    if a.shape == shape:
        a = np.broadcast_to(a, (N, *shape)).copy()
    if a.shape != (N, *shape) or not np.all(np.isfinite(a)):
        raise InputError(name, f"must be one finite array of shape {shape} or one per "
                         f"pair, {(N, *shape)}; got shape {np.shape(value)}")
    return a


def _frames(normals, tangents, N):
    """Outward normals (N, 3), tangents (N, 2, 3) and inward directions e (N, 3)."""
    nrm = _per_pair("normals", normals, N, (3,))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    if tangents is None:
        nrm, tan = node_frames({"normal": nrm}, N, 2)
    else:
        tan = _per_pair("tangents", tangents, N, (2, 3))
        frame = np.concatenate([tan, -nrm[:, None, :]], axis=1)
        err = np.abs(np.einsum("nij,nkj->nik", frame, frame) - np.eye(3)).max()
        det = np.linalg.det(frame)
        if err > 1e-6 or np.any(det < 0):
            raise InputError("tangents", "t1, t2 and the inward normal −n must form a "
                             "right-handed orthonormal frame at every pair")
    return nrm, tan, -nrm


def _stiffness(mesh, elem, materials, element_body, element, formulation):
    """Block-diagonal stiffness of all bodies (one assembly per material), N/m."""
    materials = [tuple(map(float, m)) for m in materials]
    if not materials:
        raise InputError("materials", "give at least one (E, nu)")
    for k, (E, nu) in enumerate(materials):
        if not (E > 0 and 0 <= nu < 0.5):
            raise InputError("materials", f"body {k}: need E > 0 and 0 ≤ ν < 0.5, got "
                             f"({E:g}, {nu:g})")
    nel = mesh.t.shape[1]
    eb = np.zeros(nel, int) if element_body is None else np.asarray(element_body)
    if eb.shape != (nel,) or eb.min() < 0 or eb.max() >= len(materials):
        raise InputError("element_body", f"must give for each of the {nel} elements an "
                         f"index into materials (0…{len(materials) - 1})")
    K, forms = None, []
    # P1: the strains are constant in each tetrahedron, so one quadrature point integrates
    # the stiffness exactly (the same matrix as the default four points, 3× less work)
    quad = {"intorder": 1} if element == "P1" else {}
    for k, (E, nu) in enumerate(materials):
        idx = np.flatnonzero(eb == k)
        if idx.size == 0:
            continue
        form = default_formulation(element, nu) if formulation == "auto" else formulation
        forms.append(form)
        whole = idx.size == nel
        basis = Basis(mesh, elem, **quad) if whole else Basis(mesh, elem, elements=idx,
                                                              **quad)
        Kk = stiffness(basis, E, nu, 1.0, form)
        K = Kk if K is None else K + Kk
    return K.tocsr(), forms


def reduce_contact_3d(mesh: MeshTet, *, materials: Sequence, pairs, normals,
                      fixed, element_body=None, tangents=None, gap=None,
                      cases: Sequence[Case3D] = (), element: str = "P1",
                      formulation: str = "auto", source: str = "",
                      block: int = 256) -> ReducedStiffness:
    """Condense tetrahedral elastic bodies onto N contact pairs (conventions: module doc).

    Parameters
    ----------
    mesh : skfem.MeshTet
        All bodies, m; bodies touch only through the contact pairs (or share nodes where
        they are bonded).
    materials : sequence of (E, nu)
        Young's modulus (Pa) and Poisson's ratio of each body.
    pairs : array_like of int, shape (N, 2)
        Node of body 1 and the coincident node of body 2 (−1: rigid counter-surface), as
        indices into :func:`mesh_nodes`.
    normals : array_like, shape (3,) or (N, 3)
        Outward unit normal of body 1 at each pair.
    fixed : array_like of bool, shape (n_nodes, 3)
        Held displacement components (x, y, z) of every node (zero unless a case
        prescribes them); must hold every body against rigid motion together with the
        pairs held at v = w = 0.
    element_body : array_like of int, shape (n_elements,), optional
        Index into ``materials`` of each tetrahedron (default all 0).
    tangents : array_like, shape (2, 3) or (N, 2, 3), optional
        t1, t2 of each pair; default :func:`~slipcycle.io.fe_formats.dofmap.node_frames`.
    gap : array_like, shape (N,), optional
        Initial gap g (m); default 0.
    cases : sequence of Case3D
        Basic load cases (forces and/or prescribed displacements of held components).
    element : str
        ``"P1"`` (linear tetrahedra; consistent nodal contact forces are positive, the
        choice for node-to-node friction) or ``"P2"``.
    formulation : str
        ``"displacement"``, ``"mixed"`` or ``"auto"`` (mixed for P2 with ν > 0.4).
    source : str
        Provenance text.
    block : int
        Right-hand sides per block should the condensation fall back to block solves.

    Returns
    -------
    ReducedStiffness
        A (2N, 2N), B (N, 2N), C (N, N) (N/m), ``tangential_dims`` 2, ``nodes`` the body-1
        node indices, coordinates (N, 3) of the body-1 nodes (m), ``normals`` (N, 3)
        (outward of body 1), ``tangents`` (N, 2, 3), ``loads`` {case: {"q": (2N,),
        "p": (N,)}} per unit of each case plus ``gap`` (N), p compressive positive.

    Raises
    ------
    slipcycle.errors.InputError
        Malformed arguments (named), a contact node that is held, or a node in two pairs.
    slipcycle.condensation.SingularModelError
        A body is not held against rigid motion with the pairs held.
    """
    _check_element(element)
    if formulation not in ("displacement", "mixed", "auto"):
        raise InputError("formulation", "must be 'displacement', 'mixed' or 'auto', got "
                         f"{formulation!r}")
    elem = ElementVector(ELEMENTS_3D[element]())
    basis = Basis(mesh, elem)
    dofs, xyz = node_dofs_3d(basis)

    def assemble():
        K, forms = _stiffness(mesh, elem, materials, element_body, element, formulation)
        return K, f"{element}/{'+'.join(sorted(set(forms)))}"

    return condense_contact_3d(assemble, dofs, xyz, pairs=pairs, normals=normals,
                               fixed=fixed, tangents=tangents, gap=gap, cases=cases,
                               source=source, block=block)


def condense_contact_3d(assemble: Callable, dofs: np.ndarray, xyz: np.ndarray, *, pairs,
                        normals, fixed, tangents=None, gap=None,
                        cases: Sequence[Case3D] = (), source: str = "",
                        block: int = 256) -> ReducedStiffness:
    """Condense an assembled 3-D stiffness onto N contact pairs (conventions: module doc).

    The engine of :func:`reduce_contact_3d`, for any element whose stiffness is assembled
    elsewhere (:func:`slipcycle.fe.hex8i.hex8i_stiffness`).

    Parameters
    ----------
    assemble : callable
        ``assemble() -> (K, label)``: the global stiffness (sparse, (n, n), N/m) and the
        element's name for the provenance; called once the arguments are checked.
    dofs : numpy.ndarray of int, shape (n_nodes, 3)
        DOF indices (x, y, z) of every node.
    xyz : numpy.ndarray, shape (3, n_nodes)
        Node coordinates, m.
    pairs, normals, fixed, tangents, gap, cases, source, block
        As in :func:`reduce_contact_3d`.

    Returns
    -------
    ReducedStiffness
        As :func:`reduce_contact_3d`.
    """
    t0 = time.perf_counter()
    n_nodes = dofs.shape[0]
    n = int(dofs.max()) + 1
    pairs = np.asarray(pairs)
    if pairs.ndim != 2 or pairs.shape[1] != 2 or pairs.shape[0] == 0 \
            or not np.issubdtype(pairs.dtype, np.integer):
        raise InputError("pairs", f"must be an (N, 2) integer array, got shape {pairs.shape}")
    N = pairs.shape[0]
    c1, c2 = pairs[:, 0], pairs[:, 1]
    if c1.min() < 0 or pairs.max() >= n_nodes or c2.min() < -1:
        raise InputError("pairs", f"node indices must lie in 0…{n_nodes - 1} (body 2 may "
                         "be −1)")
    used = np.concatenate([c1, c2[c2 >= 0]])
    if np.unique(used).size != used.size:
        raise InputError("pairs", "a node appears in two pairs or on both sides of one")
    nrm, tan, e = _frames(normals, tangents, N)
    g = np.zeros(N) if gap is None else np.asarray(gap, float)
    if g.shape != (N,) or not np.all(np.isfinite(g)):
        raise InputError("gap", f"must be {N} finite numbers (m)")
    held_mask = np.asarray(fixed, bool)
    if held_mask.shape != (n_nodes, 3):
        raise InputError("fixed", f"must be a boolean array of shape ({n_nodes}, 3)")
    if held_mask[c1].any():
        raise InputError("fixed", "a body-1 contact node is also held")
    K, label = assemble()

    # u = T z + u0, z = [y; v (2N, node-major); w − g (N)] (fe.reduction.transformation)
    status = np.zeros(n, np.int8)                 # 0 own, 1 held, 3 body-1 contact
    held = dofs[held_mask]
    status[held] = 1
    status[dofs[c1].ravel()] = 3
    own = np.flatnonzero(status == 0)
    col = np.full(n, -1)
    col[own] = np.arange(own.size)
    n_y = own.size
    rows, cols, vals = [own], [col[own]], [np.ones(own.size)]
    source_of = np.full(n, -1)                    # dof whose prescribed value u0 copies
    source_of[held] = held
    jv = n_y + 2 * np.arange(N)
    jw = n_y + 2 * N + np.arange(N)
    has2 = c2 >= 0
    for comp in range(3):
        r1 = dofs[c1, comp]
        rows += [r1, r1, r1]
        cols += [jv, jv + 1, jw]
        vals += [tan[:, 0, comp], tan[:, 1, comp], e[:, comp]]
        d2 = dofs[c2[has2], comp]
        st = status[d2]
        rows.append(r1[has2][st == 0])
        cols.append(col[d2[st == 0]])
        vals.append(np.ones(int(np.sum(st == 0))))
        source_of[r1[has2][st == 1]] = d2[st == 1]
    T = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n, n_y + 3 * N))
    Kp = (T.T @ K @ T).tocsr()
    F = np.zeros((Kp.shape[0], len(cases)))
    names = set()
    for k, case in enumerate(cases):
        if case.name == "gap" or case.name in names:
            raise InputError("cases", f"duplicate or reserved case name {case.name!r}")
        names.add(case.name)
        f = np.zeros(n)
        if case.force is not None:
            fn = np.asarray(case.force, float)
            if fn.shape != (n_nodes, 3):
                raise InputError(f"cases.{case.name}.force",
                                 f"must have shape ({n_nodes}, 3)")
            np.add.at(f, dofs.ravel(), fn.ravel())
        if case.displacement is not None:
            un = np.asarray(case.displacement, float)
            if un.shape != (n_nodes, 3):
                raise InputError(f"cases.{case.name}.displacement",
                                 f"must have shape ({n_nodes}, 3)")
            u_all = np.zeros(n)
            u_all[dofs.ravel()] = un.ravel()
            u0 = np.zeros(n)
            has = source_of >= 0
            u0[has] = u_all[source_of[has]]
            f -= K @ u0
        F[:, k] = T.T @ f
    t1 = time.perf_counter()
    S, r = schur_complement(Kp, n_y, F, block=block)
    t2 = time.perf_counter()
    A, B, C = S[:2 * N, :2 * N], S[2 * N:, :2 * N], S[2 * N:, 2 * N:]
    loads = {case.name: {"q": r[:2 * N, k].copy(), "p": r[2 * N:, k].copy()}
             for k, case in enumerate(cases)}
    loads["gap"] = {"q": -(B.T @ g), "p": -(C @ g)}
    info = (f"{source} [{label}, {n} dofs, {N} contact "
            f"pairs, assembly {t1 - t0:.2f} s, condensation {t2 - t1:.2f} s]")
    return ReducedStiffness(A=A.copy(), B=B.copy(), C=C.copy(), tangential_dims=2,
                            nodes=c1.copy(), coordinates=xyz[:, c1].T.copy(),
                            normals=nrm, tangents=tan, loads=loads, source=info.strip())
