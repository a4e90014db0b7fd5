"""Every output speaks a standard: each ``result.nc`` follows the CF-1.10 conventions
(Eaton et al. 2022: ``Conventions``, a coordinate variable for every dimension,
``long_name`` and ``units`` everywhere, consistent flags), each ``summary.json`` carries its
``units`` and validates against the shipped JSON Schema, and both carry the provenance
(versions, platform, command line). Every command runs once on a small case; the files it
writes are checked by the rules of :func:`slipcycle.io.metadata.cf_problems` and, where the
``cfchecker`` package and the UDUNITS-2 library are installed, by the CF checker itself.

Case files: every shipped example validates against ``case.schema.json``; the type errors
of the malformed-input corpus (tests/test_malformed_inputs.py) do not.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import xarray as xr

from slipcycle.cli.main import main
from slipcycle.examples import example_text, list_examples
from slipcycle.io.metadata import CONVENTIONS, DEPENDENCIES, cf_problems

jsonschema = pytest.importorskip("jsonschema", reason="needs the jsonschema package")

from slipcycle.examples import copy_examples  # noqa: E402
from slipcycle.io.schema import load_schema  # noqa: E402


def _small(name: str, *edits: tuple[str, str]) -> str:
    text = example_text(name)
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    return text


CASES = {
    "sphere.toml": _small("halfspace_sphere", ("steps_per_cycle = 400", "steps_per_cycle = 40")),
    "two.toml": _small("discrete_two_node", ("steps_per_cycle = 400", "steps_per_cycle = 60")),
    "rods.toml": _small("rods_spec"),
    "map.toml": _small("halfspace_rough_map", ("num = 9", "num = 2"), ("num = 19", "num = 3"),
                       ("num = 37", "num = 5"), ("steps_per_cycle = 200", "steps_per_cycle = 40"),
                       ("sliders = 100", "sliders = 30")),
    "limits.toml": _small("rods_limits_equal"),
    "three.toml": _small("discrete3d_three_node", ("steps_per_cycle = 100",
                                                    "steps_per_cycle = 40")),
    "rough.toml": _small("halfspace_topography", ("bem_grid = 128", "bem_grid = 32"),
                         ("grids = [32, 64, 128, 256]", "grids = [16, 32]"),
                         ("sliders = [100, 200, 400, 800]", "sliders = [50, 100]"),
                         ("sliders = 400", "sliders = 100"), ("num = 9}", "num = 3}"),
                         ("rings = 16", "rings = 4")),
}

COMMANDS = {
    "run-halfspace": ["run", "sphere.toml"],
    "run-discrete": ["run", "two.toml"],
    "run-rods": ["run", "rods.toml"],
    "sweep": ["sweep", "sphere.toml", "--set", "loading.Q1=10,20", "--workers", "1"],
    "shakedown": ["shakedown", "two.toml", "--workers", "1", "--lam-points", "3",
                  "--starts", "1", "--lam-tol", "1"],
    "basins": ["basins", "two.toml", "--grid", "3", "--workers", "1"],
    "map": ["map", "map.toml"],
    "limits": ["limits", "limits.toml", "--no-maps"],
    "run-discrete3d": ["run", "three.toml"],
    "roughness": ["roughness", "rough.toml"],
}


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """Every command run once: name -> its output directory (and the demo's folders)."""
    import os

    work = tmp_path_factory.mktemp("outputs")
    for name, text in CASES.items():
        (work / name).write_text(text)
    copy_examples(work / "data", ["halfspace_topography"])  # the topography it reads
    (work / "rough.toml").write_text(CASES["rough.toml"].replace(
        '"rough_surface.nc"', f'"{work / "data" / "rough_surface.nc"}"'))
    cwd = os.getcwd()
    dirs = {}
    try:
        os.chdir(work)
        for name, argv in COMMANDS.items():
            code = main([*argv, "--out", name, "-q"])
            assert code == 0, name
            dirs[name] = work / name
    finally:
        os.chdir(cwd)
    return dirs


def _result_dirs(outputs):
    return sorted(outputs.items())


def _check_netcdf(path: Path) -> None:
    with xr.open_dataset(path) as ds:
        assert cf_problems(ds) == [], path
        assert ds.attrs["Conventions"] == CONVENTIONS
        for pkg in ("slipcycle", "numpy", "scipy", "numba", "xarray"):
            assert ds.attrs[f"version_{pkg}"], pkg
        assert ds.attrs["platform"] and ds.attrs["command_line"].startswith("slipcycle ")
        for name in ds.variables:
            assert ds[name].attrs.get("units", "") != "", name
        for name in ds.dims:
            assert name in ds.coords, name


def _check_summary(path: Path, command: str) -> dict:
    summary = json.loads(path.read_text())
    jsonschema.validate(summary, load_schema("summary"))
    meta = summary["metadata"]
    assert set(DEPENDENCIES) <= set(meta["versions"]) and meta["platform"]
    assert meta["command_line"].startswith(f"slipcycle {command}")
    assert isinstance(summary["units"], dict)
    return summary


@pytest.mark.parametrize("name", list(COMMANDS))
def test_every_command_writes_cf_netcdf_and_a_schema_valid_summary(outputs, name):
    out = outputs[name]
    _check_netcdf(out / "result.nc")
    summary = _check_summary(out / "summary.json", COMMANDS[name][0])
    # every numeric entry of a run's summary has its unit (the model's own description)
    if name.startswith("run-"):
        numeric = [k for k, v in summary.items()
                   if isinstance(v, int | float) and not isinstance(v, bool)
                   and k not in ("cycles_run",)]
        missing = [k for k in numeric if k not in summary["units"]]
        assert missing == [], missing


def test_flag_variables_name_every_code(outputs):
    with xr.open_dataset(outputs["sweep"] / "result.nc") as ds:
        flagged = [v for v in ds.variables if "flag_values" in ds[v].attrs]
        assert flagged
        for v in flagged:
            words = ds[v].attrs["flag_meanings"].split()
            assert len(words) == len(ds[v].attrs["flag_values"])


def _cf_tables(tmp: Path) -> list[str]:
    """Local stand-ins of the CF standard-name, area-type and region tables (the checker
    downloads them otherwise; these files use no standard names)."""
    (tmp / "sn.xml").write_text('<?xml version="1.0"?><standard_name_table>'
                                "<version_number>84</version_number>"
                                "<last_modified>2024-01-01T00:00:00Z</last_modified>"
                                '<entry id="time"><canonical_units>s</canonical_units>'
                                "</entry></standard_name_table>")
    (tmp / "area.xml").write_text('<?xml version="1.0"?><standard_name_table>'
                                  "<version_number>10</version_number><date>2024-01-01"
                                  '</date><entry id="all_area_types"></entry>'
                                  "</standard_name_table>")
    (tmp / "region.xml").write_text('<?xml version="1.0"?><standard_region_names>'
                                    "<version_number>4</version_number><date>2024-01-01"
                                    '</date><entry id="global"></entry>'
                                    "</standard_region_names>")
    return ["-s", str(tmp / "sn.xml"), "-a", str(tmp / "area.xml"),
            "-r", str(tmp / "region.xml")]


def _cfchecks() -> str | None:
    exe = Path(sys.executable).with_name("cfchecks")
    if not exe.exists():
        return None
    probe = subprocess.run([sys.executable, "-c", "import cfunits"], capture_output=True)
    return str(exe) if probe.returncode == 0 else None


@pytest.mark.slow
@pytest.mark.skipif(_cfchecks() is None,
                    reason="the CF checker (cfchecker + UDUNITS-2) is not installed; the "
                           "same rules are checked by cf_problems above")
def test_cf_checker_finds_no_error_and_no_warning(outputs, tmp_path):
    """The CF checker of the CF community (cfchecker 4.1 knows versions up to CF-1.8, so a
    copy declaring CF-1.8 is checked: every rule used here is the same in 1.8 and 1.10)."""
    import netCDF4

    tables = _cf_tables(tmp_path)
    for name, out in _result_dirs(outputs):
        copy = tmp_path / f"{name}.nc"
        shutil.copy(out / "result.nc", copy)
        with netCDF4.Dataset(copy, "a") as f:
            assert f.Conventions == CONVENTIONS
            f.Conventions = "CF-1.8"
        proc = subprocess.run([_cfchecks(), *tables, str(copy)], capture_output=True,
                              text=True, timeout=300)
        report = proc.stdout
        assert "ERRORS detected: 0" in report and "WARNINGS given: 0" in report, \
            (name, [ln for ln in report.splitlines() if ln.startswith(("ERROR", "WARN"))])


@pytest.mark.slow
def test_demo_outputs_follow_the_same_standards(tmp_path, run_cli):
    code, _, err = run_cli("demo", "--out", tmp_path / "demo", "-q")
    assert code == 0, err
    dirs = [d for d in (tmp_path / "demo").iterdir() if d.is_dir()]
    assert len(dirs) >= 6
    for d in dirs:
        _check_netcdf(d / "result.nc")
        _check_summary(d / "summary.json", "demo")
    # a run's warning reaches the report beside its numbers (the lap joint: one mesh)
    report = (tmp_path / "demo" / "report.md").read_text()
    for d in dirs:
        message = str(json.loads((d / "summary.json").read_text()).get("message", ""))
        if "WARNING: " in message:
            assert f"**WARNING: {message.partition('WARNING: ')[2]}**" in report, d.name
    assert "**WARNING: dissipation not checked for mesh convergence" in report


# -- case files -------------------------------------------------------------------------

@pytest.mark.parametrize("name", list_examples())
def test_every_shipped_example_validates_against_the_case_schema(name):
    jsonschema.validate(tomllib.loads(example_text(name)), load_schema("case"))


def _type_errors() -> list[tuple[str, str]]:
    """The wrong-type mutations of the malformed-input corpus: (id, case text)."""
    sys.path.insert(0, str(Path(__file__).parent))
    from test_malformed_inputs import _generated

    return [(b.id, b.files["case.toml"]) for b in _generated() if b.id.endswith("-type")]


@pytest.mark.parametrize(("ident", "text"), _type_errors(), ids=lambda x: x
                         if isinstance(x, str) and not x.startswith(("model", "#")) else "")
def test_type_errors_of_the_malformed_corpus_fail_the_case_schema(ident, text):
    data = tomllib.loads(text)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(data, load_schema("case"))


def test_case_schema_is_in_step_with_the_examples():
    """The shipped schema is what ``python -m slipcycle.io.schema`` builds from the
    shipped examples (rebuild it after adding an example with new keys)."""
    from slipcycle.io.schema import case_schema

    built = case_schema({n: example_text(n) for n in list_examples()})
    shipped = load_schema("case")
    assert built == shipped, "run: python -m slipcycle.io.schema"


def test_summary_schema_is_a_valid_draft_2020_12_schema():
    for name in ("summary", "case"):
        schema = load_schema(name)
        jsonschema.Draft202012Validator.check_schema(schema)
        assert re.match(r"https://", schema["$id"])


# -- the CF completion itself -----------------------------------------------------------

from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_NAMES = st.from_regex(r"[a-z][a-z0-9_]{0,8}", fullmatch=True)
_KINDS = st.sampled_from(["f8", "i8", "bool", "str", "flag"])


@settings(max_examples=40, deadline=None)
@given(st.dictionaries(_NAMES, st.tuples(_KINDS, st.lists(st.sampled_from(["d0", "d1", "d2"]),
                                                         max_size=2, unique=True),
                                         st.booleans()),
                       min_size=1, max_size=6),
       st.integers(1, 4))
def test_completed_dataset_keeps_its_data_and_breaks_no_cf_rule(variables, size):
    """Whatever the variables (floats with a unit from the model or from the summary,
    counts, booleans, text, integer codes with flag words, scalars, dimensions without a
    coordinate), the completed Dataset has the same data and no CF problem."""
    import numpy as np

    from slipcycle.io.metadata import cf_complete

    data, units, flags = {}, {}, {}
    for name, (kind, dims, unit_in_summary) in variables.items():
        if name in ("d0", "d1", "d2"):
            continue
        shape = (size,) * len(dims)
        if kind == "f8":
            arr = np.linspace(-1.0, 1.0, int(np.prod(shape))).reshape(shape)
        elif kind in ("i8", "flag"):
            arr = np.arange(int(np.prod(shape)), dtype=np.int64).reshape(shape) % 3
        elif kind == "bool":
            arr = np.zeros(shape, bool)
        else:
            arr = np.full(shape, "word", dtype=object)
        attrs = {}
        if kind == "f8":
            (units if unit_in_summary else attrs).__setitem__(
                *((name, "N") if unit_in_summary else ("units", "m")))
        if kind == "flag":
            flags[name] = ("shakedown", "cyclic_slip", "ratcheting")
        data[name] = (tuple(dims), arr, attrs)
    ds = xr.Dataset(data)
    done = cf_complete(ds, units, flags)
    assert cf_problems(done) == []
    added = [c for c in done.variables if c not in ds.variables]
    assert all(c in ds.dims for c in added)      # only coordinates of bare dimensions
    xr.testing.assert_equal(done.drop_vars(added), ds)
    assert ds.attrs == {}                        # the model's Dataset is not modified


def test_float_without_any_unit_is_reported_not_guessed():
    import numpy as np

    from slipcycle.io.metadata import cf_complete

    ds = xr.Dataset({"force": ("t", np.ones(3))})
    assert cf_problems(cf_complete(ds)) == ["force: no units"]
    assert cf_problems(cf_complete(ds, {"force": "N"})) == []


def test_coordinates_are_written_without_fill_values(tmp_path):
    import numpy as np

    from slipcycle.io.metadata import cf_complete

    ds = xr.Dataset({"a": ("x", np.ones(3), {"units": "J"})},
                    coords={"x": ("x", np.linspace(0, 1, 3), {"units": "m"})})
    cf_complete(ds).to_netcdf(tmp_path / "a.nc")
    with xr.open_dataset(tmp_path / "a.nc") as back:
        assert cf_problems(back) == []
        assert back.x.encoding.get("_FillValue") is None
