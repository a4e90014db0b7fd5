"""`slipcycle reduce`: model files, mesh files, imported matrices, errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from slipcycle.condensation import schur_complement
from slipcycle.io.matrices import read_stiffness

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"

BLOCK = """
model = "fe"
[fe]
geometry = "block_on_rigid"
width = 0.04
height = 0.02
E = 210e9
nu = 0.3
elements = 3
"""


def test_reduce_example_and_run_discrete_case(run_cli, tmp_path):
    out, case = tmp_path / "block.npz", tmp_path / "block_discrete.toml"
    code, stdout, err = run_cli("reduce", EXAMPLES / "fe_block_nu03.toml", "--out", out,
                                "--case", case, "--quiet")
    assert code == 0, err
    data = read_stiffness(out)
    assert data["A"].shape == (9, 9) and data["p_w"].shape == (2, 9)
    meta = json.loads(str(data["metadata"]))
    assert "geometry = \"block_on_rigid\"" in meta["case"] and meta["slipcycle_version"]
    assert np.linalg.norm(data["B"]) > 0.1 * np.linalg.norm(data["A"])  # coupled, ν = 0.3
    code, stdout, err = run_cli("run", case, "--out", tmp_path / "run", "--quiet")
    assert code == 0, err
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["n_nodes"] == 9 and summary["dissipation_per_cycle"] >= 0


@pytest.mark.parametrize("edit,key", [
    (("nu = 0.3", "nu = 0.5"), "fe.nu"),
    (("width = 0.04", "width = -1.0"), "fe.width"),
    (("elements = 3", "elements = 3\nelemnts = 4"), "fe.elemnts"),
    (("block_on_rigid", "block_on_rigd"), "fe.geometry"),
])
def test_bad_model_is_refused_naming_the_key(run_cli, write_case, tmp_path, edit, key):
    path = write_case(BLOCK.replace(*edit))
    out = tmp_path / "r.npz"
    code, _, err = run_cli("reduce", path, "--out", out)
    assert code == 2
    assert err.startswith(f"error: {key}:"), err
    assert not out.exists() and not list(tmp_path.glob(".r.npz*"))


def _write_mtx(path: Path, K: np.ndarray, comment: str = "") -> None:
    from scipy.io import mmwrite

    mmwrite(str(path), K, comment=comment)


def test_import_mtx_interleaved_stated_in_file_and_on_command_line(run_cli, tmp_path):
    rng = np.random.default_rng(0)
    M = rng.normal(size=(6, 6))
    K = M @ M.T + 6 * np.eye(6)  # interleaved [v1, w1, v2, w2, v3, w3]
    t, w = [0, 2, 4], [1, 3, 5]
    _write_mtx(tmp_path / "stated.mtx", K, "dof_order: interleaved")
    _write_mtx(tmp_path / "plain.mtx", K)
    for name, extra in (("stated.mtx", []), ("plain.mtx", ["--dof-order", "interleaved"])):
        out = tmp_path / f"{name}.npz"
        code, _, err = run_cli("reduce", tmp_path / name, "--out", out, "--quiet", *extra)
        assert code == 0, err
        d = read_stiffness(out)
        assert np.allclose(d["A"], K[np.ix_(t, t)]) and np.allclose(d["B"], K[np.ix_(w, t)])
        assert np.allclose(d["C"], K[np.ix_(w, w)])
    code, _, err = run_cli("reduce", tmp_path / "stated.mtx", "--out", tmp_path / "x.npz",
                           "--dof-order", "tangential_first")
    assert code == 2 and "dof_order" in err


@pytest.mark.parametrize("kind,word", [("asym", "not symmetric"), ("indef", "not positive")])
def test_import_refuses_asymmetric_or_indefinite(run_cli, tmp_path, kind, word):
    K = np.diag([2.0, 3.0, 4.0, 5.0])
    if kind == "asym":
        K[0, 3] = 0.5
    else:
        K[1, 1] = -1.0
    _write_mtx(tmp_path / "K.mtx", K)
    out = tmp_path / "o.npz"
    code, _, err = run_cli("reduce", tmp_path / "K.mtx", "--out", out)
    assert code == 2 and word in err and "K:" in err
    assert not out.exists()


def test_npz_shape_check_names_the_array(tmp_path):
    np.savez(tmp_path / "bad.npz", A=np.eye(3), B=np.zeros((3, 2)), C=np.eye(3))
    with pytest.raises(ValueError, match="^B: wrong shape"):
        read_stiffness(tmp_path / "bad.npz")


def test_mesh_file_reduction_equals_generated_geometry(run_cli, tmp_path):
    """Write the generated block mesh as a Gmsh file with physical tags, reduce it from
    the file, and compare with the generated-geometry reduction."""
    import meshio

    from slipcycle.fe.builders import block_on_rigid
    from slipcycle.fe.reduction import reduce_problem

    ref = reduce_problem(block_on_rigid(width=0.04, height=0.02, E=210e9, nu=0.3,
                                        elements=3, grading=1.3))
    pr = block_on_rigid(width=0.04, height=0.02, E=210e9, nu=0.3, elements=3, grading=1.3)
    mesh = pr.dofs[0].body.mesh
    lines, tags = [], []
    for tag_id, name in ((1, "contact"), (2, "top")):
        f = mesh.facets[:, mesh.boundaries[name]].T
        lines.append(f)
        tags.append(np.full(len(f), tag_id))
    m = meshio.Mesh(np.c_[mesh.p.T, np.zeros(mesh.nvertices)],
                    [("triangle", mesh.t.T), ("line", np.vstack(lines))],
                    cell_data={"gmsh:physical": [np.full(mesh.nelements, 3), np.concatenate(tags)],
                               "gmsh:geometrical": [np.full(mesh.nelements, 3),
                                                    np.concatenate(tags)]},
                    field_data={"base": np.array([1, 1]), "platen": np.array([2, 1]),
                                "body": np.array([3, 2])})
    meshio.write(tmp_path / "block.msh", m, file_format="gmsh22", binary=False)
    model = tmp_path / "mesh.toml"
    model.write_text("""
model = "fe"
[fe]
geometry = "mesh"
[fe.mesh]
file = "block.msh"
contact = "base"
E = 210e9
nu = 0.3
[[fe.load_case]]
name = "normal"
boundary = "platen"
displacement = [0.0, -1.0]
[[fe.load_case]]
name = "tangential"
boundary = "platen"
displacement = [1.0, 0.0]
""")
    out = tmp_path / "mesh.npz"
    code, _, err = run_cli("reduce", model, "--out", out, "--quiet")
    assert code == 0, err
    d = read_stiffness(out)
    for k in ("A", "B", "C", "p_w", "q_w"):
        assert np.allclose(d[k], getattr(ref, k), rtol=1e-9, atol=1e-9 * np.abs(ref.A).max()), k
    bad = model.read_text().replace('contact = "base"', 'contact = "bse"')
    model.write_text(bad)
    code, _, err = run_cli("reduce", model, "--out", tmp_path / "m2.npz")
    assert code == 2 and "fe.mesh.contact" in err and "base" in err


def test_schur_fast_path_equals_block_solves():
    rng = np.random.default_rng(3)
    n, nb = 60, 8
    M = sp.random(n, n, density=0.08, random_state=4)
    K = (M @ M.T + sp.eye(n) * 2.0).tocsc()
    F = rng.normal(size=(n, 2))
    S, r = schur_complement(K, n - nb, F)
    Kd = K.toarray()
    Kii, Kib, Kbb = Kd[:-nb, :-nb], Kd[:-nb, -nb:], Kd[-nb:, -nb:]
    assert np.allclose(S, Kbb - Kib.T @ np.linalg.solve(Kii, Kib))
    assert np.allclose(r, Kib.T @ np.linalg.solve(Kii, F[:-nb]) - F[-nb:])
