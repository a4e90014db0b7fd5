"""The numbers docs/roughness.md quotes for the example surface (examples/
halfspace_topography.toml): `slipcycle roughness` on the shipped case, whose joint law is
the one `slipcycle run` solves.

Run with ``pytest -s`` to print them.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("ContactMechanics")
pytest.importorskip("SurfaceTopography")

from slipcycle.examples import copy_examples  # noqa: E402


@pytest.mark.slow
def test_example_study_gives_the_numbers_of_the_docs(tmp_path, monkeypatch, run_cli):
    monkeypatch.setenv("SLIPCYCLE_CACHE", str(tmp_path / "cache"))
    copy_examples(tmp_path / "ex")
    case = tmp_path / "ex" / "halfspace_topography.toml"
    assert run_cli("roughness", case, "--out", tmp_path / "study")[0] == 0
    assert run_cli("run", case, "--out", tmp_path / "run")[0] == 0
    s = json.loads((tmp_path / "study" / "summary.json").read_text())
    run = json.loads((tmp_path / "run" / "summary.json").read_text())
    with xr.open_dataset(tmp_path / "study" / "result.nc") as ds:
        ds = ds.load()
    W, S = s["dissipation_per_cycle"], s["stiffness"]
    lo, hi = s["exponential_fit_pressure_range"]
    short_W = ds.dissipation_short.values / W
    short_S = ds.stiffness_short.values / S
    long_W = ds.dissipation_long.values / W
    long_S = ds.stiffness_long.values / S
    phase_W = dict(zip(np.round(ds.phase.values, 3), ds.dissipation_phase.values * 1e6,
                       strict=True))
    print(f"\ngamma_sigma {s['gamma_sigma'] * 1e6:.3f} um, gamma {s['gamma']:.3f}; window "
          f"{lo / 1e6:.1f}-{hi / 1e6:.1f} MPa, {s['exponential_fit_decades']:.2f} decades, "
          f"max deviation {s['fit_max_deviation']:.3f}; W {W * 1e6:.2f} uJ (run "
          f"{run['dissipation_per_cycle'] * 1e6:.2f}), exponential "
          f"{s['dissipation_per_cycle_exponential'] * 1e6:.2f} uJ, W_hat {s['W_hat']:.3f}, "
          f"dP/dU {S:.3e} N/m, map {s['fretting_map_total'] * 1e6:.1f} uJ")
    print("short W", short_W.round(3), "dP/dU", short_S.round(3))
    print("long W", long_W.round(3), "dP/dU", long_S.round(3))
    print("cut-offs [um]", {k: None if s[k] is None else round(s[k] * 1e6) for k in (
        "short_cutoff_dissipation", "short_cutoff_stiffness", "long_cutoff_dissipation",
        "long_cutoff_stiffness")})
    # `run` and the study solve one law of the joint
    assert W == pytest.approx(run["dissipation_per_cycle"], rel=1e-9)
    assert s["gamma_sigma"] == pytest.approx(0.507e-6, abs=0.0005e-6)
    assert s["gamma"] == pytest.approx(0.519, abs=0.0005)
    assert (lo, hi) == pytest.approx((26.3e6, 87.5e6), abs=0.05e6)
    assert s["exponential_fit_decades"] == pytest.approx(0.52, abs=0.005)
    assert s["fit_max_deviation"] == pytest.approx(0.062, abs=0.0005)
    assert W == pytest.approx(143.3e-6, abs=0.05e-6)
    assert s["dissipation_per_cycle_exponential"] == pytest.approx(161.9e-6, abs=0.05e-6)
    assert s["W_hat"] == pytest.approx(0.186, abs=0.0005)
    assert S == pytest.approx(9.65e9, abs=0.005e9)
    assert s["fretting_map_total"] == pytest.approx(139.5e-6, abs=0.05e-6)
    assert phase_W[0.785] == pytest.approx(133, abs=0.5)
    assert phase_W[-0.785] == pytest.approx(53, abs=0.5)
    assert short_W == pytest.approx([1.000, 1.008, 0.932, 0.963, 0.460, 0.476, 0.138],
                                    abs=0.0005)
    assert short_S == pytest.approx([1.000, 0.974, 0.966, 1.027, 1.436, 1.888, 8.075],
                                    abs=0.0005)
    assert long_W == pytest.approx([0.185, 0.243, 0.399, 0.526, 0.636, 0.885], abs=0.0005)
    assert long_S == pytest.approx([5.876, 3.695, 2.559, 1.528, 1.382, 1.022], abs=0.0005)
    assert s["short_cutoff_dissipation"] == pytest.approx(69e-6, abs=0.5e-6)
    assert s["short_cutoff_stiffness"] == pytest.approx(128e-6, abs=0.5e-6)
    assert s["long_cutoff_dissipation"] is None
    assert s["long_cutoff_stiffness"] == pytest.approx(643e-6, abs=0.5e-6)
