"""The FE model objects validate themselves; the reduction offers the result contract."""

from __future__ import annotations

import numpy as np
import pytest

from slipcycle.errors import InputError
from slipcycle.fe import block_on_rigid, reduce_problem, two_blocks
from slipcycle.fe.geometry import Grid, Material, Solid
from slipcycle.io.case import CaseError
from slipcycle.io.matrices import read_stiffness

BLOCK = """
model = "fe"
[fe]
geometry = "block_on_rigid"
width = 0.02
height = 0.01
E = 200e9
nu = 0.3
elements = 3
"""


@pytest.mark.parametrize("make,key,problem", [
    (lambda: Material(E=-1.0, nu=0.3), "E", "must be > 0, got -1"),
    (lambda: Material(E=1.0, nu=0.5), "nu", "must be < 0.5, got 0.5"),
    (lambda: Material(E=1.0, nu=-1.0), "nu", "must be > -1, got -1"),
    (lambda: Solid(E=1.0, nu=0.3, height=0.0), "height", "must be > 0, got 0"),
    (lambda: Grid(0.02, 0.03), "contact_width", "must be <= 0.02, got 0.03"),
    (lambda: Grid(-0.02, 0.01), "width", "must be > 0, got -0.02"),
    (lambda: Grid(0.02, 0.02, elements=0), "elements", "must be >= 1, got 0"),
    (lambda: Grid(0.02, 0.02, grading=0.5), "grading", "must be >= 1, got 0.5"),
    (lambda: block_on_rigid(width=0.02, height=0.01, E=1.0, nu=0.7), "nu",
     "must be < 0.5, got 0.7"),
    (lambda: two_blocks(width=0.02, upper={"height": 0.01, "E": -2.0, "nu": 0.3},
                        lower={"height": 0.01, "E": 1.0, "nu": 0.3}), "upper.E",
     "must be > 0, got -2"),
])
def test_objects_refuse_invalid_input_naming_the_field(make, key, problem):
    with pytest.raises(InputError) as exc:
        make()
    assert exc.value.key == key and exc.value.problem == problem


@pytest.mark.parametrize("edit,key,problem", [
    (("nu = 0.3", "nu = 0.5"), "fe.nu", "must be < 0.5, got 0.5"),
    (("E = 200e9", "E = -1.0"), "fe.E", "must be > 0, got -1"),
    (("height = 0.01", "height = 0.0"), "fe.height", "must be > 0, got 0"),
    (("elements = 3", "elements = 0"), "fe.elements", "must be >= 1, got 0"),
    (("elements = 3", "elements = 3\ngrading = 0.5"), "fe.grading", "must be >= 1, got 0.5"),
    (("elements = 3", "elements = 3\ncontact_width = 0.03"), "fe.contact_width",
     "must be <= 0.02, got 0.03"),
])
def test_case_file_gives_the_same_message_under_the_toml_key(edit, key, problem):
    from slipcycle.fe.model import build_problem
    from slipcycle.io.case import parse_case_text

    with pytest.raises(CaseError) as exc:
        build_problem(parse_case_text(BLOCK.replace(*edit)))
    assert exc.value.key == key and exc.value.problem == problem


def test_reduction_contract_agrees_with_the_npz(run_cli, write_case, tmp_path):
    out = tmp_path / "r.npz"
    code, _, err = run_cli("reduce", write_case(BLOCK), "--out", out, "--quiet")
    assert code == 0, err
    data = read_stiffness(out)
    red = reduce_problem(block_on_rigid(width=0.02, height=0.01, E=200e9, nu=0.3,
                                        elements=3))
    ds = red.to_dataset()
    for name in ("A", "B", "C", "q_w", "p_w", "gap"):
        np.testing.assert_allclose(ds[name].values, data[name], rtol=1e-9, atol=1e-3)
    np.testing.assert_allclose(np.stack([ds["x"], ds["y"]], axis=1), data["coords"])
    assert ds["A"].attrs["units"] == "N/m" and ds["x"].attrs["units"] == "m"
    # text labels of a dimension are CF auxiliary coordinates "<dim>_name" (io.metadata)
    assert list(ds["load_case_name"].values) == list(data["load_cases"])
    s = red.summary()
    assert s["n_contact_nodes"] == data["A"].shape[0]
    assert s["coupling_B_over_A"] == pytest.approx(
        np.linalg.norm(data["B"]) / np.linalg.norm(data["A"]), rel=1e-9)
    assert s["dundurs_beta"] == pytest.approx((1 - 2 * 0.3) / (2 * (1 - 0.3)))
    assert s["units"]["coupling_B_over_A"] == "1" and s["units"]["dundurs_beta"] == "1"
    r = repr(red)
    assert "\n" not in r and r.startswith("<ReducedModel fe reduction:")
    assert red._repr_html_().startswith("<table>")
    assert set(red.figures()) == {"coupling"}
    assert red.figures()["coupling"]().axes
    assert red.to_outputs().summary["analysis"] == "reduction"
