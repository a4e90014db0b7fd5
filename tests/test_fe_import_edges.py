"""``slipcycle reduce`` of an FE export at the edges of what it reads: loads that load
nothing, an export of a bigger mesh, faces inside the body or named twice, repeated labels,
Abaqus instances, empty sets, unreadable mesh files, coordinates that are not numbers,
faces of no area, the mass matrix given as the stiffness, nested includes, a second body
on the first one's own surface (slipcycle.fe_import).

The stiffness files are CalculiX's (``ccx``; skipped with the reason where it is absent);
a deck edited after ccx ran changes only what slipcycle reads from it (sets, surfaces,
coordinates), which ccx has already turned into the ``.sti``.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import meshio
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from calculix import block_deck, run_ccx  # noqa: E402

from slipcycle.fe_import import import_joint, read_import_model  # noqa: E402
from slipcycle.fe_import.mesh import read_deck  # noqa: E402

SIZE = (0.01, 0.01, 0.005)
N = (3, 3, 2)

MODEL = """
model = "fe_import"
[[fe_import.body]]
stiffness = "block.sti"
mesh = "block.inp"
contact = "SBOTTOM"
[[fe_import.load]]
name = "normal"
nodes = "TOP"
displacement = [0, 0, -1e-6]
[[fe_import.load]]
name = "tangential"
nodes = "TOP"
displacement = [1e-6, 0, 0]
[fe_import.discrete]
friction = 0.5
[fe_import.discrete.mean]
normal = 1.0
[fe_import.discrete.amplitude]
tangential = 1.0
"""


def _block(tmp: Path, n=N) -> Path:
    """ccx's export of a small block, and the model file of the block on a flat."""
    run_ccx(block_deck(*n, size=SIZE), tmp, "block")
    (tmp / "model.toml").write_text(MODEL)
    return tmp / "model.toml"


def _edit_deck(tmp: Path, old: str, new: str, count: int = 1) -> None:
    deck = tmp / "block.inp"
    text = deck.read_text()
    assert old in text
    deck.write_text(text.replace(old, new, count))


def _refused(run_cli, tmp: Path, model: Path | None = None) -> str:
    """The one line of a refused ``reduce``: exit 2, nothing written, no warnings."""
    out = tmp / "out"
    code, stdout, err = run_cli("reduce", model or tmp / "model.toml", "--out", out)
    assert code == 2, (code, stdout, err)
    assert err.count("\n") == 1 and stdout == "" and "Warning" not in err, err
    assert not out.exists()
    return err


# -- load cases that load nothing ------------------------------------------------------------

def test_pressure_on_a_surface_moved_by_another_case_is_refused(tmp_path, run_cli):
    model = _block(tmp_path)
    model.write_text(model.read_text().replace(
        'nodes = "TOP"\ndisplacement = [0, 0, -1e-6]', 'surface = "STOP"\npressure = 1e6'))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.load[0].surface:") and "'STOP'" in err
    assert "held" in err and "no force on the free degrees of freedom" in err


def test_force_on_a_clamped_set_is_refused(tmp_path, run_cli):
    model = _block(tmp_path)
    text = model.read_text().replace('contact = "SBOTTOM"',
                                     'contact = "SBOTTOM"\nclamped = ["TOP"]')
    model.write_text(text.replace("displacement = [0, 0, -1e-6]", "force = [0, 0, -10.0]"))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.load[0].nodes:") and "'TOP'" in err
    assert "no force on the free degrees of freedom" in err


# -- the export and the mesh -------------------------------------------------------------------

def test_export_of_a_bigger_mesh_is_refused(tmp_path, run_cli):
    """The 2 × 2 × 1 deck's node labels are all in the 4 × 4 × 2 export: its other
    nodes' rows are not C3D8I internal nodes (the deck has no C3D8I)."""
    _block(tmp_path, (4, 4, 2))
    (tmp_path / "block.inp").write_text(block_deck(2, 2, 1, size=SIZE))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness: block.sti has rows of ")
    assert "block.inp does not have" in err and "C3D8I" in err


def test_stiffness_named_as_the_mass_matrix_is_refused(tmp_path, run_cli):
    model = _block(tmp_path)
    assert (tmp_path / "block.mas").is_file()          # ccx wrote it with the .sti
    model.write_text(model.read_text().replace('"block.sti"', '"block.mas"'))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness: block.mas is CalculiX's "
                          "mass matrix") and "block.sti" in err


def test_empty_stiffness_name_is_refused_as_empty(tmp_path, run_cli):
    model = _block(tmp_path)
    model.write_text(model.read_text().replace('"block.sti"', '""'))
    err = _refused(run_cli, tmp_path)
    assert err == "error: fe_import.body[0].stiffness: is empty: name the file\n"


def test_zero_stiffness_is_refused_as_zero(tmp_path, run_cli):
    _block(tmp_path)
    sti = tmp_path / "block.sti"
    sti.write_text("".join(f"{ln.split()[0]} {ln.split()[1]} 0.0\n"
                           for ln in sti.read_text().splitlines()))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness:") and "stiffness is zero" in err


def test_stiffness_near_the_largest_float_is_refused_without_warnings(tmp_path, run_cli):
    """numpy's overflow warnings would print around the one line of the refusal."""
    _block(tmp_path)
    sti = tmp_path / "block.sti"
    sti.write_text("".join(f"{ln.split()[0]} {ln.split()[1]} {float(ln.split()[2]) * 1e300!r}\n"
                           for ln in sti.read_text().splitlines()))
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].stiffness:")
    assert [str(w.message) for w in seen if issubclass(w.category, RuntimeWarning)] == []


# -- surfaces ---------------------------------------------------------------------------------

def test_contact_on_faces_inside_the_body_is_refused(tmp_path, run_cli):
    _block(tmp_path)
    _edit_deck(tmp_path, "EBOTTOM, S1", "EBOTTOM, S2")   # the bottom layer's top faces
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].contact: surface 'SBOTTOM': element 1, "
                          "S2 is inside the body")


@pytest.mark.parametrize("twice", [
    "EBOTTOM, S1\nEBOTTOM, S1",                                     # a line repeated
    "EBOTTOM, S1\n*SURFACE, NAME=SBOTTOM, TYPE=ELEMENT\nEBOTTOM, S1",  # a block repeated
], ids=["line", "block"])
def test_a_face_named_twice_is_one_face(tmp_path, twice):
    model = _block(tmp_path)
    once = import_joint(read_import_model(model))
    _edit_deck(tmp_path, "EBOTTOM, S1", twice)
    got = import_joint(read_import_model(model))
    assert got.report["contact_area_m2"] == pytest.approx(SIZE[0] * SIZE[1], rel=1e-12)
    np.testing.assert_allclose(got.area, once.area, rtol=1e-12)


def test_quoted_surface_name_is_the_name_inside_the_quotes(tmp_path):
    model = _block(tmp_path)
    _edit_deck(tmp_path, "NAME=SBOTTOM", 'NAME="SBOTTOM"')
    joint = import_joint(read_import_model(model))
    assert joint.report["contact_nodes"] == (N[0] + 1) * (N[1] + 1)


def test_contact_face_of_zero_area_is_refused_naming_the_element(tmp_path, run_cli):
    _block(tmp_path)
    _edit_deck(tmp_path, "2, 0.0033333333333333335, 0.0, 0.0", "2, 0.0, 0.0, 0.0")
    _edit_deck(tmp_path, "6, 0.0033333333333333335, 0.0033333333333333335, 0.0",
               "6, 0.0, 0.0033333333333333335, 0.0")
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].contact: surface 'SBOTTOM': element 1, "
                          "S1 has zero area")


@pytest.mark.parametrize("value", ["nan", "inf"])
def test_node_coordinate_that_is_not_a_number_is_refused_naming_the_line(tmp_path, run_cli,
                                                                         value):
    _block(tmp_path)
    _edit_deck(tmp_path, "\n6, 0.0033333333333333335,", f"\n6, {value},")
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].mesh: block.inp, line ")
    assert f"node 6 has a coordinate that is not a finite number ({value}" in err


# -- labels, sets, instances, includes ---------------------------------------------------------

def test_repeated_element_label_is_refused_naming_the_line(tmp_path, run_cli):
    _block(tmp_path)
    _edit_deck(tmp_path, "*NSET, NSET=BOTTOM", "1, 1, 2, 6, 5, 17, 18, 22, 21\n"
               "*NSET, NSET=BOTTOM")
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].mesh: block.inp, line ")
    assert "element 1 is defined a second time" in err


def test_repeated_node_label_is_refused_at_another_place_and_read_once_at_the_same(
        tmp_path, run_cli):
    model = _block(tmp_path)
    _edit_deck(tmp_path, "*ELEMENT", "1, 0.0, 0.0, 0.0\n*ELEMENT")     # the same place
    assert import_joint(read_import_model(model)).report["contact_nodes"] == 16
    _edit_deck(tmp_path, "*ELEMENT", "1, 0.005, 0.005, 0.0025\n*ELEMENT")
    err = _refused(run_cli, tmp_path)
    assert "node 1 is defined a second time at another place (first: block.inp, line " in err


@pytest.mark.parametrize("line", ["1, 16, 0", "16, 1", "1, 16, -1"])
def test_generate_that_names_no_label_is_refused_naming_the_line(tmp_path, run_cli, line):
    _block(tmp_path)
    _edit_deck(tmp_path, "*MATERIAL", f"*NSET, NSET=GEN, GENERATE\n{line}\n*MATERIAL")
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].mesh: block.inp, line ")
    assert "GENERATE" in err and "names no label" in err


@pytest.mark.parametrize(("edit", "key"), [
    (('nodes = "TOP"\ndisplacement = [1e-6', 'nodes = "EMPTY"\ndisplacement = [1e-6'),
     "fe_import.load[1].nodes"),
    (('contact = "SBOTTOM"', 'contact = "SBOTTOM"\nclamped = ["EMPTY"]'),
     "fe_import.body[0].clamped"),
    (('contact = "SBOTTOM"', 'contact = "EMPTY"'), "fe_import.body[0].contact"),
], ids=["load", "clamped", "contact"])
def test_empty_set_is_refused_where_it_is_used(tmp_path, run_cli, edit, key):
    model = _block(tmp_path)
    _edit_deck(tmp_path, "*MATERIAL", "*NSET, NSET=EMPTY\n*MATERIAL")
    model.write_text(model.read_text().replace(*edit))
    err = _refused(run_cli, tmp_path)
    assert err.startswith(f"error: {key}: node set 'EMPTY' of block.inp is empty")


def test_abaqus_instance_translates_then_rotates_its_parts_nodes(tmp_path):
    """*INSTANCE data lines: a translation, then a rotation about the axis a → b by an
    angle in degrees (Abaqus keyword reference, *INSTANCE)."""
    deck = block_deck(1, 1, 1, size=(1.0, 1.0, 1.0), step=None)
    head, tail = deck.split("*MATERIAL")
    part = head.replace("*NODE", "*PART, NAME=P\n*NODE") + "*END PART\n"
    inst = ("*ASSEMBLY, NAME=A\n*INSTANCE, NAME=P-1, PART=P\n0.0, 0.0, 1.0\n"
            "0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 90.0\n*END INSTANCE\n*END ASSEMBLY\n")
    (tmp_path / "a.inp").write_text(part + inst + "*MATERIAL" + tail)
    mesh = read_deck(tmp_path / "a.inp", "mesh")
    node2 = mesh.points[mesh.index_of()[2]]            # (1, 0, 0) → (1, 0, 1) → (0, 1, 1)
    np.testing.assert_allclose(node2, [0.0, 1.0, 1.0], atol=1e-15)
    node7 = mesh.points[mesh.index_of()[7]]            # (0, 1, 1) → (0, 1, 2) → (−1, 0, 2)
    np.testing.assert_allclose(node7, [-1.0, 0.0, 2.0], atol=1e-15)


def test_nested_include_is_found_from_the_main_decks_folder_as_ccx_does(tmp_path):
    """``sub/mesh.inp`` includes ``sub/nodes.inp``: a name ccx opens from the directory it
    runs in, the main deck's."""
    deck = block_deck(*N, size=SIZE)
    start, end = deck.index("*NODE"), deck.index("*ELEMENT")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "nodes.inp").write_text(deck[start:end])
    (tmp_path / "sub" / "mesh.inp").write_text("*INCLUDE, INPUT=sub/nodes.inp\n")
    run_ccx(deck[:start] + "*INCLUDE, INPUT=sub/mesh.inp\n" + deck[end:], tmp_path, "block")
    (tmp_path / "model.toml").write_text(MODEL)
    joint = import_joint(read_import_model(tmp_path / "model.toml"))
    assert joint.report["contact_nodes"] == 16


# -- mesh files meshio reads ------------------------------------------------------------------

@pytest.mark.parametrize("name", ["block.msh", "block.vtu"])
def test_unreadable_mesh_file_is_one_line_naming_it(tmp_path, run_cli, name):
    model = _block(tmp_path)
    (tmp_path / name).write_text("this is not a mesh\n")
    model.write_text(model.read_text().replace('"block.inp"', f'"{name}"'))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[0].mesh: cannot read mesh file ")
    assert name in err


def test_gmsh_mesh_prints_only_the_summary(tmp_path, run_cli):
    """meshio's Gmsh reader prints a blank line on stdout: kept off the command's output."""
    model = _block(tmp_path)
    m = meshio.read(tmp_path / "block.inp")            # node k has label k + 1
    hexes = m.cells_dict["hexahedron"]
    bottom = hexes[:N[0] * N[1], :4]
    top = hexes[-N[0] * N[1]:, 4:]
    tags = [np.zeros(len(hexes), int), np.full(len(bottom), 1), np.full(len(top), 2)]
    meshio.Mesh(m.points, [("hexahedron", hexes), ("quad", bottom), ("quad", top)],
                cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                field_data={"SBOTTOM": np.array([1, 2]), "TOP": np.array([2, 2])}).write(
        tmp_path / "block.msh", file_format="gmsh22", binary=False)
    model.write_text(model.read_text().replace('"block.inp"', '"block.msh"'))
    code, stdout, err = run_cli("reduce", model, "--out", tmp_path / "out")
    assert code == 0, err
    assert stdout.splitlines() == [stdout.strip()] and stdout.startswith("16 contact nodes")


# -- the model file ---------------------------------------------------------------------------

@pytest.mark.parametrize(("text", "said"), [
    ('model = "fe_import"\n[[fe_import.body]\n', "not a valid TOML case file"),
    ("", "error: model: required key is missing"),
], ids=["syntax", "empty"])
def test_model_file_is_refused_before_the_out_directory(tmp_path, run_cli, text, said):
    (tmp_path / "model.toml").write_text(text)
    err = _refused(run_cli, tmp_path)
    assert said in err and "--out" not in err


# -- two bodies -------------------------------------------------------------------------------

TWO = MODEL.replace('contact = "SBOTTOM"\n', 'contact = "SBOTTOM"\n[[fe_import.body]]\n'
                    'stiffness = "{stiffness}"\nmesh = "{mesh}"\ncontact = "{contact}"\n'
                    'clamped = ["BOTTOM"]\n')


def test_second_body_on_the_first_ones_own_surface_is_refused(tmp_path, run_cli):
    _block(tmp_path)
    (tmp_path / "model.toml").write_text(TWO.format(stiffness="block.sti", mesh="block.inp",
                                                    contact="SBOTTOM"))
    err = _refused(run_cli, tmp_path)
    assert err.startswith("error: fe_import.body[1].contact: the contact 'SBOTTOM' of body 2 "
                          "is body 1's contact itself")


def test_second_body_whose_contact_does_not_face_the_first_is_refused(tmp_path, run_cli):
    """The lower block's bottom (its outward normal −z, as the upper block's) instead of
    its top: the two surfaces do not face each other."""
    _block(tmp_path)
    run_ccx(block_deck(*N, size=SIZE, origin=(0.0, 0.0, -SIZE[2])), tmp_path / "lower",
            "block")
    (tmp_path / "model.toml").write_text(TWO.format(
        stiffness="lower/block.sti", mesh="lower/block.inp", contact="SBOTTOM").replace(
        'clamped = ["BOTTOM"]', 'clamped = ["SIDE"]'))
    err = _refused(run_cli, tmp_path)
    assert "fe_import.body[1].contact" in err and "does not face body 1's 'SBOTTOM'" in err
