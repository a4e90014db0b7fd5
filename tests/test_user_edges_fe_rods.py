"""Input at the edges of the rods, limits, 2-D FE, discrete and reduce paths: every case a
user can write either runs to a meaningful answer or is refused in one line naming the key
(or file/option), exit code 2, nothing written."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from slipcycle.io import parse_case_text

RODS = """
model = "rods"
[rods]
L = [{L1}, {L2}]
radius = [0.01, 0.01]
E = [200e9, 200e9]
nu = [0.3, 0.3]
density = [7850.0, 7850.0]
friction = {friction}
axial_force = 1.0e4
interface = "distributed"
interface_stiffness = 1.0e13
damping_ratio = {zeta}
modes = 8
rings = 20
[loading]
rotation_amplitude = {amp}
frequency_ratio = {ratio}
[run]
steps_per_cycle = 128
cycles = 60
regularisation = false
"""


def _rods(L1=0.5, L2=0.5, friction=0.3, zeta=0.01, amp=0.014, ratio=0.3, limits=""):
    return RODS.format(L1=L1, L2=L2, friction=friction, zeta=zeta, amp=amp,
                       ratio=ratio) + limits


def _refused(run_cli, tmp_path, argv, key):
    """Run the CLI; assert exit 2, one line naming ``key`` and nothing written."""
    code, out, err = run_cli(*argv, "--out", tmp_path / "o")
    assert code == 2, err
    assert err.startswith(f"error: {key}:"), err
    assert err.count("\n") == 1, err
    assert not (tmp_path / "o").exists()
    return err


# --- limits: the [limits] axes -------------------------------------------------------------
@pytest.mark.parametrize("line, key, words", [
    ("frequency_ratio = []", "limits.frequency_ratio", "at least one value"),
    ("amplitude_ratio = []", "limits.amplitude_ratio", "at least one value"),
    ("position = []", "limits.position", "at least one value"),
    ("frequency_ratio = [0.1, 0.1, 0.2]", "limits.frequency_ratio", "more than once"),
    ("amplitude_ratio = [0.5, 0.5]", "limits.amplitude_ratio", "more than once"),
    ("position = [0.3, 0.3]", "limits.position", "more than once"),
    ("frequency_ratio = {start = 0.2, stop = 0.2, num = 3}", "limits.frequency_ratio",
     "more than once"),
])
def test_limits_axis_empty_or_repeated_is_refused_naming_the_key(run_cli, write_case,
                                                                 tmp_path, line, key, words):
    err = _refused(run_cli, tmp_path, ("limits", write_case(_rods(limits="[limits]\n" + line
                                                                 + "\n"))), key)
    assert words in err


def test_limits_descending_frequency_range_gives_the_ascending_answer(run_cli, write_case,
                                                                       tmp_path):
    found = {}
    for name, rng in (("down", "start = 1.5, stop = 0.05"), ("up", "start = 0.05, stop = 1.5")):
        text = _rods(limits=f"[limits]\nfrequency_ratio = {{{rng}, num = 6}}\n")
        code, out, err = run_cli("limits", write_case(text, f"{name}.toml"), "--no-maps",
                                 "--out", tmp_path / name)
        assert code == 0, err
        found[name] = json.loads((tmp_path / name / "summary.json").read_text())
    assert found["down"]["qs_limit_frequency_ratio_status"] == "found"
    for key in ("qs_limit_frequency_ratio", "qs_limit_frequency_ratio_dissipation"):
        # the same grid (up to the round-off of geomspace in either direction)
        assert found["down"][key] == pytest.approx(found["up"][key], rel=1e-9)


# --- rods: friction, amplitude, undamped resonance --------------------------------------
def test_rods_zero_friction_is_refused_naming_the_key(run_cli, write_case, tmp_path):
    err = _refused(run_cli, tmp_path, ("run", write_case(_rods(friction=0.0))), "rods.friction")
    assert "> 0" in err


def test_rods_subnormal_amplitude_gives_a_clean_stuck_result(run_cli, write_case, tmp_path):
    code, out, err = run_cli("run", write_case(_rods(amp=5e-324)), "--out", tmp_path / "o",
                             "--quiet")
    assert code == 0, err
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["steady_state_class"] == "shakedown" and s["dissipation_per_cycle"] == 0.0
    assert s["torque_ratio"] is None  # 0/0: both torques underflow


def test_rods_undamped_torque_free_resonance_is_refused_as_a_pole(run_cli, write_case,
                                                                  tmp_path):
    # equal rods: each rod with its interface end free vibrates at ω1 — a mode that carries
    # no interface torque, unbounded whatever the friction
    err = _refused(run_cli, tmp_path, ("run", write_case(_rods(zeta=0.0, ratio=1.0))),
                   "loading.frequency_ratio")
    assert "pole" in err and "damping_ratio" in err


def test_limits_flags_the_undamped_torque_free_resonance_as_a_pole():
    from slipcycle.rods.case import parse_case
    from slipcycle.rods.limits import make_study

    study, _ = make_study(parse_case(parse_case_text(_rods(zeta=0.0)), limits=True))
    assert study.poles(3.5) == pytest.approx([1.0, 3.0], rel=1e-9)
    assert study.solve(1.0, 0.014).pole


def test_rods_undamped_slip_without_a_cycle_says_so_without_warnings(run_cli, write_case,
                                                                     tmp_path):
    # rod 2 (0.7 m, interface end free) resonates at Ω: the modal model is singular there
    text = _rods(L1=0.3, L2=0.7, zeta=0.0, ratio=1.0 / 1.4)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        code, out, err = run_cli("run", write_case(text), "--out", tmp_path / "o")
    assert code == 0, err
    # one line, and no RuntimeWarning from the modal model on its singular frequency
    assert err.count("\n") == 1 and "undamped (rods.damping_ratio = 0)" in err, err
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["steady_state_class"] == "not_converged"


def test_rods_undamped_stuck_cycle_has_no_energy_balance_error(run_cli, write_case,
                                                               tmp_path):
    code, out, err = run_cli("run", write_case(_rods(zeta=0.0, amp=0.005)), "--out",
                             tmp_path / "o", "--quiet")
    assert code == 0, err
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["steady_state_class"] == "shakedown"
    assert s["energy_balance_error"] == 0.0  # 0/0 — nothing to balance


def test_modal_frf_is_finite_on_an_undamped_rod_frequency():
    from slipcycle.rods.case import interface_bed, parse_case
    from slipcycle.rods.modal import modal_basis, modal_frf

    rc = parse_case(parse_case_text(_rods(L1=0.3, L2=0.7, zeta=0.0)))
    basis, k = modal_basis(rc.rods, 8, True), interface_bed(rc)[0].stiffness
    W = float(basis.omega[8])  # rod 2's first mode, interface end free
    with np.errstate(all="raise"):
        T = modal_frf(basis, W, k)
    near = modal_frf(basis, W * (1 + 1e-7), k)
    assert np.isfinite(T) and T == pytest.approx(near, rel=1e-4)


# --- 2-D/3-D FE mesh models: load cases that put no force on the contact ------------------
MESH2D = """
model = "fe"
[fe]
geometry = "mesh"
element = "P1"
thickness = 0.01
[fe.mesh]
file = "rect.msh"
contact = "base"
E = 210e9
nu = 0.3
{extra}
[[fe.load_case]]
name = "normal"
boundary = "top"
{first}
[[fe.load_case]]
name = "tangential"
boundary = "top"
displacement = [1, 0]
[fe.discrete]
friction = 0.5
cycles = 10
steps_per_cycle = 20
[fe.discrete.mean]
normal = 2e-6
[fe.discrete.amplitude]
tangential = 3e-6
"""


@pytest.fixture
def rect_msh(tmp_path):
    """A 2-D gmsh mesh of a 10 × 5 mm rectangle with line groups base and top."""
    meshio = pytest.importorskip("meshio")
    nx, ny = 6, 3
    x, y = np.meshgrid(np.linspace(0, 0.01, nx + 1), np.linspace(0, 0.005, ny + 1))
    pts = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    idx = np.arange(pts.shape[0]).reshape(ny + 1, nx + 1)
    tri = []
    for j in range(ny):
        for i in range(nx):
            a, b, c, d = idx[j, i], idx[j, i + 1], idx[j + 1, i + 1], idx[j + 1, i]
            tri += [[a, b, c], [a, c, d]]
    base = [[idx[0, i], idx[0, i + 1]] for i in range(nx)]
    top = [[idx[ny, i], idx[ny, i + 1]] for i in range(nx)]
    cells = [("triangle", np.array(tri)), ("line", np.array(base + top))]
    phys = [np.full(len(tri), 3), np.array([1] * nx + [2] * nx)]
    mesh = meshio.Mesh(pts, cells, cell_data={"gmsh:physical": phys,
                                              "gmsh:geometrical": phys})
    mesh.field_data = {"base": np.array([1, 1]), "top": np.array([2, 1]),
                       "body": np.array([3, 2])}
    path = tmp_path / "rect.msh"
    meshio.write(path, mesh, file_format="gmsh22", binary=False)
    return path


def test_fe_mesh_example_of_this_file_runs(run_cli, write_case, rect_msh, tmp_path):
    """The fixture's case itself is valid (so the refusals below are the edits' doing)."""
    case = write_case(MESH2D.format(extra="", first="displacement = [0, -1]"))
    code, out, err = run_cli("run", case, "--out", tmp_path / "ok", "--quiet")
    assert code == 0, err


@pytest.mark.parametrize("extra, first, key, words", [
    ("", "traction = [0, -1]", "fe.load_case[0].traction", "held by the displacement case"),
    ('clamped = ["top"]', "traction = [0, -1]", "fe.load_case[0].traction", "clamped"),
    ("", "displacement = [0, 0]", "fe.load_case[0].displacement", "zero in every component"),
    ("", "traction = [0, 0]", "fe.load_case[0].traction", "zero in every component"),
    ('clamped = ["top"]', "displacement = [0, -1]", "fe.load_case[0].boundary",
     "also clamped"),
])
def test_fe_load_case_without_force_on_the_contact_is_refused(run_cli, write_case, rect_msh,
                                                              tmp_path, extra, first, key,
                                                              words):
    case = write_case(MESH2D.format(extra=extra, first=first))
    err = _refused(run_cli, tmp_path, ("run", case), key)
    assert words in err


def test_press_first_block_shakes_down_after_two_cycles(run_cli, tmp_path):
    """docs/fe.md, history dependence: press first → shakedown after 2 cycles, D = 0."""
    from conftest import EXAMPLES

    code, out, err = run_cli("reduce", EXAMPLES / "fe_block_nu03.toml", "--out",
                             tmp_path / "b.npz", "--case", tmp_path / "b.toml")
    assert code == 0, err
    code, out, err = run_cli("run", tmp_path / "b.toml", "--out", tmp_path / "r", "--quiet")
    assert code == 0, err
    s = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert (s["steady_state_class"], s["cycles_run"]) == ("shakedown", 2)
    assert s["dissipation_per_cycle"] == 0.0


# --- reduce and examples: options that would overwrite or be ignored ----------------------
def test_reduce_case_equal_to_out_is_refused(run_cli, tmp_path):
    from conftest import EXAMPLES

    out = tmp_path / "X.npz"
    code, _, err = run_cli("reduce", EXAMPLES / "fe_block_nu03.toml", "--out", out,
                           "--case", out)
    assert code == 2 and err.startswith("error: --case:") and err.count("\n") == 1, err
    assert not out.exists()


def test_reduce_dof_order_on_a_model_file_is_refused(run_cli, tmp_path):
    from conftest import EXAMPLES

    code, _, err = run_cli("reduce", EXAMPLES / "fe_block_nu03.toml", "--out",
                           tmp_path / "b.npz", "--dof-order", "interleaved")
    assert code == 2 and err.startswith("error: --dof-order:"), err
    assert not (tmp_path / "b.npz").exists()


def test_examples_copy_onto_a_file_and_force_alone_are_refused(run_cli, tmp_path):
    target = tmp_path / "afile"
    target.write_text("mine")
    code, _, err = run_cli("examples", "--copy", target)
    assert code == 2 and err.startswith("error: --copy:") and "Errno" not in err, err
    assert target.read_text() == "mine"
    code, _, err = run_cli("examples", "--force")
    assert code == 2 and err.startswith("error: --force:"), err


# --- discrete: [run] and stiffness-file contents ------------------------------------------
DISCRETE = """
model = "discrete"
[discrete]
{matrices}
friction = 0.5
[loading]
lam = 1.0
p0 = [1.0, 1.0]
q0 = [0.0, 0.0]
p1 = [0.3, 0.2]
p1_phase = [0.0, 1.0]
q1 = [0.8, 0.9]
q1_phase = [0.5, 2.0]
[run]
cycles = 40
{run}
"""
INLINE = ("A = [[1.0, -0.3], [-0.3, 0.8]]\nB = [[0.4, 0.1], [-0.2, 0.3]]\n"
          "C = [[1.0, -0.2], [-0.2, 1.0]]")


@pytest.mark.parametrize("run, key, words", [
    ("steps_per_cycle = 1", "run.steps_per_cycle", ">= 4"),
    ("steps_per_cycle = 3", "run.steps_per_cycle", ">= 4"),
    ("min_cycles = 100", "run.min_cycles", "<= cycles (40)"),
])
def test_discrete_run_settings_without_a_meaningful_cycle_are_refused(run_cli, write_case,
                                                                      tmp_path, run, key,
                                                                      words):
    err = _refused(run_cli, tmp_path, ("run", write_case(DISCRETE.format(matrices=INLINE,
                                                                         run=run))), key)
    assert words in err


@pytest.mark.parametrize("kind, words", [("text", "text"), ("complex", "complex"),
                                         ("bool", "booleans")])
def test_stiffness_file_of_non_real_numbers_is_refused_naming_file_and_array(
        run_cli, write_case, tmp_path, kind, words):
    A = np.array([[1.0, -0.3], [-0.3, 0.8]])
    A = {"text": A.astype(str), "complex": A + 0j, "bool": A > 0}[kind]
    np.savez(tmp_path / "k.npz", A=A, B=[[0.4, 0.1], [-0.2, 0.3]],
             C=[[1.0, -0.2], [-0.2, 1.0]])
    case = write_case(DISCRETE.format(matrices='stiffness_file = "k.npz"', run=""))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning on the way
        err = _refused(run_cli, tmp_path, ("run", case), "discrete.stiffness_file")
    assert "k.npz: array A" in err and words in err


def test_discrete_inline_empty_a_is_blamed_on_a(run_cli, write_case, tmp_path):
    text = DISCRETE.format(matrices=INLINE.replace("A = [[1.0, -0.3], [-0.3, 0.8]]",
                                                   "A = [[]]"), run="")
    err = _refused(run_cli, tmp_path, ("run", write_case(text)), "discrete.A")
    assert "square" in err
