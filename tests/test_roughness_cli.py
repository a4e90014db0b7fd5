"""``slipcycle roughness`` and ``profile = "topography"`` end to end, from a topography file;
the refusal of a base install without the ``topo`` extra; P(U) tables from files."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("ContactMechanics")
pytest.importorskip("SurfaceTopography")

from slipcycle.halfspace.topography import synthetic_surface  # noqa: E402

CASE = """
model = "halfspace"
[halfspace]
profile = "topography"
topography_file = "surface.nc"
nominal_area = 1.0e-4
bem_grid = 32
bem_loads = 10
fit = "{fit}"
E = [200e9, 200e9]
nu = [0.3, 0.3]
friction = 0.5
[loading]
P0 = 5000.0
P1 = 2000.0
Q1 = 1000.0
phase = 1.5707963267948966
[run]
cycles = 3
steps_per_cycle = 60
sliders = 100
"""

STUDY = """
[roughness]
short_cutoffs = [1.0e-4, 3.0e-4]
long_cutoffs = [3.0e-4, 6.0e-4]
phases = [0.0, 1.5707963267948966]
grids = [16, 32]
sliders = [50, 100]
rings = 4
"""


@pytest.fixture
def surface_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("SLIPCYCLE_CACHE", str(tmp_path / "cache"))
    topo = synthetic_surface(32, 1e-3, hurst=0.8, rms_height=1e-6, short_cutoff=1e-3 / 8,
                             long_cutoff=2.5e-4, seed=2)
    topo.to_netcdf(str(tmp_path / "surface.nc"))
    return tmp_path


def test_roughness_command_writes_study_from_a_topography_file(surface_dir, run_cli):
    case = surface_dir / "case.toml"
    case.write_text(CASE.format(fit="table") + STUDY)
    code, out, err = run_cli("roughness", case, "--out", surface_dir / "out")
    assert code == 0, err
    s = json.loads((surface_dir / "out" / "summary.json").read_text())
    assert s["analysis"] == "roughness"
    assert s["dissipation_per_cycle"] > 0
    assert s["units"]["dissipation_per_area"] == "J/m^2"
    assert s["dissipation_per_area"] == pytest.approx(s["dissipation_per_cycle"] / 1e-4)
    # the smooth flat punch of the nominal area sticks: the roughness alone dissipates
    assert abs(s["fretting_map_smooth_dissipation"]) < 1e-9 * s["dissipation_per_cycle"]
    assert s["fretting_map_total"] > 0
    assert s["slider_convergence_dissipation"] < 0.02
    for name in ("normal_law", "cutoff_study", "dissipation_vs_phase", "fretting_map"):
        assert (surface_dir / "out" / "figures" / f"{name}.png").is_file()
    with xr.open_dataset(surface_dir / "out" / "result.nc") as ds:
        assert ds.ring_dissipation.attrs["units"] == "J/m^2"
        assert all("units" in ds[v].attrs for v in ds.data_vars)
        # the map is what the summary totals
        total = float((ds.ring_dissipation * ds.ring_area).sum())
        assert total == pytest.approx(s["fretting_map_total"], rel=1e-12)
    assert list((surface_dir / "cache").glob("bem-*.npz"))


def test_run_with_topography_profile_uses_the_bem_law(surface_dir, run_cli):
    for fit in ("table", "exponential"):
        case = surface_dir / f"{fit}.toml"
        case.write_text(CASE.format(fit=fit))
        code, out, err = run_cli("run", case, "--out", surface_dir / fit)
        assert code == 0, err
        s = json.loads((surface_dir / fit / "summary.json").read_text())
        assert s["profile"] == {"table": "tabulated", "exponential": "rough_exponential"}[fit]
        assert s["dissipation_per_cycle"] > 0
        # the summary says which surface the law came from; σ recomputed from the file
        heights = xr.open_dataset(surface_dir / "surface.nc").heights.values
        surface = s["surface"]
        assert surface["file"] == "surface.nc" and surface["fit"] == fit
        assert surface["map_points"] == [32, 32] and surface["bem_grid"] == 32
        assert surface["map_size"] == pytest.approx([1e-3, 1e-3], rel=1e-6)
        assert surface["rms_height"] == pytest.approx(np.std(heights), rel=1e-6)
        assert s["units"]["surface.rms_height"] == "m"
        assert ("gamma_sigma" in surface) == (fit == "exponential")


def test_base_install_refuses_in_one_line_naming_the_extra(surface_dir, run_cli,
                                                          monkeypatch):
    case = surface_dir / "case.toml"
    case.write_text(CASE.format(fit="table"))
    monkeypatch.setitem(sys.modules, "SurfaceTopography", None)   # import fails
    code, out, err = run_cli("run", case, "--out", surface_dir / "out")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1
    assert "pip install 'slipcycle[topo]'" in lines[0]
    assert lines[0].startswith("error: halfspace.topography_file:")
    assert not (surface_dir / "out").exists()


def test_topography_case_errors_name_the_key(surface_dir, run_cli):
    case = surface_dir / "case.toml"
    case.write_text(CASE.format(fit="table").replace('"surface.nc"', '"missing.nc"'))
    code, _, err = run_cli("run", case, "--out", surface_dir / "out")
    assert code == 2 and err.startswith("error: halfspace.topography_file: file not found")
    case.write_text(CASE.format(fit="tabel"))
    code, _, err = run_cli("run", case, "--out", surface_dir / "out")
    assert code == 2 and "halfspace.fit" in err
    case.write_text(CASE.format(fit="table").replace("nominal_area = 1.0e-4",
                                                     "nominal_area = -1.0"))
    code, _, err = run_cli("run", case, "--out", surface_dir / "out")
    assert code == 2 and "halfspace.nominal_area" in err
    case.write_text(CASE.format(fit="table") + STUDY.replace("rings", "ringz"))
    code, _, err = run_cli("roughness", case, "--out", surface_dir / "out")
    assert code == 2 and err.startswith("error: roughness.ringz: unknown key")
    case.write_text(CASE.format(fit="table") + STUDY.replace("grids = [16, 32]",
                                                             "grids = [4, 32]"))
    code, _, err = run_cli("roughness", case, "--out", surface_dir / "out")
    assert code == 2 and err.startswith("error: roughness.grids:")


TABLE = """
model = "halfspace"
[halfspace]
profile = "tabulated"
{table}
compliance_ratio = 1.2
friction = 0.5
[loading]
P0 = 50.0
P1 = 20.0
Q1 = 10.0
phase = 1.0
[run]
cycles = 3
steps_per_cycle = 80
"""


def test_table_file_gives_the_same_run_as_the_inline_table(tmp_path, run_cli):
    U = np.linspace(0.0, 3e-6, 13)
    P = 100.0 * (np.exp(U / 1e-6) - 1.0)       # convex, from 0
    (tmp_path / "law.csv").write_text("U,P\n" + "".join(f"{u!r},{p!r}\n" for u, p in
                                                        zip(U.tolist(), P.tolist(), strict=True)))
    inline = f"table_U = {U.tolist()!r}\ntable_P = {P.tolist()!r}"
    results = []
    for name, table in (("file", 'table_file = "law.csv"'), ("inline", inline)):
        case = tmp_path / f"{name}.toml"
        case.write_text(TABLE.format(table=table))
        code, _, err = run_cli("run", case, "--out", tmp_path / name)
        assert code == 0, err
        results.append(json.loads((tmp_path / name / "summary.json").read_text()))
    assert results[0]["dissipation_per_cycle"] == results[1]["dissipation_per_cycle"]
    bad = tmp_path / "bad.csv"
    bad.write_text("U,P\n0,0\n1e-6,2\n2e-6,3\n")   # concave: no slider bed
    case = tmp_path / "bad.toml"
    case.write_text(TABLE.format(table='table_file = "bad.csv"'))
    code, _, err = run_cli("run", case, "--out", tmp_path / "bad")
    assert code == 2 and err.startswith("error: halfspace.table_file:")
