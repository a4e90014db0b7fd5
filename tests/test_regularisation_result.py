"""The rods regularisation study returns a result object of the analysis contract."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import case_text

from slipcycle.io.case import parse_case_text
from slipcycle.result import StudyResult
from slipcycle.rods.case import solve_case
from slipcycle.rods.regularisation import REG_MODELS, RegularisationResult

CASE = case_text("rods_spec", rods={"modes": 6, "rings": 10},
                 loading={"rotation_amplitude": 0.001},
                 run={"steps_per_cycle": 64, "regularisation_points": 8})


@pytest.fixture(scope="module")
def run():
    return solve_case(parse_case_text(CASE))


@pytest.fixture(scope="module")
def reg(run):
    return run.analysis["reg"]


def test_is_a_study_result_and_a_mapping(reg):
    assert isinstance(reg, RegularisationResult) and isinstance(reg, StudyResult)
    assert set(reg) >= {"amplitude", "gross_slip_torque", "theta_gross", "iwan_params",
                        "first_slip_torque", "_beds", *REG_MODELS}
    assert reg["amplitude"] is reg.amplitude
    assert reg["distributed"] is reg.models["distributed"]
    assert reg["_beds"] is reg.beds
    with pytest.raises(KeyError):
        reg["nope"]
    with pytest.raises(AttributeError):  # frozen
        reg.theta_gross = 1.0


def test_summary_agrees_with_the_rods_run_summary(run, reg):
    rs = run.summary()["regularisation"]
    s = reg.summary()
    for m in REG_MODELS:
        assert s[m] == rs[m]
    assert s["iwan_fit"] == rs["iwan_fit"]
    assert s["analysis"] == "regularisation" and s["model"] == "rods"
    assert s["gross_slip_torque"] == pytest.approx(run.summary()["gross_slip_torque"])
    assert s["units"]["gross_slip_torque"] == "N m"
    assert s["units"]["theta_gross"] == "rad"
    assert s["units"]["iwan_fit.K_T"] == "N m/rad"
    json.dumps(s)  # JSON-ready
    assert s["points"] == reg.amplitude.size


def test_dataset_agrees_with_the_rods_run_dataset(run, reg):
    ds, rds = reg.to_dataset(), run.to_dataset()
    assert ds["amplitude"].attrs["units"] == "rad"
    np.testing.assert_array_equal(ds["amplitude"].values, rds["amplitude"].values)
    for m in REG_MODELS:
        for v, unit in ((f"reg_T_{m}", "N m"), (f"reg_D_{m}", "J")):
            assert ds[v].attrs["units"] == unit == rds[v].attrs["units"]
            np.testing.assert_array_equal(ds[v].values, rds[v].values)
    assert list(rds.data_vars)[-8:] == [f"reg_{q}_{m}" for m in REG_MODELS for q in "TD"]


def test_figures_repr_and_html(run, reg):
    assert set(reg.figures()) == {"regularisation"}
    assert "regularisation" in run.figures()
    r = repr(reg)
    assert "\n" not in r and r.startswith("<RegularisationResult rods regularisation:")
    assert "gross_slip_torque=" in r
    h = reg._repr_html_()
    assert h.startswith("<table>") and "theta_gross" in h
    assert reg.wall_time_s > 0 and math.isfinite(reg.wall_time_s)
    assert reg.flags["analysis"] == ("regularisation",)
    out = reg.to_outputs()
    assert out.summary["analysis"] == "regularisation"
