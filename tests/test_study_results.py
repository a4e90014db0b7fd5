"""Every analysis returns a result of the one contract (``slipcycle.result.StudyResult``):
its ``summary()`` and ``to_dataset()`` are what the command writes (summary.json,
result.nc), its figures are the files written, its ``repr`` is one line and it shows as an
HTML table in a notebook."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from conftest import case_text

from slipcycle.io.results import to_jsonable
from slipcycle.result import StudyResult

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"

MAP_CASE = """
model = "halfspace"
[map]
P1_hat = [0.0, 0.4]
Q1_hat = [0.1, 0.3]
phase = {start = -3.0, stop = 3.0, num = 3}
fig7_Q1_hat = [0.2, 0.4]
[run]
steps_per_cycle = 32
sliders = 20
"""

RODS_CASE = case_text(
    "rods_spec", rods={"modes": 6}, loading={"rotation_amplitude": 0.014, "frequency_ratio": None},
    run={"steps_per_cycle": 64, "cycles": 40},
    limits={"frequency_ratio": [0.05, 0.5], "amplitude_ratio": [0.5, 2.0], "position": [0.4],
            "position_frequencies": 2})


def _capture(monkeypatch, module, name):
    """Wrap ``module.name`` so that what it returns is kept (the CLI imports it at call)."""
    import importlib

    mod = importlib.import_module(module)
    original = getattr(mod, name)
    kept = []

    def wrapper(*args, **kwargs):
        kept.append(original(*args, **kwargs))
        return kept[-1]

    monkeypatch.setattr(mod, name, wrapper)
    return kept


def _same_json(a, b):
    """JSON values equal, floats to the last bit (NaN/inf are written as null)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys()
        for k in a:
            _same_json(a[k], b[k])
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _same_json(x, y)
    elif isinstance(a, float) and isinstance(b, float):
        assert a == b or (math.isnan(a) and math.isnan(b))
    else:
        assert a == b and type(a) is type(b)


def _check_against_files(result: StudyResult, out: Path):
    """summary(), to_dataset() and figures() equal summary.json, result.nc, figures/."""
    written = json.loads((out / "summary.json").read_text())
    written.pop("metadata")
    _same_json(json.loads(json.dumps(to_jsonable(result.summary()))), written)
    ds = result.to_dataset()
    with xr.open_dataset(out / "result.nc") as nc:
        assert set(ds.data_vars) == set(nc.data_vars)
        assert set(ds.coords) == set(nc.coords)
        for name in list(ds.data_vars) + list(ds.coords):
            np.testing.assert_array_equal(ds[name].values, nc[name].values)
            assert ds[name].dtype == nc[name].dtype, name
            assert ds[name].dims == nc[name].dims, name
            assert to_jsonable(dict(ds[name].attrs)) == to_jsonable(
                {k: v for k, v in nc[name].attrs.items() if k in ds[name].attrs}), name
            assert set(ds[name].attrs) <= set(nc[name].attrs), name
        for k, v in ds.attrs.items():
            assert nc.attrs[k] == v
    figs = out / "figures"
    assert {f"{k}.png" for k in result.figures(ds)} == (
        {p.name for p in figs.iterdir()} if figs.exists() else set())
    # to_outputs is the same
    outputs = result.to_outputs()
    _same_json(to_jsonable(outputs.summary), to_jsonable(result.summary()))
    assert outputs.flags == result.flags and set(outputs.figures) == set(result.figures())
    assert list(outputs.dataset.data_vars) == list(ds.data_vars)


def _check_display(result: StudyResult, cls: str, model: str, analysis: str):
    text = repr(result)
    assert "\n" not in text and text.startswith(f"<{cls} {model} {analysis}: ")
    assert text.endswith(">") and len(text) < 400
    html = result._repr_html_()
    assert html.startswith("<table>") and html.endswith("</table>")
    assert f"<caption>{cls} ({model} {analysis})</caption>" in html
    for key, _, _ in result.headline():
        assert key in html


def test_shakedown_result_is_what_the_command_writes(run_cli, monkeypatch, tmp_path):
    from slipcycle.studies.shakedown import ShakedownResult

    kept = _capture(monkeypatch, "slipcycle.studies.shakedown", "shakedown_study")
    out = tmp_path / "sd"
    code, _, err = run_cli("shakedown", EXAMPLES / "shakedown_triangle.toml", "--out", out,
                           "--lam-points", "4", "--starts", "1", "--lam-tol", "0.25",
                           "--workers", "1", "--no-progress")
    assert code == 0, err
    (status,) = kept
    result = status.result
    assert isinstance(result, ShakedownResult) and isinstance(result, StudyResult)
    _check_against_files(result, out)
    _check_display(result, "ShakedownResult", "discrete", "shakedown")
    assert result.lambda1 <= result.lambda2 and result.wall_time_s > 0
    assert "lambda1=" in repr(result) and "regime=" in repr(result)


@pytest.mark.parametrize("mode", [("--grid", "5"), ("--random", "3")], ids=["grid", "random"])
def test_basins_result_is_what_the_command_writes(run_cli, monkeypatch, tmp_path, mode):
    from slipcycle.studies.basins import BasinsResult

    kept = _capture(monkeypatch, "slipcycle.studies.basins", "basins_study")
    out = tmp_path / "b"
    code, _, err = run_cli("basins", EXAMPLES / "shakedown_triangle.toml", "--out", out,
                           *mode, "--workers", "1", "--no-progress")
    assert code == 0, err
    (status,) = kept
    result = status.result
    assert isinstance(result, BasinsResult) and result.mode == mode[0][2:]
    _check_against_files(result, out)
    _check_display(result, "BasinsResult", "discrete", "basins")
    assert sum(result.class_counts.values()) == result.steady_state.size


def test_basins_stopped_early_has_no_result(tmp_path):
    from slipcycle.io import read_case
    from slipcycle.studies.basins import basins_study

    case = read_case(EXAMPLES / "shakedown_triangle.toml")
    status = basins_study(case, tmp_path, grid=3, workers=1, progress=False, stop_after=1)
    assert not status.complete and status.result is None and status.outputs is None


def test_w_hat_map_result_is_what_the_command_writes(run_cli, write_case, monkeypatch,
                                                     tmp_path):
    from slipcycle.studies.w_hat_map import WHatMapResult

    kept = _capture(monkeypatch, "slipcycle.studies.w_hat_map", "w_hat_map_study")
    out = tmp_path / "map"
    code, _, err = run_cli("map", write_case(MAP_CASE), "--out", out)
    assert code == 0, err
    (result,) = kept
    assert isinstance(result, WHatMapResult)
    _check_against_files(result, out)
    _check_display(result, "WHatMapResult", "halfspace", "w_hat_map")
    assert result.W_hat.shape == (2, 2, 3)


@pytest.mark.parametrize("maps", [True, False], ids=["maps", "no-maps"])
def test_limits_result_is_what_the_command_writes(run_cli, write_case, monkeypatch, tmp_path,
                                                  maps):
    from slipcycle.studies.limits import LimitsResult

    kept = _capture(monkeypatch, "slipcycle.studies.limits", "limits_study")
    out = tmp_path / "l"
    code, _, err = run_cli("limits", write_case(RODS_CASE), "--tolerance", "0.05", "--out",
                           out, *(() if maps else ("--no-maps",)))
    assert code == 0, err
    (result,) = kept
    assert isinstance(result, LimitsResult) and (result.regime is not None) == maps
    _check_against_files(result, out)
    _check_display(result, "LimitsResult", "rods", "limits")
    assert result.qs_limit_frequency_ratio == result.summary()["qs_limit_frequency_ratio"]


def test_the_outputs_functions_give_the_result_outputs():
    """``w_hat_study`` and ``run_limits`` (RunOutputs) are the results' ``to_outputs()``."""
    from slipcycle.io import parse_case_text
    from slipcycle.studies.w_hat_map import parse_map_case, w_hat_map_study, w_hat_study

    args = parse_map_case(parse_case_text(MAP_CASE))
    out = w_hat_study(*args)
    res = w_hat_map_study(*args)
    s, r = out.summary, res.summary()
    s.pop("wall_time_s"), r.pop("wall_time_s")
    _same_json(to_jsonable(s), to_jsonable(r))
    xr.testing.assert_identical(out.dataset, res.to_dataset())
    assert set(out.figures) == set(res.figures()) and out.flags == res.flags
