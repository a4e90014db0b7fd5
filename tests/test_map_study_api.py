"""The Ŵ-map study called from Python (what ``slipcycle map`` runs)."""

from __future__ import annotations

import numpy as np
import pytest

from slipcycle.io import CaseError, parse_case_text
from slipcycle.studies.w_hat_map import (
    CUBIC_LAW_Q1_HAT,
    FIG7_PHASE,
    cubic_law_slope,
    map_memory_estimate,
    parse_map_case,
    w_hat_study,
)

SMALL = """
model = "halfspace"
[map]
P1_hat = [0.0, 0.4]
Q1_hat = [0.2, 0.5]
phase = [0.0]
fig7_Q1_hat = [0.4]
[run]
steps_per_cycle = 64
sliders = 40
"""


def test_parse_map_case_reads_grid_and_settings():
    P1, Q1, ph, fig_P1, fig_Q1, settings = parse_map_case(parse_case_text(SMALL))
    np.testing.assert_array_equal(P1, [0.0, 0.4])
    np.testing.assert_array_equal(Q1, [0.2, 0.5])
    assert fig_P1 == 0.4 and list(fig_Q1) == [0.4]
    assert settings == {"steps_per_cycle": 64, "n_sliders": 40}


def test_a_map_case_without_its_table_is_refused():
    with pytest.raises(CaseError) as exc:
        parse_map_case(parse_case_text('model = "halfspace"\n'))
    assert exc.value.key == "map"


def test_study_gives_the_map_the_fig7_curves_and_the_cubic_law():
    out = w_hat_study(*parse_map_case(parse_case_text(SMALL)))
    s, ds = out.summary, out.dataset
    assert ds["W_hat"].shape == (2, 2, 1)
    assert ds["fig7_W_hat"].shape == (1, FIG7_PHASE.size)
    assert ds["cubic_law_W_hat"].shape == CUBIC_LAW_Q1_HAT.shape
    assert s["grid_points"] == 4
    # Ŵ = (2/3) Q̂1³ at small amplitude (Barber 2012): slope 3 on log axes
    assert s["cubic_law_slope"] == pytest.approx(3.0, abs=0.1)
    assert s["cubic_law_slope"] == cubic_law_slope(CUBIC_LAW_Q1_HAT,
                                                   ds["cubic_law_W_hat"].values)
    assert set(out.figures) == {"w_hat_vs_phase", "w_hat_cubic_law"}


def test_memory_estimate_grows_with_the_grid():
    assert map_memory_estimate(2000, 200, 100, threads=1) > \
        map_memory_estimate(1000, 200, 100, threads=1)
