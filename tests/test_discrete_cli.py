"""The discrete model through the CLI: example, outputs, refused inputs."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"

BASE = """
model = "discrete"
[discrete]
A = {A}
B = {B}
C = {C}
friction = {f}
{extra}
[loading]
p0 = [1.0, 1.0]
p1 = [0.3, 0.2]
p1_phase = [0.0, 1.0]
q1 = [0.4, 0.5]
q1_phase = [0.5, 2.0]
[run]
cycles = 5
steps_per_cycle = 40
"""

GOOD = {"A": "[[1.0, -0.3], [-0.3, 0.8]]", "B": "[[0.4, 0.1], [-0.2, 0.3]]",
        "C": "[[1.0, -0.2], [-0.2, 1.0]]", "f": "0.5", "extra": ""}


def case_text(**kw):
    return BASE.format(**{**GOOD, **kw})


def test_spec_example_runs_as_written(run_cli, tmp_path):
    out = tmp_path / "out"
    code, stdout, err = run_cli("run", EXAMPLES / "discrete_two_node.toml", "--out", out,
                                "--quiet")
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    for key in ("steady_state", "dissipation_per_cycle", "dissipation_per_node",
                "slipping_nodes", "permanently_stuck_nodes", "cycles_run", "f_crit",
                "residual", "energy_balance_error"):
        assert key in summary
    assert summary["steady_state"] in ("shakedown", "cyclic_slip", "ratcheting",
                                       "not_converged")
    assert summary["f_crit"] > 0.5
    assert {p.name for p in (out / "figures").iterdir()} == {
        "slip_and_tractions.png", "hysteresis.png", "v_space.png"}
    with xr.open_dataset(out / "result.nc") as ds:
        for name in ("slip", "separation", "tangential_reaction", "normal_reaction",
                     "node_state"):
            assert name in ds
        for var in list(ds.data_vars) + list(ds.coords):
            assert "units" in ds[var].attrs, var
        assert ds.sizes["cycle"] == summary["cycles_run"]


def test_all_discrete_examples_run(run_cli, tmp_path):
    for path in sorted(EXAMPLES.glob("discrete_*.toml")):
        code, _, err = run_cli("run", path, "--out", tmp_path / path.stem, "--quiet")
        assert code == 0, f"{path.name}: {err}"


def test_stiffness_file_and_protocol(run_cli, write_case, tmp_path):
    A = np.array([[1.0, -0.3], [-0.3, 0.8]])
    B = np.array([[0.4, 0.1], [-0.2, 0.3]])
    C = np.array([[1.0, -0.2], [-0.2, 1.0]])
    np.savez(tmp_path / "reduced.npz", A=A, B=B, C=C, p_w=np.array([[0.5, 0.5]]),
             q_w=np.array([[0.1, -0.1]]))
    text = case_text().replace(
        'A = [[1.0, -0.3], [-0.3, 0.8]]\nB = [[0.4, 0.1], [-0.2, 0.3]]\n'
        'C = [[1.0, -0.2], [-0.2, 1.0]]', 'stiffness_file = "reduced.npz"')
    text = text.replace("[loading]", "[[discrete.protocol]]\np_w = [1.0, 0.2]\n"
                        "q_w = [0.0, 0.1]\n[loading]")
    text += "[[loading.load_case]]\nfile_case = 0\nmean = 0.0\namplitude = 0.5\nphase = 1.0\n"
    code, out, err = run_cli("run", write_case(text), "--out", tmp_path / "o", "--quiet")
    assert code == 0, err


@pytest.mark.parametrize("kw, key, words", [
    ({"C": "[[1.0, 2.0], [2.0, 1.0]]"}, "discrete.C", "positive definite"),
    ({"A": "[[1.0, 0.5], [-0.3, 0.8]]"}, "discrete.A", "symmetric"),
    ({"B": "[[4.0, 0.1], [-0.2, 0.3]]"}, "discrete.B", "not positive definite"),
    ({"B": "[[0.4, 0.1, 0.0], [-0.2, 0.3, 0.0]]"}, "discrete.B", "wrong shape"),
    ({"f": "2.5"}, "discrete.friction", "f_crit = 1.89"),
    ({"f": "-0.1"}, "discrete.friction", ">= 0"),
    ({"f": "nan"}, "discrete.friction", "finite"),
    ({"extra": "initial_slip = [0.5, 0.0]"}, "discrete.initial_slip", "node 0"),
    ({"extra": "initial_slip = [0.0]"}, "discrete.initial_slip", "wrong shape"),
    ({"extra": "frictoin = 0.3"}, "discrete.frictoin", "unknown key"),
    ({"extra": "initial_slip = [0.0, 0.0]\n[[discrete.protocol]]\np_w = [1.0, 1.0]"},
     "discrete.protocol", "not both"),
])
def test_bad_input_refused_with_named_key(run_cli, write_case, tmp_path, kw, key, words):
    out = tmp_path / "out"
    code, _, err = run_cli("run", write_case(case_text(**kw)), "--out", out)
    assert code == 2
    assert err.startswith(f"error: {key}:"), err
    assert words in err
    assert not out.exists()


def test_ill_posed_model_can_be_accepted_explicitly(run_cli, write_case, tmp_path):
    text = case_text(f="2.5", extra="accept_ill_posed = true")
    code, out, err = run_cli("run", write_case(text), "--out", tmp_path / "o", "--quiet")
    # it runs (or stops with a clear rate-problem error); it is not refused up front
    assert "f_crit" not in err or code == 0
    if code == 0:
        summary = json.loads((tmp_path / "o" / "summary.json").read_text())
        assert summary["well_posed"] is False
