"""Every number quoted in the headers of the discrete, FE and shakedown examples and in
docs/discrete.md, docs/fe.md (history section) is produced here, to the quoted precision."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from slipcycle.discrete.case import read_discrete_case, run_case
from slipcycle.discrete.shakedown import lambda1, lambda2, safe_region
from slipcycle.io import parse_case_text, read_case

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


def _dc(name):
    return read_discrete_case(read_case(EXAMPLES / name))


def test_block_nu03_dundurs_beta_is_0_286():
    nu = 0.3
    assert round((1 - 2 * nu) / (2 * (1 - nu)), 3) == 0.286


def test_slid_block_run_slips_cyclically_at_edge_node_8_with_4_26e_6_J_after_145_cycles():
    """fe_block_nu03*.toml headers and docs/fe.md: cyclic slip of node 8 only, nodes 0-7
    stuck, D = 4.26e-6 J (docs: 4.259e-6 J) after 145 cycles (residual 1e-9)."""
    s = run_case(read_case(EXAMPLES / "fe_block_nu03_slid_discrete.toml")).summary
    assert s["steady_state"] == "cyclic_slip"
    assert s["cycles_run"] == 145
    assert float(f"{s['dissipation_per_cycle']:.3g}") == 4.26e-6
    assert float(f"{s['dissipation_per_cycle']:.4g}") == 4.259e-6
    assert float(f"{s['residual']:.1g}") == 1e-9
    assert s["slipping_nodes"] == [8]
    assert s["permanently_stuck_nodes"] == list(range(8))


def test_block_nu03_reduced_model_coupling_0_23_and_f_crit_1_35():
    """docs/fe.md: ‖B‖/‖A‖ = 0.23, f_crit = 1.35 of the 9-node reduced block."""
    dc = _dc("fe_block_nu03_slid_discrete.toml")
    A, B = dc.system.A, dc.system.B
    assert dc.system.n_nodes == 9
    assert round(np.linalg.norm(B) / np.linalg.norm(A), 2) == 0.23
    assert dc.f_crit.method == "exact"
    assert round(dc.f_crit.f_crit, 2) == 1.35


def test_triangle_example_lambda1_0_946_and_lambda2_1_104():
    dc = _dc("shakedown_triangle.toml")
    region = safe_region(dc.system, dc.load)
    l2 = lambda2(region)[0]
    l1 = lambda1(region, l2)["lambda1"]
    assert round(l1, 3) == 0.946
    assert round(l2, 3) == 1.104


def test_triangle_protocol_shakes_down_and_initial_slip_slips_node_1_with_node_0_stuck():
    """discrete_triangle_protocol.toml header (nodes from 0)."""
    text = (EXAMPLES / "discrete_triangle_protocol.toml").read_text()
    s = run_case(read_case(EXAMPLES / "discrete_triangle_protocol.toml")).summary
    assert s["steady_state"] == "shakedown"
    alt = re.sub(r"\[\[discrete\.protocol\]\]\np_w = .*\nq_w = .*\n", "", text)
    alt = alt.replace("friction = 0.5\n", "friction = 0.5\ninitial_slip = [-0.518, 0.528]\n")
    assert "p_w" not in alt
    s = run_case(parse_case_text(alt)).summary
    assert s["steady_state"] == "cyclic_slip"
    assert s["slipping_nodes"] == [1]
    assert s["permanently_stuck_nodes"] == [0]


def test_unstable_example_slope_product_f_crit_and_wandering_dissipation():
    """unstable_two_node.toml: slope product −2.3 (node 0 at q = +f p, node 1 at q = −f p),
    f_crit = 0.643, not_converged with D wandering between about 1.0 and 2.7 J over cycles
    21–60."""
    dc = _dc("unstable_two_node.toml")
    A, B, f = dc.system.A, dc.system.B, dc.system.friction

    def slope(j, s):
        # node j's slip per unit slip of the other node on its friction line s q + f p = 0
        k = 1 - j
        return -(s * A[j, k] + f[j] * B[j, k]) / (s * A[j, j] + f[j] * B[j, j])

    assert round(slope(0, -1) * slope(1, +1), 1) == -2.3
    assert round(dc.f_crit.f_crit, 3) == 0.643
    out = run_case(read_case(EXAMPLES / "unstable_two_node.toml"))
    assert out.summary["steady_state"] == "not_converged"
    hist = np.asarray(out.dataset["dissipation_history"])[20:]
    assert hist.size == 40
    assert round(float(hist.min()), 1) == 1.0
    assert round(float(hist.max()), 1) == 2.7


@pytest.mark.parametrize("name", ["discrete_two_node.toml", "discrete_triangle_protocol.toml",
                                  "fe_block_nu03.toml", "fe_block_nu03_slid_discrete.toml",
                                  "fe_cylinder.toml", "fe_two_blocks.toml",
                                  "shakedown_triangle.toml", "unstable_two_node.toml"])
def test_example_headers_cite_literature_not_internal_documents(name):
    text = (EXAMPLES / name).read_text()
    assert "SPEC" not in text and "seed" not in text.lower()
