"""Three-dimensional bodies read from mesh files (``slipcycle.fe.meshfile3d``).

Specification:
- a tetrahedral mesh written to a Gmsh file with physical surfaces reduces to the same
  A, B, C and load cases as the generated block reduced directly (one engine:
  ``reduce_contact_3d``), P1 and P2;
- a uniform traction's consistent nodal forces have its resultant and its moment (P1,
  P2);
- the initial gap of a tilted contact surface is its height along the flat's normal above
  the lowest contact node (recovered exactly from the ``gap`` case, p = −C g);
- the tributary areas of the contact nodes sum to the contact area;
- ``slipcycle reduce`` writes the reduced model and a discrete3d case that
  ``slipcycle run`` and ``slipcycle.run`` solve to the same dissipation, and
  ``slipcycle run`` of the model file itself gives the same numbers with the verdict of
  its (one-mesh) study;
- every mistake in the model file ends in one line naming the key, exit code 2, and no
  output left behind.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

meshio = pytest.importorskip("meshio")

from skfem import MeshTet  # noqa: E402

from slipcycle.fe.meshfile3d import MeshSolid, node_areas, read_mesh_solid, reduce_mesh_solid  # noqa: E402
from slipcycle.fe.solid3d import TOP_CASES, reduce_on_rigid_flat  # noqa: E402

E, NU = 210e9, 0.3
LX, LY, H = 0.02, 0.01, 0.008


def box(nx=4, ny=3, nz=2, tilt=0.0) -> MeshTet:
    """A box [0, LX] × [0, LY] × [0, H] of tetrahedra; ``tilt`` lifts the base z = tilt·x
    (the top stays flat)."""
    m = MeshTet.init_tensor(np.linspace(0, LX, nx + 1), np.linspace(0, LY, ny + 1),
                            np.linspace(0, H, nz + 1))
    p = m.p.copy()
    p[2] += tilt * p[0] * (1 - p[2] / H)
    return MeshTet(p, m.t)


def faces_on(mesh: MeshTet, where) -> np.ndarray:
    """(k, 3) vertex triples of the boundary faces whose centroids satisfy ``where``."""
    f = mesh.facets[:, mesh.boundary_facets()]
    c = mesh.p[:, f].mean(axis=1)
    return f[:, where(c)].T


def write_msh(path, mesh: MeshTet, surfaces: dict) -> None:
    """The mesh as a Gmsh 2.2 file: physical volume 99 "body", one physical surface per
    entry of ``surfaces`` (name → (k, 3) triangles), numbered 1, 2, ..."""
    cells, phys = [("tetra", mesh.t.T)], [np.full(mesh.t.shape[1], 99)]
    field = {"body": np.array([99, 3])}
    for k, (name, tri) in enumerate(surfaces.items(), start=1):
        cells.append(("triangle", tri))
        phys.append(np.full(len(tri), k))
        field[name] = np.array([k, 2])
    meshio.write(path, meshio.Mesh(mesh.p.T, cells, cell_data={
        "gmsh:physical": phys, "gmsh:geometrical": phys}, field_data=field),
        file_format="gmsh22", binary=False)


@pytest.mark.parametrize("element", ["P1", "P2"])
def test_mesh_file_reduction_equals_the_generated_block(tmp_path, element):
    mesh = box()
    ref = reduce_on_rigid_flat(mesh, E=E, nu=NU, element=element,
                               contact=lambda x: np.abs(x[2]) < 1e-12,
                               top=lambda x: np.abs(x[2] - H) < 1e-12)
    write_msh(tmp_path / "box.msh", mesh, {
        "base": faces_on(mesh, lambda c: np.abs(c[2]) < 1e-12),
        "top": faces_on(mesh, lambda c: np.abs(c[2] - H) < 1e-12)})
    read, surfaces = read_mesh_solid(tmp_path / "box.msh", {"contact": "base", "top": "top"})
    loads = tuple({"name": name, "boundary": "top", "displacement": move}
                  for name, _, move in TOP_CASES)
    red, area = reduce_mesh_solid(MeshSolid(read, surfaces, E, NU, np.array([0, 0, 1.0]),
                                            loads=loads, element=element))
    scale = np.abs(ref.A).max()
    for k in ("A", "B", "C"):
        assert np.abs(getattr(red, k) - getattr(ref, k)).max() < 1e-10 * scale, k
    assert np.allclose(red.coordinates, ref.coordinates, atol=1e-15)
    assert np.allclose(red.tangents, ref.tangents) and np.allclose(red.normals, ref.normals)
    for name in ("normal", "tangential", "tangential2", "gap"):
        for part in ("p", "q"):
            assert np.abs(red.loads[name][part] - ref.loads[name][part]).max() \
                <= 1e-10 * scale, (name, part)
    assert area.sum() == pytest.approx(LX * LY, rel=1e-12) and np.all(area > 0)


def test_a_rotated_body_in_millimetres_on_a_flat_normal_to_x_reduces_alike(tmp_path):
    """The box turned by (x, y, z) → (z, x, y), written in mm (scale 1e-3), on a flat x = 0
    (normal [1, 0, 0]): the default frames (t1 = y, t2 = z) are the turned t1 = x, t2 = y,
    the node order is the same, so A, B, C and the load cases must be the same numbers."""
    mesh = box()
    base = {"base": faces_on(mesh, lambda c: np.abs(c[2]) < 1e-12),
            "top": faces_on(mesh, lambda c: np.abs(c[2] - H) < 1e-12)}
    loads = ({"name": "normal", "boundary": "top", "displacement": (0, 0, -1)},
             {"name": "shear", "boundary": "top", "displacement": (1, 0, 0)})
    turned_loads = ({"name": "normal", "boundary": "top", "displacement": (-1, 0, 0)},
                    {"name": "shear", "boundary": "top", "displacement": (0, 1, 0)})
    write_msh(tmp_path / "box.msh", mesh, base)
    write_msh(tmp_path / "turned.msh", MeshTet(1e3 * mesh.p[[2, 0, 1]], mesh.t), base)
    reds = []
    for name, normal, specs, scale in (("box", (0, 0, 1.0), loads, 1.0),
                                       ("turned", (1.0, 0, 0), turned_loads, 1e-3)):
        read, surfaces = read_mesh_solid(tmp_path / f"{name}.msh",
                                         {"contact": "base", "top": "top"}, scale=scale)
        reds.append(reduce_mesh_solid(MeshSolid(read, surfaces, E, NU, np.array(normal),
                                                loads=specs, element="P1"))[0])
    ref, red = reds
    scale = np.abs(ref.A).max()
    for k in ("A", "B", "C"):
        assert np.abs(getattr(red, k) - getattr(ref, k)).max() < 1e-9 * scale, k
    for case in ("normal", "shear", "gap"):
        for part in ("p", "q"):
            assert np.abs(red.loads[case][part] - ref.loads[case][part]).max() \
                <= 1e-9 * scale, (case, part)
    assert np.allclose(red.tangents[:, 0], [0, 1, 0]) and np.allclose(red.tangents[:, 1],
                                                                      [0, 0, 1])
    assert np.allclose(red.coordinates, ref.coordinates[:, [2, 0, 1]], atol=1e-15)


@pytest.mark.parametrize("element", ["P1", "P2"])
def test_traction_forces_are_consistent_resultant_and_moment(element):
    """Σ f = t · area and Σ x f = t · ∫x dA for a uniform traction t on the top face."""
    from skfem import Basis, ElementVector

    from slipcycle.fe.contact3d import ELEMENTS_3D, node_dofs_3d
    from slipcycle.fe.meshfile3d import _traction_forces

    mesh = box()
    bf = mesh.boundary_facets()
    top = bf[np.all(np.abs(mesh.p[2, mesh.facets[:, bf]] - H) < 1e-12, axis=0)]
    basis = Basis(mesh, ElementVector(ELEMENTS_3D[element]()))
    dofs, xyz = node_dofs_3d(basis)
    t = np.array([0.3, -1.0, 2.0])
    f = _traction_forces(basis, dofs, top, t)
    assert f.sum(axis=0) == pytest.approx(t * LX * LY, rel=1e-12)
    assert (xyz[0][:, None] * f).sum(axis=0) == pytest.approx(t * LX * LY * LX / 2,
                                                             rel=1e-12)
    assert np.abs(f[np.abs(xyz[2] - H) > 1e-12]).max() < 1e-14 * LX * LY


@pytest.mark.parametrize("element", ["P1", "P2"])
def test_tributary_areas_sum_to_the_contact_area(element):
    mesh = box(5, 2, 1)
    bf = mesh.boundary_facets()
    base = bf[np.all(np.abs(mesh.p[2, mesh.facets[:, bf]]) < 1e-12, axis=0)]
    a = node_areas(mesh, base, element)
    assert a.sum() == pytest.approx(LX * LY, rel=1e-12)
    on = a > 0
    nv = mesh.p.shape[1]
    assert np.all(np.abs(mesh.p[2, np.flatnonzero(on[:nv])]) < 1e-12)


MODEL = """
model = "fe"
[fe]
geometry = "mesh"
element = "P1"
[fe.mesh]
file = "box.msh"
contact = "base"
clamped = []
E = 210e9
nu = 0.3
scale = 1.0
[[fe.load_case]]
name = "normal"
boundary = "top"
displacement = [0, 0, -1]
[[fe.load_case]]
name = "tangential"
boundary = "top"
displacement = [1, 0, 0]
[fe.discrete]
friction = 0.3
cycles = 80
steps_per_cycle = 24
[fe.discrete.mean]
normal = 1e-6
[fe.discrete.amplitude]
tangential = 6e-7
"""


@pytest.fixture
def box_model(tmp_path):
    mesh = box()
    write_msh(tmp_path / "box.msh", mesh, {
        "base": faces_on(mesh, lambda c: np.abs(c[2]) < 1e-12),
        "top": faces_on(mesh, lambda c: np.abs(c[2] - H) < 1e-12),
        "side": faces_on(mesh, lambda c: np.abs(c[0]) < 1e-12)})
    (tmp_path / "box.toml").write_text(MODEL)
    return tmp_path


def test_reduce_writes_a_discrete3d_case_that_run_and_the_python_api_solve_alike(
        run_cli, box_model):
    import slipcycle

    d = box_model
    code, out, err = run_cli("reduce", d / "box.toml", "--out", d / "box.npz",
                             "--case", d / "case.toml")
    assert code == 0, err
    text = (d / "case.toml").read_text()
    assert 'model = "discrete3d"' in text and 'file_case = "gap"' in text
    code, out, err = run_cli("run", d / "case.toml", "--out", d / "run")
    assert code == 0, err
    summary = json.loads((d / "run" / "summary.json").read_text())
    assert summary["steady_state"] == "cyclic_slip"
    assert summary["dissipation_per_cycle"] > 0
    assert abs(summary["energy_balance_error"]) < 1e-6
    assert sum(summary["dissipation_per_node"]) == pytest.approx(
        summary["dissipation_per_cycle"], rel=1e-12)
    res = slipcycle.run(d / "case.toml")
    assert res.dissipation_per_cycle == summary["dissipation_per_cycle"]


@pytest.mark.parametrize("edit, key", [
    (('contact = "base"', 'contact = "nowhere"'), "fe.mesh.contact"),
    (('clamped = []', 'clamped = ["side", "base"]'), "fe.mesh.clamped"),
    (('displacement = [0, 0, -1]', 'displacement = [0, -1]'), "displacement"),
    (('[fe.mesh]', 'thickness = 0.01\n[fe.mesh]'), "fe.thickness"),
    (('file = "box.msh"', 'file = "missing.msh"'), "fe.mesh.file"),
    (('scale = 1.0', 'scale = 1.0\nnormal = [0, 0, -1]'), "fe.mesh.normal"),
])
def test_mistakes_in_a_3d_mesh_model_end_in_one_line_naming_the_key(run_cli, box_model,
                                                                    edit, key):
    d = box_model
    (d / "box.toml").write_text(MODEL.replace(*edit))
    code, out, err = run_cli("reduce", d / "box.toml", "--out", d / "box.npz",
                             "--case", d / "case.toml")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and key in lines[0] and "Traceback" not in err
    assert not (d / "box.npz").exists() and not (d / "case.toml").exists()


def test_run_of_the_model_file_equals_reduce_then_run_and_warns_of_one_mesh(run_cli,
                                                                           box_model):
    """`slipcycle run model.toml` reduces and solves in one go: the same numbers as the
    discrete3d case `slipcycle reduce --case` writes, with the mesh study's verdict."""
    d = box_model
    assert run_cli("reduce", d / "box.toml", "--out", d / "box.npz",
                   "--case", d / "case.toml")[0] == 0
    assert run_cli("run", d / "case.toml", "--out", d / "two")[0] == 0
    code, out, err = run_cli("run", d / "box.toml", "--out", d / "one")
    assert code == 0, err
    one = json.loads((d / "one" / "summary.json").read_text())
    two = json.loads((d / "two" / "summary.json").read_text())
    assert one["model"] == "fe" and one["steady_state_class"] == "cyclic_slip"
    assert one["dissipation_per_cycle"] == two["dissipation_per_cycle"] > 0
    assert one["dissipation_per_node"] == two["dissipation_per_node"]
    assert one["cycles_run"] == two["cycles_run"]
    assert one["dissipation_mesh_converged"] is None
    assert "WARNING: mesh convergence of the dissipation not assessed (one mesh; run " \
           "finer meshes of your own" in one["message"]
    assert one["node_spacing"] == pytest.approx(np.sqrt(LX * LY / 20), rel=1e-12)
    assert (d / "one" / "figures" / "mesh_convergence.png").exists()


def test_a_triangle_that_is_not_a_face_of_the_tetrahedra_is_refused(tmp_path):
    from slipcycle.io.case import CaseError

    mesh = box()
    write_msh(tmp_path / "bad.msh", mesh, {"base": np.array([[0, 1, mesh.p.shape[1] - 1]])})
    with pytest.raises(CaseError, match="not faces of the tetrahedra"):
        read_mesh_solid(tmp_path / "bad.msh", {"contact": "base"})


def test_the_documented_3d_mesh_model_is_the_one_tested_here():
    import re
    import tomllib
    from pathlib import Path

    doc = (Path(__file__).parents[1] / "docs" / "fe.md").read_text()
    section = doc.split("### Three-dimensional mesh files", 1)[1]
    block = re.search(r"```toml\n(.*?)```", section, re.S).group(1)
    shown, tested = tomllib.loads(block), tomllib.loads(MODEL)
    for k in ("clamped", "scale"):      # defaults, spelled out in the test
        del tested["fe"]["mesh"][k]
    assert shown == tested


def test_a_contact_surface_too_fine_for_memory_is_refused_before_the_reduction(
        run_cli, box_model, monkeypatch):
    """20 contact nodes need 4 · 8 · (3 · 20)² B ≈ 115 kB; a 100 kB budget refuses them."""
    d = box_model
    monkeypatch.setenv("SLIPCYCLE_MEMORY_LIMIT", "100kB")
    code, out, err = run_cli("reduce", d / "box.toml", "--out", d / "box.npz",
                             "--case", d / "case.toml")
    assert code == 2 and "fe.mesh.contact" in err and "20 contact nodes" in err
    assert len(err.strip().splitlines()) == 1
    assert not (d / "box.npz").exists() and not (d / "case.toml").exists()


def test_shakedown_of_a_3d_mesh_model_dissipates_nothing(run_cli, box_model):
    """f = 0.6: every node sticks in the steady cycle; the FE result reports D = 0 (as on
    2-D meshes), not the solver's round-off."""
    d = box_model
    (d / "box.toml").write_text(MODEL.replace("friction = 0.3", "friction = 0.6"))
    code, out, err = run_cli("run", d / "box.toml", "--out", d / "run")
    assert code == 0, err
    s = json.loads((d / "run" / "summary.json").read_text())
    assert s["steady_state_class"] == "shakedown"
    assert s["dissipation_per_cycle"] == 0.0 and s["dissipation_mesh_values"] == [0.0]


def test_a_sweep_of_a_3d_mesh_model_stores_what_run_gives(run_cli, box_model):
    import xarray as xr

    d = box_model
    code, out, err = run_cli("sweep", d / "box.toml", "--set", "fe.discrete.friction=0.25,0.3",
                             "--out", d / "sweep", "--workers", "1", "--no-progress")
    assert code == 0, err
    with xr.open_dataset(d / "sweep" / "result.nc") as ds:
        stored = ds["dissipation_per_cycle"].values.tolist()
    for f, value in zip((0.25, 0.3), stored, strict=True):
        (d / f"f{f}.toml").write_text(MODEL.replace("friction = 0.3", f"friction = {f}"))
        assert run_cli("run", d / f"f{f}.toml", "--out", d / f"run{f}")[0] == 0
        s = json.loads((d / f"run{f}" / "summary.json").read_text())
        assert value == s["dissipation_per_cycle"] > 0


@settings(max_examples=25, deadline=None)
@given(nx=st.integers(1, 5), ny=st.integers(1, 4), tilt=st.floats(0.0, 0.2),
       scale=st.sampled_from([1.0, 1e-3]))
@example(nx=4, ny=3, tilt=0.01, scale=1.0)
def test_gap_and_areas_of_any_tilted_box_in_any_unit(tmp_path_factory, nx, ny, tilt, scale):
    """Whatever the mesh, the base's tilt and the file's unit: the gap case holds the
    height of each contact node above the lowest along the flat's normal, and the
    tributary areas sum to the base's area (√(1 + tilt²) L_x L_y)."""
    tmp = tmp_path_factory.mktemp("box")
    mesh = box(nx, ny, 1, tilt=tilt)
    write_msh(tmp / "b.msh", MeshTet(mesh.p / scale, mesh.t), {
        "base": faces_on(mesh, lambda c: np.abs(c[2] - tilt * c[0]) < 1e-12),
        "top": faces_on(mesh, lambda c: np.abs(c[2] - H) < 1e-12)})
    read, surfaces = read_mesh_solid(tmp / "b.msh", {"contact": "base", "top": "top"},
                                     scale=scale)
    red, area = reduce_mesh_solid(MeshSolid(read, surfaces, E, NU, np.array([0, 0, 1.0]),
                                            loads=({"name": "normal", "boundary": "top",
                                                    "displacement": (0, 0, -1)},),
                                            element="P1"))
    g = -np.linalg.solve(red.C, red.loads["gap"]["p"])
    x, z = red.coordinates[:, 0], red.coordinates[:, 2]
    assert np.abs(z - tilt * x).max() < 1e-12 * LX
    assert np.abs(g - tilt * x).max() <= 1e-9 * max(tilt, 1e-3) * LX
    assert area.sum() == pytest.approx(np.sqrt(1 + tilt**2) * LX * LY, rel=1e-12)
    assert red.n_nodes == (nx + 1) * (ny + 1)


def test_a_flat_on_the_wrong_side_is_refused_by_run_and_nothing_is_written(run_cli,
                                                                         box_model):
    """The box lies above z = 0: a flat normal [0, 0, -1] points away from it (the gaps
    and normal loads would change sign and every node stay open). `run` refuses it in one
    line naming fe.mesh.normal; the right normal [0, 0, 1] runs."""
    d = box_model
    (d / "box.toml").write_text(MODEL.replace("scale = 1.0", "scale = 1.0\nnormal = [0, 0, -1]"))
    code, out, err = run_cli("run", d / "box.toml", "--out", d / "run")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "fe.mesh.normal" in lines[0], err
    assert "points away from the body" in lines[0] and "Traceback" not in err
    assert not (d / "run").exists()
    (d / "box.toml").write_text(MODEL.replace("scale = 1.0", "scale = 1.0\nnormal = [0, 0, 1]"))
    code, out, err = run_cli("run", d / "box.toml", "--out", d / "run")
    assert code == 0, err
    assert json.loads((d / "run" / "summary.json").read_text())["dissipation_per_cycle"] > 0


def _rotation(axis, angle) -> np.ndarray:
    """Rodrigues rotation matrix (3, 3) about the unit ``axis`` by ``angle`` (rad)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


@settings(max_examples=40, deadline=None)
@given(axis=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
       # tilt · LX < H: at tilt = H / LX = 0.4 the base meets the top at x = LX (the end
       # face collapses onto the base plane), beyond it the tetrahedra there invert
       angle=st.floats(-np.pi, np.pi), tilt=st.floats(0.0, 0.3), flip=st.booleans())
@example(axis=(1, 0, 0), angle=np.pi, tilt=0.0, flip=False)
@example(axis=(0, 1, 0), angle=np.pi / 2, tilt=0.3, flip=True)
def test_the_flat_side_check_accepts_the_rotated_normal_and_refuses_its_reverse(
        axis, angle, tilt, flip):
    """A box on its (tilted) base, turned by any rotation R: the flat's normal into the
    body is R e_z, accepted; its reverse −R e_z is refused under the key ``normal``. The
    tetrahedra's vertex order (either orientation) does not matter."""
    from slipcycle.errors import InputError
    from slipcycle.fe.meshfile3d import check_flat_side

    mesh = box(3, 2, 1, tilt=tilt)
    R = _rotation(axis, angle)
    turned = MeshTet(R @ mesh.p, mesh.t[[0, 2, 1, 3]] if flip else mesh.t)
    bf = turned.boundary_facets()
    on = mesh.p[:, turned.facets[:, bf]]  # the vertices' unturned coordinates
    base = bf[np.all(np.abs(on[2] - tilt * on[0]) < 1e-12, axis=0)]
    assert base.size == 2 * 3 * 2
    check_flat_side(turned, base, R @ [0, 0, 1.0])
    with pytest.raises(InputError) as info:
        check_flat_side(turned, base, -(R @ [0, 0, 1.0]))
    assert info.value.key == "normal"


@pytest.mark.parametrize("command", ["reduce", "run"])
def test_a_triangle_only_mesh_with_3d_coordinates_is_refused_as_having_no_volume_elements(
        run_cli, tmp_path, command):
    """The triangulated skin of the box (no tetrahedra, z varies) with the 3-D model's
    loads: one line naming fe.mesh.file that says the mesh has no volume elements (it was
    blamed on the shape of fe.load_case[0].displacement); nothing written. The Python
    reader of plane meshes refuses it alike."""
    from slipcycle.fe.meshfile import read_mesh_body
    from slipcycle.io.case import CaseError

    mesh = box()
    skin = mesh.facets[:, mesh.boundary_facets()].T
    base = faces_on(mesh, lambda c: np.abs(c[2]) < 1e-12)
    top = faces_on(mesh, lambda c: np.abs(c[2] - H) < 1e-12)
    meshio.write(tmp_path / "box.msh", meshio.Mesh(
        mesh.p.T, [("triangle", skin), ("triangle", base), ("triangle", top)],
        cell_data={"gmsh:physical": [np.full(len(skin), 9), np.full(len(base), 1),
                                     np.full(len(top), 2)],
                   "gmsh:geometrical": [np.full(len(skin), 9), np.full(len(base), 1),
                                        np.full(len(top), 2)]},
        field_data={"base": np.array([1, 2]), "top": np.array([2, 2])}),
        file_format="gmsh22", binary=False)
    (tmp_path / "box.toml").write_text(MODEL)
    out = ("--out", tmp_path / "o.npz", "--case", tmp_path / "c.toml") \
        if command == "reduce" else ("--out", tmp_path / "run")
    code, _, err = run_cli(command, tmp_path / "box.toml", *out)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: fe.mesh.file:"), err
    assert "no 3-D (volume) elements" in lines[0] and "load_case" not in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.msh", "box.toml"]
    with pytest.raises(CaseError, match="no 3-D"):
        read_mesh_body(tmp_path / "box.msh", {"contact": "1"}, E, NU)
