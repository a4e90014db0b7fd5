"""The basin map in blocks of rows: the same steady state for every start as one run each.

``basins_study(grid=…)`` runs a block of grid rows per sweep cell, all its starts in one
call of the compiled kernel (in a scattered order, with padding rows past the last v2).
None of that may change what a start gives: each start of the map is compared with its
own run (:func:`run_record`, one start per call), class for class and to 1e-9 in the
dissipation per cycle (Ahn, Bertocchi & Barber 2008: the basins are the map of exactly
these runs).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.discrete.basins import INADMISSIBLE, admissible_box, run_record
from slipcycle.io import read_case
from slipcycle.studies.basins import (
    basin_block_task,
    basins_study,
    grid_blocks,
    load_discrete_case,
)

EXAMPLE = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples" / \
    "shakedown_triangle.toml"


@pytest.fixture(scope="module")
def triangle():
    case = read_case(EXAMPLE)
    return case, load_discrete_case(case.text, str(case.path))


def _per_start(dc, v1, v2):
    """The map start by start: one run_record per start, (v2, v1) arrays."""
    run = {k: dc.run[k] for k in ("cycles", "steps_per_cycle", "tol", "min_cycles")}
    recs = [[run_record(dc.system, dc.load, initial_slip=[a, b], **run) for a in v1]
            for b in v2]
    return {k: np.array([[r[k] for r in row] for row in recs]) for k in recs[0][0]}


def test_block_map_equals_one_run_per_start(triangle, tmp_path):
    case, dc = triangle
    grid = 7
    status = basins_study(case, tmp_path, grid=grid, workers=1, progress=False)
    data = status.result.data
    ref = _per_start(dc, status.result.v1, status.result.v2)
    cls = data["steady_state"]
    assert cls.shape == (grid, grid)
    np.testing.assert_array_equal(cls, ref["steady_state"])
    # both outcomes and inadmissible corners occur: the comparison covers every branch
    assert {0, 1, INADMISSIBLE} <= set(np.unique(cls).tolist())
    ok = cls != INADMISSIBLE
    np.testing.assert_allclose(data["dissipation_per_cycle"][ok],
                               ref["dissipation_per_cycle"][ok], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(data["dissipation_per_node"][ok],
                               ref["dissipation_per_node"][ok], rtol=1e-9, atol=1e-15)
    for key in ("cycles_run", "n_slipping", "memory_erased"):
        np.testing.assert_array_equal(data[key][ok], ref[key][ok])


def test_padding_rows_of_the_last_block_are_not_runs(triangle):
    case, dc = triangle
    box = admissible_box(dc.system, dc.load)
    v1, v2 = np.linspace(*box[0], 3), np.linspace(*box[1], 5)
    # block 1 of 3 rows holds rows 3, 4 and one padding row
    out = basin_block_task({"block": 1}, case.text, str(case.path), tuple(v1), tuple(v2),
                           rows=3)
    assert out["steady_state"].shape == (3, 3)
    assert (out["steady_state"][2] == INADMISSIBLE).all()
    assert np.isnan(out["dissipation_per_cycle"][2]).all()
    ref = _per_start(dc, v1, v2[3:])
    np.testing.assert_array_equal(out["steady_state"][:2], ref["steady_state"])


@settings(max_examples=60, deadline=None)
@given(st.integers(2, 5000), st.integers(1, 20000))
def test_blocks_cover_every_row_at_least_twice_split(grid, per_block):
    blocks, rows = grid_blocks(grid, per_block)
    assert blocks >= 2 and rows >= 1
    assert (blocks - 1) * rows < grid <= blocks * rows   # no empty block, every row in one
