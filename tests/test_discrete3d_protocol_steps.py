"""Assembly protocols of a ``discrete3d`` case as steps (issue 33 item 2).

``[discrete3d] steps`` takes the step vocabulary of ``[lap_joint.protocols.steps]`` with
the same reader (:func:`slipcycle.loading.protocol.read_step`): nodes play the bolts, the
service level multiplies the tangential load at θ = 0. Checked: the case file and Python
give the same states and the same result; steps equal to a ``[[protocol]]`` of load
states reproduce its result exactly; over random valid step lists (hypothesis), the TOML
form reads back to the same states, and with B = 0 every protocol ends in the same
steady dissipation (Klarbring, Ciavarella & Barber 2007: the frictional Melan converse),
while with coupling B ≠ 0 a fit-up or an overload decides between shakedown and cyclic
slip; bad steps are refused in one line naming the step and key.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_malformed_inputs import refused_in_one_line

import slipcycle
from slipcycle.cli.main import main
from slipcycle.discrete3d.case import assembly_states, read_discrete3d_case, solve_model
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import embed_2d
from slipcycle.io import parse_case_text
from slipcycle.loading.protocol import Step, step_states

EXAMPLE = (Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
           / "discrete3d_three_node.toml").read_text(encoding="utf-8")
FAST = (EXAMPLE.replace('fields = ["xdmf", "pvd"]', "fields = []")
        .replace("steps_per_cycle = 100", "steps_per_cycle = 40")
        .replace("step_tolerance = 1e-7", "step_tolerance = 1e-6"))


def _with_steps(text: str, steps: str) -> str:
    return text.replace("\n[loading]", f"\nsteps = {steps}\n[loading]", 1)


def _toml_step(s: Step) -> str:
    """The inline TOML table of a step."""
    if s.action == "release":
        return "{release = true}"
    if s.action in ("tighten", "loosen"):
        force = "" if s.force is None else \
            f", force = {[float(x) for x in np.atleast_1d(s.force)]}"
        return f"{{{s.action} = {list(s.bolts)}{force}}}"
    return f"{{{s.action} = {s.force!r}}}"


FIT_UP = (Step("service", force=0.8), Step("tighten", (0, 1, 2)), Step("release"))


def test_steps_through_the_case_file_and_python_give_the_same_result(tmp_path):
    """``slipcycle run`` on a case with steps and ``solve_model`` with the same Step
    objects: the same assembly states and the same steady cycle, to the last bit."""
    text = _with_steps(FAST, "[{service = 0.8}, {tighten = [0, 1, 2]}, {release = true}]")
    (tmp_path / "case.toml").write_text(text, encoding="utf-8")
    assert main(["run", str(tmp_path / "case.toml"), "--out", str(tmp_path / "o")]) == 0
    summary = json.loads((tmp_path / "o" / "summary.json").read_text(encoding="utf-8"))
    dc = read_discrete3d_case(parse_case_text(FAST))
    res = solve_model(dc.system, dc.load, {"cycles": 40, "steps_per_cycle": 40,
                                           "tol": 1e-8, "step_tol": 1e-6},
                      protocol=list(FIT_UP), fields=())
    via_file = read_discrete3d_case(parse_case_text(text)).protocol
    np.testing.assert_array_equal(via_file, res.case.protocol)
    assert summary["dissipation_per_cycle"] == res.summary()["dissipation_per_cycle"]
    assert summary["steady_state"] == res.summary()["steady_state"]


def test_steps_equal_to_load_states_reproduce_their_result():
    """Tightening every node to p_w = [1, 1.2, 1] with no tangential load is the
    ``[[discrete3d.protocol]]`` state p_w = [1, 1.2, 1]: the same states, the same D."""
    states = _with_steps(FAST, "[{tighten = [0, 1, 2], force = [1.0, 1.2, 1.0]}]")
    table = FAST.replace("\n[loading]", "\n[[discrete3d.protocol]]\np_w = [1.0, 1.2, 1.0]\n"
                         "[loading]", 1)
    a, b = slipcycle.run(states), slipcycle.run(table)
    np.testing.assert_array_equal(a.case.protocol, b.case.protocol)
    assert a.summary()["dissipation_per_cycle"] == b.summary()["dissipation_per_cycle"]
    assert a.summary()["steady_state"] == b.summary()["steady_state"]


def test_step_states_follow_the_step_table():
    """Node targets default to the normal load at θ = 0 (tighten) and 0 (loosen); the
    service level multiplies the tangential load at θ = 0; an overload goes out and back."""
    q0, p0 = np.array([[1.0, 2.0], [0.0, -1.0]]), np.array([3.0, 4.0])
    s = step_states([Step("tighten", (1,)), Step("service", force=0.5),
                     Step("tighten", (0,), force=7.0), Step("overload", force=2.0),
                     Step("loosen", (1,)), Step("release")], q0, p0)
    half, two = 0.5 * q0.ravel(), 2.0 * q0.ravel()
    expected = [[*0 * half, 0.0, 4.0], [*half, 0.0, 4.0], [*half, 7.0, 4.0],
                [*two, 7.0, 4.0], [*half, 7.0, 4.0], [*half, 7.0, 0.0],
                [*0 * half, 7.0, 0.0]]
    np.testing.assert_array_equal(s, np.array(expected))


def _steps(n_nodes: int):
    """Valid step lists over ``n_nodes`` nodes, with the edges of every range."""
    nodes = st.lists(st.integers(0, n_nodes - 1), min_size=1, max_size=n_nodes, unique=True)
    step = st.one_of(
        st.builds(lambda b: Step("tighten", tuple(b)), nodes),
        st.builds(lambda b, f: Step("tighten", tuple(b), force=f), nodes,
                  st.one_of(st.just(0.0), st.just(2.0), st.floats(0.0, 2.0))),
        st.builds(lambda b: Step("loosen", tuple(b)), nodes),
        st.builds(lambda f: Step("service", force=f),
                  st.one_of(st.just(-1.0), st.just(1.0), st.floats(-1.0, 1.0))),
        st.builds(lambda f: Step("overload", force=f), st.floats(0.1, 2.0)),
        st.just(Step("release")),
    )
    return st.lists(step, min_size=1, max_size=5)


@settings(max_examples=40, deadline=None)
@given(steps=_steps(3))
def test_any_valid_step_list_reads_back_from_toml_to_the_same_states(steps):
    text = _with_steps(FAST, "[" + ", ".join(_toml_step(s) for s in steps) + "]")
    dc = read_discrete3d_case(parse_case_text(text))
    np.testing.assert_allclose(dc.protocol, assembly_states(steps, dc.load), rtol=1e-15)
    assert dc.protocol.shape == (len(steps) + sum(s.action == "overload" for s in steps), 9)


# a coupled 2-node system (embedded along t1) whose assembly decides shakedown: plain
# tightening shakes down, a fit-up or an overload ends in cyclic slip
_A2 = np.array([[1.0, 0.247075047227736], [0.247075047227736, 1.0]])
_B2 = np.array([[-0.41656197222519253, 0.2554683150798821],
                [0.41714925630544075, -0.11852910240884229]])
_LOAD2 = Load3D.harmonic([1.0, 1.0], [0.0] * 4, [0.20104226346888293, 0.0004598945554328826],
                         [0.36807381387725213, 0.0, 0.452574442452916, 0.0],
                         [3.476172521227298, 3.0127103968364217],
                         [6.022577628933113, 0.0, 1.9935154643203314, 0.0])
_RUN2 = {"cycles": 60, "steps_per_cycle": 100, "tol": 1e-8, "step_tol": 1e-7}
#: work scale of the service load: max |q1|² / k [J]
_W2 = 0.452574442452916 ** 2


def _triangle(B, steps):
    res = solve_model(embed_2d(_A2, B, np.eye(2), 0.5), _LOAD2, _RUN2, protocol=list(steps),
                      fields=())
    return res.summary()


_PLAIN = (Step("tighten", (0, 1)),)
_FIT_UP2 = (Step("service", force=1.0), Step("tighten", (0, 1)), Step("release"))
_OVERLOAD2 = (Step("tighten", (0, 1)), Step("overload", force=2.0))


def test_with_coupling_the_step_protocol_decides_shakedown():
    """B ≠ 0: plain tightening shakes down; holding the tangential load at θ = 0 while
    tightening, then releasing it (fit-up), or an overload to twice it, end in cyclic
    slip: what the B = 0 test below must tell apart."""
    s = [_triangle(_B2, p) for p in (_PLAIN, _FIT_UP2, _OVERLOAD2)]
    assert [x["steady_state"] for x in s] == ["shakedown", "cyclic_slip", "cyclic_slip"]
    assert min(x["dissipation_per_cycle"] for x in s[1:]) > 1e-2 * _W2


_D_PLAIN_B0 = _triangle(0 * _B2, _PLAIN)["dissipation_per_cycle"]


@settings(max_examples=25, deadline=None)
@given(steps=_steps(2))
def test_with_b_0_every_step_protocol_ends_in_the_same_dissipation(steps):
    """B = 0: the steady dissipation does not depend on the assembly (the frictional
    Melan converse, Klarbring, Ciavarella & Barber 2007), whatever the valid step list:
    within 1e-6 of the service work scale, where coupled protocols differ by 1e-2."""
    s = _triangle(0 * _B2, steps)
    assert s["steady_state"] in ("shakedown", "cyclic_slip")
    assert abs(s["dissipation_per_cycle"] - _D_PLAIN_B0) <= 1e-6 * _W2


BAD_STEPS = {
    "not-a-list": ("{tighten = [0]}", "discrete3d.steps"),
    "empty": ("[]", "discrete3d.steps"),
    "not-a-table": ("[3]", "discrete3d.steps[0]"),
    "two-actions": ("[{tighten = [0], release = true}]", "discrete3d.steps[0]"),
    "no-action": ("[{force = 1.0}]", "discrete3d.steps[0]"),
    "unknown-key": ("[{tighten = [0], forse = 1.0}]", "discrete3d.steps[0].forse"),
    "node-float": ("[{tighten = [0.5]}]", "discrete3d.steps[0].tighten"),
    "node-out-of-range": ("[{tighten = [0]}, {tighten = [3]}]", "discrete3d.steps[1].tighten"),
    "node-twice": ("[{tighten = [1, 1]}]", "discrete3d.steps[0]"),
    "force-negative": ("[{tighten = [0], force = -1.0}]", "discrete3d.steps[0].force"),
    "force-count": ("[{tighten = [0, 1], force = [1.0, 1.0, 1.0]}]",
                    "discrete3d.steps[0].force"),
    "service-string": ('[{service = "half"}]', "discrete3d.steps[0].service"),
    "service-nan": ("[{service = nan}]", "discrete3d.steps[0].service"),
    "overload-zero": ("[{overload = 0.0}]", "discrete3d.steps[0].overload"),
    "release-false": ("[{release = false}]", "discrete3d.steps[0].release"),
    "turn": ("[{turn = [0], by = 1e-6}]", "discrete3d.steps[0].turn"),
    "offset": ("[{offset = 1e-6}]", "discrete3d.steps[0].offset"),
    "service-takes-no-force": ("[{service = 0.5, force = 1.0}]", "discrete3d.steps[0].force"),
    "with-protocol": ("[{tighten = [0]}]\n[[discrete3d.protocol]]\np_w = 1.0\n",
                      "discrete3d.steps"),
}


@pytest.mark.parametrize("name", sorted(BAD_STEPS))
def test_a_bad_step_is_refused_in_one_line_naming_the_step_and_key(name, tmp_path,
                                                                   monkeypatch, capsys):
    steps, key = BAD_STEPS[name]
    (tmp_path / "case.toml").write_text(_with_steps(FAST, steps), encoding="utf-8")
    line = refused_in_one_line(("run", "case.toml", "--out=out"), tmp_path, monkeypatch,
                               capsys)
    assert key in line, line


def test_a_service_level_needs_a_tangential_load_at_theta_0(tmp_path, monkeypatch, capsys):
    """No tangential load at θ = 0: a service level scales nothing and is refused."""
    text = _with_steps(FAST, "[{service = 0.5}]").replace(
        "q1 = [[0.6, 0.6], [0.3, 0.0], [0.6, 0.6]]", "q1 = [[0.0, 0.0], [0.0, 0.0], "
        "[0.0, 0.0]]")
    (tmp_path / "case.toml").write_text(text, encoding="utf-8")
    line = refused_in_one_line(("run", "case.toml", "--out=out"), tmp_path, monkeypatch,
                               capsys)
    assert "discrete3d.steps[0].service" in line and "zero" in line, line
