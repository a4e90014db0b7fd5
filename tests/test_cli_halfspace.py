"""The command line: results on disk, and bad input refused with one clear message."""

from __future__ import annotations

import json

import pytest
import xarray as xr
from conftest import case_text

GOOD = case_text("halfspace_sphere", run={"steps_per_cycle": 200, "sliders": 500})


def test_run_writes_summary_dataset_figures(run_cli, write_case, tmp_path):
    out = tmp_path / "out"
    code, stdout, err = run_cli("run", write_case(GOOD), "--out", out)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steady_state"] == "steady"
    assert summary["dissipation_per_cycle"] > 0
    assert summary["metadata"]["slipcycle_version"]
    ds = xr.open_dataset(out / "result.nc")
    assert ds.Q.attrs["units"] == "N" and "radius = 0.01" in ds.attrs["case"]
    assert {p.name for p in (out / "figures").iterdir()} >= {"hysteresis.png", "load_path.png",
                                                              "tractions.png"}


def test_gross_slip_is_reported_with_time_and_loads(run_cli, write_case, tmp_path):
    out = tmp_path / "out"
    text = GOOD.replace("Q1 = 30.0", "Q1 = 60.0").replace(
        "phase = 0.0", "phase = 0.0\n[[loading.protocol]]\nP = 100.0\nQ = 0.0")
    code, _, err = run_cli("run", write_case(text), "--out", out)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    g = summary["gross_slip"]
    # normal preload first, then Q ramps towards 60 N: gross slip when Q reaches fP = 50 N
    assert summary["steady_state"] == "gross_slip" and g["cycle"] == -1
    assert g["P"] == pytest.approx(100.0)
    assert 50.0 <= g["Q"] <= 50.0 + 60.0 / 50  # within one assembly step of fP


BAD = [
    ("unknown", GOOD.replace("friction = 0.5", "friction = 0.5\nfricton = 0.3"),
     "halfspace.fricton"),
    ("missing", GOOD.replace("radius = 0.01\n", ""), "halfspace.radius"),
    ("negative f", GOOD.replace("friction = 0.5", "friction = -0.5"), "halfspace.friction"),
    ("shape", GOOD.replace("E = [200e9, 200e9]", "E = [200e9]"), "halfspace.E"),
    ("nan", GOOD.replace("P0 = 100.0", "P0 = nan"), "loading.P0"),
    ("nu", GOOD.replace("nu = [0.3, 0.3]", "nu = [0.3, 0.7]"), "halfspace.nu"),
    ("profile", GOOD.replace('"sphere"', '"spere"'), "halfspace.profile"),
    ("tensile", GOOD.replace("P1 = 0.0", "P1 = 150.0"), "loading.P1"),
    ("model", GOOD.replace('model = "halfspace"', 'model = "halfspase"'), "model"),
    ("mixed control", GOOD.replace("Q1 = 30.0", "Q1 = 30.0\nV1 = 1e-6"), "loading.V0"),
    ("table", GOOD.replace("[run]", "[runn]"), "runn"),
    ("toml", GOOD + "\n[[[", "TOML"),
]


@pytest.mark.parametrize("name,text,key", BAD, ids=[b[0] for b in BAD])
def test_bad_input_refused_with_key_and_no_output(run_cli, write_case, tmp_path, name, text, key):
    out = tmp_path / "out"
    code, stdout, err = run_cli("run", write_case(text), "--out", out)
    assert code == 2
    assert key in err and err.startswith("error:") and err.count("\n") == 1
    assert not out.exists()
    assert not list(tmp_path.glob(".out.partial*"))


def test_map_command_writes_fig7(run_cli, write_case, tmp_path):
    text = """
model = "halfspace"
[map]
P1_hat = [0.0, 0.4]
Q1_hat = [0.1, 0.3]
phase = {start = -3.0, stop = 3.0, num = 5}
fig7_Q1_hat = [0.2, 0.4]
[run]
steps_per_cycle = 64
sliders = 40
"""
    out = tmp_path / "map"
    code, _, err = run_cli("map", write_case(text), "--out", out)
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["grid_points"] == 20 and 2.8 < s["cubic_law_slope"] < 3.2
    assert (out / "figures" / "w_hat_vs_phase.png").exists()
