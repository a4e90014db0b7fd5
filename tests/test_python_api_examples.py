"""Every model's Python example runs and prints the numbers of the same case run from a
case file (the TOML path used by the command line)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import case_text

from slipcycle.io import parse_case_text

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"  # the Python example scripts


def run_example(name: str, tmp_path: Path) -> dict:
    env = {**os.environ, "SLIPCYCLE_EXAMPLES_OUT": str(tmp_path), "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, str(EXAMPLES / f"python_{name}.py")], env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    out = {}
    for line in proc.stdout.splitlines():
        m = re.match(r"^(\w+) = (\S+)", line)
        if m:
            out[m.group(1)] = m.group(2)
    assert list(tmp_path.glob("*.png")), "the example saved no figure"
    return out


def close(printed: str, value: float) -> bool:
    return np.isclose(float(printed), value, rtol=1e-8, atol=1e-300)


def test_halfspace_example(tmp_path):
    from slipcycle.halfspace.case import run_case

    got = run_example("halfspace", tmp_path)
    ref = run_case(parse_case_text(case_text(
        "halfspace_sphere", loading={"P1": None, "Q0": None, "phase": None}))).summary
    assert close(got["dissipation_per_cycle"], ref["dissipation_per_cycle"])
    assert (got["steady"] == "True") == (ref["steady_state"] == "steady")


def test_discrete_example(tmp_path):
    from slipcycle.discrete.case import run_case

    got = run_example("discrete", tmp_path)
    ref = run_case(parse_case_text(case_text(
        "discrete_two_node", discrete={"initial_slip": None}, loading={"lam": None}))).summary
    assert close(got["dissipation_per_cycle"], ref["dissipation_per_cycle"])
    assert close(got["f_crit"], ref["f_crit"])
    assert got["steady_state"] == ref["steady_state"]
    assert int(got["cycles_run"]) == ref["cycles_run"]


def test_rods_example(tmp_path):
    from slipcycle.rods.case import run_case

    got = run_example("rods", tmp_path)
    text = case_text("rods_spec", loading={"rotation_amplitude": 1.5e-2},
                     run={"regularisation": False})
    ref = run_case(parse_case_text(text)).summary
    for key in ("omega1", "T_dyn_max", "T_qs_max", "dissipation_per_cycle"):
        assert close(got[key], ref[key]), key
    assert ref["dissipation_per_cycle"] > 0   # the example slips
    assert (got["steady_state_reached"] == "True") == ref["steady_state_reached"]


def test_fe_example(tmp_path):
    from slipcycle.fe.checks import coupling_ratio
    from slipcycle.fe.model import build_problem
    from slipcycle.fe.reduction import reduce_problem

    got = run_example("fe", tmp_path)
    red = reduce_problem(build_problem(parse_case_text("""model = "fe"
[fe]
geometry = "block_on_rigid"
width = 0.04
height = 0.02
E = 210e9
nu = 0.3
elements = 4
grading = 1.3
element = "P2"
thickness = 0.01
top = "displacement"
""")))
    assert int(got["n_nodes"]) == red.n
    assert close(got["trace_A"], np.trace(red.A))
    assert close(got["trace_C"], np.trace(red.C))
    assert close(got["coupling_ratio"], coupling_ratio(red))


@pytest.mark.parametrize("name", ["halfspace", "discrete", "rods", "fe"])
def test_examples_build_no_case_file(name):
    text = (EXAMPLES / f"python_{name}.py").read_text()
    assert "parse_case_text" not in text and "read_case" not in text and ".toml" not in text
