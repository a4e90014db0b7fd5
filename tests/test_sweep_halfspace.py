"""The sweep machinery serves the half-space Ŵ maps: same numbers as the map kernel."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from slipcycle.halfspace.wmap import w_hat_point

ROUGH = """
model = "halfspace"
[halfspace]
profile = "rough_exponential"
gamma_sigma = 1e-6
compliance_ratio = 1.0
friction = 0.5
[loading]
P0 = 100.0
P1 = 40.0
Q1 = 25.0
phase = 0.0
[run]
cycles = 6
steps_per_cycle = 400
sliders = 1500
"""


def test_sweep_over_phase_reproduces_w_hat_map(run_cli, write_case, tmp_path):
    out = tmp_path / "sweep"
    code, _, err = run_cli("sweep", write_case(ROUGH), "--set", "loading.phase=0.5,1.0,2.0",
                           "--out", out, "--workers", "1", "--no-progress")
    assert code == 0, err
    ds = xr.open_dataset(out / "result.nc")
    name = next(v for v in ds.data_vars if "W_hat" in v)
    W = np.asarray(ds[name]).ravel()
    expected = [w_hat_point(0.4, 0.5, phi, n_sliders=400, steps_per_cycle=400)
                for phi in (0.5, 1.0, 2.0)]
    assert W == pytest.approx(expected, rel=3e-3)
    assert json.loads((out / "summary.json").read_text())
