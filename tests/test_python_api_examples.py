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

from slipcycle.io import parse_case_text

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


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
    ref = run_case(parse_case_text("""model = "halfspace"
[halfspace]
profile = "sphere"
radius = 0.01
E = [200e9, 200e9]
nu = [0.3, 0.3]
friction = 0.5
[loading]
P0 = 100.0
Q1 = 30.0
[run]
cycles = 3
steps_per_cycle = 400
""")).summary
    assert close(got["dissipation_per_cycle"], ref["dissipation_per_cycle"])
    assert (got["steady"] == "True") == (ref["steady_state"] == "steady")


def test_discrete_example(tmp_path):
    from slipcycle.discrete.case import run_case

    got = run_example("discrete", tmp_path)
    ref = run_case(parse_case_text("""model = "discrete"
[discrete]
A = [[1.0, -0.3], [-0.3, 0.8]]
B = [[0.4, 0.1], [-0.2, 0.3]]
C = [[1.0, -0.2], [-0.2, 1.0]]
friction = 0.5
[loading]
p0 = [1.0, 1.0]
q0 = [0.0, 0.0]
p1 = [0.3, 0.2]
p1_phase = [0.0, 1.0]
q1 = [0.4, 0.5]
q1_phase = [0.5, 2.0]
[run]
cycles = 40
steps_per_cycle = 400
""")).summary
    assert close(got["dissipation_per_cycle"], ref["dissipation_per_cycle"])
    assert close(got["f_crit"], ref["f_crit"])
    assert got["steady_state"] == ref["steady_state"]
    assert int(got["cycles_run"]) == ref["cycles_run"]


def test_rods_example(tmp_path):
    from slipcycle.rods.case import run_case

    got = run_example("rods", tmp_path)
    ref = run_case(parse_case_text("""model = "rods"
[rods]
L = [0.5, 0.5]
radius = [0.01, 0.01]
E = [200e9, 200e9]
nu = [0.3, 0.3]
density = [7850.0, 7850.0]
friction = 0.3
axial_force = 1.0e4
interface = "distributed"
interface_stiffness = 1.0e13
damping_ratio = 0.01
modes = 50
[loading]
rotation_amplitude = 1.5e-2
frequency_ratio = 0.3
[run]
regularisation = false
""")).summary
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
