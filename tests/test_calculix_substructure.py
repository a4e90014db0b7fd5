"""What CalculiX's two stiffness exports hold, measured with the real ``ccx``.

The same deck (a C3D8 or C3D8I block, bottom face retained, top face clamped, one layer of
interior nodes to condense) is exported both ways CalculiX offers:

- ``*FREQUENCY, SOLVER=MATRIXSTORAGE``: the full stiffness K of the free dofs (``.sti`` +
  ``.dof``); its Schur complement onto the bottom face is the condensed (Guyan) stiffness.
- ``*SUBSTRUCTURE GENERATE`` + ``*RETAINED NODAL DOFS`` + ``*SUBSTRUCTURE MATRIX OUTPUT``:
  ccx 2.20 writes the uncondensed retained block K_bb (to 1e-13), whatever the deck's
  boundary conditions, solver or ordering. slipcycle refuses that file in one line naming
  the ``.sti`` route, and reads the ``.sti`` route to the Schur complement.

Skipped where ``ccx`` is not installed (tests/calculix.py says why); run in CI.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from calculix import block_deck, run_ccx

from slipcycle.io.fe_formats import abaqus
from slipcycle.io.matrices import StiffnessError, read_reduced_stiffness

NX, NY, NZ = 3, 3, 2

SUB_OUT = ("*SUBSTRUCTURE MATRIX OUTPUT, STIFFNESS=YES, OUTPUT FILE=USER DEFINED, "
           "FILE NAME=sub\n*END STEP\n")
#: deck details that might have mattered; ccx 2.20 writes K_bb with every one of them
VARIANTS = {
    "clamp_in_model": "*BOUNDARY\nTOP, 1, 3\n*STEP\n*SUBSTRUCTURE GENERATE\n"
                      "*RETAINED NODAL DOFS\nBOTTOM, 1, 3\n" + SUB_OUT,
    "clamp_in_step": "*STEP\n*SUBSTRUCTURE GENERATE\n*BOUNDARY\nTOP, 1, 3\n"
                     "*RETAINED NODAL DOFS\nBOTTOM, 1, 3\n" + SUB_OUT,
    "unsorted_spooles": "*BOUNDARY\nTOP, 1, 3\n*STEP\n*SUBSTRUCTURE GENERATE, SOLVER=SPOOLES\n"
                        "*RETAINED NODAL DOFS, SORTED=NO\nBOTTOM, 1, 3\n" + SUB_OUT,
}
STI_STEP = "*BOUNDARY\nTOP, 1, 3\n*STEP\n*FREQUENCY, SOLVER=MATRIXSTORAGE\n1\n*END STEP\n"


def _deck(element: str) -> str:
    return block_deck(NX, NY, NZ, element=element, step=None)


def _bottom_nodes() -> np.ndarray:
    """Labels of the z = 0 nodes of :func:`calculix.block_deck` (numbered x, then y, then z)."""
    return np.arange(1, (NX + 1) * (NY + 1) + 1)


def _blocks(sti: Path, retained_labels: np.ndarray):
    """K_bb and the Schur complement K_bb − K_bi K_ii⁻¹ K_ib of the full ``.sti`` K on the
    rows labelled ``retained_labels`` (node, dof), in that order."""
    raw = abaqus.read(sti, "calculix")
    K = raw.K.toarray()
    row = {tuple(lab): i for i, lab in enumerate(raw.labels)}
    b = np.array([row[tuple(lab)] for lab in retained_labels])
    i = np.setdiff1d(np.arange(K.shape[0]), b)
    Kbb, Kbi = K[np.ix_(b, b)], K[np.ix_(b, i)]
    return Kbb, Kbb - Kbi @ np.linalg.solve(K[np.ix_(i, i)], Kbi.T)


@pytest.fixture(scope="module", params=["C3D8", "C3D8I"])
def exports(request, tmp_path_factory):
    """The ``.sti`` and the substructure ``.mtx`` of each deck variant, for one element."""
    element = request.param
    d = tmp_path_factory.mktemp(f"ccx_{element}")
    sti = run_ccx(_deck(element) + STI_STEP, d / "sti", "block").out(".sti")
    subs = {}
    for name, step in VARIANTS.items():
        subs[name] = run_ccx(_deck(element) + step, d / name, "block").deck.with_name("sub.mtx")
    return element, sti, subs


def test_ccx_substructure_export_is_the_uncondensed_block_whatever_the_deck(exports):
    element, sti, subs = exports
    for name, mtx in subs.items():
        raw = abaqus.read(mtx, "calculix", check_condensed=False)
        Kbb, S = _blocks(sti, raw.labels)
        K = raw.K.toarray()
        assert sorted(map(tuple, raw.labels)) == [(j, a) for j in _bottom_nodes()
                                                   for a in (1, 2, 3)]
        scale = np.linalg.norm(Kbb)
        # K_bb to round-off of the assembly, far from the condensed stiffness
        assert np.linalg.norm(K - Kbb) / scale < 1e-10, (element, name)
        assert np.linalg.norm(K - S) / scale > 0.1, (element, name)


def test_the_uncondensed_substructure_export_is_refused_naming_the_sti_route(exports):
    _, _, subs = exports
    for mtx in subs.values():
        with pytest.raises(StiffnessError) as err:
            read_reduced_stiffness(mtx, tangential_dims=2, frames={"normal": [0, 0, -1]})
        msg = str(err.value)
        assert "\n" not in msg and "sub.mtx" in msg
        assert "uncondensed" in msg and "SOLVER=MATRIXSTORAGE" in msg and "*DENSITY" in msg


def test_the_sti_route_of_the_same_deck_reads_to_the_schur_complement(exports):
    _, sti, _ = exports
    bottom = _bottom_nodes()
    red = read_reduced_stiffness(sti, tangential_dims=2, contact_nodes=bottom,
                                 frames={"normal": [0.0, 0.0, -1.0]})
    assert np.array_equal(red.nodes, bottom)
    labels = [(j, a) for j in bottom for a in (1, 2, 3)]
    _, S = _blocks(sti, np.array(labels))
    # outward normal −z: t1 = x, t2 = y, the opening w along +z (dof 3)
    t = np.array([3 * k + a for k in range(bottom.size) for a in (0, 1)])
    w = np.arange(bottom.size) * 3 + 2
    scale = np.linalg.norm(S)
    for got, want in ((red.A, S[np.ix_(t, t)]), (red.B, S[np.ix_(w, t)]),
                      (red.C, S[np.ix_(w, w)])):
        assert np.linalg.norm(got - want) / scale < 1e-10


def test_refusal_through_a_case_is_one_line_exit_2_nothing_written(exports, run_cli,
                                                                     tmp_path):
    _, _, subs = exports
    mtx = subs["clamp_in_model"]
    n = _bottom_nodes().size
    case = tmp_path / "case.toml"
    case.write_text(
        'model = "discrete3d"\n[discrete3d]\n'
        f'stiffness_file = "{mtx}"\nfriction = 0.5\narea = 1.0\n'
        '[discrete3d.stiffness]\nformat = "calculix"\nnormal = [0.0, 0.0, -1.0]\n'
        f'[loading]\np0 = {[1.0] * n}\nq1 = {[[0.1, 0.0]] * n}\n'
        '[run]\ncycles = 3\n[output]\nfields = []\n')
    before = sorted(p.name for p in tmp_path.iterdir())
    code, out, err = run_cli("run", case, "--out", tmp_path / "res")
    assert code == 2, (out, err)
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err
    assert "stiffness_file" in lines[0] and "sub.mtx" in lines[0]
    assert "SOLVER=MATRIXSTORAGE" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == before
