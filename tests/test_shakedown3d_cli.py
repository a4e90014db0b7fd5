"""``slipcycle shakedown`` / ``slipcycle basins`` of ``discrete3d`` and ``lap_joint``
cases: the command line and the Python API give the same λ2, limits and classes; the
engine's limits bracket the cone program's λ2 where every start reaches it; bad options
end in one line and exit 2."""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

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
