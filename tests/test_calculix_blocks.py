"""CalculiX's real stiffness export against slipcycle's own reduction of the same mesh.

For each element type (C3D4, C3D8, C3D8I, C3D10) a 10 × 10 × 5 mm steel block and a lap of
two plates (C3D8I) are written as CalculiX decks from the meshes slipcycle assembles
itself, run through ``ccx`` (``*FREQUENCY, SOLVER=MATRIXSTORAGE``), and read back:

- the full stiffness of the ``.sti`` / ``.dof`` equals slipcycle's assembly
  (:func:`slipcycle.fe.assembly.stiffness` on P1/P2 tetrahedra and trilinear hexahedra,
  :func:`slipcycle.fe.hex8i.hex8i_stiffness` for incompatible modes) to 1e-10;
- the contact blocks A, B, C read with :func:`~slipcycle.io.matrices.read_reduced_stiffness`
  (contact nodes named, top face clamped in the deck) and every load case (the top face or
  the grip moved, condensed by :func:`~slipcycle.fe.contact3d.condense_contact_3d` from
  ccx's K) equal slipcycle's own reduction to 1e-10; so do A, B, C and the load cases of
  ``slipcycle reduce``'s pipeline (:mod:`slipcycle.fe_import`, the deck and its ``.sti``);
- a periodic run of both reductions ends in the same steady-state class with the same
  dissipation per cycle (1e-8).

The same comparison for a tetrahedral deck read by meshio (Abaqus ``.inp`` format,
:func:`~slipcycle.fe.meshfile3d.read_mesh_solid`). Skipped where ``ccx`` is not installed.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp
from calculix import run_ccx
from skfem import Basis, ElementHex1, ElementVector, MeshHex, MeshTet

from slipcycle.discrete3d import FrictionalSystem3D, Load3D
from slipcycle.discrete3d.case import solve_model
from slipcycle.fe.assembly import stiffness
from slipcycle.fe.contact3d import (
    ELEMENTS_3D,
    Case3D,
    condense_contact_3d,
    node_dofs_3d,
)
from slipcycle.fe.hex8i import hex8i_stiffness
from slipcycle.fe.meshfile3d import MeshSolid, read_mesh_solid, reduce_mesh_solid
from slipcycle.fe_import import import_joint, read_import_model
from slipcycle.io.fe_formats import abaqus
from slipcycle.io.matrices import read_reduced_stiffness

E, NU, RHO, FRICTION = 210e9, 0.3, 7800.0, 0.5
SIZE = (0.01, 0.01, 0.005)
RTOL = 1e-10
#: ccx's local vertex order of a hexahedron (bottom counter-clockwise, then top)
_HEX = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                 [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])
#: ccx's C3D10 mid-side nodes 5..10 on the edges (1,2) (2,3) (3,1) (1,4) (2,4) (3,4)
_TET10_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))


# -- meshes in slipcycle's numbering and their decks ----------------------------------------
def _grid(n=(3, 3, 1), size=SIZE, origin=(0.0, 0.0, 0.0)):
    return [np.linspace(o, o + s, k + 1) for o, s, k in zip(origin, size, n, strict=True)]


def _hexes(mesh: MeshHex) -> np.ndarray:
    """Vertices of each box (m, 8) in ccx's order, from its corners' coordinates."""
    t = mesh.t.T
    out = np.empty_like(t)
    for e, v in enumerate(t):
        X = mesh.p[:, v].T
        rel = (X > X.mean(axis=0)).astype(int)
        for k, corner in enumerate(_HEX):
            out[e, k] = v[np.flatnonzero((rel == corner).all(axis=1))[0]]
    return out


def _tets(mesh: MeshTet, element: str) -> np.ndarray:
    """Nodes of each tetrahedron in ccx's order (positive volume; C3D10 mid-sides as
    slipcycle numbers them: vertices, then the edges of ``mesh.edges``)."""
    t = mesh.t.T.copy()
    X = mesh.p.T
    vol = np.einsum("ij,ij->i", X[t[:, 1]] - X[t[:, 0]],
                    np.cross(X[t[:, 2]] - X[t[:, 0]], X[t[:, 3]] - X[t[:, 0]]))
    t[vol < 0, 1], t[vol < 0, 2] = t[vol < 0, 2], t[vol < 0, 1].copy()
    if element == "P1":
        return t
    nv = mesh.p.shape[1]
    edge = {tuple(sorted(e)): nv + k for k, e in enumerate(mesh.edges.T.tolist())}
    mids = [[edge[tuple(sorted((int(c[a]), int(c[b]))))] for a, b in _TET10_EDGES]
            for c in t]
    return np.hstack([t, np.array(mids)])


def _deck(xyz: np.ndarray, cells: list, sets: dict, step: str) -> str:
    """A ccx deck: nodes (label = index + 1), element blocks ``[(type, (m, k) nodes,
    material (E, nu))]``, node sets (indices) and a step."""
    out = ["*NODE, NSET=NALL"] + [f"{j + 1}, {x:.17g}, {y:.17g}, {z:.17g}"
                                  for j, (x, y, z) in enumerate(xyz)]
    e = 1
    for k, (etype, conn, (Ek, nuk)) in enumerate(cells):
        out.append(f"*ELEMENT, TYPE={etype}, ELSET=E{k}")
        for c in conn:
            labels = [str(int(j) + 1) for j in c]
            rows = [labels[i:i + 15] for i in range(0, len(labels), 15)]
            out.append(f"{e}, " + ",\n".join(", ".join(r) for r in rows))
            e += 1
        out += [f"*MATERIAL, NAME=M{k}", "*ELASTIC", f"{Ek:.17g}, {nuk:.17g}", "*DENSITY",
                f"{RHO:.17g}", f"*SOLID SECTION, ELSET=E{k}, MATERIAL=M{k}"]
    for name, idx in sets.items():
        lab = [str(int(j) + 1) for j in idx]
        out += [f"*NSET, NSET={name}"] + [", ".join(lab[i:i + 10])
                                          for i in range(0, len(lab), 10)]
    return "\n".join(out) + "\n" + step


CLAMP = "*BOUNDARY\n{held}, 1, 3\n"
STI = "*STEP\n*FREQUENCY, SOLVER=MATRIXSTORAGE\n1\n*END STEP\n"


# -- the two routes ---------------------------------------------------------------------------
def _ccx_K(sti: Path, dofs: np.ndarray) -> sp.csr_matrix:
    """ccx's K of the ``.sti`` in slipcycle's dof numbering (rows of held dofs absent).

    ccx gives each C3D8I three internal nodes of its own (labels above the mesh's) for the
    incompatible modes; they are condensed out here, as slipcycle condenses them element
    by element."""
    raw = abaqus.read(sti, "calculix")
    assert raw.labels is not None and set(raw.labels[:, 1].tolist()) == {1, 2, 3}
    mine = raw.labels[:, 0] <= dofs.shape[0]
    K = raw.K.toarray()
    if not mine.all():
        Kme = K[np.ix_(mine, ~mine)]
        K = K[np.ix_(mine, mine)] - Kme @ np.linalg.solve(K[np.ix_(~mine, ~mine)], Kme.T)
    lab = raw.labels[mine]
    idx = dofs[lab[:, 0] - 1, lab[:, 1] - 1]
    n = int(dofs.max()) + 1
    out = np.zeros((n, n))
    out[np.ix_(idx, idx)] = K
    return sp.csr_matrix(out)


def _reduce(K, dofs, xyz, pairs, normal, held, moved, tangents):
    """Condense K with the ``held`` nodes fixed; one load case per direction of
    ``moved`` (displacement of those held nodes, per metre)."""
    fixed = np.zeros((xyz.shape[1], 3), bool)
    fixed[held] = True
    cases = []
    for name, u in moved.items():
        disp = np.zeros((xyz.shape[1], 3))
        disp[u[0]] = u[1]
        cases.append(Case3D(name, "m", displacement=disp))
    return condense_contact_3d(lambda: (K.tocsr(), "K"), dofs, xyz, pairs=pairs,
                               normals=normal, tangents=tangents, fixed=fixed, cases=cases)


def _close(a, b, what):
    scale = max(np.abs(b).max(), 1e-300)
    assert np.abs(np.asarray(a) - np.asarray(b)).max() <= RTOL * scale, what


def _same_reduction(red, ref, what, rtol=RTOL, names=None):
    for k in ("A", "B", "C"):
        _close(getattr(red, k), getattr(ref, k), f"{what}: {k}")
    if names is None:
        assert set(red.loads) == set(ref.loads)
    for name in names or ref.loads:
        scale = max(np.abs(ref.loads[name]["p"]).max(), np.abs(ref.loads[name]["q"]).max())
        for part in ("q", "p"):
            assert np.abs(red.loads[name][part] - ref.loads[name][part]).max() \
                <= rtol * max(scale, 1e-300), f"{what}: load {name} {part}"


def _permuted(red, pos: np.ndarray) -> SimpleNamespace:
    """A, B, C and loads of ``red`` with its nodes taken in the order ``pos``."""
    t = (2 * pos[:, None] + np.arange(2)).ravel()  # node-major t1, t2
    loads = {k: {"q": v["q"][t], "p": v["p"][pos]} for k, v in red.loads.items()}
    return SimpleNamespace(A=red.A[np.ix_(t, t)], B=red.B[np.ix_(pos, t)],
                           C=red.C[np.ix_(pos, pos)], loads=loads)


PIPELINE = """model = "fe_import"
[[fe_import.body]]
stiffness = "block.sti"
mesh = "block.inp"
contact = "BOTTOM"
[[fe_import.load]]
name = "normal"
nodes = "TOP"
displacement = [0, 0, -1]
[[fe_import.load]]
name = "tangential"
nodes = "TOP"
displacement = [1, 0, 0]
[fe_import.discrete]
friction = 0.5
"""


def _through_pipeline(directory: Path, own, own_nodes: np.ndarray, what: str) -> None:
    """The free deck's export read by ``slipcycle reduce``'s pipeline (contact the node set
    BOTTOM, the top face moved) equals slipcycle's own reduction, node for node."""
    (directory / "model.toml").write_text(PIPELINE)
    red = import_joint(read_import_model(directory / "model.toml")).reduced
    pos = np.searchsorted(own_nodes, red.nodes)
    assert np.array_equal(own_nodes[pos], red.nodes)
    _same_reduction(red, _permuted(own, pos), f"{what} (fe_import)",
                    names=("normal", "tangential"))


def _periodic(red, frac, normal="normal", tangential="tangential"):
    """Steady state of the joint: the normal case (1 µm) held, the tangential case swept
    to Q = ``frac`` f P; (class, dissipation per cycle)."""
    n = red.C.shape[0]
    pn, qn = 1e-6 * red.loads[normal]["p"], 1e-6 * red.loads[normal]["q"]
    qt = red.loads[tangential]["q"]
    scale = frac * FRICTION * pn.sum() / np.abs(qt[0::2].sum())
    system = FrictionalSystem3D(red.A, red.B, red.C, np.full(n, FRICTION),
                                accept_ill_posed=True)
    load = Load3D.harmonic(pn, qn, scale * red.loads[tangential]["p"], scale * qt)
    # steady-state tolerance 1e-10: the dissipation is then settled well below the 1e-8
    # compared (at the default 1e-8 a slow approach stops a cycle apart, 2e-8 off). The
    # residual is measured against the service cycle's displacement: the C3D10 block,
    # creeping by 0.96 per cycle, needs 369 cycles (80 sufficed against the whole load's
    # scale, where it stopped with D 2.5e-5 off its limit)
    res = solve_model(system, load, {"cycles": 400, "steps_per_cycle": 16, "tol": 1e-10},
                      fields=())
    return res.steady_state, res.dissipation_per_cycle


def _agree(red, ref, frac):
    cls, D = _periodic(red, frac)
    cls_ref, D_ref = _periodic(ref, frac)
    assert cls == cls_ref == "cyclic_slip"
    assert D > 0 and D == pytest.approx(D_ref, rel=1e-8)
    return cls, D


# -- one block per element type -----------------------------------------------------------------
#: elements across the block (x, y, z) and Q / f P of the periodic run: small meshes and a
#: load whose periodic state is cyclic slip reached in a few cycles (partial slip on the
#: tetrahedra; gross slip on the hexahedra, whose partial slip at 0.7 f P shakes down)
MESH = {"C3D4": ((3, 3, 1), 0.7), "C3D8": ((2, 2, 1), 1.3), "C3D8I": ((2, 2, 1), 1.3),
        "C3D10": ((1, 1, 1), 0.9)}


def _block(element: str):
    """(slipcycle's K, dofs, xyz, ccx connectivity) of the block."""
    x, y, z = _grid(MESH[element][0])
    if element in ("C3D4", "C3D10"):
        mesh = MeshTet.init_tensor(x, y, z)
        el = "P1" if element == "C3D4" else "P2"
        basis = Basis(mesh, ElementVector(ELEMENTS_3D[el]()))
        dofs, xyz = node_dofs_3d(basis)
        return stiffness(basis, E, NU), dofs, xyz, _tets(mesh, el)
    mesh = MeshHex.init_tensor(x, y, z)
    basis = Basis(mesh, ElementVector(ElementHex1()))
    dofs, xyz = node_dofs_3d(basis)
    hexes = _hexes(mesh)
    K = (stiffness(basis, E, NU) if element == "C3D8"
         else hex8i_stiffness(mesh.p, hexes.T, E, NU))
    return K, dofs, xyz, hexes


@pytest.mark.parametrize("element", ["C3D4", "C3D8", "C3D8I",
                                     pytest.param("C3D10", marks=pytest.mark.slow)])
def test_ccx_block_gives_slipcycles_stiffness_reduction_and_periodic_state(element,
                                                                           tmp_path):
    K, dofs, xyz, conn = _block(element)
    bottom = np.flatnonzero(np.isclose(xyz[2], 0.0))
    bottom = bottom[np.lexsort((xyz[0, bottom], xyz[1, bottom]))]
    top = np.flatnonzero(np.isclose(xyz[2], SIZE[2]))
    sets = {"BOTTOM": bottom, "TOP": top}
    cells = [(element, conn, (E, NU))]
    free = run_ccx(_deck(xyz.T, cells, sets, STI), tmp_path / "free", "block").out(".sti")
    clamped = run_ccx(_deck(xyz.T, cells, sets, CLAMP.format(held="TOP") + STI),
                      tmp_path / "clamped", "block").out(".sti")
    # the full stiffness: ccx's equals slipcycle's assembly of the same mesh
    K_ccx = _ccx_K(free, dofs)
    assert abs(K_ccx - K).max() <= RTOL * abs(K).max()
    # the user's route: the clamped deck's .sti read with its contact nodes named
    red = read_reduced_stiffness(clamped, tangential_dims=2, contact_nodes=bottom + 1,
                                 frames={"normal": [0.0, 0.0, -1.0]})
    assert np.array_equal(red.nodes, np.sort(bottom + 1))
    order = np.searchsorted(np.sort(bottom), bottom)
    pairs = np.column_stack([np.sort(bottom), np.full(bottom.size, -1)])
    moved = {"normal": (top, (0.0, 0.0, -1.0)), "tangential": (top, (1.0, 0.0, 0.0)),
             "tangential2": (top, (0.0, 1.0, 0.0))}
    args = (dofs, xyz, pairs, (0.0, 0.0, -1.0), top, moved, red.tangents)
    own = _reduce(K, *args)
    from_ccx = _reduce(K_ccx, *args)
    for k in ("A", "B", "C"):
        _close(getattr(red, k), getattr(own, k), f"{element}: {k} (.sti read)")
    _same_reduction(from_ccx, own, element)
    _through_pipeline(tmp_path / "free", own, np.sort(bottom), element)
    assert order.size == bottom.size
    _agree(from_ccx, own, MESH[element][1])


# -- two bodies: a lap of two plates --------------------------------------------------------------
def test_ccx_lap_of_two_plates_gives_slipcycles_reduction_and_periodic_state(tmp_path):
    """Plate 1 (x ∈ [0, 20] mm, z ∈ [0, 2] mm) clamped at x = 0, plate 2 (x ∈ [10, 30] mm,
    z ∈ [2, 4] mm) gripped at x = 30 mm; their faces meet node to node on the overlap.
    C3D8I (incompatible modes: plates in bending)."""
    m1 = MeshHex.init_tensor(*_grid((6, 3, 2), (0.02, 0.01, 0.002)))
    m2 = MeshHex.init_tensor(*_grid((6, 3, 2), (0.02, 0.01, 0.002), (0.01, 0.0, 0.002)))
    n1 = m1.p.shape[1]
    p = np.hstack([m1.p, m2.p])
    h1, h2 = _hexes(m1), _hexes(m2) + n1
    K = sp.block_diag([hex8i_stiffness(m1.p, h1.T, E, NU),
                       hex8i_stiffness(m2.p, (h2 - n1).T, E, NU)]).tocsr()
    dofs = np.arange(3 * p.shape[1]).reshape(-1, 3)
    lower = np.flatnonzero(np.isclose(p[2], 0.002) & (p[0] >= 0.01 - 1e-12)
                           & (np.arange(p.shape[1]) < n1))
    upper = np.array([np.flatnonzero(np.all(np.isclose(p[:, n1:], p[:, [j]]), axis=0))[0]
                      + n1 for j in lower])
    clamp = np.flatnonzero(np.isclose(p[0], 0.0))
    grip = np.flatnonzero(np.isclose(p[0], 0.03))
    cells = [("C3D8I", h1, (E, NU)), ("C3D8I", h2, (E, NU))]
    sti = run_ccx(_deck(p.T, cells, {"CLAMP": clamp, "GRIP": grip}, STI), tmp_path,
                  "lap").out(".sti")
    K_ccx = _ccx_K(sti, dofs)
    assert abs(K_ccx - K).max() <= RTOL * abs(K).max()
    pairs = np.column_stack([lower, upper])
    held = np.concatenate([clamp, grip])
    # plate 1's outward normal on its top face is +z; the grip pressed down and pulled
    moved = {"normal": (grip, (0.0, 0.0, -1.0)), "tangential": (grip, (1.0, 0.0, 0.0))}
    # t1, t2 and the inward normal −n = −z right-handed: t1 = x, t2 = −y
    tangents = np.tile([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0]], (lower.size, 1, 1))
    args = (dofs, p, pairs, (0.0, 0.0, 1.0), held, moved, tangents)
    own = _reduce(K, *args)
    # ccx writes the .sti to 14 digits (1.4009971509972e+08); the grip's load cases pass
    # through the bending of the thin plates, which amplifies that rounding to 1.3e-10
    _same_reduction(_reduce(K_ccx, *args), own, "lap", rtol=1e-9)
    # the grip pressing down (−z) pushes plate 2 onto plate 1: compressive p
    assert own.loads["normal"]["p"].sum() > 0
    _agree(_reduce(K_ccx, *args), own, 0.7)


# -- the deck read by meshio (Abaqus .inp) ------------------------------------------------------
def _inp_for_meshio(path: Path, xyz, tets, tri_sets: dict) -> None:
    """The block's tetrahedra and its named surfaces (S3 triangles in element sets), in
    the Abaqus format meshio reads."""
    out = ["*NODE"] + [f"{j + 1}, {x:.17g}, {y:.17g}, {z:.17g}"
                       for j, (x, y, z) in enumerate(xyz.T)]
    out.append("*ELEMENT, TYPE=C3D4, ELSET=SOLID")
    out += [f"{e + 1}, " + ", ".join(str(j + 1) for j in c) for e, c in enumerate(tets)]
    e = len(tets)
    for name, tri in tri_sets.items():
        out.append(f"*ELEMENT, TYPE=S3, ELSET={name}")
        for c in tri:
            e += 1
            out.append(f"{e}, " + ", ".join(str(int(j) + 1) for j in c))
    path.write_text("\n".join(out) + "\n")


def test_ccx_deck_read_by_meshio_reduces_to_the_sti_route(tmp_path):
    x, y, z = _grid(MESH["C3D4"][0])
    mesh = MeshTet.init_tensor(x, y, z)
    xyz = mesh.p
    tets = _tets(mesh, "P1")
    faces = mesh.facets[:, mesh.boundary_facets()]
    on = {name: faces[:, np.all(np.isclose(xyz[2, faces], h), axis=0)].T
          for name, h in (("BOTTOM", 0.0), ("TOP", SIZE[2]))}
    inp = tmp_path / "block.inp"
    _inp_for_meshio(inp, xyz, tets, on)
    m, surfaces = read_mesh_solid(inp, {"contact": "BOTTOM", "top": "TOP"})
    solid = MeshSolid(m, surfaces, E, NU, normal=np.array([0.0, 0.0, 1.0]),
                      loads=({"name": "normal", "boundary": "top",
                              "displacement": (0.0, 0.0, -1.0)},
                             {"name": "tangential", "boundary": "top",
                              "displacement": (1.0, 0.0, 0.0)}),
                      element="P1", formulation="displacement")
    red_mesh, _ = reduce_mesh_solid(solid)
    # the ccx route on the same nodes: the deck's .sti, condensed by slipcycle
    bottom = np.flatnonzero(np.isclose(xyz[2], 0.0))
    top = np.flatnonzero(np.isclose(xyz[2], SIZE[2]))
    sti = run_ccx(_deck(xyz.T, [("C3D4", tets, (E, NU))], {"TOP": top}, STI), tmp_path,
                  "block").out(".sti")
    basis = Basis(mesh, ElementVector(ELEMENTS_3D["P1"]()))
    dofs, _ = node_dofs_3d(basis)
    # node order of the meshio route: by z, then y, then x; its frames
    order = bottom[np.lexsort((xyz[0, bottom], xyz[1, bottom], xyz[2, bottom]))]
    assert np.allclose(xyz[:, order].T, red_mesh.coordinates, rtol=0, atol=1e-15)
    pairs = np.column_stack([order, np.full(order.size, -1)])
    moved = {"normal": (top, (0.0, 0.0, -1.0)), "tangential": (top, (1.0, 0.0, 0.0))}
    from_ccx = _reduce(_ccx_K(sti, dofs), dofs, xyz, pairs, (0.0, 0.0, -1.0), top, moved,
                       red_mesh.tangents)
    ref = red_mesh
    _same_reduction(from_ccx, ref, "meshio .inp")
    _agree(from_ccx, ref, 0.7)
