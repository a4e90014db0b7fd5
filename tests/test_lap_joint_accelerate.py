"""``[run] accelerate`` of a lap-joint study: the Anderson-mixed steady state of each
protocol (:mod:`slipcycle.discrete3d.steady`), certified by plain cycles, against plain
cycling run to its limit; the key read from a case file, refused when it is no bool, and
the certificate reported per protocol in the summary."""

import json

import numpy as np
import pytest

import slipcycle
from slipcycle.api import as_case
from slipcycle.examples import example_path, example_text
from slipcycle.joints.lap_joint_case import read_lap_joint_case

SMALL = {"lap_joint.refine": 0, "lap_joint.convergence.coarsening": [],
         "lap_joint.protocols.names": ["sequential"], "output.fields": []}


def test_accelerated_protocol_lands_on_plain_cyclings_limit_in_fewer_cycles():
    """The shipped joint on its unrefined mesh (203 nodes), the sequential protocol:
    plain cycling to 1e-10 is the limit. The accelerated run (steady_tol 1e-6) ends
    within 1e-6 of its D (measured 4e-12), with the same class, the same slipping,
    separating and stuck nodes, in fewer cycles (8 against 10 of plain cycling at
    1e-6), and reports ``anderson`` with its certified residual below steady_tol."""
    limit = slipcycle.run(example_path("bolted_lap_joint.toml"),
                          {**SMALL, "run.steady_tol": 1e-10, "run.cycles": 300}).summary()
    plain = slipcycle.run(example_path("bolted_lap_joint.toml"), SMALL).summary()
    acc = slipcycle.run(example_path("bolted_lap_joint.toml"),
                        {**SMALL, "run.accelerate": True}).summary()
    assert acc["protocol_acceleration"] == ["anderson"]
    assert plain["protocol_acceleration"] == ["none"]
    assert acc["protocol_certified_residual"][0] <= 1e-6
    assert acc["protocol_memory_distance"][0] > 0 and acc["protocol_dissipation_distance"][0] > 0
    np.testing.assert_allclose(acc["protocol_dissipation_per_cycle"],
                               limit["protocol_dissipation_per_cycle"], rtol=1e-6)
    for key in ("protocol_steady_state", "protocol_slipping_nodes",
                "protocol_separating_nodes"):
        assert acc[key] == limit[key]
    np.testing.assert_allclose(acc["protocol_stuck_area"], limit["protocol_stuck_area"],
                               rtol=1e-12)
    assert acc["protocol_cycles_run"][0] < plain["protocol_cycles_run"][0]
    assert acc["units"]["protocol_certified_residual"] == "1"


def test_accelerate_is_read_from_the_case_file_and_a_non_bool_is_one_line(tmp_path,
                                                                          run_cli):
    """The CLI reads ``[run] accelerate`` (its summary names the method per protocol),
    and ``accelerate = "yes"`` ends in one line naming run.accelerate, exit code 2,
    nothing written."""
    bad = tmp_path / "bad.toml"
    bad.write_text(_small_text('"yes"'), encoding="utf-8")
    code, out, err = run_cli("run", bad, "--out", tmp_path / "bad_out")
    assert code == 2 and "run.accelerate" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "bad_out").exists()
    case = read_lap_joint_case(as_case(example_path("bolted_lap_joint.toml"),
                                       {"run.accelerate": True}))
    assert case.settings.run["accelerate"] is True
    default = read_lap_joint_case(as_case(example_path("bolted_lap_joint.toml")))
    assert default.settings.run["accelerate"] is False


def _small_text(accelerate: str) -> str:
    """The shipped case on its unrefined mesh, the sequential protocol only."""
    text = example_text("bolted_lap_joint")
    for a, b in (("\nrefine = 1 ", "\nrefine = 0 "), ("\ncoarsening = [2.0]", "\ncoarsening = []"),
                 ('names = ["sequential", "reversed", "simultaneous"]',
                  'names = ["sequential"]'), ('fields = ["xdmf"]', "fields = []"),
                 ("accelerate = false", f"accelerate = {accelerate}")):
        assert a in text, a
        text = text.replace(a, b, 1)
    return text


@pytest.mark.parametrize("value", ["true", "false"])
def test_python_and_the_command_line_report_the_same_certificate(tmp_path, run_cli,
                                                                  value):
    """`slipcycle run CASE` and `slipcycle.run(CASE)` with ``accelerate = …`` give the
    same per-protocol method and D."""
    case = tmp_path / "joint.toml"
    case.write_text(_small_text(value), encoding="utf-8")
    py = slipcycle.run(case).summary()
    code, out, err = run_cli("run", case, "--out", tmp_path / "out")
    assert code == 0, err
    cli = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    assert cli["protocol_acceleration"] == py["protocol_acceleration"]
    assert (py["protocol_acceleration"] == ["anderson"]) == (value == "true")
    np.testing.assert_allclose(cli["protocol_dissipation_per_cycle"],
                               py["protocol_dissipation_per_cycle"], rtol=1e-12)
