"""``slipcycle reduce MODEL.toml --out DIR`` of an FE code's export (slipcycle.fe_import),
against real CalculiX output (``ccx``; skipped with the reason where it is absent).

The reference is slipcycle's own reduction of the same mesh: the same nodes, sets and loads
found from the coordinates (not from the deck), the element stiffness assembled by
slipcycle (scikit-fem's trilinear hexahedron for C3D8, :mod:`slipcycle.fe.hex8i` for
C3D8I), condensed by :func:`slipcycle.fe.contact3d.condense_contact_3d`.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from calculix import block_deck, run_ccx  # noqa: E402

import slipcycle  # noqa: E402
from slipcycle.fe.contact3d import Case3D, condense_contact_3d  # noqa: E402
from slipcycle.fe.files import _savez, _stiffness_arrays  # noqa: E402
from slipcycle.fe.model import discrete3d_case_text  # noqa: E402
from slipcycle.fe_import import import_joint, read_import_model, write_import  # noqa: E402
from slipcycle.io.case import CaseError  # noqa: E402

E, NU, SIZE = 210e9, 0.3, (0.01, 0.01, 0.005)
#: the mesh of the periodic runs: 49 contact nodes (the sampled critical friction of
#: discrete3d tries node pairs below about 40 nodes, which takes tens of seconds)
RUN_MESH = (6, 6, 3)

MODEL = """
model = "fe_import"
[[fe_import.body]]
stiffness = "block.sti"
mesh = "block.inp"
contact = "{contact}"
[[fe_import.load]]
name = "normal"
nodes = "TOP"
displacement = [0, 0, -1e-6]
[[fe_import.load]]
name = "tangential"
nodes = "TOP"
displacement = [1e-6, 0, 0]
[[fe_import.load]]
name = "side"
nodes = "SIDE"
force = [2.0, 0.5, -1.0]
[fe_import.discrete]
friction = 0.5
cycles = {cycles}
steps_per_cycle = 40
[fe_import.discrete.mean]
normal = 1.0
[fe_import.discrete.amplitude]
tangential = {amplitude}
"""


def _block(tmp: Path, element: str = "C3D8", n=(4, 4, 2), contact: str = "SBOTTOM",
           cycles: int = 30, amplitude: float = 2.5) -> Path:
    run_ccx(block_deck(*n, size=SIZE, element=element, E=E, nu=NU), tmp, "block")
    path = tmp / "model.toml"
    path.write_text(MODEL.format(contact=contact, cycles=cycles, amplitude=amplitude))
    return path


def _own_reduction(deck: Path, element: str):
    """slipcycle's reduction of the deck's mesh, sets found from the coordinates."""
    from skfem import Basis, ElementHex1, ElementVector
    from skfem.io.meshio import from_meshio

    from slipcycle.fe.assembly import stiffness
    from slipcycle.fe.hex8i import hex8i_stiffness

    m = meshio.read(deck)                      # node k: label k + 1 in block_deck
    hexes = m.cells_dict["hexahedron"]
    xyz = m.points.T.copy()
    n = xyz.shape[1]
    dofs = np.arange(3 * n).reshape(n, 3)
    if element == "C3D8":
        basis = Basis(from_meshio(meshio.Mesh(m.points, [("hexahedron", hexes)])),
                      ElementVector(ElementHex1()))
        assert np.array_equal(basis.nodal_dofs.T, dofs)
        K = stiffness(basis, E, NU)
    else:
        K = hex8i_stiffness(xyz, hexes.T, E, NU)
    eps = 1e-9
    bottom = np.flatnonzero(np.abs(xyz[2]) < eps)
    c = bottom[np.lexsort((xyz[0, bottom], xyz[1, bottom], xyz[2, bottom]))]
    top = np.abs(xyz[2] - SIZE[2]) < eps
    side = (np.abs(xyz[0]) < eps) & ~top & (np.abs(xyz[2]) > eps)
    fixed = np.zeros((n, 3), bool)
    fixed[top] = True
    cases = []
    for name, d in (("normal", (0, 0, -1e-6)), ("tangential", (1e-6, 0, 0))):
        u = np.zeros((n, 3))
        u[top] = d
        cases.append(Case3D(name, "1", displacement=u))
    f = np.zeros((n, 3))
    f[side] = (2.0, 0.5, -1.0)
    cases.append(Case3D("side", "1", force=f))
    return condense_contact_3d(lambda: (K, element), dofs, xyz,
                               pairs=np.column_stack([c, np.full(c.size, -1)]),
                               normals=(0.0, 0.0, -1.0), fixed=fixed, cases=cases)


def _rel(a, b) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


@pytest.mark.parametrize("element", ["C3D8", "C3D8I"])
def test_calculix_sti_import_equals_slipcycles_own_reduction(tmp_path, element):
    joint = import_joint(read_import_model(_block(tmp_path, element)))
    own = _own_reduction(tmp_path / "block.inp", element)
    red = joint.reduced
    for k in "ABC":
        assert _rel(getattr(red, k), getattr(own, k)) < 1e-10, k
    for name in ("normal", "tangential", "side"):
        for part in ("q", "p"):
            assert _rel(red.loads[name][part], own.loads[name][part]) < 1e-10, (name, part)
    assert set(red.loads) == {"normal", "tangential", "side"}
    assert np.allclose(red.coordinates, own.coordinates, rtol=0, atol=1e-15)
    assert np.allclose(red.normals, [0, 0, -1]) and np.allclose(red.tangents, own.tangents)
    # tributary areas of a 4 x 4 grid: corners 1/4, edges 1/2, inside 1 element area
    assert joint.area.sum() == pytest.approx(SIZE[0] * SIZE[1], rel=1e-13)
    assert joint.area.max() == pytest.approx(SIZE[0] * SIZE[1] / 16, rel=1e-13)
    assert joint.area.min() == pytest.approx(SIZE[0] * SIZE[1] / 64, rel=1e-13)


def test_contact_as_node_set_gives_the_surfaces_reduction(tmp_path):
    by_surface = import_joint(read_import_model(_block(tmp_path, contact="SBOTTOM")))
    path = tmp_path / "model.toml"
    path.write_text(path.read_text().replace('"SBOTTOM"', '"BOTTOM"'))
    by_nodes = import_joint(read_import_model(path))
    assert np.array_equal(by_nodes.reduced.A, by_surface.reduced.A)
    assert np.array_equal(by_nodes.area, by_surface.area)


def _own_case_dir(tmp: Path, model_path: Path, own) -> Path:
    """The discrete3d case of the own reduction, with the import's [discrete] table."""
    model = read_import_model(model_path)
    area = import_joint(model).area
    d = tmp / "own"
    d.mkdir()
    _savez(d / "stiffness.npz", _stiffness_arrays(own, {}))
    (d / "case.toml").write_text(discrete3d_case_text(model.discrete, own, "stiffness.npz",
                                                      area, key="fe_import.discrete"))
    return d / "case.toml"


def test_periodic_run_of_import_and_own_reduction_agree(tmp_path):
    path = _block(tmp_path, n=RUN_MESH, cycles=30, amplitude=2.5)
    model = read_import_model(path)
    write_import(model, import_joint(model), tmp_path / "imported")
    own_case = _own_case_dir(tmp_path, path, _own_reduction(tmp_path / "block.inp", "C3D8"))
    a = slipcycle.run(tmp_path / "imported" / "case.toml")
    b = slipcycle.run(own_case)
    assert a.steady_state == b.steady_state == "cyclic_slip"
    assert a.cycles_run == b.cycles_run
    assert a.dissipation_per_cycle > 0
    assert a.dissipation_per_cycle == pytest.approx(b.dissipation_per_cycle, rel=1e-8)


def test_reduce_then_run_writes_fields_at_the_nodes_with_their_areas(tmp_path, run_cli):
    path = _block(tmp_path, n=RUN_MESH, cycles=30, amplitude=2.5)
    code, out, err = run_cli("reduce", path, "--out", tmp_path / "case")
    assert code == 0 and err == "" and "49 contact nodes" in out
    assert sorted(p.name for p in (tmp_path / "case").iterdir()) == [
        "case.toml", "report.txt", "stiffness.npz"]
    report = json.loads((tmp_path / "case" / "report.txt").read_text())
    assert report["contact_nodes"] == 49 and report["bodies"][0]["format"] == "calculix"
    code, out, err = run_cli("-q", "run", tmp_path / "case" / "case.toml", "--out",
                             tmp_path / "run")
    assert code == 0, err
    joint = import_joint(read_import_model(path))
    vtu = sorted((tmp_path / "run" / "fields").glob("interface_*.vtu"))
    assert vtu
    m = meshio.read(vtu[-1])
    assert np.allclose(m.points, joint.reduced.coordinates, rtol=0, atol=1e-15)
    D = m.point_data["dissipation"]
    assert D.sum() > 0
    np.testing.assert_allclose(m.point_data["dissipation_per_area"] * joint.area, D,
                               rtol=1e-12, atol=1e-30)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["dissipation_per_cycle"] == pytest.approx(D.sum(), rel=1e-9)


# -- every mistake in a model file: one line naming the key, exit 2, nothing written -----------

def _mistake(tmp_path, run_cli, edit) -> str:
    path = _block(tmp_path)
    text = edit(path.read_text(), tmp_path)
    path.write_text(text)
    code, out, err = run_cli("reduce", path, "--out", tmp_path / "out")
    assert code == 2, (code, out, err)
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    return err


def test_missing_set_names_the_key(tmp_path, run_cli):
    err = _mistake(tmp_path, run_cli, lambda t, _: t.replace('"TOP"\ndisplacement = [0',
                                                              '"TOPP"\ndisplacement = [0'))
    assert "fe_import.load[0].nodes" in err and "'TOPP'" in err and "TOP" in err


def test_contact_set_not_on_the_surface_is_refused(tmp_path, run_cli):
    def edit(t, tmp):
        deck = tmp / "block.inp"
        deck.write_text(deck.read_text().replace("*MATERIAL", "*NSET, NSET=MIXED\n1, 2, 40\n"
                                                 "*MATERIAL"))
        return t.replace('contact = "SBOTTOM"', 'contact = "MIXED"')

    err = _mistake(tmp_path, run_cli, edit)
    assert "fe_import.body[0].contact" in err and "not on a face" in err


def test_load_on_a_contact_node_is_refused(tmp_path, run_cli):
    err = _mistake(tmp_path, run_cli, lambda t, _: t.replace('nodes = "SIDE"',
                                                              'nodes = "BOTTOM"'))
    assert "fe_import.load[2].nodes" in err and "contact node" in err


def test_clamp_on_a_contact_node_is_refused(tmp_path, run_cli):
    err = _mistake(tmp_path, run_cli, lambda t, _: t.replace(
        'contact = "SBOTTOM"', 'contact = "SBOTTOM"\nclamped = ["BOTTOM"]'))
    assert "fe_import.body[0].clamped" in err and "contact node" in err


def test_export_of_another_code_is_refused(tmp_path, run_cli):
    def edit(t, tmp):
        (tmp / "other.npz").write_bytes((tmp / "block.inp").read_bytes()[:0])
        np.savez(tmp / "other.npz", A=np.eye(2), B=np.zeros((2, 2)), C=np.eye(2))
        return t.replace('"block.sti"', '"other.npz"')

    err = _mistake(tmp_path, run_cli, edit)
    assert "fe_import.body[0].stiffness" in err and "other.npz" in err


def test_export_of_another_mesh_is_refused(tmp_path, run_cli):
    def edit(t, tmp):
        run_ccx(block_deck(2, 2, 1), tmp / "small", "small")
        return t.replace('"block.sti"', '"small/small.sti"')

    err = _mistake(tmp_path, run_cli, edit)
    assert "fe_import.body[0].stiffness" in err and "small.sti" in err


def test_truncated_export_is_refused(tmp_path, run_cli):
    def edit(t, tmp):
        sti = tmp / "block.sti"
        lines = sti.read_text().splitlines()
        sti.write_text("\n".join(lines[: len(lines) // 2]) + "\n")
        return t

    err = _mistake(tmp_path, run_cli, edit)
    assert "fe_import.body[0].stiffness" in err and "block.sti" in err


def test_deck_with_boundary_on_a_moved_set_is_refused(tmp_path, run_cli):
    def edit(t, tmp):
        deck = tmp / "block.inp"
        deck.write_text(deck.read_text().replace("*STEP", "*BOUNDARY\nTOP, 1, 3\n*STEP"))
        run_ccx(deck.read_text(), tmp, "block")
        return t

    err = _mistake(tmp_path, run_cli, edit)
    assert "fe_import.load[0].nodes" in err and "no row" in err


# -- two bodies: contact surfaces matched node to node ----------------------------------------

TWO = """
model = "fe_import"
[fe_import]
tolerance = 1e-9
[[fe_import.body]]
stiffness = "upper/block.sti"
mesh = "upper/block.inp"
contact = "SBOTTOM"
[[fe_import.body]]
stiffness = "lower/block.sti"
mesh = "lower/block.inp"
contact = "STOP"
clamped = ["BOTTOM"]
[[fe_import.load]]
name = "normal"
nodes = "TOP"
displacement = [0, 0, -1e-6]
[[fe_import.load]]
name = "pull"
body = 2
nodes = "SIDE"
force = [3.0, 0.0, 0.0]
[fe_import.discrete]
friction = 0.5
"""


def _two_blocks(tmp: Path, shift: float = 0.0) -> Path:
    run_ccx(block_deck(3, 3, 2, size=SIZE, E=E, nu=NU), tmp / "upper", "block")
    run_ccx(block_deck(3, 3, 2, size=(0.01, 0.01, 0.003), E=E, nu=NU,
                       origin=(shift, 0.0, -0.003)), tmp / "lower", "block")
    (tmp / "model.toml").write_text(TWO)
    return tmp / "model.toml"


def test_two_bodies_equal_the_condensation_of_both_meshes(tmp_path):
    from skfem import Basis, ElementHex1, ElementVector
    from skfem.io.meshio import from_meshio

    from slipcycle.fe.assembly import stiffness

    red = import_joint(read_import_model(_two_blocks(tmp_path))).reduced
    meshes = [meshio.read(tmp_path / d / "block.inp") for d in ("upper", "lower")]
    Ks = [stiffness(Basis(from_meshio(meshio.Mesh(m.points, [("hexahedron",
                                                               m.cells_dict["hexahedron"])])),
                          ElementVector(ElementHex1())), E, NU) for m in meshes]
    import scipy.sparse as sp

    xyz = np.vstack([m.points for m in meshes]).T
    n1, n = len(meshes[0].points), xyz.shape[1]
    z = xyz[2]
    c1 = np.flatnonzero((np.arange(n) < n1) & (np.abs(z) < 1e-12))
    c2 = np.flatnonzero((np.arange(n) >= n1) & (np.abs(z) < 1e-12))
    c1 = c1[np.lexsort((xyz[0, c1], xyz[1, c1]))]
    c2 = c2[np.lexsort((xyz[0, c2], xyz[1, c2]))]
    fixed = np.zeros((n, 3), bool)
    top = (np.arange(n) < n1) & (np.abs(z - SIZE[2]) < 1e-12)
    fixed[top] = True
    fixed[(np.arange(n) >= n1) & (np.abs(z + 0.003) < 1e-12)] = True
    u = np.zeros((n, 3))
    u[top] = (0, 0, -1e-6)
    f = np.zeros((n, 3))
    f[(np.arange(n) >= n1) & (np.abs(xyz[0]) < 1e-12) & (z < -1e-12) & (z > -0.003 + 1e-12)] \
        = (3.0, 0, 0)
    own = condense_contact_3d(lambda: (sp.block_diag(Ks, format="csr"), "hex1"),
                              np.arange(3 * n).reshape(n, 3), xyz,
                              pairs=np.column_stack([c1, c2]), normals=(0, 0, -1.0),
                              fixed=fixed, cases=[Case3D("normal", "1", displacement=u),
                                                  Case3D("pull", "1", force=f)])
    for k in "ABC":
        assert _rel(getattr(red, k), getattr(own, k)) < 1e-10, k
    for name in ("normal", "pull"):
        for part in ("q", "p"):
            assert _rel(red.loads[name][part], own.loads[name][part]) < 1e-10, (name, part)


def test_two_bodies_that_do_not_match_name_the_first_unmatched_node(tmp_path, run_cli):
    path = _two_blocks(tmp_path, shift=1e-6)
    code, _, err = run_cli("reduce", path, "--out", tmp_path / "out")
    assert code == 2 and err.count("\n") == 1 and not (tmp_path / "out").exists()
    assert "fe_import.tolerance" in err and "contact node 1 of body 1" in err \
        and "1e-06 m" in err


# -- tetrahedra, a node-set contact and a pressure: against slipcycle's own mesh-file path -----

_KUHN = ((0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6))


def _tet_deck(n=(3, 3, 3)) -> tuple[str, np.ndarray, np.ndarray]:
    """The hexahedra of block_deck split into six C3D4 each (one diagonal: conforming)."""
    hexdeck = block_deck(*n, size=SIZE, step=None)
    lines = hexdeck.splitlines()
    i0 = next(i for i, ln in enumerate(lines) if ln.startswith("*ELEMENT"))
    i1 = next(i for i, ln in enumerate(lines) if i > i0 and ln.startswith("*"))
    pts = np.array([[float(v) for v in ln.split(",")[1:]]
                    for ln in lines[lines.index("*NODE, NSET=NALL") + 1:i0]])
    hexes = np.array([[int(v) for v in ln.split(",")[1:]] for ln in lines[i0 + 1:i1]])
    tets = np.vstack([hexes[:, list(k)] for k in _KUHN])
    X = pts[tets - 1]
    vol = np.einsum("ij,ij->i", X[:, 1] - X[:, 0],
                    np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]))
    tets[vol < 0, 1], tets[vol < 0, 2] = tets[vol < 0, 2], tets[vol < 0, 1].copy()
    body = ["*ELEMENT, TYPE=C3D4, ELSET=EALL"] + [
        f"{e + 1}, " + ", ".join(map(str, t)) for e, t in enumerate(tets)]
    rest = lines[i1:]
    # the node sets, then the material (the hexahedra's element sets and faces dropped)
    keep = (rest[:next(j for j, ln in enumerate(rest) if ln.startswith("*ELSET"))]
            + rest[rest.index("*MATERIAL, NAME=STEEL"):])
    deck = "\n".join(lines[:i0] + body + keep) + \
        "\n*STEP\n*FREQUENCY, SOLVER=MATRIXSTORAGE\n*END STEP\n"
    return deck, pts, tets - 1


PRESSURE = """
model = "fe_import"
[[fe_import.body]]
stiffness = "block.sti"
mesh = "block.inp"
contact = "BOTTOM"
[[fe_import.load]]
name = "normal"
nodes = "TOP"
displacement = [0, 0, -1e-6]
[[fe_import.load]]
name = "press"
surface = "SIDE"
pressure = 1e6
[fe_import.discrete]
friction = 0.5
"""


def test_c3d4_pressure_and_areas_equal_the_mesh_file_reduction(tmp_path):
    from skfem import MeshTet

    from slipcycle.fe.meshfile3d import MeshSolid, reduce_mesh_solid

    deck, pts, tets = _tet_deck()
    run_ccx(deck, tmp_path, "block")
    (tmp_path / "model.toml").write_text(PRESSURE)
    joint = import_joint(read_import_model(tmp_path / "model.toml"))
    mesh = MeshTet(np.ascontiguousarray(pts.T), np.ascontiguousarray(tets.T))
    f = mesh.p[:, mesh.facets]                                 # (3, 3, nf)
    h = SIZE[2] / 3

    def facets(pred):
        return np.flatnonzero(pred(f).all(axis=0))

    surfaces = {"contact": facets(lambda x: np.abs(x[2]) < 1e-12),
                "top": facets(lambda x: np.abs(x[2] - SIZE[2]) < 1e-12),
                "side": facets(lambda x: (np.abs(x[0]) < 1e-12) & (x[2] > h - 1e-12)
                               & (x[2] < SIZE[2] - h + 1e-12))}
    solid = MeshSolid(mesh, surfaces, E, NU, np.array([0.0, 0.0, 1.0]), loads=(
        {"name": "normal", "boundary": "top", "displacement": (0.0, 0.0, -1e-6)},
        {"name": "press", "boundary": "side", "traction": (1e6, 0.0, 0.0)}),
        element="P1", formulation="displacement")
    own, area = reduce_mesh_solid(solid)
    red = joint.reduced
    assert np.allclose(red.coordinates, own.coordinates, rtol=0, atol=1e-15)
    for k in "ABC":
        assert _rel(getattr(red, k), getattr(own, k)) < 1e-10, k
    for name in ("normal", "press"):
        for part in ("q", "p"):
            assert _rel(red.loads[name][part], own.loads[name][part]) < 1e-10, (name, part)
    np.testing.assert_allclose(joint.area, area, rtol=1e-12)
    assert joint.area.sum() == pytest.approx(SIZE[0] * SIZE[1], rel=1e-13)


def test_gmsh_mesh_with_physical_groups_gives_the_decks_reduction(tmp_path):
    """The same tetrahedra as a Gmsh file (node k has label k + 1), the contact, the
    pressed wall and the moved grip as physical groups of triangles, give the deck's
    reduction."""
    deck, pts, tets = _tet_deck()
    run_ccx(deck, tmp_path, "block")
    (tmp_path / "model.toml").write_text(PRESSURE)
    by_deck = import_joint(read_import_model(tmp_path / "model.toml"))
    faces = np.vstack([tets[:, [0, 1, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 3]],
                       tets[:, [1, 2, 3]]])
    X = pts[faces]
    h = SIZE[2] / 3
    bottom = faces[np.all(np.abs(X[..., 2]) < 1e-12, axis=1)]
    side = faces[np.all((np.abs(X[..., 0]) < 1e-12) & (X[..., 2] > h - 1e-12)
                        & (X[..., 2] < SIZE[2] - h + 1e-12), axis=1)]
    top = faces[np.all(np.abs(X[..., 2] - SIZE[2]) < 1e-12, axis=1)]
    tags = [np.zeros(len(tets), int), np.full(len(bottom), 1), np.full(len(side), 2),
            np.full(len(top), 3)]
    mesh = meshio.Mesh(pts, [("tetra", tets), ("triangle", bottom), ("triangle", side),
                             ("triangle", top)],
                       cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                       field_data={"contact": np.array([1, 2]), "wall": np.array([2, 2]),
                                   "grip": np.array([3, 2])})
    mesh.write(tmp_path / "block.msh", file_format="gmsh22", binary=False)
    text = PRESSURE.replace('"block.inp"', '"block.msh"').replace('"BOTTOM"', '"contact"')
    text = text.replace('"TOP"', '"grip"').replace('"SIDE"', '"wall"')
    (tmp_path / "gmsh.toml").write_text(text)
    by_gmsh = import_joint(read_import_model(tmp_path / "gmsh.toml"))
    for k in "ABC":
        assert _rel(getattr(by_gmsh.reduced, k), getattr(by_deck.reduced, k)) < 1e-12, k
    for name in ("normal", "press"):
        for part in ("q", "p"):
            assert _rel(by_gmsh.reduced.loads[name][part],
                        by_deck.reduced.loads[name][part]) < 1e-12, (name, part)
    np.testing.assert_allclose(by_gmsh.area, by_deck.area, rtol=1e-12)


def test_deck_in_millimetres_gives_the_si_decks_reduction(tmp_path):
    si = import_joint(read_import_model(_block(tmp_path / "si")))
    mm = tmp_path / "mm"
    run_ccx(block_deck(4, 4, 2, size=(10.0, 10.0, 5.0), E=E * 1e-6, nu=NU, density=7.8e-9),
            mm, "block")
    text = (tmp_path / "si" / "model.toml").read_text()
    (mm / "model.toml").write_text(text.replace('contact = "SBOTTOM"',
                                                'contact = "SBOTTOM"\nunits = "mm"'))
    got = import_joint(read_import_model(mm / "model.toml"))
    for k in "ABC":
        assert _rel(getattr(got.reduced, k), getattr(si.reduced, k)) < 1e-10, k
    for name in ("normal", "tangential", "side"):
        for part in ("q", "p"):
            assert _rel(got.reduced.loads[name][part], si.reduced.loads[name][part]) < 1e-10
    np.testing.assert_allclose(got.reduced.coordinates, si.reduced.coordinates, rtol=1e-14,
                               atol=1e-18)
    np.testing.assert_allclose(got.area, si.area, rtol=1e-12)


# -- the other codes' export formats carry the same K ----------------------------------------

def _export(fmt: str, tmp: Path, K, labels) -> str:
    import fe_export_writers as w

    if fmt == "abaqus":
        return w.abaqus_matrix_input(tmp / "job_STIF1.mtx", K, labels).name
    if fmt == "harwell-boeing":
        return w.harwell_boeing(tmp / "block.rsa", K, labels).name
    if fmt == "matlab":
        return w.matlab_v5(tmp / "block.mat", K, labels).name
    if fmt == "nastran-dmig":
        return w.nastran_dmig_punch(tmp / "block.pch", K, labels).name
    order = np.lexsort((labels[:, 1], labels[:, 0]))          # x, y, z node by node
    return w.matrix_market(tmp / "block_mm.mtx", K[np.ix_(order, order)]).name


@pytest.mark.parametrize(("fmt", "digits"), [("abaqus", 1e-12), ("harwell-boeing", 1e-10),
                                              ("matlab", 1e-12), ("nastran-dmig", 1e-8),
                                              ("matrix-market", 1e-12)])
def test_other_codes_exports_of_the_same_k_give_the_same_reduction(tmp_path, fmt, digits):
    """The ccx stiffness written in each code's layout (tests/fe_export_writers.py, written
    independently of the readers): the same A, B, C and load cases, to the digits each
    layout stores."""
    from slipcycle.io.fe_formats import read_raw

    path = _block(tmp_path)
    ref = import_joint(read_import_model(path))
    raw = read_raw(tmp_path / "block.sti", "calculix", None)
    K = raw.K.toarray()
    name = _export(fmt, tmp_path, K, np.asarray(raw.labels))
    path.write_text(path.read_text().replace('"block.sti"', f'"{name}"'))
    got = import_joint(read_import_model(path))
    for k in "ABC":
        assert _rel(getattr(got.reduced, k), getattr(ref.reduced, k)) < digits, k
    for case in ("normal", "tangential", "side"):
        for part in ("q", "p"):
            assert _rel(got.reduced.loads[case][part], ref.reduced.loads[case][part]) < digits


def test_calculix_substructure_export_is_refused_naming_the_sti_route(tmp_path, run_cli):
    """CalculiX 2.20's *SUBSTRUCTURE MATRIX OUTPUT is the uncondensed block of the retained
    dofs (issue 30): refused in one line that names the .sti route."""
    path = _block(tmp_path)
    deck = block_deck(4, 4, 2, size=SIZE, E=E, nu=NU, step=None) + (
        "*BOUNDARY\nTOP, 1, 3\n*STEP\n*SUBSTRUCTURE GENERATE\n*RETAINED NODAL DOFS\n"
        "BOTTOM, 1, 3\n*SUBSTRUCTURE MATRIX OUTPUT, STIFFNESS=YES, OUTPUT FILE=USER DEFINED, "
        "FILE NAME=sub\n*END STEP\n")
    run_ccx(deck, tmp_path / "sub", "sub")
    path.write_text(path.read_text().replace('"block.sti"', '"sub/sub.mtx"'))
    code, _, err = run_cli("reduce", path, "--out", tmp_path / "out")
    assert code == 2 and err.count("\n") == 1 and not (tmp_path / "out").exists()
    assert "fe_import.body[0].stiffness" in err and "sub.mtx" in err and ".sti" in err


def test_abaqus_substructure_of_contact_and_grip_nodes_gives_the_sti_reduction(tmp_path):
    """A condensed export of the retained contact and grip nodes (Abaqus *SUBSTRUCTURE
    GENERATE, written as its user element; here the Schur complement of the ccx K) supplies
    A, B, C and the grip's load cases; a force on a node it does not hold is refused."""
    import fe_export_writers as w

    from slipcycle.fe_import.mesh import read_deck
    from slipcycle.io.fe_formats import read_raw

    path = _block(tmp_path)
    text = path.read_text()
    path.write_text(text[:text.index("[[fe_import.load]]\nname = \"side\"")]
                    + text[text.index("[fe_import.discrete]"):])
    ref = import_joint(read_import_model(path))
    raw = read_raw(tmp_path / "block.sti", "calculix", None)
    K, labels = raw.K.toarray(), np.asarray(raw.labels)
    mesh = read_deck(tmp_path / "block.inp", "mesh")
    keep = set(mesh.labels[np.concatenate([mesh.node_sets["BOTTOM"], mesh.node_sets["TOP"]])])
    b = np.flatnonzero([lab in keep for lab in labels[:, 0]])
    i = np.setdiff1d(np.arange(len(K)), b)
    S = K[np.ix_(b, b)] - K[np.ix_(b, i)] @ np.linalg.solve(K[np.ix_(i, i)], K[np.ix_(i, b)])
    w.abaqus_user_element(tmp_path / "sub.mtx", 0.5 * (S + S.T), labels[b])
    path.write_text(path.read_text().replace('"block.sti"', '"sub.mtx"'))
    got = import_joint(read_import_model(path))
    for k in "ABC":
        assert _rel(getattr(got.reduced, k), getattr(ref.reduced, k)) < 1e-9, k
    for case in ("normal", "tangential"):
        for part in ("q", "p"):
            assert _rel(got.reduced.loads[case][part], ref.reduced.loads[case][part]) < 1e-9
    path.write_text(path.read_text() + '[[fe_import.load]]\nname = "side"\nnodes = "SIDE"\n'
                    'force = [1.0, 0.0, 0.0]\n')
    with pytest.raises(CaseError, match=r"fe_import.load\[2\].nodes: node \d+ of 'SIDE' has "
                                        "no row in the export"):
        import_joint(read_import_model(path))


def test_out_must_be_a_directory(tmp_path, run_cli):
    path = _block(tmp_path)
    code, _, err = run_cli("reduce", path, "--out", tmp_path / "reduced.npz")
    assert code == 2 and err.count("\n") == 1 and "--out" in err and "directory" in err
    assert not (tmp_path / "reduced.npz").exists()


def test_deck_of_shell_elements_is_refused_naming_the_line(tmp_path, run_cli):
    def edit(t, tmp):
        deck = tmp / "block.inp"
        deck.write_text(deck.read_text().replace("TYPE=C3D8,", "TYPE=S4,"))
        return t

    err = _mistake(tmp_path, run_cli, edit)
    assert "fe_import.body[0].mesh" in err and "block.inp, line" in err and "S4" in err


def test_truncated_deck_is_refused(tmp_path, run_cli):
    def edit(t, tmp):
        deck = tmp / "block.inp"
        text = deck.read_text()
        cut = text.index("*NSET, NSET=BOTTOM")
        deck.write_text(text[:cut - 4])          # inside the last element's node list
        return t

    err = _mistake(tmp_path, run_cli, edit)
    assert "fe_import.body[0].mesh" in err and "block.inp" in err
