"""The assembly showcase of a lap joint in one command (issue 33 item 6).

The shipped ``lap_joint_assembly.toml`` (elastic bolts, tightening orders, a fit-up and an
overload protocol, ``melan_check = true`` and a ``[lap_joint.window]``) runs, on two
meshes, the protocol study, the same protocols with B = 0 and the shakedown window.
Checked on it (two meshes of 75 and 92 contact nodes): the report's tables and
figures; B = 0 gives one dissipation for every protocol (the frictional Melan converse)
where the coupled joint's fit-up differs by more than 20 %; every protocol's shakedown
limit lies at or below its λ2 (the cone program, independent of the engine's runs); the
Python API gives the numbers of the command line.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from slipcycle.cli.main import main
from slipcycle.examples import example_path
from slipcycle.io import parse_case_text
from slipcycle.joints.lap_joint_case import joint_contact, read_lap_joint_case
from slipcycle.joints.lap_joint_showcase import LapJointShowcase, lap_joint_showcase

#: the shipped one-command showcase (the small joint of tests/test_lap_joint_study.py with
#: elastic bolts, a fit-up and an overload protocol, B = 0 twins and the window)
SHOWCASE = example_path("lap_joint_assembly.toml").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def showcase_cli(tmp_path_factory):
    work = tmp_path_factory.mktemp("showcase")
    (work / "case.toml").write_text(SHOWCASE, encoding="utf-8")
    assert main(["run", str(work / "case.toml"), "--out", str(work / "out"), "-q"]) == 0
    return work / "out"


def _summary(out):
    return json.loads((out / "summary.json").read_text(encoding="utf-8"))


def test_one_command_writes_the_report_with_its_tables_and_figures(showcase_cli):
    report = (showcase_cli / "report.md").read_text(encoding="utf-8")
    for head in ("## Protocols", "## Bolt forces", "## Mesh convergence",
                 "## B = 0: one answer for every protocol", "## Shakedown window"):
        assert head in report, head
    assert "Elastic bolts, k_b = " in report and " N/m;" in report   # the unit as written
    for name in ("fit_up", "overload", "sequential", "simultaneous"):
        assert f"| {name} |" in report
    for i in (0, 1):
        assert (showcase_cli / "figures" / f"shakedown_map_mesh{i}.png").stat().st_size > 0
    assert (showcase_cli / "figures" / "dissipation_by_protocol.png").exists()
    s = _summary(showcase_cli)
    assert len(s["mesh_spacing"]) == len(s["window_mesh_spacing"]) == 2
    assert s["units"]["window_lambda2"] == "N"


def test_b_0_gives_one_answer_where_the_coupled_fit_up_differs(showcase_cli):
    """On both meshes: with B = 0 the protocols' dissipation agrees to 1e-3 (left: the
    bolt forces the assembly leaves, 0.14 % apart), while the coupled fit-up is more
    than 20 % above plain tightening."""
    s = _summary(showcase_cli)
    coupled = np.array(s["mesh_dissipation"])
    decoupled = np.array(s["decoupled_mesh_dissipation"])
    names = s["protocols"]
    fit, seq = names.index("fit_up"), names.index("sequential")
    for m in range(2):
        d0 = decoupled[m]
        assert (d0.max() - d0.min()) / d0.max() < 1e-3
        assert coupled[m, fit] > 1.2 * coupled[m, seq]


def test_every_protocol_shakes_down_only_below_its_lambda2(showcase_cli):
    """λ2 (the cone program with separation) bounds the amplitude at which any start can
    shake down; the engine's limits, found independently on the amplitude grid and by
    bisection, respect it on both meshes."""
    s = _summary(showcase_cli)
    for lam2, limits in zip(s["window_lambda2"], s["window_shakedown_limits"], strict=True):
        for l2, (lo, _) in zip(lam2, limits, strict=True):
            assert 0 <= lo <= l2 * (1 + 1e-6)
    for win in s["window_protocol_class_window"]:
        assert win is None or win[0] <= win[1]


def test_python_gives_the_numbers_of_the_command_line(showcase_cli):
    """The coarse mesh through :func:`lap_joint_showcase` (no window): the command line's
    coupled and B = 0 dissipation of every protocol on that mesh."""
    lc = read_lap_joint_case(parse_case_text(SHOWCASE))
    from slipcycle.joints.lap_joint_case import coarser_joint

    coarse = joint_contact(coarser_joint(lc.joint, lc.coarsening[0]))
    res = lap_joint_showcase(coarse, lc.protocols, lc.settings, fields=())
    assert isinstance(res, LapJointShowcase) and res.windows == ()
    s = _summary(showcase_cli)
    np.testing.assert_allclose(res.dissipation, s["mesh_dissipation"][0], rtol=1e-9)
    np.testing.assert_allclose(res.decoupled.dissipation, s["decoupled_mesh_dissipation"][0],
                               rtol=1e-9)


def test_docs_showcase_numbers_are_the_command_lines(showcase_cli):
    """docs/lap_joint.md, "The showcase on the small joint of the tests": every number."""
    import re
    from pathlib import Path

    docs = (Path(__file__).resolve().parents[1] / "docs" / "lap_joint.md").read_text(
        encoding="utf-8")
    text = " ".join(docs[docs.index("**The showcase on the small joint"):
                         docs.index("## Case file")].split())

    def quoted(pattern):
        found = re.search(pattern, text)
        assert found is not None, pattern
        return [float(g) for g in found.groups()]

    s = _summary(showcase_cli)
    d = 1e6 * np.array(s["mesh_dissipation"])            # (mesh, protocol) [µJ]
    d0 = 1e6 * np.array(s["decoupled_mesh_dissipation"])
    seq, sim, fit, ovl = (s["protocols"].index(n) for n in
                          ("sequential", "simultaneous", "fit_up", "overload"))
    num = r"([0-9.]+)"
    np.testing.assert_allclose(quoted(rf"sequential {num} / {num} µJ"), d[:, seq], rtol=6e-4)
    np.testing.assert_allclose(quoted(rf"simultaneous {num} / {num} µJ"), d[:, sim],
                               rtol=6e-4)
    np.testing.assert_allclose(quoted(rf"fit-up {num} / {num} µJ"), d[:, fit], rtol=6e-4)
    np.testing.assert_allclose(quoted(rf"overload {num} / {num} µJ"), d[:, ovl], rtol=6e-4)
    orders = quoted(rf"the orders differ by {num} % and {num} %, far less than the {num} % "
                    "between the meshes")
    np.testing.assert_allclose(orders[:2], [100 * abs(d[0, sim] / d[0, seq] - 1),
                                            100 * abs(d[1, sim] / d[1, seq] - 1)],
                               atol=0.06)        # percent, quoted to one decimal
    assert orders[2] == pytest.approx(100 * (1 - d[1, seq] / d[0, seq]), rel=0.03)
    assert orders[2] > 10 * max(orders[:2])
    pct = quoted(rf"{num} % / {num} % above sequential")
    assert pct == [round(100 * (d[m, fit] / d[m, seq] - 1)) for m in range(2)]
    np.testing.assert_allclose(quoted(rf"every protocol {num}–{num} µJ on the fine mesh"),
                               [d0[1].min(), d0[1].max()], rtol=6e-4)

    def spread(x):
        return 100 * (x.max() - x.min()) / x.max()

    np.testing.assert_allclose(quoted(rf"a spread of {num} % \(coarse {num} %\) against the "
                                      rf"coupled {num} %"),
                               [spread(d0[1]), spread(d0[0]), spread(d[1])], rtol=2e-2)
    lam2 = quoted(rf"λ2 with separation {num} N \(coarse\) and {num} N \(fine\)")
    np.testing.assert_allclose(lam2, [s["window_lambda2"][m][seq] for m in range(2)],
                               rtol=1e-3)
    windows = quoted(rf"class window is \[{num}, {num}\] N on the coarse mesh and "
                     rf"\[{num}, {num}\] N on the fine")
    np.testing.assert_allclose(windows, np.ravel(s["window_protocol_class_window"]),
                               rtol=5e-3)
