"""One engine per physics: FE load cases are combined into discrete loads in one function.

:func:`slipcycle.fe.loads.combined_loads` returns p^w(θ), q^w(θ); the discrete case file of
``slipcycle reduce --case`` is its text (a swapped-in combination shows up in the text),
and the loads read back from that text are the function's to the 12 digits written.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.fe import model as fe_model
from slipcycle.fe.builders import block_on_rigid
from slipcycle.fe.loads import combined_loads
from slipcycle.fe.model import discrete_case_text
from slipcycle.fe.reduction import reduce_problem
from slipcycle.loading import HarmonicLoad

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


@pytest.fixture(scope="module")
def reduced_and_table():
    model = tomllib.loads((EXAMPLES / "fe_block_nu03.toml").read_text())["fe"]
    r = reduce_problem(block_on_rigid(width=model["width"], height=model["height"],
                                      E=model["E"], nu=model["nu"], elements=4,
                                      thickness=model["thickness"]))
    table = dict(model["discrete"])
    table.setdefault("phase", {})
    table["lam"] = 0.7
    return r, table


def test_combination_is_the_superposition_of_the_cases(reduced_and_table):
    r, t = reduced_and_table
    p, q = combined_loads(r, t["mean"], t["amplitude"], t["phase"], t["lam"])
    th = np.linspace(0, 2 * np.pi, 13)
    ref_p = np.zeros((th.size, r.n))
    ref_q = np.zeros((th.size, r.n))
    for i, name in enumerate(r.load_cases):
        g = (t["mean"].get(name, 1.0 if name == "gap" else 0.0) + t["lam"]
             * t["amplitude"].get(name, 0.0) * np.cos(th + t["phase"].get(name, 0.0)))
        ref_p += g[:, None] * r.p_w[i]
        ref_q += g[:, None] * r.q_w[i]
    scale = np.abs(ref_p).max()
    assert np.allclose(p(th), ref_p, rtol=0, atol=1e-12 * scale)
    assert np.allclose(q(th), ref_q, rtol=0, atol=1e-12 * scale)
    load = DiscreteLoad(p, q)
    assert np.allclose(load(th), np.hstack([ref_q, ref_p]), rtol=0, atol=1e-12 * scale)


def test_unknown_case_is_refused(reduced_and_table):
    r, _ = reduced_and_table
    with pytest.raises(ValueError, match="amplitude.shear: unknown load case"):
        combined_loads(r, amplitude={"shear": 1.0})


def test_case_text_is_the_text_of_the_one_function(reduced_and_table):
    r, t = reduced_and_table
    text = discrete_case_text(t, r, "k.npz")
    ld = tomllib.loads(text)["loading"]
    p, q = combined_loads(r, t["mean"], t["amplitude"], t["phase"], t["lam"])
    written = DiscreteLoad.harmonic(ld["p0"], ld["q0"], ld["p1"], ld["q1"], ld["p1_phase"],
                                    ld["q1_phase"], ld["lam"])
    th = np.linspace(0, 2 * np.pi, 9)
    ref = DiscreteLoad(p, q)(th)
    assert np.allclose(written(th), ref, rtol=0, atol=1e-11 * np.abs(ref).max())


def test_swapping_the_function_changes_the_case_text(reduced_and_table, monkeypatch):
    r, t = reduced_and_table
    n = r.n
    fake = (HarmonicLoad(np.full(n, 7.0), np.full(n, 3.0), np.full(n, 0.25), 0.5),
            HarmonicLoad(np.full(n, -1.0), np.full(n, 2.0), np.full(n, -0.5), 0.5))
    monkeypatch.setattr(fe_model, "combined_loads", lambda *a, **k: fake)
    ld = tomllib.loads(discrete_case_text(t, r, "k.npz"))["loading"]
    assert ld["lam"] == 0.5
    assert ld["p0"] == [7.0] * n and ld["p1"] == [3.0] * n and ld["p1_phase"] == [0.25] * n
    assert ld["q0"] == [-1.0] * n and ld["q1"] == [2.0] * n and ld["q1_phase"] == [-0.5] * n
