"""Edges of the rough-surface cases (``profile = "topography"``, ``slipcycle roughness``,
``slipcycle map``): what a user can get wrong is refused in one line naming the key, what
the model cannot compute is said, and `run` and the study solve one law of the joint."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("ContactMechanics")
pytest.importorskip("SurfaceTopography")

from slipcycle.halfspace.elastic import ContactElasticity  # noqa: E402
from slipcycle.halfspace.topography import SurfaceMap, synthetic_surface  # noqa: E402

CASE = """
model = "halfspace"
[halfspace]
profile = "topography"
topography_file = "{file}"
nominal_area = {area}
bem_grid = 32
bem_loads = 10
fit = "table"
E = [200e9, 200e9]
nu = [0.3, 0.3]
friction = 0.5
{extra}
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
short_cutoffs = [1.0e-4]
long_cutoffs = [6.0e-4]
phases = [1.5707963267948966]
grids = [32]
sliders = [100]
rings = 4
"""


def _nc(path, heights, x=None, length=1e-3):
    """A height map as SurfaceTopography's netCDF (heights in m, periodic)."""
    nx, ny = heights.shape
    x = np.arange(nx) * length / nx if x is None else x
    y = np.arange(ny) * length / ny
    attrs = {"length": length, "periodic": 1, "unit": "m"}
    xr.Dataset({"heights": (("x", "y"), heights, {"unit": "m"})},
               coords={"x": ("x", x, attrs), "y": ("y", y, attrs)}
               ).to_netcdf(path, format="NETCDF3_64BIT")


@pytest.fixture
def rough(tmp_path, monkeypatch):
    """A directory with surface.nc (32², 1 mm, σ = 1 µm) and an empty BEM cache."""
    monkeypatch.setenv("SLIPCYCLE_CACHE", str(tmp_path / "cache"))
    topo = synthetic_surface(32, 1e-3, hurst=0.8, rms_height=1e-6, short_cutoff=1e-3 / 8,
                             long_cutoff=2.5e-4, seed=2)
    topo.to_netcdf(str(tmp_path / "surface.nc"))
    return tmp_path


def _case(directory, *, file="surface.nc", area="1.0e-4", extra="", study=""):
    path = directory / "case.toml"
    path.write_text(CASE.format(file=file, area=area, extra=extra) + study)
    return path


def _refused(run_cli, cmd, case, out, key):
    """``cmd`` refuses ``case`` in one line naming ``key``, exit code 2, nothing written."""
    code, _, err = run_cli(cmd, case, "--out", out)
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith(f"error: {key}:"), err
    assert not out.exists()
    return lines[0]


# -- 1. no exponential window -------------------------------------------------------------
def test_study_without_exponential_window_writes_nan_and_says_none(rough, run_cli,
                                                                    monkeypatch):
    import slipcycle.studies.roughness as study

    real = study.fit_exponential
    # a band no BEM law meets: no window of three points
    monkeypatch.setattr(study, "fit_exponential", lambda P, U, tol: real(P, U, 1e-12))
    code, _, err = run_cli("roughness", _case(rough, study=STUDY), "--out", rough / "out")
    assert code == 0, err
    assert "no load window" in err
    s = json.loads((rough / "out" / "summary.json").read_text())
    assert s["exponential_fit"] == "none" and s["gamma_sigma"] is None
    assert s["dissipation_per_cycle"] > 0
    with xr.open_dataset(rough / "out" / "result.nc") as ds:
        assert np.isnan(ds.attrs["gamma_sigma"])
        assert ds.attrs["exponential_fit"] == "none"


# -- 2, 9. lists and counts of [roughness] ------------------------------------------------
@pytest.mark.parametrize("key", ["phases", "grids", "sliders", "short_cutoffs",
                                 "long_cutoffs"])
def test_empty_roughness_lists_are_refused_naming_the_key(rough, run_cli, key):
    study = "\n".join(f"{key} = []" if line.startswith(f"{key} =") else line
                      for line in STUDY.splitlines())
    line = _refused(run_cli, "roughness", _case(rough, study=study), rough / "out",
                    f"roughness.{key}")
    assert "empty" in line


@pytest.mark.parametrize("key, value", [("grids", "[32.7]"), ("sliders", "[100.5]")])
def test_non_integral_counts_are_refused_not_truncated(rough, run_cli, key, value):
    study = STUDY.replace(f"{key} = [{'32' if key == 'grids' else '100'}]",
                          f"{key} = {value}")
    line = _refused(run_cli, "roughness", _case(rough, study=study), rough / "out",
                    f"roughness.{key}")
    assert value.strip("[]") in line


# -- 3, 10. map axes and Fig. 7 curves in gross slip --------------------------------------
MAP = """
model = "halfspace"
[map]
P1_hat = [0.0, 0.4]
Q1_hat = [0.05, 0.5]
phase = [0.0, 1.5707963267948966]
{extra}
[run]
steps_per_cycle = 40
sliders = 30
"""


@pytest.mark.parametrize("key", ["P1_hat", "Q1_hat", "phase", "fig7_Q1_hat"])
def test_map_refuses_empty_axes_naming_the_key(tmp_path, run_cli, key):
    text = "\n".join(ln for ln in MAP.format(extra="").splitlines()
                     if not ln.startswith(f"{key} ="))
    text = text.replace("[map]", f"[map]\n{key} = []")
    case = tmp_path / "map.toml"
    case.write_text(text)
    _refused(run_cli, "map", case, tmp_path / "out", f"map.{key}")


def test_map_draws_the_fig7_curves_that_exist_and_lists_those_in_gross_slip(tmp_path,
                                                                            run_cli):
    case = tmp_path / "map.toml"
    # P̂1 = 0.7: the smallest load is 0.3 P0, so Q̂1 = 0.8 slips grossly at every phase
    case.write_text(MAP.format(extra="fig7_P1_hat = 0.7\nfig7_Q1_hat = [0.2, 0.8]"))
    code, _, err = run_cli("map", case, "--out", tmp_path / "out")
    assert code == 0, err
    assert "0.8" in err and "gross slip" in err
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["fig7_W_hat_max"]["0.8"] is None and s["fig7_W_hat_max"]["0.2"] > 0
    assert s["fig7_gross_slip_Q1_hat"] == [0.8]
    assert (tmp_path / "out" / "figures" / "w_hat_vs_phase.png").is_file()


def test_map_whose_fig7_curves_all_slip_grossly_is_refused(tmp_path, run_cli):
    case = tmp_path / "map.toml"
    case.write_text(MAP.format(extra="fig7_P1_hat = 0.7\nfig7_Q1_hat = [0.8, 0.9]"))
    line = _refused(run_cli, "map", case, tmp_path / "out", "map.fig7_Q1_hat")
    assert "0.3" in line   # the Q̂1 below which no curve slips grossly


# -- 4, 18. undefined points --------------------------------------------------------------
def test_roughness_study_fills_undefined_points_and_warns_once(rough, run_cli):
    with xr.open_dataset(rough / "surface.nc") as ds:
        h = np.array(ds["heights"].values)
    h[5:8, 5:8] = np.nan
    _nc(rough / "holes.nc", h)
    case = _case(rough, file="holes.nc", extra="fill_undefined = true", study=STUDY)
    code, _, err = run_cli("roughness", case, "--out", rough / "out")
    assert code == 0, err
    warnings = [ln for ln in err.splitlines() if "undefined height points filled" in ln]
    assert len(warnings) == 1 and "halfspace.topography_file: 9 of 1024" in warnings[0]


def test_a_map_with_no_defined_height_says_so(rough, run_cli):
    _nc(rough / "nan.nc", np.full((16, 16), np.nan))
    line = _refused(run_cli, "run", _case(rough, file="nan.nc", extra="fill_undefined = true"),
                    rough / "out", "halfspace.topography_file")
    assert "all 256 height points are undefined" in line


# -- 5. flat maps and filters that keep nothing -------------------------------------------
def test_constant_heights_are_refused_as_flat(rough, run_cli):
    _nc(rough / "const.nc", np.full((32, 32), 2e-6))
    line = _refused(run_cli, "run", _case(rough, file="const.nc"), rough / "out",
                    "halfspace.topography_file")
    assert "perfectly flat" in line


def test_flatness_is_relative_to_the_heights_and_the_map_size():
    flat = SurfaceMap(np.full((8, 8), 5.0) + 1e-17 * np.arange(64).reshape(8, 8), (1e-3,) * 2)
    rough = SurfaceMap(1e-9 * np.random.default_rng(0).normal(size=(8, 8)), (1e-3,) * 2)
    assert flat.rms_height > 0 and flat.flat
    assert not rough.flat


@pytest.mark.parametrize("key, value", [("short_cutoffs", "[1.0]"),
                                        ("long_cutoffs", "[1e-9]")])
def test_study_filters_that_keep_no_wavelength_are_refused(rough, run_cli, key, value):
    study = "\n".join(f"{key} = {value}" if ln.startswith(f"{key} =") else ln
                      for ln in STUDY.splitlines())
    line = _refused(run_cli, "roughness", _case(rough, study=study), rough / "out",
                    f"roughness.{key}")
    assert "keeps no wavelength" in line


def test_case_filter_that_keeps_nothing_names_its_bounds(rough, run_cli):
    line = _refused(run_cli, "run", _case(rough, extra="short_cutoff = 1.0"), rough / "out",
                    "halfspace.short_cutoff")
    assert "None" not in line and "from 1 m to the map" in line


# -- 6. complete contact ------------------------------------------------------------------
def test_complete_contact_pressure_of_a_wavy_surface_is_johnsons():
    n, L, h, E = 64, 1e-3, 1e-6, 1e11
    x = np.arange(n) * L / n
    wavy = SurfaceMap(np.repeat(h * np.cos(2 * np.pi * x / L)[:, None], n, axis=1), (L, L))
    # Johnson (1985): p* = π E* h / λ
    assert wavy.complete_contact_pressure(E) == pytest.approx(np.pi * E * h / L, rel=1e-9)


def test_nominal_pressure_beyond_complete_contact_is_refused(rough, run_cli):
    line = _refused(run_cli, "run", _case(rough, area="1e-30"), rough / "out",
                    "halfspace.nominal_area")
    assert "complete contact" in line


# -- 7. one law for run and the study -----------------------------------------------------
def test_run_and_roughness_study_give_the_same_joint(rough, run_cli):
    for fit in ("table", "exponential"):
        case = _case(rough, study=STUDY)
        case.write_text(case.read_text().replace('fit = "table"', f'fit = "{fit}"'))
        assert run_cli("run", case, "--out", rough / f"run_{fit}")[0] == 0
        assert run_cli("roughness", case, "--out", rough / f"study_{fit}")[0] == 0
    run = {f: json.loads((rough / f"run_{f}" / "summary.json").read_text())
           for f in ("table", "exponential")}
    study = json.loads((rough / "study_table" / "summary.json").read_text())
    assert study["dissipation_per_cycle"] == pytest.approx(
        run["table"]["dissipation_per_cycle"], rel=1e-9)
    assert study["dissipation_per_cycle_exponential"] == pytest.approx(
        run["exponential"]["dissipation_per_cycle"], rel=1e-9)


# -- 11. λ_c of dissimilar materials ------------------------------------------------------
ROUGH_EXP = """
model = "halfspace"
[halfspace]
profile = "rough_exponential"
gamma_sigma = 1e-6
{materials}
friction = 0.5
[loading]
P0 = 100.0
P1 = 40.0
Q1 = 20.0
phase = 1.0
[run]
cycles = 3
steps_per_cycle = 60
sliders = 200
"""


def test_rough_exponential_combines_dissimilar_materials_as_every_profile(run_cli,
                                                                          write_case,
                                                                          tmp_path):
    (E1, E2), (nu1, nu2) = (200e9, 1e9), (0.1, 0.45)
    G1, G2 = E1 / (2 * (1 + nu1)), E2 / (2 * (1 + nu2))
    e_star = 1 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
    ratio = e_star / (4 / ((2 - nu1) / G1 + (2 - nu2) / G2))   # Mindlin 1949: E*/(4G*)
    assert ContactElasticity.from_materials((E1, E2), (nu1, nu2), plane=False
                                            ).compliance_ratio == pytest.approx(ratio)
    out = {}
    for name, mat in (("E", f"E = [{E1!r}, {E2!r}]\nnu = [{nu1}, {nu2}]"),
                      ("ratio", f"compliance_ratio = {ratio!r}")):
        code, _, err = run_cli("run", write_case(ROUGH_EXP.format(materials=mat), f"{name}.toml"),
                               "--out", tmp_path / name)
        assert code == 0, err
        out[name] = json.loads((tmp_path / name / "summary.json").read_text())
    assert out["E"]["dissipation_per_cycle"] == pytest.approx(
        out["ratio"]["dissipation_per_cycle"], rel=1e-9)
    line = _refused(run_cli, "run", write_case(ROUGH_EXP.format(materials="nu = [0.1, 0.45]"),
                                               "nu.toml"), tmp_path / "nu", "halfspace.E")
    assert "dissimilar" in line


# -- 12, 13. files without a size, non-uniform grids --------------------------------------
def test_npy_heights_need_topography_size_and_run_with_it(rough, run_cli):
    with xr.open_dataset(rough / "surface.nc") as ds:
        np.save(rough / "h.npy", np.array(ds["heights"].values))
    line = _refused(run_cli, "run", _case(rough, file="h.npy"), rough / "out",
                    "halfspace.topography_file")
    assert "topography_size = [Lx, Ly]" in line
    code, _, err = run_cli("run", _case(rough, file="h.npy",
                                        extra="topography_size = [1e-3, 1e-3]"),
                           "--out", rough / "npy")
    assert code == 0, err
    # an NPY map is a measurement: non-periodic, detrended and mirror-stitched
    assert json.loads((rough / "npy" / "summary.json").read_text())[
        "dissipation_per_cycle"] > 0


def test_non_uniform_grids_are_refused(rough, run_cli):
    with xr.open_dataset(rough / "surface.nc") as ds:
        h = np.array(ds["heights"].values)
    x = np.sort(np.random.default_rng(1).uniform(0, 1e-3, 32))
    _nc(rough / "nonuni.nc", h, x=x)
    line = _refused(run_cli, "run", _case(rough, file="nonuni.nc"), rough / "out",
                    "halfspace.topography_file")
    assert "grid not uniform" in line
    X, Y = np.meshgrid(x, np.arange(32) * 1e-3 / 32, indexing="ij")
    np.savetxt(rough / "xyz.txt", np.c_[X.ravel(), Y.ravel(), h.ravel()])
    line = _refused(run_cli, "run", _case(rough, file="xyz.txt"), rough / "out",
                    "halfspace.topography_file")
    assert "grid not uniform" in line


# -- 17. BEM memory -----------------------------------------------------------------------
def test_bem_grid_beyond_the_memory_budget_is_refused_before_work(rough, run_cli,
                                                                  monkeypatch):
    case = _case(rough)
    case.write_text(case.read_text().replace("bem_grid = 32", "bem_grid = 4096"))
    line = _refused(run_cli, "run", case, rough / "out", "halfspace.bem_grid")
    assert "4096 x 4096" in line and "limit 4 GB" in line
    # without bem_grid the file's own grid is what the BEM solves
    monkeypatch.setenv("SLIPCYCLE_MEMORY_LIMIT", "100kB")
    case.write_text(case.read_text().replace("bem_grid = 4096\n", ""))
    _refused(run_cli, "run", case, rough / "out", "halfspace.topography_file")
    assert not list(rough.glob("cache/bem-*.npz"))   # refused before any BEM


def test_a_table_file_gives_one_law_whatever_its_units_encoding_and_name(tmp_path):
    """A netCDF table in micrometres was read as metres (D 1e6 too large), a spreadsheet's
    CSV with a byte-order mark was refused, and a netCDF file named .dat was read as
    text: all now give the D of the plain CSV in SI units."""
    import slipcycle

    U = np.array([0.0, 1e-7, 3e-7, 1e-6, 3e-6])
    P = np.array([0.0, 10.0, 40.0, 150.0, 500.0])
    rows = "U,P\n" + "".join(f"{float(u)!r},{float(p)!r}\n" for u, p in zip(U, P, strict=True))
    (tmp_path / "plain.csv").write_text(rows, encoding="utf-8")
    (tmp_path / "bom.csv").write_text(rows, encoding="utf-8-sig")
    xr.Dataset({"U": ("k", U * 1e6, {"units": "um"}),
                "P": ("k", P, {"units": "N"})}).to_netcdf(tmp_path / "micro.nc")
    xr.Dataset({"U": ("k", U), "P": ("k", P)}).to_netcdf(tmp_path / "table.dat")

    def run(name):
        text = (f'model = "halfspace"\n[halfspace]\nprofile = "tabulated"\n'
                f'table_file = "{name}"\ncompliance_ratio = 1.2142857142857144\n'
                "friction = 0.5\n[loading]\nP0 = 100.0\nQ1 = 30.0\n[run]\ncycles = 3\n"
                "steps_per_cycle = 200\nsliders = 200\n")
        (tmp_path / "case.toml").write_text(text)
        return slipcycle.run(tmp_path / "case.toml").dissipation_per_cycle

    ref = run("plain.csv")
    assert ref > 0
    for name in ("bom.csv", "micro.nc", "table.dat"):
        assert run(name) == pytest.approx(ref, rel=1e-12), name
