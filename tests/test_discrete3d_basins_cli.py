"""``slipcycle basins`` on ``model = "discrete3d"`` cases: the command line and the Python
functions give the same steady states (one engine, simulate3d); the study result has
summary with units, Dataset and figures; bad inputs end with one line and exit 2."""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import slipcycle
from slipcycle.discrete3d.basins import basins3d, random_starts
from slipcycle.io import parse_case_text
from slipcycle.studies.basins3d import (
    STEADY_CODES,
    Basins3DResult,
    basins3d_study,
    load_discrete3d_case,
    start_scale,
)

EXAMPLE = Path(slipcycle.__file__).parent / "examples" / "discrete3d_three_node.toml"


def _case_text() -> str:
    # short runs: the comparison is between two paths through the same engine
    return (EXAMPLE.read_text().replace("cycles = 40", "cycles = 4")
            .replace("steps_per_cycle = 100", "steps_per_cycle = 40")
            .replace("step_tolerance = 1e-7", "step_tolerance = 1e-4")
            .replace('fields = ["xdmf", "pvd"]', "fields = []"))


PROTOCOLS = """
[[protocol]]
p_w = [[0.5, 0.5, 0.5], [1.0, 1.2, 1.0]]
q_w = [[[0.1, 0.0], [0.0, 0.1], [-0.1, 0.0]], [[0.2, 0.1], [0.0, 0.0], [0.0, -0.2]]]
[[protocol]]
p_w = [[1.0, 1.2, 1.0]]
"""


def test_cli_random_starts_agree_with_python_basins3d(run_cli, tmp_path, write_case):
    case = write_case(_case_text())
    out = tmp_path / "r"
    code, stdout, err = run_cli("basins", case, "--out", out, "--random", "2", "--seed", "3",
                                "--workers", "1", "--no-progress")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["model"] == "discrete3d" and s["mode"] == "random" and s["starts"] == 2
    assert s["units"]["dissipation_per_cycle.min"] == "J"
    assert s["units"]["start_scale"] == "m"
    ds = xr.open_dataset(out / "result.nc")
    assert ds["dissipation_per_cycle"].attrs["units"] == "J"
    assert (out / "figures" / "basin_dissipation.png").is_file()

    dc = load_discrete3d_case(case.read_text(), str(case))
    scale = start_scale(dc.system, dc.load, dc.run["steps_per_cycle"])
    assert s["start_scale"] == pytest.approx(scale, rel=1e-12)
    starts = random_starts(dc.system, dc.load, 2, scale, seed=3)
    py = basins3d(dc.system, dc.load, starts=starts, **dc.run)
    np.testing.assert_allclose(ds["dissipation_per_cycle"].values, py.dissipation_per_cycle,
                               rtol=1e-12)
    assert [STEADY_CODES[c] for c in ds["steady_state"].values] == list(py.steady_state)
    np.testing.assert_array_equal(ds["cycles_run"].values, py.cycles_run)


def test_cli_protocols_agree_with_python_and_the_study_result(run_cli, tmp_path,
                                                              write_case):
    case = write_case(_case_text())
    protos = write_case(PROTOCOLS, "protocols.toml")
    out = tmp_path / "p"
    code, _, err = run_cli("basins", case, "--out", out, "--protocols", protos,
                           "--lam", "0.8", "--workers", "1", "--no-progress")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["mode"] == "protocols" and s["starts"] == 2 and s["lam"] == 0.8
    ds = xr.open_dataset(out / "result.nc")

    dc = load_discrete3d_case(case.read_text(), str(case))
    p0 = np.hstack([np.array([[0.1, 0.0, 0.0, 0.1, -0.1, 0.0], [0.2, 0.1, 0, 0, 0, -0.2]]),
                    np.array([[0.5, 0.5, 0.5], [1.0, 1.2, 1.0]])])
    p1 = np.hstack([np.zeros((1, 6)), np.array([[1.0, 1.2, 1.0]])])
    py = basins3d(dc.system, dc.load.with_lam(0.8), protocols=[p0, p1], **dc.run)
    np.testing.assert_allclose(ds["dissipation_per_cycle"].values, py.dissipation_per_cycle,
                               rtol=1e-12)

    # the same study from Python: a StudyResult with summary, units, Dataset, figures
    st = basins3d_study(parse_case_text(case.read_text(), case), tmp_path / "py",
                        protocols=protos, lam=0.8, workers=1, progress=False)
    res = st.result
    assert isinstance(res, Basins3DResult) and st.complete
    summ = res.summary()
    assert summ["class_counts"] == s["class_counts"]
    assert set(summ["units"]) >= {"lam", "starts", "wall_time_s"}
    np.testing.assert_allclose(res.to_dataset()["dissipation_per_cycle"].values,
                               py.dissipation_per_cycle, rtol=1e-12)
    fig = res.figures()["basin_dissipation"]()
    assert fig.axes[0].get_ylabel() == "dissipation per cycle [J]"
    assert "discrete3d basins" in repr(res)


@pytest.mark.parametrize("args, key", [
    (("--grid", "5"), "--grid"),
    (("--v1", "0:1"), "--v1"),
    (("--lam", "-1"), "--lam"),
    (("--random", "0"), "--random"),
])
def test_bad_options_end_with_one_line_and_exit_2(run_cli, tmp_path, write_case, args, key):
    case = write_case(_case_text())
    code, _, err = run_cli("basins", case, "--out", tmp_path / "x", *args, "--workers", "1")
    assert code == 2
    assert key in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x" / "summary.json").exists()


@pytest.mark.parametrize("text, key", [
    ("[[protocol]]\np_w = [[1.0, 1.0]]\n", "p_w"),
    ("[[protocol]]\np_w = [[1.0, 1.0, 1.0]]\nq_w = [[1.0, 0.0, 0.0]]\n", "q_w"),
    ("not toml [", "--protocols"),
    ("title = 'none'\n", "protocol"),
])
def test_bad_protocol_files_are_refused_naming_the_key(run_cli, tmp_path, write_case,
                                                         text, key):
    case = write_case(_case_text())
    protos = write_case(text, "protocols.toml")
    code, _, err = run_cli("basins", case, "--out", tmp_path / "x", "--protocols", protos,
                           "--workers", "1")
    assert code == 2
    assert key in err and len(err.strip().splitlines()) == 1
