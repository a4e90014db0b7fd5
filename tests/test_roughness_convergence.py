"""Convergence of the example rough joint (examples/halfspace_topography.toml) in the BEM
grid and in the slider count: the numbers of the table in docs/roughness.md.

Run with ``pytest -s`` to print the table.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("ContactMechanics")
pytest.importorskip("SurfaceTopography")

from slipcycle.halfspace.model import solve  # noqa: E402
from slipcycle.halfspace.topography import (  # noqa: E402
    bem_normal_law,
    fit_exponential,
    read_surface,
    resample,
    smooth_table,
)
from slipcycle.io import read_case  # noqa: E402
from slipcycle.studies.roughness import parse_roughness_case  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


def _W(model, profile):
    return solve(replace(model, profile=profile, profile_name=""),
                 record_last_cycle=False)[1].dissipation_per_cycle


@pytest.mark.slow
def test_example_joint_converges_in_bem_grid_and_slider_count(tmp_path, monkeypatch):
    monkeypatch.setenv("SLIPCYCLE_CACHE", str(tmp_path))
    model, source, _ = parse_roughness_case(read_case(EXAMPLES / "halfspace_topography.toml"))
    A, p0 = source.nominal_area, float(model.normal.mean[0]) / source.nominal_area
    native = read_surface(source.path)
    pressures = source.pressures(7000.0 / A)
    rows = []
    laws = {}
    for n in (32, 64, 128, 256):
        law = bem_normal_law(resample(native, n), source.contact_modulus, pressures)
        laws[n] = law
        fit = fit_exponential(law.pressure, law.approach, 0.1)
        rows.append((n, fit.gamma_sigma, A * float(law.stiffness(p0)),
                     _W(model, smooth_table(law, A, 400))))
    sliders = [(m, _W(model, smooth_table(laws[128], A, m))) for m in (100, 200, 400, 800,
                                                                         1600)]
    loads = []
    for k in (12, 48):   # BEM load samples (the case uses 24)
        law = bem_normal_law(resample(native, 128), source.contact_modulus,
                             replace(source, bem_loads=k).pressures(7000.0 / A))
        loads.append((k, _W(model, smooth_table(law, A, 400))))
    loads.insert(1, (24, rows[2][3]))
    print("\ngrid  gamma_sigma [um]  dP/dU at P0 [N/m]  W [uJ]  W/A [J/m^2]")
    for n, gs, S, W in rows:
        print(f"{n:4d}  {gs * 1e6:.4f}  {S:.4e}  {W * 1e6:.2f}  {W / A:.4f}")
    print("sliders  W [uJ] (grid 128)")
    for m, W in sliders:
        print(f"{m:5d}  {W * 1e6:.3f}")
    print("BEM loads  W [uJ] (grid 128)")
    for k, W in loads:
        print(f"{k:5d}  {W * 1e6:.3f}")
    W = np.array([r[3] for r in rows])
    S = np.array([r[2] for r in rows])
    gs = np.array([r[1] for r in rows])
    # the shortest wavelength (L/32) on 4 and 8 pixels: the two finest grids agree to 3 %
    assert abs(W[3] / W[2] - 1) < 0.03
    assert abs(S[3] / S[2] - 1) < 0.03
    assert abs(gs[3] / gs[2] - 1) < 0.02
    Ws = np.array([w for _, w in sliders])
    # the slider bed converges much faster: 0.1 % from 400 sliders on
    assert np.all(np.abs(Ws[2:] / Ws[-1] - 1) < 1e-3)
    # interpolating U(ln p) between BEM loads: 24 and 48 loads agree to 1 %
    assert abs(loads[1][1] / loads[2][1] - 1) < 0.01
