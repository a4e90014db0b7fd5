"""The shakedown study called from Python (what ``slipcycle shakedown`` runs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slipcycle.discrete.case import read_discrete_case
from slipcycle.discrete.shakedown import lambda1, lambda2, safe_region
from slipcycle.discrete.steady import STEADY_CODES
from slipcycle.io import CaseError, read_case
from slipcycle.studies.shakedown import SUMMARY_UNITS, shakedown_study

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


@pytest.fixture(scope="module")
def case():
    return read_case(EXAMPLES / "shakedown_triangle.toml")


def test_study_returns_the_lambdas_of_the_linear_programs(case, tmp_path):
    status = shakedown_study(case, tmp_path, lam_points=4, starts=1, lam_tol=0.25, workers=1,
                             progress=False)
    assert status.complete and status.cells_done == status.cells_total == 4 * 2
    dc = read_discrete_case(case)
    region = safe_region(dc.system, dc.load)
    l2 = lambda2(region)[0]
    s = status.outputs.summary
    assert s["lambda2"] == pytest.approx(l2, rel=1e-12)
    assert s["lambda1"] == pytest.approx(lambda1(region, l2)["lambda1"], rel=1e-8)
    assert s["units"] == SUMMARY_UNITS
    ds = status.outputs.dataset
    assert ds["steady_state"].shape == (4, 2)
    assert set(np.unique(ds["steady_state"].values)) <= set(range(len(STEADY_CODES)))
    # the refined bracket lies inside the grid bracket
    for b in ("lambda3", "lambda4"):
        lo, hi = s[f"{b}_bracket"]
        glo, ghi = s[f"{b}_grid_bracket"]
        assert lo >= glo and (ghi is None or hi <= ghi)
    assert (tmp_path / "scan.zarr").exists() and (tmp_path / "refine.json").exists()


def test_study_stopped_early_reports_its_progress_and_resumes(case, tmp_path):
    status = shakedown_study(case, tmp_path, lam_points=3, starts=0, lam_tol=1.0, workers=1,
                             progress=False, stop_after=1)
    assert not status.complete and status.outputs is None
    assert status.cells_done < status.cells_total == 3
    status = shakedown_study(case, tmp_path, lam_points=3, starts=0, lam_tol=1.0, workers=1,
                             progress=False, resume=True)
    assert status.complete and status.outputs.summary["scan"]["starts"] == 1


@pytest.mark.parametrize(("option", "kwargs"), [
    ("--lam-points", {"lam_points": 1}), ("--starts", {"starts": -1}),
    ("--lam-max", {"lam_max": -1.0}), ("--tol", {"tol": 2.0}), ("--lam-tol", {"lam_tol": 0.0}),
])
def test_bad_options_are_refused_before_any_work(case, tmp_path, option, kwargs):
    with pytest.raises(CaseError) as exc:
        shakedown_study(case, tmp_path / "o", workers=1, progress=False, **kwargs)
    assert exc.value.key == option
    assert not (tmp_path / "o").exists()
