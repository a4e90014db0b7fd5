"""A 3-D reduced model exported from an FE code runs from a case file.

The three-node example's K = [[A, Bᵀ], [B, C]] is written as an Abaqus ``*MATRIX OUTPUT``
file in global x, y, z dofs (node labels 1..3; contact on a flat with outward normal −z, so
t1 = x, t2 = y and the opening w is +z) and named by a ``discrete3d`` case: the run gives
the numbers of the inline matrices.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from conftest import EXAMPLES
from fe_export_writers import abaqus_matrix_input

import slipcycle
from slipcycle.io import parse_case_text


def _inline_case():
    return (EXAMPLES / "discrete3d_three_node.toml").read_text()


def test_abaqus_export_of_a_3d_model_runs_and_gives_the_inline_numbers(tmp_path):
    text = _inline_case()
    d = parse_case_text(text).data["discrete3d"]
    A, B, C = (np.array(d[k], float) for k in ("A", "B", "C"))
    n = C.shape[0]
    K = np.zeros((3 * n, 3 * n))
    t = np.array([3 * i + a for i in range(n) for a in (0, 1)])
    w = np.array([3 * i + 2 for i in range(n)])
    K[np.ix_(t, t)], K[np.ix_(w, t)], K[np.ix_(t, w)], K[np.ix_(w, w)] = A, B, B.T, C
    labels = [(i + 1, a + 1) for i in range(n) for a in range(3)]
    abaqus_matrix_input(tmp_path / "joint_STIF1.mtx", K, labels)
    # the same case with the matrices read from the export
    exported = re.sub(r"(?ms)^A = \[\[.*?^C = \[\[[^\n]*\n", 'stiffness_file = "joint_STIF1.mtx"\n',
                      text)
    exported = exported.replace("[loading]", "[discrete3d.stiffness]\nformat = \"abaqus\"\n"
                                "normal = [0.0, 0.0, -1.0]\n[loading]", 1)
    assert "A = [[" not in exported
    case_file = tmp_path / "case.toml"
    case_file.write_text(exported.replace('fields = ["xdmf", "pvd"]', "fields = []"))
    ref = slipcycle.run(text.replace('fields = ["xdmf", "pvd"]', "fields = []"))
    res = slipcycle.run(case_file)
    assert res.steady_state == ref.steady_state
    assert res.cycles_run == ref.cycles_run
    assert res.dissipation_per_cycle == pytest.approx(ref.dissipation_per_cycle, rel=1e-9)
