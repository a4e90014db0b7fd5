"""``slipcycle shakedown`` / ``slipcycle basins`` of ``discrete3d`` and ``lap_joint``
cases: the command line and the Python API give the same λ2, limits and classes; the
engine's limits bracket the cone program's λ2 where every start reaches it; bad options
end in one line and exit 2."""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from test_lap_joint_study import SMALL

import slipcycle
from slipcycle.discrete3d.shakedown import lambda2_open
from slipcycle.io import parse_case_text
from slipcycle.studies.basins3d import load_discrete3d_case
from slipcycle.studies.shakedown3d import shakedown3d_study

EXAMPLE = Path(slipcycle.__file__).parent / "examples" / "discrete3d_three_node.toml"

PROTOCOLS = """
[[protocol]]
p_w = [[0.5, 0.5, 0.5], [1.0, 1.2, 1.0]]
q_w = [[[0.1, 0.0], [0.0, 0.1], [-0.1, 0.0]], [[0.2, 0.1], [0.0, 0.0], [0.0, -0.2]]]
"""


def _case_text() -> str:
    return (EXAMPLE.read_text().replace("steps_per_cycle = 100", "steps_per_cycle = 40")
            .replace("step_tolerance = 1e-7", "step_tolerance = 1e-5")
            .replace('fields = ["xdmf", "pvd"]', "fields = []"))


@pytest.fixture(scope="module")
def api_result(tmp_path_factory):
    work = tmp_path_factory.mktemp("sd3")
    (work / "p.toml").write_text(PROTOCOLS)
    st = shakedown3d_study(parse_case_text(_case_text()), protocols=work / "p.toml",
                           lam_points=3, lam_tol=0.03)
    return st.result


def test_engine_limits_bracket_lambda2_of_the_cone_program(api_result):
    """Every start of the three-node example shakes down up to λ2 (its limit bracket
    holds the cone program's λ2, found independently)."""
    dc = load_discrete3d_case(_case_text(), None)
    lam2 = lambda2_open(dc.system, dc.load, 40).lambda2
    assert api_result.lambda2 == pytest.approx([lam2, lam2], rel=1e-9)
    for lo, hi in api_result.limits:
        assert lo <= lam2 * (1 + 1e-6) <= hi * (1 + 2e-6)
    lo, hi = api_result.lambda1_bracket
    assert lo <= lam2 <= hi * (1 + 2e-6) and hi - lo <= 0.03 * api_result.lam[-1] + 1e-12


def test_cli_shakedown_discrete3d_agrees_with_the_api(api_result, run_cli, tmp_path,
                                                      write_case):
    case = write_case(_case_text())
    (tmp_path / "p.toml").write_text(PROTOCOLS)
    out = tmp_path / "o"
    code, stdout, err = run_cli("shakedown", case, "--out", out, "--lam-points", "3",
                                "--lam-tol", "0.03", "--protocols", tmp_path / "p.toml",
                                "-q")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["model"] == "discrete3d" and s["subjects"] == ["case", "protocol 0"]
    np.testing.assert_allclose(s["lambda2"], api_result.lambda2, rtol=1e-9)
    np.testing.assert_allclose(np.array(s["shakedown_limits"], float), api_result.limits,
                               rtol=1e-9)
    assert s["units"]["lambda2"] == "1"
    ds = xr.open_dataset(out / "result.nc")
    np.testing.assert_array_equal(ds["steady_state"].values, api_result.steady_state)
    assert ds["dissipation_per_cycle"].attrs["units"] == "J"
    assert (out / "figures" / "shakedown_map.png").is_file()


@pytest.mark.parametrize("argv, key", [
    (["--starts", "3"], "--starts"),
    (["--lam-points", "1"], "--lam-points"),
    (["--lam-tol", "0"], "--lam-tol"),
    (["--lam-max", "-1"], "--lam-max"),
])
def test_cli_shakedown_discrete3d_refuses_bad_options_in_one_line(argv, key, run_cli,
                                                                  tmp_path, write_case):
    case = write_case(_case_text())
    out = tmp_path / "o"
    code, _, err = run_cli("shakedown", case, "--out", out, *argv)
    assert code == 2
    assert key in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


# -- the lap joint (small, one protocol): it must be the joint ------------------------------

def _lap_text() -> str:
    """The small joint of the lap-joint study tests, one protocol."""
    old = 'names = ["sequential", "reversed", "simultaneous"]'
    assert old in SMALL
    return SMALL.replace(old, 'names = ["simultaneous"]')


@pytest.fixture(scope="module")
def lap_cli(tmp_path_factory):
    from slipcycle.cli.main import main

    work = tmp_path_factory.mktemp("lapsd")
    (work / "lap.toml").write_text(_lap_text())
    assert main(["shakedown", str(work / "lap.toml"), "--out", str(work / "o"),
                 "--lam-points", "2", "--lam-tol", "0.1", "-q"]) == 0
    return json.loads((work / "o" / "summary.json").read_text())


def test_cli_shakedown_lap_joint_lambda2_is_confirmed_by_the_engine(lap_cli):
    """λ2 of the joint with its open nodes (the all-closed program is infeasible) equals
    the API's, and the engine started from the program's safe state shakes down up to
    it: its limit bracket holds λ2, while simultaneous tightening slips far below."""
    from slipcycle.discrete3d.shakedown import lambda2_socp
    from slipcycle.joints.lap_joint_shakedown import lap_joint_subjects

    s = lap_cli
    assert s["model"] == "lap_joint"
    # λ of a lap joint is the service amplitude: every amplitude is in newtons
    for key in ("lambda2", "lambda1_bracket", "class_window", "shakedown_limits", "lam_max"):
        assert s["units"][key] == "N", key
    assert s["subjects"] == ["simultaneous", "safe state (simultaneous)"]
    subjects, run = lap_joint_subjects(parse_case_text(_lap_text()))
    sub = subjects[0]
    region = lambda2_open(sub.system, sub.load, run["steps_per_cycle"])
    assert region.consistent and region.open_set.any()
    assert lambda2_socp(sub.system, sub.load, run["steps_per_cycle"]).lambda2 == 0.0
    assert s["lambda2"][0] == pytest.approx(region.lambda2, rel=1e-6)
    lo, hi = s["shakedown_limits"][1]
    assert lo <= region.lambda2 <= hi
    weak_hi = s["shakedown_limits"][0][1]
    assert weak_hi < lo and s["class_window"] == pytest.approx([weak_hi, lo])
    # the numbers docs/discrete3d.md quotes
    assert s["lambda2"][0] == pytest.approx(165.8, abs=0.05)
    np.testing.assert_allclose(s["shakedown_limits"], [[51.3, 57.0], [159.6, 171.0]],
                               atol=0.05)
    text = (Path(__file__).parents[1] / "docs" / "discrete3d.md").read_text()
    assert "λ2 = 165.8 N" in text and "[159.6, 171.0] N" in text and "[51.3, 57.0] N" in text


@pytest.mark.parametrize("argv, key", [(["--random", "3"], "--random"),
                                       (["--grid", "5"], "--grid"),
                                       (["--seed", "3"], "--seed"),
                                       (["--lam", "-1"], "--lam")])
def test_cli_basins_lap_joint_refuses_start_options_in_one_line(argv, key, run_cli,
                                                                 tmp_path, write_case):
    case = write_case(_lap_text())
    out = tmp_path / "o"
    code, _, err = run_cli("basins", case, "--out", out, *argv)
    assert code == 2 and key in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_cli_shakedown_lap_joint_refuses_protocols_file(run_cli, tmp_path, write_case):
    case = write_case(_lap_text())
    (tmp_path / "p.toml").write_text(PROTOCOLS)
    code, _, err = run_cli("shakedown", case, "--out", tmp_path / "o", "--protocols",
                           tmp_path / "p.toml")
    assert code == 2 and "--protocols" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("command, which", [("shakedown", "discrete3d"),
                                            ("shakedown", "lap_joint"),
                                            ("basins", "lap_joint")])
@pytest.mark.parametrize("argv, key", [(["--workers", "2"], "--workers"),
                                       (["--resume"], "--resume"),
                                       (["--scheduler", "tcp://127.0.0.1:8786"],
                                        "--scheduler")])
def test_3d_studies_without_a_sweep_store_refuse_the_sweep_options_in_one_line(
        command, which, argv, key, run_cli, tmp_path, write_case):
    """These studies run their simulations serially in this process: --workers,
    --resume and --scheduler would be silently ignored, so they are refused (exit 2, one
    line naming the option, before any run: no output directory)."""
    case = write_case(_case_text() if which == "discrete3d" else _lap_text())
    out = tmp_path / "o"
    code, _, err = run_cli(command, case, "--out", out, *argv)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith(f"error: {key}:"), err
    assert "without a sweep store" in lines[0] and "Traceback" not in err
    assert not out.exists()
