"""The case-file readers translate keys; the model objects check the values.

For every check a reader used to repeat, three things hold:

- the case file still gives the same one-line message, naming the TOML key (exit 2);
- the Python object refuses the same input with the same problem, under its field name;
- the check has one source: switching the model's check off (monkeypatch) lets the case
  file through, or a problem the model raises comes out under the TOML key.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from slipcycle.discrete import FrictionalSystem, critical_friction
from slipcycle.discrete.case import read_discrete_case
from slipcycle.discrete.model import ModelError
from slipcycle.errors import InputError
from slipcycle.halfspace import model as halfspace_model
from slipcycle.halfspace.case import parse_case
from slipcycle.halfspace.model import HalfspaceModel, LoadPathError
from slipcycle.io import CaseError, parse_case_text

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
SPHERE = (EXAMPLES / "halfspace_sphere.toml").read_text(encoding="utf-8")
TWO_NODE = (EXAMPLES / "discrete_two_node.toml").read_text(encoding="utf-8")

LOADS = "P0 = 100.0\nP1 = 0.0\nQ0 = 0.0\nQ1 = 30.0\nphase = 0.0"
ROUGH = """model = "halfspace"
[halfspace]
profile = "rough_exponential"
gamma_sigma = 1e-6
compliance_ratio = 1.2
friction = 0.5
[loading]
P0 = 100.0
P1 = 50.0
Q1 = 3.0
[run]
sliders = 100
"""
TABLE = """model = "halfspace"
[halfspace]
profile = "tabulated"
table_U = [0.0, 1e-6, 2e-6]
table_P = [0.0, 100.0, 400.0]
compliance_ratio = 1.0
friction = 0.5
[loading]
P0 = 100.0
Q1 = 3.0
"""


def _with(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def _cli_message(run_cli, write_case, tmp_path, text: str) -> str:
    """The one line ``slipcycle run`` prints for ``text`` (exit 2, nothing written)."""
    out = tmp_path / "out"
    code, _, err = run_cli("run", write_case(text), "--out", out)
    assert code == 2 and err.count("\n") == 1 and err.startswith("error: "), err
    assert not out.exists()
    return err.strip()


# -- half-space: fields checked in HalfspaceModel.__post_init__ ------------------------------
#: (id, case text, message through the case file, model field, bad value of the field)
HALFSPACE_FIELDS = [
    ("friction-negative", _with(SPHERE, "friction = 0.5", "friction = -0.5"),
     "halfspace.friction: must be > 0, got -0.5", "friction", -0.5),
    ("friction-zero", _with(SPHERE, "friction = 0.5", "friction = 0"),
     "halfspace.friction: must be > 0, got 0", "friction", 0.0),
    ("ratio-zero-sphere", _with(SPHERE, "nu = [0.3, 0.3]",
                                "nu = [0.3, 0.3]\ncompliance_ratio = 0.0"),
     "halfspace.compliance_ratio: must be > 0, got 0", "compliance_ratio", 0.0),
    ("ratio-negative-modulus", SPHERE.replace("E = [200e9, 200e9]", "contact_modulus = 1e11")
     .replace("nu = [0.3, 0.3]", "compliance_ratio = -1.0"),
     "halfspace.compliance_ratio: must be > 0, got -1", "compliance_ratio", -1.0),
    ("ratio-zero-rough", _with(ROUGH, "compliance_ratio = 1.2", "compliance_ratio = 0.0"),
     "halfspace.compliance_ratio: must be > 0, got 0", "compliance_ratio", 0.0),
    ("ratio-negative-table", _with(TABLE, "compliance_ratio = 1.0", "compliance_ratio = -2.0"),
     "halfspace.compliance_ratio: must be > 0, got -2", "compliance_ratio", -2.0),
    ("steps", _with(SPHERE, "steps_per_cycle = 400", "steps_per_cycle = 4"),
     "run.steps_per_cycle: must be >= 8, got 4", "steps_per_cycle", 4),
    ("cycles", _with(SPHERE, "cycles = 3", "cycles = 0"),
     "run.cycles: must be >= 1, got 0", "max_cycles", 0),
    ("sliders", _with(SPHERE, "cycles = 3", "cycles = 3\nsliders = 5"),
     "run.sliders: must be >= 10, got 5", "n_sliders", 5),
    ("assembly-steps", _with(SPHERE, "cycles = 3", "cycles = 3\nassembly_steps = 0"),
     "run.assembly_steps: must be >= 1, got 0", "assembly_steps", 0),
    ("snapshots-negative", _with(SPHERE, "cycles = 3", "cycles = 3\nsnapshots = [-1.0, 1.0]"),
     "run.snapshots: must be >= 0, got -1", "snapshots", [-1.0, 1.0]),
    ("snapshots-above-2pi", _with(SPHERE, "cycles = 3", "cycles = 3\nsnapshots = [1.0, 7.0]"),
     "run.snapshots: must be <= 6.28319, got 7", "snapshots", [1.0, 7.0]),
    ("steady-tol-zero", _with(SPHERE, "cycles = 3", "cycles = 3\nsteady_tol = 0.0"),
     "run.steady_tol: must be > 0, got 0", "steady_tol", 0.0),
    ("steady-tol-one", _with(SPHERE, "cycles = 3", "cycles = 3\nsteady_tol = 1.0"),
     "run.steady_tol: must be < 1, got 1", "steady_tol", 1.0),
]
HS_IDS = [c[0] for c in HALFSPACE_FIELDS]


def _good_model(text: str) -> HalfspaceModel:
    """The model of ``text`` with every [run] and [halfspace] value back to a valid one."""
    fixed = parse_case_text(text)
    hs = fixed.data["halfspace"]
    if hs.get("friction", 1.0) <= 0:
        hs["friction"] = 0.5
    if hs.get("compliance_ratio", 1.0) <= 0:
        hs["compliance_ratio"] = 1.0
    fixed.data.pop("run", None)
    return parse_case(fixed)


@pytest.mark.parametrize(("cid", "text", "message", "field", "value"), HALFSPACE_FIELDS,
                         ids=HS_IDS)
def test_halfspace_case_message_names_the_toml_key(run_cli, write_case, tmp_path, cid, text,
                                                   message, field, value):
    assert _cli_message(run_cli, write_case, tmp_path, text) == f"error: {message}"


@pytest.mark.parametrize(("cid", "text", "message", "field", "value"), HALFSPACE_FIELDS,
                         ids=HS_IDS)
def test_halfspace_model_gives_the_same_problem_under_the_field(cid, text, message, field,
                                                                 value):
    good = _good_model(text)
    with pytest.raises(InputError) as err:
        dataclasses.replace(good, **{field: value})
    assert err.value.key == field
    assert err.value.problem == message.split(": ", 1)[1]


@pytest.mark.parametrize(("cid", "text", "message", "field", "value"), HALFSPACE_FIELDS,
                         ids=HS_IDS)
def test_halfspace_reader_leaves_the_check_to_the_model(monkeypatch, cid, text, message,
                                                        field, value):
    # without the model's bound checks the reader lets every one of these values through
    monkeypatch.setattr(halfspace_model, "_bound", lambda *args: None)
    model = parse_case(parse_case_text(text))
    assert np.array_equal(np.asarray(getattr(model, field)), np.asarray(value, float))


def test_halfspace_model_problem_comes_out_under_the_toml_key(monkeypatch):
    def refuse(self):
        raise InputError("n_sliders", "checked by the model")

    monkeypatch.setattr(HalfspaceModel, "__post_init__", refuse)
    with pytest.raises(CaseError) as err:
        parse_case(parse_case_text(SPHERE))
    assert str(err.value) == "run.sliders: checked by the model"


def test_case_file_bound_of_the_cycles_stays_with_the_reader():
    # the model takes any number of cycles; a case file at most 10000
    text = _with(SPHERE, "cycles = 3", "cycles = 20000")
    with pytest.raises(CaseError, match=r"^run\.cycles: must be <= 10000, got 20000$"):
        parse_case(parse_case_text(text))
    assert dataclasses.replace(_good_model(SPHERE), max_cycles=20000).max_cycles == 20000


def test_nested_snapshots_are_blamed_on_the_toml_key():
    # a model error the reader used to let through under the bare field name
    text = _with(SPHERE, "cycles = 3", "cycles = 3\nsnapshots = [[1.0]]")
    with pytest.raises(CaseError) as err:
        parse_case(parse_case_text(text))
    assert err.value.key == "run.snapshots"


# -- half-space: the load path, checked by HalfspaceModel.check_loads --------------------------
CYLINDER = (SPHERE.replace('profile = "sphere"', 'profile = "cylinder"')
            .replace("radius = 0.01", "radius = 0.01\nreference_depth = 1e-9"))
#: (id, case text, message through the case file, field of the model's error)
LOAD_PATHS = [
    ("never-compressive", _with(SPHERE, "P0 = 100.0", "P0 = -100.0"),
     "loading.P0: the normal load never compresses the contact", "normal"),
    ("never-compressive-zero", _with(SPHERE, "P0 = 100.0", "P0 = 0.0"),
     "loading.P0: the normal load never compresses the contact", "normal"),
    ("tensile", _with(SPHERE, "P1 = 0.0", "P1 = 150.0"),
     "loading.P1: normal load becomes tensile (minimum -50 N); adhesion is not modelled",
     "normal"),
    ("tensile-protocol", _with(SPHERE, "[run]", "[[loading.protocol]]\nP = 5.0\nQ = 0.0\n"
                               "[[loading.protocol]]\nP = -50.0\n[run]"),
     "loading.protocol[1].P: normal load becomes tensile (minimum -50 N); adhesion is not "
     "modelled", "protocol[1]"),
    ("tensile-table", _with(SPHERE, LOADS, "theta = [0.0, 3.0]\nP = [100.0, -10.0]\n"
                            "Q = [0.0, 1.0]"),
     "loading.P: normal load becomes tensile (minimum -9.9926 N); adhesion is not modelled",
     "normal"),
    ("never-compressive-table", _with(SPHERE, LOADS, "theta = [0.0, 3.0]\n"
                                      "P = [-100.0, -10.0]\nQ = [0.0, 1.0]"),
     "loading.P: the normal load never compresses the contact", "normal"),
    ("rough-unloaded", _with(ROUGH, "P1 = 50.0", "P1 = 100.0"),
     "loading.P1: a rough contact needs P > 0 throughout the load path (minimum 0 N)",
     "normal"),
    ("cylinder-reference-depth", CYLINDER,
     "halfspace.reference_depth: too shallow for the largest load: the plane approach "
     "needs a < 2d/e", "profile.reference_depth"),
    ("table-too-short", _with(TABLE, "P0 = 100.0", "P0 = 500.0"),
     "halfspace.table_P: table ends at 400 N but the loads reach 500 N", "profile"),
]
LP_IDS = [c[0] for c in LOAD_PATHS]


@pytest.mark.parametrize(("cid", "text", "message", "field"), LOAD_PATHS, ids=LP_IDS)
def test_load_path_case_message_names_the_toml_key(run_cli, write_case, tmp_path, cid, text,
                                                   message, field):
    assert _cli_message(run_cli, write_case, tmp_path, text) == f"error: {message}"


@pytest.mark.parametrize(("cid", "text", "message", "field"), LOAD_PATHS, ids=LP_IDS)
def test_load_path_has_one_source_the_model(monkeypatch, cid, text, message, field):
    # with check_loads switched off the reader accepts the case ...
    real = HalfspaceModel.check_loads
    monkeypatch.setattr(HalfspaceModel, "check_loads", lambda self: None)
    model = parse_case(parse_case_text(text))
    # ... and the model itself refuses it with the same problem, under its field name
    with pytest.raises(LoadPathError) as err:
        real(model)
    assert err.value.key == field
    assert err.value.problem == message.split(": ", 1)[1]
    monkeypatch.undo()
    with pytest.raises(LoadPathError):   # what solve() checks first
        halfspace_model.solve(model)


# -- discrete: FrictionalSystem.__post_init__ -----------------------------------------------
ILL_POSED = ("f = 2.5 is not below the critical friction coefficient f_crit = 1.89314 "
             "({method}; nodes [0, 1], slip signs [1, -1]): the rate problem is ill posed "
             "(Klarbring P-matrix condition)")
#: (id, case text, message through the case file, field, bad value, the model's problem)
DISCRETE = [
    ("friction-negative", _with(TWO_NODE, "friction = 0.5", "friction = -0.1"),
     "discrete.friction: must be >= 0, got -0.1", "friction", -0.1, None),
    ("friction-negative-node", _with(TWO_NODE, "friction = 0.5", "friction = [0.3, -0.2]"),
     "discrete.friction: must be >= 0, got -0.2", "friction", [0.3, -0.2], None),
    ("ill-posed", _with(TWO_NODE, "friction = 0.5", "friction = 2.5"),
     "discrete.friction: " + ILL_POSED.format(method="exact")
     + ". Set discrete.accept_ill_posed = true to run anyway", "friction", 2.5,
     ILL_POSED.format(method="exact") + ". Pass accept_ill_posed=True to run anyway"),
    ("ill-posed-bound", _with(TWO_NODE, "friction = 0.5",
                              "friction = 2.5\nf_crit_exact_max_nodes = 0"),
     "discrete.friction: " + ILL_POSED.format(method="bound")
     + ". Set discrete.accept_ill_posed = true to run anyway", "friction", 2.5,
     ILL_POSED.format(method="bound") + ". Pass accept_ill_posed=True to run anyway"),
    ("exact-max-above", _with(TWO_NODE, "friction = 0.5",
                              "friction = 0.5\nf_crit_exact_max_nodes = 15"),
     "discrete.f_crit_exact_max_nodes: must be <= 14, got 15", "f_crit_exact_max_nodes", 15,
     None),
    ("exact-max-negative", _with(TWO_NODE, "friction = 0.5",
                                 "friction = 0.5\nf_crit_exact_max_nodes = -1"),
     "discrete.f_crit_exact_max_nodes: must be >= 0, got -1", "f_crit_exact_max_nodes", -1,
     None),
]
D_IDS = [c[0] for c in DISCRETE]


def _good_system(text: str) -> FrictionalSystem:
    case = parse_case_text(text)
    case.data["discrete"]["friction"] = 0.5
    case.data["discrete"].pop("f_crit_exact_max_nodes", None)
    return read_discrete_case(case).system


@pytest.mark.parametrize(("cid", "text", "message", "field", "value", "problem"), DISCRETE,
                         ids=D_IDS)
def test_discrete_case_message_names_the_toml_key(run_cli, write_case, tmp_path, cid, text,
                                                  message, field, value, problem):
    assert _cli_message(run_cli, write_case, tmp_path, text) == f"error: {message}"


@pytest.mark.parametrize(("cid", "text", "message", "field", "value", "problem"), DISCRETE,
                         ids=D_IDS)
def test_discrete_system_gives_the_same_problem_under_the_field(cid, text, message, field,
                                                                value, problem):
    good = _good_system(text)
    changes = {field: value}
    if cid == "ill-posed-bound":
        changes["f_crit_exact_max_nodes"] = 0
    with pytest.raises(ModelError) as err:
        dataclasses.replace(good, **changes)
    assert err.value.key == field
    assert err.value.problem == (problem or message.split(": ", 1)[1])


@pytest.mark.parametrize(("cid", "text", "message", "field", "value", "problem"), DISCRETE,
                         ids=D_IDS)
def test_discrete_model_problem_comes_out_under_the_toml_key(monkeypatch, cid, text, message,
                                                             field, value, problem):
    # the reader refuses nothing itself: the model's problem reaches the case file
    def refuse(self):
        raise ModelError(field, "checked by the model")

    monkeypatch.setattr(FrictionalSystem, "__post_init__", refuse)
    with pytest.raises(CaseError) as err:
        read_discrete_case(parse_case_text(text))
    assert str(err.value) == f"{message.split(': ', 1)[0]}: checked by the model"


def test_ill_posed_check_has_one_source(monkeypatch):
    text = _with(TWO_NODE, "friction = 0.5", "friction = 2.5")
    monkeypatch.setattr(FrictionalSystem, "_check_well_posed", lambda self: None)
    dc = read_discrete_case(parse_case_text(text))
    assert np.max(dc.system.friction) >= dc.f_crit.f_crit


def test_accept_ill_posed_is_passed_to_the_model():
    text = _with(TWO_NODE, "friction = 0.5", "friction = 2.5\naccept_ill_posed = true")
    dc = read_discrete_case(parse_case_text(text))
    assert dc.system.accept_ill_posed is True
    assert dc.f_crit is dc.system.critical_friction and dc.f_crit.f_crit < 2.5
    dc = read_discrete_case(parse_case_text(TWO_NODE))
    assert dc.system.accept_ill_posed is False


def test_python_default_refuses_ill_posed_systems():
    A, B = [[2.0, -1.0], [-1.0, 2.0]], [[0.0, 0.8], [-0.8, 0.0]]
    fc = critical_friction(np.asarray(A), np.asarray(B)).f_crit
    assert FrictionalSystem(A, B, np.eye(2), 0.9 * fc).critical_friction.f_crit == fc
    with pytest.raises(ModelError) as err:
        FrictionalSystem(A, B, np.eye(2), 1.1 * fc)
    assert err.value.key == "friction" and err.value.remedy[0] == "accept_ill_posed"
    assert FrictionalSystem(A, B, np.eye(2), 1.1 * fc, accept_ill_posed=True).accept_ill_posed
    with pytest.raises(ModelError) as err:
        FrictionalSystem(A, B, np.eye(2), 0.1, accept_ill_posed=None)
    assert err.value.key == "accept_ill_posed"
