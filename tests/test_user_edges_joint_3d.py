"""Edges of the lap-joint and discrete3d user paths: every input a user can get wrong is
one line naming its key (exit code 2, nothing written), and the edge physics ends in a
sensible result. Each case was found by probing the command line and the Python API."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import case_text

import slipcycle
from slipcycle.discrete3d.case import discrete3d_case, read_discrete3d_case
from slipcycle.errors import InputError
from slipcycle.examples import example_path
from slipcycle.io import parse_case_text
from slipcycle.joints.lap_joint_protocol import Protocol
from slipcycle.loading.protocol import Step
from slipcycle.studies.case_sweep import summary_numbers

#: a small two-bolt joint (75 contact nodes); ``{lap}``, ``{protocols}`` and ``{steps}``
#: take extra lines of those tables
JOINT = """model = "lap_joint"
[lap_joint]
plate_width = 0.052
bolt_count = 2
bolt_diameter = 0.006
washer_diameter = 0.016
mesh_size = 0.010
friction = {friction}
{lap}
[lap_joint.loading]
preload = {preload}
service_amplitude = 2e3
[lap_joint.protocols]
names = {names}
[lap_joint.protocols.steps]
{steps}
[lap_joint.convergence]
coarsening = []
[run]
cycles = 10
steps_per_cycle = 12
step_tolerance = 1e-4
[output]
fields = ["xdmf"]
"""


def joint(*, friction=0.3, lap="", preload=10e3, names='["a"]',
          steps="a = [{tighten = [0, 1]}]") -> str:
    return JOINT.format(friction=friction, lap=lap, preload=preload, names=names,
                        steps=steps)


def refused(run_cli, write_case, tmp_path, text, key, *extra, command="run"):
    """The case is refused in one line naming ``key``, with exit code 2 and no output."""
    out = tmp_path / "out"
    code, _, err = run_cli(command, write_case(text), "--out", out, "-q", *extra)
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and key in lines[0], err
    assert not out.exists()
    return lines[0]


def test_a_protocol_name_that_is_no_plain_file_name_is_refused(run_cli, write_case,
                                                                tmp_path):
    """A protocol's name names its field files: '../../x' wrote them outside --out."""
    text = joint(names='["../../escaped"]', steps='"../../escaped" = [{tighten = [0, 1]}]')
    refused(run_cli, write_case, tmp_path, text, "lap_joint.protocols.names")
    assert not (tmp_path.parent / "escaped").exists()
    for name in ("a/b", "..", "", ".hidden", "a b"):
        with pytest.raises(InputError):
            Protocol(name, ((0,), (1,)))


@pytest.mark.parametrize("table, edit, key", [
    ("discrete3d", {"friction": True}, "discrete3d.friction"),
    ("discrete3d", {"area": [True, 1.0, 1.0]}, "discrete3d.area"),
    ("loading", {"p0": [True, 1.2, 1.0]}, "loading.p0"),
])
def test_true_or_false_where_a_number_goes_is_refused(table, edit, key, run_cli,
                                                      write_case, tmp_path):
    """NumPy reads true as 1.0: a switch in a list of numbers ran as a number."""
    refused(run_cli, write_case, tmp_path, case_text("discrete3d_three_node", **{table: edit}),
            key)


@pytest.mark.parametrize("edits, key", [
    ({"steps": "a = [{tighten = [0, 1], force = [true, 10e3]}]"},
     "lap_joint.protocols.steps.a[0].force"),
    ({"lap": "bolt_positions = [[0.0, -0.013], [false, 0.013]]"},
     "lap_joint.bolt_positions"),
])
def test_true_or_false_in_a_joints_list_is_refused(edits, key, run_cli, write_case,
                                                   tmp_path):
    refused(run_cli, write_case, tmp_path, joint(**edits), key)


@pytest.mark.parametrize("lap, key", [
    ("E_lower = 1e-3", "lap_joint.E_lower"),
    ("E_lower = 1e30", "lap_joint.E_lower"),
    ("bolt_shank_diameter = 0.005", "lap_joint.bolt_shank_diameter"),
    ("bolt_length = 0.01", "lap_joint.bolt_length"),
])
def test_plate_and_bolt_values_without_meaning_are_refused(lap, key, run_cli, write_case,
                                                           tmp_path):
    """A lower plate 1e14 times softer made the reduction singular (an internal error);
    a shank given without a bolt modulus was silently ignored."""
    refused(run_cli, write_case, tmp_path, joint(lap=lap), key)


@pytest.mark.parametrize("steps, key", [
    ("a = [{tighten = [0, 1]}, {overload = 1e20}]", "steps.a[1].overload"),
    ("a = [{service = 1e30}, {tighten = [0, 1]}]", "steps.a[0].service"),
    ("a = [{tighten = [0, 1], force = 1e30}]", "steps.a[0].force"),
    ("a = [{tighten = [0, 1], force = 0.0}]", "steps.a[0].force"),
    ("a = [{loosen = [0]}, {tighten = [0, 1]}]", "steps.a[0].loosen"),
    ("a = [{tighten = [0, 1]}, {loosen = [0], force = 2e4}]", "steps.a[1].force"),
    ("a = [{tighten = [0, 1]}, {loosen = [5]}]", "steps.a[1].loosen"),
    ("a = [{tighten = [0, 2]}]", "steps.a[0].tighten"),
])
def test_a_step_without_meaning_is_refused_naming_the_step(steps, key, run_cli, write_case,
                                                           tmp_path):
    """An overload of 1e20 N on a 10 kN joint ran with round-off for a state; a tighten
    to 0 N left the joint open; loosening a bolt never tightened, or to more than its
    force, passed as a step."""
    line = refused(run_cli, write_case, tmp_path, joint(steps=steps),
                   f"lap_joint.protocols.{key}")
    if "[5]" in steps or "[0, 2]" in steps:
        assert "no bolt" in line and "exactly once" not in line


def test_a_preload_beyond_any_joint_is_refused(run_cli, write_case, tmp_path):
    refused(run_cli, write_case, tmp_path, joint(preload=1e13), "lap_joint.loading.preload")


@pytest.mark.parametrize("typo, meant", [("bolt_modlus = 2e11", "bolt_modulus"),
                                         ("E_lowr = 7e10", "E_lower"),
                                         ("melan_chek = true", "melan_check")])
def test_a_misspelt_key_is_offered_the_key_meant(typo, meant, run_cli, write_case,
                                                 tmp_path):
    """The suggestion comes from every key the table knows, not only those in the file."""
    line = refused(run_cli, write_case, tmp_path, joint(lap=typo), typo.split()[0])
    assert f"did you mean {meant!r}" in line


def test_a_friction_above_the_critical_value_is_one_short_line_naming_the_case_key(
        run_cli, write_case, tmp_path):
    line = refused(run_cli, write_case, tmp_path, joint(friction=100.0),
                   "lap_joint.friction")
    assert "lap_joint.accept_ill_posed = true" in line
    assert len(line) < 400 and "in all" in line      # the node list is cut short


def test_a_matrix_of_another_size_than_c_says_where_the_node_count_comes_from(
        run_cli, write_case, tmp_path):
    text = case_text("discrete3d_three_node", discrete3d={"C": [[2.0, -0.3], [-0.3, 2.0]]})
    line = refused(run_cli, write_case, tmp_path, text, "discrete3d.A")
    assert "from the 2×2 C" in line


def test_a_window_of_a_billion_points_is_refused_before_any_run(run_cli, tmp_path):
    out = tmp_path / "out"
    code, _, err = run_cli("shakedown", example_path("discrete3d_three_node.toml"), "--out",
                           out, "--lam-points", "1e9", "-q")
    assert code == 2 and "--lam-points" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_frictionless_interface_dissipates_exactly_nothing():
    """f = 0: the tangential reactions are round-off, which was booked as D = -2.7e-18
    J with negative node values; every D_j is now 0."""
    res = slipcycle.run(example_path("discrete3d_three_node.toml"),
                        {"discrete3d.friction": 0.0})
    assert res.dissipation_per_cycle == 0.0
    assert np.all(np.asarray(res.summary()["dissipation_per_node"]) == 0.0)


def test_python_entry_points_refuse_void_inputs_with_the_key():
    dc = read_discrete3d_case(parse_case_text(
        example_path("discrete3d_three_node.toml").read_text(encoding="utf-8")))
    with pytest.raises(InputError, match="protocol"):
        discrete3d_case(dc.system, dc.load, protocol=[])
    with pytest.raises(InputError, match="initial_slip"):
        discrete3d_case(dc.system, dc.load, initial_slip=np.full((3, 2), np.nan))
    with pytest.raises(InputError, match="more than 0 N") as err:
        Protocol("a", (Step("tighten", (0,), force=0.0), Step("tighten", (1,)))).check(2)
    assert err.value.step == (0, "force")
    with pytest.raises(TypeError, match="mapping"):
        slipcycle.run(example_path("discrete3d_three_node.toml"), "discrete3d.friction=0.2")


def test_one_worker_is_accepted_for_a_model_of_one_simulation(run_cli, tmp_path):
    code, _, err = run_cli("run", example_path("discrete3d_three_node.toml"), "--out",
                           tmp_path / "out", "--workers", "1", "-q")
    assert code == 0, err


def test_a_sweep_keeps_the_tables_of_a_summary():
    """protocol × bolt forces and mesh × protocol dissipation were dropped by sweeps."""
    cell = summary_numbers({"protocol_bolt_force": [[1.0, 2.0], [3.0, 4.0]],
                            "protocol_dissipation_per_cycle": [5.0, 6.0],
                            "units": {"protocol_bolt_force": "N",
                                      "protocol_dissipation_per_cycle": "J"}})
    assert cell["protocol_bolt_force"].shape == (2, 2)
    assert cell.attrs["protocol_bolt_force"]["units"] == "N"
    assert cell["protocol_dissipation_per_cycle"].shape == (2,)
