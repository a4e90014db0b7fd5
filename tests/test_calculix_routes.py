"""A real CalculiX model goes into ``slipcycle reduce`` without hand work, checked against
what ``ccx`` itself computes from the same deck.

Every deck here is run by ``ccx`` (tests/calculix.py; skipped with the reason where it is
absent): the ``*FREQUENCY, SOLVER=MATRIXSTORAGE`` step exports K (``.sti`` + ``.dof``),
slipcycle reduces it onto the contact, and an independent ccx ``*STATIC`` run of the same
mesh is the reference:

- nodal forces F on the contact nodes, the clamp held: ccx's displacements of the contact
  nodes equal K_c⁻¹ F of the reduced stiffness (rotated back to x, y, z), to the 7 digits
  that ccx prints in its ``.dat`` file;
- a ``*DLOAD`` pressure on a face, the contact held: ccx's reaction forces at the contact
  nodes equal the reduction's held-contact reactions p^w, q^w of the same pressure case.

Blocks of every CalculiX solid (C3D4, C3D10, C3D6, C3D15, C3D8, C3D8R, C3D20, C3D20R) are
meshed here by one structured generator (:func:`_mesh`): quadratic elements have their
mid-side nodes, the faces on the block's sides are numbered S1…S6 as in the CalculiX
manual, so the contact lies on faces of every kind (3-, 4-, 6- and 8-node).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).parent))
from calculix import run_ccx  # noqa: E402

from slipcycle.fe_import import import_joint, read_import_model  # noqa: E402

SIZE = (0.01, 0.01, 0.005)
#: ccx prints 7 significant digits in its .dat file: the agreement the comparisons ask for
DAT_RTOL = 1e-5

# 1-based corner nodes of the faces S1, S2, ... (CalculiX manual, §6.2)
_FACES = {"hex": ((1, 2, 3, 4), (5, 8, 7, 6), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 8, 4),
                  (4, 8, 5, 1)),
          "wedge": ((1, 2, 3), (4, 6, 5), (1, 2, 5, 4), (2, 3, 6, 5), (3, 1, 4, 6)),
          "tet": ((1, 2, 3), (1, 4, 2), (2, 4, 3), (3, 4, 1))}
_FAMILY = {"C3D8": "hex", "C3D8R": "hex", "C3D20": "hex", "C3D20R": "hex", "C3D6": "wedge",
           "C3D15": "wedge", "C3D4": "tet", "C3D10": "tet"}
_QUADRATIC = ("C3D20", "C3D20R", "C3D15", "C3D10")
_CUBE = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1),
                  (1, 1, 1), (0, 1, 1)])
_EDGES = {"hex": ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4),
                  (1, 5), (2, 6), (3, 7)),
          "wedge": ((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)),
          "tet": ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))}
#: the six tetrahedra of a cube around its diagonal 0-6 (Kuhn)
_KUHN = ((0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6))


def _mesh(element: str, n=(2, 2, 2), R=None):
    """Nodes (k, 3) and connectivity (1-based, CalculiX order) of a SIZE block of
    ``element``; the index (i, j, k) of each node on the half-spacing lattice."""
    fam = _FAMILY[element]
    lattice: dict = {}
    elements = []
    for iz in range(n[2]):
        for iy in range(n[1]):
            for ix in range(n[0]):
                C = 2 * np.array([ix, iy, iz]) + 2 * _CUBE
                if fam == "hex":
                    cells = [C]
                elif fam == "wedge":
                    cells = [C[[0, 1, 2, 4, 5, 6]], C[[0, 2, 3, 4, 6, 7]]]
                else:
                    cells = []
                    for t in _KUHN:
                        P = C[list(t)]
                        if np.cross(P[1] - P[0], P[2] - P[0]) @ (P[3] - P[0]) < 0:
                            P = P[[0, 2, 1, 3]]
                        cells.append(P)
                for P in cells:
                    pts = list(map(tuple, P))
                    if element in _QUADRATIC:
                        pts += [tuple((P[a] + P[b]) // 2) for a, b in _EDGES[fam]]
                    elements.append([lattice.setdefault(p, len(lattice)) for p in pts])
    index = np.array(list(lattice), float)
    X = index / 2.0 / np.array(n) * np.array(SIZE)
    if R is not None:
        X = X @ np.asarray(R).T
    return X, [[v + 1 for v in e] for e in elements], index.astype(int), np.array(n) * 2


def _deck(element: str, n=(2, 2, 2), R=None, extra: str = "", step: str = "sti",
          loads=(), mm: bool = False) -> tuple[str, np.ndarray]:
    """The deck of :func:`_mesh` with node sets BOTTOM, TOP, XMIN, XMAX, SIDE (x = 0 off
    the bottom) and element-face surfaces SBOTTOM, STOP, SXMIN, SXMAX.

    ``step``: ``"sti"`` exports K; ``"static"`` holds TOP and applies ``loads`` (node, dof,
    force) with the displacements of BOTTOM printed; ``"dload"`` holds BOTTOM and SIDE,
    applies the pressure ``loads`` (Pa) on STOP and prints the reactions of BOTTOM.
    ``mm``: the deck in mm, N, MPa (t/mm³) instead of m, N, Pa.
    """
    X, conn, ijk, top = _mesh(element, n, R)
    X = X * 1e3 if mm else X
    sets = {"BOTTOM": ijk[:, 2] == 0, "TOP": ijk[:, 2] == top[2],
            "XMIN": ijk[:, 0] == 0, "XMAX": ijk[:, 0] == top[0],
            "SIDE": (ijk[:, 0] == 0) & (ijk[:, 2] > 0)}
    lines = ["*HEADING", f"block of {element}", "*NODE, NSET=NALL"]
    # at most 20 characters a field: ccx reads no more
    lines += [f"{i + 1}, {x:.13g}, {y:.13g}, {z:.13g}" for i, (x, y, z) in enumerate(X)]
    lines.append(f"*ELEMENT, TYPE={element}, ELSET=EALL")
    for e, c in enumerate(conn, 1):
        tokens = [str(e)] + [str(v) for v in c]
        rows = [tokens[i:i + 15] for i in range(0, len(tokens), 15)]   # ccx: 16 a line
        lines += [", ".join(r) + ("," if k < len(rows) - 1 else "") for k, r in enumerate(rows)]
    for name, mask in sets.items():
        ids = list(np.flatnonzero(mask) + 1)
        lines += [f"*NSET, NSET={name}"] + [", ".join(map(str, ids[i:i + 10]))
                                            for i in range(0, len(ids), 10)]
    for name in ("BOTTOM", "TOP", "XMIN", "XMAX"):
        on = set((np.flatnonzero(sets[name]) + 1).tolist())
        lines.append(f"*SURFACE, NAME=S{name}, TYPE=ELEMENT")
        lines += [f"{e}, S{s}" for e, c in enumerate(conn, 1)
                  for s, f in enumerate(_FACES[_FAMILY[element]], 1)
                  if all(c[i - 1] in on for i in f)]
    lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC",
              "210000.0, 0.3" if mm else "210000000000.0, 0.3", "*DENSITY",
              "7.8e-09" if mm else "7800.0", "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"]
    if extra:
        lines.append(extra)
    if step == "sti":
        lines += ["*STEP", "*FREQUENCY, SOLVER=MATRIXSTORAGE", "*END STEP"]
    elif step == "static":
        lines += ["*BOUNDARY", "TOP, 1, 3", "*STEP", "*STATIC", "*CLOAD"]
        lines += [f"{nd}, {d}, {v:.13g}" for nd, d, v in loads]
        lines += ["*NODE PRINT, NSET=BOTTOM", "U", "*END STEP"]
    elif step == "dload":
        lines += ["*BOUNDARY", "BOTTOM, 1, 3", "SIDE, 1, 3", "*STEP", "*STATIC", "*DLOAD"]
        stop = lines.index("*SURFACE, NAME=STOP, TYPE=ELEMENT")
        for ln in lines[stop + 1:]:
            if ln.startswith("*"):
                break
            e, s = ln.split(", ")
            lines.append(f"{e}, P{s[1]}, {loads:.13g}")
        lines += ["*NODE PRINT, NSET=BOTTOM", "RF", "*END STEP"]
    return "\n".join(lines) + "\n", X


MODEL = """model = "fe_import"
[[fe_import.body]]
stiffness = "block.sti"
mesh = "block.inp"
contact = "{contact}"
clamped = ["{clamp}"]
{loads}
[fe_import.discrete]
friction = 0.5
"""


def _model(d: Path, contact="SBOTTOM", clamp="TOP", loads="") -> Path:
    path = d / "model.toml"
    path.write_text(MODEL.format(contact=contact, clamp=clamp, loads=loads))
    return path


def _dat(path: Path) -> dict:
    """node → the three values of each ``*NODE PRINT`` line of a ccx ``.dat`` file."""
    out = {}
    for line in path.read_text().splitlines():
        f = line.split()
        if len(f) == 4 and f[0].isdigit():
            out[int(f[0])] = np.array([float(v) for v in f[1:]])
    return out


def _frame(red) -> np.ndarray:
    """P (3N, 3N): global x, y, z of every contact node from the local (v, w) of K."""
    N = red.n_nodes
    P = np.zeros((3 * N, 3 * N))
    for j in range(N):
        P[3 * j:3 * j + 3, 2 * j:2 * j + 2] = red.tangents[j].T
        P[3 * j:3 * j + 3, 2 * N + j] = -red.normals[j]
    return P


def _labels(red, X) -> np.ndarray:
    dist, idx = cKDTree(X).query(red.coordinates)
    assert dist.max() < 1e-12
    return idx + 1


def _compliance_check(tmp: Path, element: str, R=None, extra: str = ""):
    """Reduce the ccx export (contact SBOTTOM, TOP clamped), then compare K_c⁻¹ F with
    ccx's static displacements of the contact under the forces F."""
    text, X = _deck(element, R=R, extra=extra)
    run_ccx(text, tmp, "block")
    joint = import_joint(read_import_model(_model(tmp)))
    red = joint.reduced
    labels = _labels(red, X)
    F = np.random.default_rng(3).standard_normal((red.n_nodes, 3)) * 100.0   # N
    static, _ = _deck(element, R=R, extra=extra, step="static",
                      loads=[(int(k), a + 1, F[i, a]) for i, k in enumerate(labels)
                             for a in range(3)])
    U = _dat(run_ccx(static, tmp / "static", "block").out(".dat"))
    got = np.array([U[int(k)] for k in labels])
    P = _frame(red)
    want = np.linalg.solve(P @ red.K @ P.T, F.ravel()).reshape(-1, 3)
    assert np.linalg.norm(want - got) < DAT_RTOL * np.linalg.norm(got)
    return joint


@pytest.mark.parametrize("element", ["C3D20", "C3D20R", "C3D15", "C3D10", "C3D8R", "C3D6",
                                     "C3D4"])
def test_reduced_stiffness_of_every_solid_gives_ccx_static_displacements(tmp_path, element):
    """C3D20, C3D20R, C3D15 were refused ("not a solid element slipcycle reads"); every
    CalculiX solid's contact compliance now equals ccx's own static solution."""
    joint = _compliance_check(tmp_path, element)
    assert joint.reduced.n_nodes == {"C3D20": 21, "C3D20R": 21, "C3D15": 25,
                                     "C3D10": 25}.get(element, 9)


@pytest.mark.parametrize("element", ["C3D20", "C3D15", "C3D10"])
def test_tributary_areas_of_quadratic_faces_are_positive_and_sum_to_the_face(tmp_path,
                                                                            element):
    """On 8-node (C3D20 sides, C3D15 sides) and 6-node faces the corner integrals of the
    shape functions are negative or zero; the sub-triangle rule gives every node a positive
    area, all of them the face's: 1e-4 m² (bottom) and 5e-5 m² (side x = 0)."""
    run_ccx(_deck(element)[0], tmp_path, "block")
    for contact, clamp, area in (("SBOTTOM", "TOP", 1e-4), ("SXMIN", "XMAX", 5e-5)):
        joint = import_joint(read_import_model(_model(tmp_path, contact, clamp)))
        assert np.all(joint.area > 0)
        assert joint.area.sum() == pytest.approx(area, rel=1e-12)


def test_quad8_face_areas_are_a_24th_at_corners_and_5_24ths_at_mid_points():
    from slipcycle.fe_import.mesh import FaceSet
    from slipcycle.fe_import.surface import face_areas, node_areas, node_normals

    # a 2 × 3 rectangle, tilted out of every plane, with straight edges
    corners = np.array([[0, 0, 0], [2, 0, 0], [2, 3, 0], [0, 3, 0]], float)
    mids = 0.5 * (corners + np.roll(corners, -1, axis=0))
    R = np.linalg.qr(np.random.default_rng(0).standard_normal((3, 3)))[0]
    pts = np.vstack([corners, mids]) @ R.T
    fs = FaceSet("quad8", np.arange(8)[None, :], (pts.mean(axis=0) - R[:, 2])[None, :])
    assert face_areas(pts, fs)[0] == pytest.approx(6.0, rel=1e-12)
    a = node_areas(pts, [fs], np.arange(8))
    np.testing.assert_allclose(a, [6 / 24] * 4 + [6 * 5 / 24] * 4, rtol=1e-12)
    np.testing.assert_allclose(node_normals(pts, [fs], np.arange(8)),
                               np.tile(R[:, 2], (8, 1)), atol=1e-12)


@pytest.mark.parametrize("element", ["C3D20", "C3D15", "C3D10", "C3D8"])
def test_pressure_on_faces_gives_the_reactions_of_ccx_dload(tmp_path, element):
    """A pressure load case on STOP (consistent nodal forces of 8-, 6-, 4-node faces)
    against ccx's *DLOAD of the same pressure: the reactions at the held contact."""
    run_ccx(_deck(element)[0], tmp_path, "block")
    load = '[[fe_import.load]]\nname = "press"\nsurface = "STOP"\npressure = 1e6'
    red = import_joint(read_import_model(_model(tmp_path, "SBOTTOM", "SIDE", load))).reduced
    text, X = _deck(element, step="dload", loads=1e6)
    RF = _dat(run_ccx(text, tmp_path / "dload", "block").out(".dat"))
    rf = np.array([RF[int(k)] for k in _labels(red, X)])
    p = np.einsum("nd,nd->n", rf, -red.normals)
    q = np.einsum("nad,nd->na", red.tangents, rf).ravel()
    scale = np.abs(p).max()
    assert np.abs(red.loads["press"]["p"] - p).max() < DAT_RTOL * scale
    assert np.abs(red.loads["press"]["q"] - q).max() < DAT_RTOL * scale


def _rotation() -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler("xyz", [30.0, -50.0, 70.0], degrees=True).as_matrix()


@pytest.mark.parametrize("element", ["C3D20", "C3D10"])
def test_rotated_block_gives_the_same_contact_stiffness_and_ccx_static(tmp_path, element):
    """The block turned so that its contact normal lies along no axis: the normal block C
    and the spectrum of K are those of the unrotated block (to round-off of K's norm),
    and the compliance is ccx's."""
    R = _rotation()
    flat = _compliance_check(tmp_path / "flat", element).reduced
    turned = _compliance_check(tmp_path / "turned", element, R=R).reduced
    dist, idx = cKDTree(turned.coordinates).query(flat.coordinates @ R.T)
    assert dist.max() < 1e-12
    np.testing.assert_allclose(turned.normals[idx], flat.normals @ R.T, atol=1e-12)
    scale = np.abs(flat.K).max()
    assert np.abs(turned.C[np.ix_(idx, idx)] - flat.C).max() < 1e-10 * scale
    assert np.abs(np.linalg.eigvalsh(turned.K) - np.linalg.eigvalsh(flat.K)).max() \
        < 1e-10 * scale


def test_deck_in_mm_n_mpa_gives_the_si_reduction_and_the_report_says_so(tmp_path):
    """A C3D20 deck in mm, N, MPa with ``units = "mm"``: K (N/mm → N/m), coordinates and
    areas (m²) as from the SI deck; report.txt names the units the deck was read in."""
    run_ccx(_deck("C3D20")[0], tmp_path / "si", "block")
    run_ccx(_deck("C3D20", mm=True)[0], tmp_path / "mm", "block")
    si = import_joint(read_import_model(_model(tmp_path / "si")))
    path = _model(tmp_path / "mm")
    path.write_text(path.read_text().replace('clamped', 'units = "mm"\nclamped'))
    mm = import_joint(read_import_model(path))
    assert np.abs(mm.reduced.K - si.reduced.K).max() < 1e-9 * np.abs(si.reduced.K).max()
    np.testing.assert_allclose(mm.reduced.coordinates, si.reduced.coordinates, atol=1e-15)
    np.testing.assert_allclose(mm.area, si.area, rtol=1e-12)
    assert mm.report["bodies"][0]["units"].startswith("mm, N, MPa")
    assert si.report["bodies"][0]["units"] == "m, N, Pa"


def test_equation_and_transform_on_interior_nodes_are_ccx_constraints(tmp_path):
    """*EQUATION and a *BOUNDARY in a *TRANSFORM frame on interior nodes: ccx eliminates a
    dependent dof (no row in the .sti, K already constrained); the reduction equals ccx's
    static solution of the constrained deck."""
    X, _, ijk, top = _mesh("C3D8")
    mid = np.flatnonzero(ijk[:, 2] == top[2] // 2) + 1
    extra = (f"*EQUATION\n2\n{mid[0]}, 1, 1.0, {mid[-1]}, 2, -0.5\n"
             f"*NSET, NSET=NT\n{mid[1]}\n*TRANSFORM, NSET=NT, TYPE=R\n1., 1., 0., -1., 1., 0.\n"
             "*BOUNDARY\nNT, 1, 1")
    joint = _compliance_check(tmp_path, "C3D8", extra=extra)
    assert joint.report["bodies"][0]["mesh_dofs_without_rows"] == 2


def test_contact_node_constrained_by_an_equation_is_refused_naming_it(tmp_path, run_cli):
    X, _, ijk, _ = _mesh("C3D8")
    node = int(np.flatnonzero((ijk[:, 2] == 0) & (ijk[:, 0] == 2) & (ijk[:, 1] == 2))[0]) + 1
    text, _ = _deck("C3D8", extra=f"*EQUATION\n2\n{node}, 3, 1.0, 1, 3, -1.0")
    run_ccx(text, tmp_path, "block")
    code, out, err = run_cli("reduce", _model(tmp_path), "--out", tmp_path / "out")
    assert code == 2 and err.count("\n") == 1 and not (tmp_path / "out").exists()
    assert err.startswith("error: fe_import.body[0].stiffness:")
    assert f"contact node {node}" in err and "*EQUATION" in err


def test_nonzero_prescribed_displacement_in_the_deck_is_refused_naming_the_line(tmp_path,
                                                                               run_cli):
    """*BOUNDARY with a value: the .sti leaves the dof out and slipcycle could hold it at
    zero only (it was accepted so, silently); a zero value (or none) is a clamp, accepted."""
    X, _, ijk, top = _mesh("C3D8")
    node = int(np.flatnonzero(ijk[:, 2] == top[2] // 2)[0]) + 1
    text, _ = _deck("C3D8", extra=f"*BOUNDARY\n{node}, 1, 1, 1.0e-6")
    run_ccx(text, tmp_path, "block")
    code, out, err = run_cli("reduce", _model(tmp_path), "--out", tmp_path / "out")
    assert code == 2 and err.count("\n") == 1 and not (tmp_path / "out").exists()
    line = text.splitlines().index("*BOUNDARY") + 2
    assert err.startswith(f"error: fe_import.body[0].mesh: block.inp, line {line}: "
                          "*BOUNDARY prescribes 1e-06")
    _compliance_check(tmp_path / "zero", "C3D8", extra=f"*BOUNDARY\n{node}, 1, 3, 0.0")


# -- the files of a failed or partial ccx run --------------------------------------------------

def _refused(run_cli, tmp: Path) -> str:
    code, out, err = run_cli("reduce", tmp / "model.toml", "--out", tmp / "out")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert not (tmp / "out").exists()
    return err


def test_sti_cut_after_a_whole_line_is_refused_naming_it(tmp_path, run_cli):
    """The .sti's last line (the last diagonal entry) lost: its row count still matched the
    .dof and the reduction went through with K[n, n] = 0."""
    run_ccx(_deck("C3D8")[0], tmp_path, "block")
    _model(tmp_path)
    sti = tmp_path / "block.sti"
    sti.write_text("".join(sti.read_text().splitlines(keepends=True)[:-1]))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness: block.sti: K has no diagonal "
                          "entry for node")


def test_sti_without_its_dof_file_is_refused_naming_the_dof_file(tmp_path, run_cli):
    """Without jobname.dof the rows were taken as x, y, z of the mesh nodes in label order
    whenever the count matched: a guess, now refused."""
    run_ccx(_deck("C3D8")[0], tmp_path, "block")
    _model(tmp_path)
    (tmp_path / "block.dof").unlink()
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness: block.sti: block.dof is "
                          "missing beside it")


@pytest.mark.parametrize("name", ["block.dat", "block.sta", "block.12d", "block.frd",
                                  "block.mas", "block.cvg"])
def test_other_files_of_a_ccx_run_named_as_the_stiffness_are_refused(tmp_path, run_cli, name):
    run_ccx(_deck("C3D8")[0], tmp_path, "block")
    path = _model(tmp_path)
    path.write_text(path.read_text().replace('"block.sti"', f'"{name}"'))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness:") and name in err


def test_sti_of_the_deck_before_it_was_edited_is_refused(tmp_path, run_cli):
    """The deck made twice as long after ccx ran (same node labels, other coordinates): the
    stiffness was read on the new coordinates silently; a rigid rotation of the new nodes
    is resisted by the old K, which tells."""
    run_ccx(_deck("C3D8")[0], tmp_path, "block")
    _model(tmp_path)
    text = _deck("C3D8")[0].splitlines()
    start = text.index("*NODE, NSET=NALL") + 1
    for i in range(start, len(text)):
        if text[i].startswith("*"):
            break
        k, x, y, z = text[i].split(", ")
        text[i] = f"{k}, {2 * float(x):.13g}, {y}, {z}"
    (tmp_path / "block.inp").write_text("\n".join(text) + "\n")
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness: block.sti is not the stiffness "
                          "of block.inp's nodes where they are now")


def test_failed_ccx_run_leaves_no_sti_and_is_refused_naming_it(tmp_path, run_cli):
    """A deck without *DENSITY: ccx stops before it writes block.sti."""
    text = _deck("C3D8")[0].replace("*DENSITY\n7800.0\n", "")
    (tmp_path / "block.inp").write_text(text)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    exe = os.environ.get("SLIPCYCLE_CCX") or shutil.which("ccx")
    if exe is None:
        pytest.skip("ccx is not installed")
    subprocess.run([exe, "-i", "block"], cwd=tmp_path, capture_output=True, env=env,
                   timeout=60)
    _model(tmp_path)
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness:") and "block.sti" in err


# -- two bodies of one deck ------------------------------------------------------------------

def _pair_deck(blocks) -> str:
    """C3D8 blocks of 2 × 2 × 2 elements (labels offset by 100; node sets BOT, MID, TOP,
    surfaces SBOT, STOP), stacked at z = 0 when there are two, with a *CONTACT PAIR."""
    lines = ["*HEADING"]
    for name, z0, off in blocks:
        X, conn, ijk, top = _mesh("C3D8", (2, 2, 2))
        X = X + [0.0, 0.0, z0]
        lines.append(f"*NODE, NSET=N{name}")
        lines += [f"{i + 1 + off}, {x:.13g}, {y:.13g}, {z:.13g}" for i, (x, y, z) in enumerate(X)]
        lines.append(f"*ELEMENT, TYPE=C3D8, ELSET=E{name}")
        lines += [", ".join(map(str, [e + 1 + off] + [v + off for v in c]))
                  for e, c in enumerate(conn)]
        for side, k, s in (("BOT", 0, 1), ("MID", top[2] // 2, 0), ("TOP", top[2], 2)):
            lines += [f"*NSET, NSET={name}{side}"] + [str(i + 1 + off) for i in
                                                      np.flatnonzero(ijk[:, 2] == k)]
            if s:                               # S1 of the lower, S2 of the upper layer
                layer = range(4) if s == 1 else range(4, 8)
                lines += [f"*SURFACE, NAME=S{name}{side}"] + [f"{e + 1 + off}, S{s}"
                                                             for e in layer]
    names = ",".join(f"E{b[0]}" for b in blocks)
    lines += [f"*ELSET, ELSET=EALL\n{names}", "*MATERIAL, NAME=STEEL", "*ELASTIC",
              "210000000000.0, 0.3", "*DENSITY", "7800.0",
              "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"]
    if len(blocks) == 2:
        lines += ["*SURFACE INTERACTION, NAME=SI", "*SURFACE BEHAVIOR, "
                  "PRESSURE-OVERCLOSURE=LINEAR", "1e13, 0., 1e6", "*FRICTION", "0.5, 1e10",
                  "*CONTACT PAIR, INTERACTION=SI, TYPE=SURFACE TO SURFACE", "SBTOP, SABOT"]
    lines += ["*STEP", "*FREQUENCY, SOLVER=MATRIXSTORAGE", "*END STEP"]
    return "\n".join(lines) + "\n"


PAIR = """model = "fe_import"
[[fe_import.body]]
stiffness = "{a}.sti"
mesh = "{a}.inp"
contact = "SABOT"
[[fe_import.body]]
stiffness = "{b}.sti"
mesh = "{b}.inp"
contact = "SBTOP"
clamped = ["BBOT"]
[[fe_import.load]]
name = "normal"
nodes = "ATOP"
displacement = [0, 0, -1e-6]
[[fe_import.load]]
name = "push"
body = 2
nodes = "BMID"
force = [0, 1.0, 0]
[[fe_import.load]]
name = "tangential"
nodes = "ATOP"
displacement = [1e-6, 0, 0]
[fe_import.discrete]
friction = 0.5
"""


def test_two_bodies_of_one_deck_reduce_as_the_two_decks(tmp_path, run_cli):
    """Both bodies named from one deck (CalculiX meshes a *CONTACT PAIR so): the export
    was taken twice, each copy with the other body floating, and refused as "not held
    against rigid motion". One K now: the same A, B, C and loads as two decks."""
    run_ccx(_pair_deck([("A", 0.0, 0), ("B", -0.005, 100)]), tmp_path, "pair")
    run_ccx(_pair_deck([("A", 0.0, 0)]), tmp_path, "A")
    run_ccx(_pair_deck([("B", -0.005, 100)]), tmp_path, "B")
    one = tmp_path / "one.toml"
    one.write_text(PAIR.format(a="pair", b="pair"))
    two = tmp_path / "two.toml"
    two.write_text(PAIR.format(a="A", b="B"))
    got = import_joint(read_import_model(one)).reduced
    ref = import_joint(read_import_model(two)).reduced
    for k in "ABC":
        ref_k = getattr(ref, k)
        assert np.abs(getattr(got, k) - ref_k).max() <= 1e-12 * np.abs(ref_k).max()
    for case in ("normal", "push", "tangential"):
        for part in ("p", "q"):
            want = ref.loads[case][part]
            assert np.abs(got.loads[case][part] - want).max() <= 1e-12 * np.abs(want).max()
    # body 2's clamp or load on body 1's contact is refused, as on its own contact
    one.write_text(PAIR.format(a="pair", b="pair").replace('clamped = ["BBOT"]',
                                                           'clamped = ["BBOT", "ABOT"]'))
    err = _refused_model(run_cli, one, tmp_path)
    assert err.startswith("error: fe_import.body[1].clamped: clamped holds contact node")


def _refused_model(run_cli, model: Path, tmp: Path) -> str:
    code, out, err = run_cli("reduce", model, "--out", tmp / "out")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert not (tmp / "out").exists()
    return err
