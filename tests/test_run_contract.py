"""One run/result contract: ``slipcycle.run`` takes a case in any form and every model
returns a result with the same vocabulary, whose outputs are those ``slipcycle run``
writes."""

from __future__ import annotations

import json
import subprocess
import sys
import tomllib

import numpy as np
import pytest
import xarray as xr
from conftest import case_text

import slipcycle
from slipcycle.io import CaseError, parse_case_text
from slipcycle.io.metadata import cf_complete
from slipcycle.result import STEADY_STATES, RunResult, SteadyState

SPHERE = case_text("halfspace_sphere", loading={"P1": None, "Q0": None, "phase": None},
                   run={"steps_per_cycle": 64, "sliders": 200})

TWO_NODE = case_text("discrete_two_node", run={"cycles": 10, "steps_per_cycle": 64})

RODS = case_text("rods_spec",
                 rods={"interface": "jenkins", "damping_ratio": None, "modes": 10},
                 loading={"rotation_amplitude": 0.014},
                 run={"steps_per_cycle": 64, "cycles": 50, "regularisation": False})

CASES = {"halfspace": SPHERE, "discrete": TWO_NODE, "rods": RODS}

#: the old summary keys of the shared fields, aliases kept for one release
ALIASES = {
    "halfspace": {"state_change": "residual"},
    "rods": {"steady_residual": "residual", "steady_state_reached": "converged"},
}


def _model_object(model: str, text: str):
    case = parse_case_text(text)
    if model == "halfspace":
        from slipcycle.halfspace.case import parse_case
        return parse_case(case)
    if model == "discrete":
        from slipcycle.discrete.case import read_discrete_case
        return read_discrete_case(case)
    from slipcycle.rods.case import parse_case
    return parse_case(case)


def _comparable(summary: dict) -> dict:
    s = json.loads(json.dumps(summary, default=lambda o: np.asarray(o).tolist()))
    s.pop("wall_time_s", None)
    return s


@pytest.fixture(scope="module", params=sorted(CASES))
def model(request):
    return request.param


@pytest.fixture(scope="module")
def results(model, tmp_path_factory):
    text = CASES[model]
    path = tmp_path_factory.mktemp(model) / "case.toml"
    path.write_text(text)
    return {"path": slipcycle.run(path), "path_str": slipcycle.run(str(path)),
            "text": slipcycle.run(text), "dict": slipcycle.run(tomllib.loads(text)),
            "object": slipcycle.run(_model_object(model, text))}


def test_every_input_kind_gives_the_same_summary(model, results):
    ref = _comparable(results["text"].summary())
    assert ref["model"] == model
    for kind, res in results.items():
        assert isinstance(res, RunResult) and res.model == model, kind
        assert _comparable(res.summary()) == ref, kind


def test_discrete_system_and_load_tuple_is_a_model_object():
    dc = _model_object("discrete", TWO_NODE)
    a = slipcycle.run((dc.system, dc.load, {"cycles": 10, "steps_per_cycle": 64},))
    b = slipcycle.run(parse_case_text(TWO_NODE.replace("initial_slip = [0.0, 0.0]\n", "")))
    assert _comparable(a.summary()) == _comparable(b.summary())


def test_shared_vocabulary_agrees_with_the_summary(model, results):
    res = results["text"]
    s = res.summary()
    assert isinstance(res.steady_state, SteadyState)
    assert s["steady_state_class"] == res.steady_state.value
    assert res.flags["steady_state_class"] == STEADY_STATES
    assert s["dissipation_per_cycle"] == res.dissipation_per_cycle
    assert s["units"]["dissipation_per_cycle"] == res.dissipation_unit
    assert s["cycles_run"] == res.cycles_run
    # the same keys in every model's summary, no per-model map
    assert s["residual"] == res.residual and s["units"]["residual"] == "1"
    assert s["converged"] == res.converged
    assert s["wall_time_s"] == res.wall_time_s and s["units"]["wall_time_s"] == "s"
    for old, new in ALIASES.get(model, {}).items():
        assert s[old] == s[new]
    assert isinstance(res.message, str) and res.message
    if model == "discrete":
        assert res.steady_state_detail == s["steady_state"] == res.steady_state.value
    if model == "halfspace":
        assert res.steady_state_detail == s["steady_state"]


def test_repr_is_one_line_and_html_is_a_table(results):
    res = results["text"]
    text = repr(res)
    assert "\n" not in text and res.steady_state.value in text
    assert "dissipation_per_cycle" in text
    html = res._repr_html_()
    assert html.startswith("<table") and html.endswith("</table>")
    assert "cycles_run" in html


def test_to_dataset_equals_result_nc_of_the_cli(model, results, run_cli, tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(CASES[model])
    code, _, err = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert code == 0, err
    with xr.open_dataset(tmp_path / "out" / "result.nc") as written:
        # the writer completes the Dataset to CF-1.10 (long_name, units, Conventions) and
        # adds the provenance; nothing else differs
        out = results["text"].to_outputs()
        ds = cf_complete(results["text"].to_dataset(), out.summary.get("units"), out.flags)
        written = written.load()
        written.attrs = {k: v for k, v in written.attrs.items() if k in ds.attrs}
        xr.testing.assert_identical(ds, written)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    summary.pop("metadata")
    assert _comparable(summary) == _comparable(results["text"].summary())
    figures = sorted(p.stem for p in (tmp_path / "out" / "figures").glob("*.png"))
    assert figures == sorted(results["text"].figures())


def test_to_outputs_is_summary_dataset_figures_and_flags(results):
    res = results["text"]
    out = res.to_outputs()
    assert _comparable(out.summary) == _comparable(res.summary())
    xr.testing.assert_identical(out.dataset, res.to_dataset())
    assert sorted(out.figures) == sorted(res.figures())
    assert out.flags == res.flags


def test_halfspace_classes_shakedown_and_gross_slip():
    no_q = slipcycle.run(SPHERE.replace("Q1 = 30.0", "P1 = 30.0"))
    assert no_q.steady_state is SteadyState.SHAKEDOWN
    assert no_q.steady_state_detail == "steady" and no_q.converged
    slip = slipcycle.run(SPHERE)
    assert slip.steady_state is SteadyState.CYCLIC_SLIP and slip.dissipation_per_cycle > 0
    gross = slipcycle.run(SPHERE.replace("Q1 = 30.0", "Q1 = 60.0"))
    assert gross.steady_state is SteadyState.GROSS_SLIP
    assert gross.dissipation_per_cycle is None and not gross.converged
    assert gross.summary()["steady_state"] == "gross_slip"
    assert "gross slip" in gross.message


def test_overrides_equal_an_edited_case():
    a = slipcycle.run(SPHERE, overrides={"loading.Q1": 20.0})
    b = slipcycle.run(SPHERE.replace("Q1 = 30.0", "Q1 = 20.0"))
    assert a.summary() == b.summary()
    with pytest.raises(CaseError, match="nowhere"):
        slipcycle.run(SPHERE, overrides={"nowhere.x": 1.0})


def test_refusals():
    with pytest.raises(TypeError):
        slipcycle.run(42)
    with pytest.raises(TypeError):
        slipcycle.run(_model_object("halfspace", SPHERE), overrides={"loading.Q1": 1.0})
    with pytest.raises(CaseError, match="reduce"):
        slipcycle.run({"model": "fe", "fe": {}})
    with pytest.raises(CaseError, match="no_such_case_file.toml: case file not found"):
        slipcycle.run("no_such_case_file.toml")


def test_import_slipcycle_stays_cheap():
    code = ("import sys, slipcycle; assert 'slipcycle.api' not in sys.modules; "
            "assert 'numpy' not in sys.modules; slipcycle.run; "
            "assert 'slipcycle.api' in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)
