"""The basins study called from Python (what ``slipcycle basins`` runs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slipcycle.discrete.steady import STEADY_CODES
from slipcycle.io import CaseError, read_case
from slipcycle.studies.basins import basins_study, parse_range, read_protocols

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


@pytest.fixture(scope="module")
def case():
    return read_case(EXAMPLES / "shakedown_triangle.toml")


def test_grid_map_from_python(case, tmp_path):
    status = basins_study(case, tmp_path, grid=5, workers=1, progress=False)
    assert status.complete
    s, ds = status.outputs.summary, status.outputs.dataset
    assert s["mode"] == "grid" and s["starts"] == 25 and s["grid"] == [5, 5]
    assert ds["steady_state"].shape == (5, 5)
    assert sum(s["class_counts"].values()) == 25
    assert s["steady_state_codes"] == list(STEADY_CODES)
    assert "basin_map" in status.outputs.figures


def test_random_starts_and_protocols_from_python(case, tmp_path):
    status = basins_study(case, tmp_path / "r", random=3, seed=1, workers=1, progress=False)
    assert status.complete and status.outputs.summary["starts"] == 3
    assert status.outputs.dataset["converged"].dtype == bool
    protos = tmp_path / "p.toml"
    protos.write_text("[[protocol]]\np_w = [[1.0, 1.0]]\n")
    status = basins_study(case, tmp_path / "p", protocols=protos, workers=1, progress=False)
    assert status.outputs.summary["mode"] == "protocols"
    assert status.outputs.summary["starts"] == 1


def test_protocols_and_ranges_are_read_and_checked(tmp_path):
    protos = tmp_path / "p.toml"
    protos.write_text("[[protocol]]\np_w = [[0.1, 1.0], [1.0, 1.0]]\n"
                      "q_w = [[0.3, 0.0], [0.0, 0.0]]\n")
    (p,) = read_protocols(protos, 2)
    np.testing.assert_array_equal(p, [[0.3, 0.0, 0.1, 1.0], [0.0, 0.0, 1.0, 1.0]])
    protos.write_text("")
    with pytest.raises(CaseError) as exc:
        read_protocols(protos, 2)
    assert exc.value.key == "protocol"
    assert parse_range("-1e-6:2e-6", "--v1") == (-1e-6, 2e-6)
    with pytest.raises(CaseError) as exc:
        parse_range("2:1", "--v2")
    assert exc.value.key == "--v2"


def test_grid_needs_two_nodes_and_a_valid_lam(case, tmp_path):
    with pytest.raises(CaseError) as exc:
        basins_study(case, tmp_path, grid=1, workers=1, progress=False)
    assert exc.value.key == "--grid"
    with pytest.raises(CaseError) as exc:
        basins_study(case, tmp_path, lam=-1.0, workers=1, progress=False)
    assert exc.value.key == "--lam"
