"""The demo report's Ŵ map is the study of ``slipcycle map`` (one Dataset builder, the
study's figures): the files it writes hold the study's numbers, and its cubic law has the
closed-form slope 3 (Ŵ = (2/3) Q̂1³ at small amplitude, Barber 2012)."""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from slipcycle.demo import write_report
from slipcycle.studies.w_hat_map import w_hat_map_study


def test_demo_writes_the_w_hat_map_study(tmp_path):
    report = write_report(tmp_path, cases={})
    out = tmp_path / "rough_w_map"
    assert sorted(p.name for p in (out / "figures").glob("*.png")) == [
        "w_hat_cubic_law.png", "w_hat_vs_phase.png"]
    assert "rough_w_map/figures/w_hat_vs_phase.png" in report.read_text()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["analysis"] == "w_hat_map"
    assert abs(summary["cubic_law_slope"] - 3.0) < 0.05
    Q1 = np.array([0.2, 0.4, 0.6, 0.8])
    study = w_hat_map_study(np.array([0.4]), Q1, np.linspace(-np.pi, np.pi, 37), 0.4, Q1, {})
    with xr.open_dataset(out / "result.nc") as ds:
        np.testing.assert_array_equal(ds["W_hat"].values, study.W_hat)
        assert ds["W_hat"].attrs["units"] == "1"
