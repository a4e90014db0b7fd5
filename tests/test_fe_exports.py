"""Reduced stiffness from the exports of FE codes (Abaqus, CalculiX, ANSYS HBMAT, MATLAB,
Nastran DMIG, Matrix Market, npz): each file, written in its code's layout by the writers
of ``fe_export_writers``, gives the contact blocks A, B, C of the Schur complement of its
K computed here independently (static condensation, Guyan 1965), rotated into the node
frames; loads give the reactions with the contact held; the frame rule, permutations of
the rows and rotations of the global frame leave A, B, C unchanged; every refusal is one
line with exit code 2; the example 2-D discrete case runs identically from every format.
"""

from __future__ import annotations

import json
from pathlib import Path

import fe_export_writers as W
import numpy as np
import pytest
import scipy.io as sio
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import slipcycle
from slipcycle.fe.contact import tangent_of
from slipcycle.fe.model import build_problem
from slipcycle.fe.reduction import reduce_problem
from slipcycle.io import parse_case_text, read_case
from slipcycle.io.fe_formats import matlab
from slipcycle.io.fe_formats.dofmap import node_frames
from slipcycle.io.matrices import (
    ReducedStiffness,
    StiffnessError,
    read_reduced_stiffness,
    read_stiffness,
)

DATA = Path(__file__).resolve().parent / "data" / "fe_exports"
EXAMPLE = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples" / \
    "discrete_two_node.toml"
CONTACT = [11, 12, 13]
RETAINED = [21, 22]


# -- the reference: a labelled SPD K and its condensed, rotated blocks ---------------------
def labelled_model(seed: int, t: int, integer: bool = False):
    """SPD K over contact nodes 11-13 and retained nodes 21-22, t+1 translations each."""
    rng = np.random.default_rng(seed)
    labels = [(a, k) for a in CONTACT + RETAINED for k in range(1, t + 2)]
    n = len(labels)
    if integer:
        M = rng.integers(-9, 10, size=(n, n)).astype(float)
        K = M @ M.T + 40.0 * np.eye(n)
    else:
        M = rng.normal(size=(n, n))
        K = (M @ M.T + n * np.eye(n)) * 1e6
    return K, labels


def default_axes(t: int, normal) -> np.ndarray:
    """Rows (t1, [t2,] e) of a node frame, e = −n the separation direction, by the rule of
    the docs: 2-D t1 = (e_y, −e_x); 3-D t1 = x projected (y when |e_x| > 0.9), t2 = e × t1."""
    e = -np.asarray(normal, float) / np.linalg.norm(normal)
    if t == 1:
        return np.array([[e[1], -e[0]], [e[0], e[1]]])
    a = np.array([0.0, 1.0, 0.0]) if abs(e[0]) > 0.9 else np.array([1.0, 0.0, 0.0])
    t1 = a - (a @ e) * e
    t1 /= np.linalg.norm(t1)
    return np.array([t1, np.cross(e, t1), e])


def reference(K, labels, contact, axes, loads=None):
    """A, B, C (and q^w, p^w) by explicit Schur complement and rotation."""
    c = [i for i, (a, _) in enumerate(labels) if a in contact]
    r = [i for i, (a, _) in enumerate(labels) if a not in contact]
    Kcc, Kcr, Krr = K[np.ix_(c, c)], K[np.ix_(c, r)], K[np.ix_(r, r)]
    S = Kcc - Kcr @ np.linalg.solve(Krr, Kcr.T)
    d = axes.shape[0]
    N = len(contact)
    R = np.kron(np.eye(N), axes)                    # local = R global, node-major
    Kl = R @ S @ R.T
    t = d - 1
    tang = [j * d + k for j in range(N) for k in range(t)]
    norm = [j * d + t for j in range(N)]
    out = {"A": Kl[np.ix_(tang, tang)], "B": Kl[np.ix_(norm, tang)],
           "C": Kl[np.ix_(norm, norm)]}
    if loads is not None:
        f = np.asarray(loads, float)
        rw = R @ (Kcr @ np.linalg.solve(Krr, f[r]) - f[c])
        out["q"], out["p"] = rw[tang], rw[norm]
    return out


def assert_blocks(rs, ref, rtol=1e-11):
    for k in ("A", "B", "C"):
        scale = np.abs(ref[k]).max() + np.abs(ref["A"]).max()
        np.testing.assert_allclose(getattr(rs, k), ref[k], rtol=0, atol=rtol * scale,
                                   err_msg=k)


NORMAL = {1: [0.0, -1.0], 2: [0.0, 0.0, -1.0]}


# -- one writer per layout: (path, keyword arguments of read_reduced_stiffness) -------------
def _abaqus_mi(tmp, K, lab, f, contact, retained):
    return W.abaqus_matrix_input(tmp / "job_STIF2.mtx", K, lab, f), {"retained": retained}


def _abaqus_coord(tmp, K, lab, f, contact, retained):
    p = W.abaqus_coordinate(tmp / "job_STIF2.mtx", K)
    roles = {1: "x", 2: "y", 3: "z"}
    (tmp / "map.csv").write_text("".join(
        f"{a},{d},{roles[d] if a in contact else 'retained'}\n" for a, d in lab))
    return p, {"dof_map": tmp / "map.csv", "format": "abaqus"}


def _abaqus_ue(tmp, K, lab, f, contact, retained):
    return W.abaqus_user_element(tmp / "sub.mtx", K, lab), {"contact_nodes": contact}


def _ccx_ue(tmp, K, lab, f, contact, retained):
    return W.calculix_user_element(tmp / "substruc.mtx", K, lab), {"retained": retained}


def _ccx_sti(tmp, K, lab, f, contact, retained):
    return W.calculix_matrix_storage(tmp / "job.sti", K, lab), {"contact_nodes": contact}


def _hb(tmp, K, lab, f, contact, retained):
    return W.harwell_boeing(tmp / "stiff.matrix", K, lab, f), {"retained": retained,
                                                                "format": "harwell-boeing"}


def _mat5(tmp, K, lab, f, contact, retained):
    return W.matlab_v5(tmp / "rom.mat", K, lab, f), {"retained": retained,
                                                     "keys": {"loads": "Fv"}}


def _mat73(tmp, K, lab, f, contact, retained):
    return W.matlab_v73(tmp / "rom73.mat", K, lab, f), {"retained": retained,
                                                        "keys": {"loads": "Fv"}}


def _dmig(tmp, K, lab, f, contact, retained):
    coords = {a: (0.1 * a, 0.0, 0.0) for a in contact + retained}
    return (W.nastran_dmig_punch(tmp / "model.pch", K, lab, f, coords),
            {"retained": retained})


def _mm(tmp, K, lab, f, contact, retained):
    p = W.matrix_market(tmp / "k.mtx", K, lab)
    return p, {"dof_map": p.with_suffix(".csv"), "retained": retained}


def _npz(tmp, K, lab, f, contact, retained):
    np.savez(tmp / "k.npz", K=K, dof_labels=np.array(lab))
    return tmp / "k.npz", {"retained": retained}


WRITERS = {"abaqus-matrix-input": _abaqus_mi, "abaqus-coordinate": _abaqus_coord,
           "abaqus-user-element": _abaqus_ue, "calculix-user-element": _ccx_ue,
           "calculix-matrixstorage": _ccx_sti, "ansys-hbmat": _hb, "matlab-v5": _mat5,
           "matlab-v7.3": _mat73, "nastran-dmig-punch": _dmig, "matrix-market-csv": _mm,
           "npz-labelled": _npz}
#: digits a layout keeps: DMIG large field 10, HB E20.12 12, CalculiX E20.13 13
PRECISION = {"nastran-dmig-punch": 1e-8, "ansys-hbmat": 1e-10, "calculix-user-element": 1e-11}
WITH_LOADS = {"abaqus-matrix-input": "LOAD", "ansys-hbmat": "RHS", "matlab-v5": "Fv",
              "matlab-v7.3": "Fv", "nastran-dmig-punch": "PAX_1"}


@pytest.mark.parametrize("t", [1, 2], ids=["2-D", "3-D"])
@pytest.mark.parametrize("fmt", list(WRITERS))
def test_export_gives_the_schur_complement_rotated_into_the_node_frames(fmt, t, tmp_path):
    K, lab = labelled_model(7 + t, t)
    f = np.random.default_rng(3).normal(size=len(lab)) * 1e3
    path, kw = WRITERS[fmt](tmp_path, K, lab, f, CONTACT, RETAINED)
    rs = read_reduced_stiffness(path, tangential_dims=t, frames={"normal": NORMAL[t]}, **kw)
    ref = reference(K, lab, CONTACT, default_axes(t, NORMAL[t]), f)
    assert rs.tangential_dims == t and list(rs.nodes) == CONTACT
    tol = PRECISION.get(fmt, 1e-11)
    assert_blocks(rs, ref, tol)
    if fmt in WITH_LOADS:
        case = rs.loads[WITH_LOADS[fmt]]
        np.testing.assert_allclose(case["q"], ref["q"], atol=100 * tol * np.abs(f).max())
        np.testing.assert_allclose(case["p"], ref["p"], atol=100 * tol * np.abs(f).max())
    if fmt == "nastran-dmig-punch":                  # GRID coordinates come along
        np.testing.assert_allclose(rs.coordinates[:, 0], 0.1 * np.array(CONTACT))


def test_nastran_small_field_bulk_deck_is_read_exactly(tmp_path):
    K, lab = labelled_model(5, 2, integer=True)
    path = W.nastran_dmig_bulk(tmp_path / "model.bdf", K, lab)
    rs = read_reduced_stiffness(path, frames={"normal": NORMAL[2]}, retained=RETAINED)
    assert_blocks(rs, reference(K, lab, CONTACT, default_axes(2, NORMAL[2])), rtol=1e-13)


def test_unlabelled_orderings_match_the_original_reader(tmp_path):
    """.npz / .mtx through the new reader give what read_stiffness always gave."""
    rng = np.random.default_rng(1)
    M = rng.normal(size=(6, 6))
    K = M @ M.T + 6 * np.eye(6)
    W.matrix_market(tmp_path / "k.mtx", K)
    for order in ("tangential_first", "interleaved"):
        old = read_stiffness(tmp_path / "k.mtx", order)
        new = read_reduced_stiffness(tmp_path / "k.mtx", dof_map=order)
        for k in "ABC":
            np.testing.assert_allclose(getattr(new, k), old[k], rtol=1e-14, atol=1e-14)


# -- frames -------------------------------------------------------------------------------------
def _rotation(rng, t):
    if t == 1:
        a = rng.uniform(0, 2 * np.pi)
        return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


@pytest.mark.parametrize("t", [1, 2], ids=["2-D", "3-D"])
def test_a_rotated_global_frame_gives_the_same_local_blocks(t, tmp_path):
    K, lab = labelled_model(11, t)
    rng = np.random.default_rng(4)
    base = read_reduced_stiffness(W.abaqus_matrix_input(tmp_path / "a_STIF1.mtx", K, lab),
                                  frames={"normal": NORMAL[t]}, retained=RETAINED)
    for _ in range(3):
        Q = _rotation(rng, t)
        Kr = np.kron(np.eye(len(lab) // (t + 1)), Q) @ K @ np.kron(np.eye(len(lab) // (t + 1)),
                                                                    Q).T
        frames = {"normal": Q @ np.asarray(NORMAL[t]),
                  "t1": Q @ default_axes(t, NORMAL[t])[0]}
        rot = read_reduced_stiffness(W.abaqus_matrix_input(tmp_path / "b_STIF1.mtx", Kr, lab),
                                     frames=frames, retained=RETAINED)
        for k in "ABC":
            np.testing.assert_allclose(getattr(rot, k), getattr(base, k), rtol=0,
                                       atol=1e-9 * np.abs(base.A).max())
        np.testing.assert_allclose(rot.normals[0], frames["normal"] / np.linalg.norm(
            frames["normal"]) if t == 2 else np.append(frames["normal"], 0), atol=1e-14)


@given(st.floats(0, 2 * np.pi))
@settings(max_examples=50, deadline=None)
def test_2d_tangent_rule_is_that_of_the_plane_strain_fe_models(angle):
    """t1 = (e_y, −e_x) with e = −n, exactly slipcycle.fe.contact.tangent_of(e)."""
    n = np.array([np.cos(angle), np.sin(angle)])
    normals, tangents = node_frames({"normal": n}, 1, 1)
    np.testing.assert_allclose(tangents[0, 0, :2], tangent_of(-n), atol=1e-15)
    assert tangents[0, 0, 2] == 0 and np.allclose(normals[0, :2], n)


@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(
    lambda v: np.linalg.norm(v) > 1e-3))
@settings(max_examples=100, deadline=None)
def test_3d_frames_are_orthonormal_right_handed_and_follow_the_rule(v):
    normals, tangents = node_frames({"normal": v}, 1, 2)
    e = -normals[0]
    F = np.array([tangents[0, 0], tangents[0, 1], e])
    np.testing.assert_allclose(F @ F.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(F) == pytest.approx(1.0)
    np.testing.assert_allclose(F, default_axes(2, v), atol=1e-12)


def test_a_block_on_a_flat_below_has_t1_x_t2_y():
    normals, tangents = node_frames({"normal": [0, 0, -1]}, 2, 2)
    np.testing.assert_allclose(tangents[1], [[1, 0, 0], [0, 1, 0]], atol=0)
    _, t2d = node_frames({"normal": [0, -1]}, 1, 1)
    np.testing.assert_allclose(t2d[0, 0], [1, 0, 0], atol=0)


# -- the order of the rows does not matter ----------------------------------------------------
@given(seed=st.integers(0, 2**31 - 1), t=st.sampled_from([1, 2]),
       n_contact=st.integers(1, 3), n_retained=st.integers(0, 2),
       scale=st.floats(1e-3, 1e9))
@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_permuting_the_dof_listing_leaves_a_b_c_unchanged(tmp_path, seed, t, n_contact,
                                                          n_retained, scale):
    rng = np.random.default_rng(seed)
    contact = sorted(rng.choice(np.arange(1, 50), n_contact, replace=False).tolist())
    retained = [100 + k for k in range(n_retained)]
    lab = [(a, k) for a in contact + retained for k in range(1, t + 2)]
    n = len(lab)
    M = rng.normal(size=(n, n))
    K = (M @ M.T + 0.1 * n * np.eye(n)) * scale
    perm = rng.permutation(n)
    Kp, labp = K[np.ix_(perm, perm)], [lab[i] for i in perm]
    frames = {"normal": NORMAL[t]}
    ref = reference(K, lab, contact, default_axes(t, NORMAL[t]))
    kw = {"retained": retained} if retained else {}
    a = read_reduced_stiffness(W.abaqus_matrix_input(tmp_path / "p_STIF1.mtx", Kp, labp),
                               frames=frames, **kw)
    W.matrix_market(tmp_path / "p.mtx", Kp, labp)
    b = read_reduced_stiffness(tmp_path / "p.mtx", dof_map=tmp_path / "p.csv",
                               frames=frames, **kw)
    for rs in (a, b):
        assert list(rs.nodes) == contact
        assert_blocks(rs, ref, rtol=1e-9)


# -- refusals ----------------------------------------------------------------------------------
def _case(tmp_path, stiffness_lines: str) -> Path:
    text = EXAMPLE.read_text()
    i = text.index("A = [[")
    j = text.index("friction")
    text = text[:i] + stiffness_lines + "\n" + text[j:]
    path = tmp_path / "case.toml"
    path.write_text(text)
    return path


def _one_line(code, err, *words):
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


def test_refusals_are_one_line_with_exit_code_2(run_cli, tmp_path):
    out = tmp_path / "out"
    # a dof map shorter than K: 9 dofs, 2 nodes × 3 dofs listed
    rng = np.random.default_rng(0)
    M = rng.normal(size=(9, 9))
    W.matrix_market(tmp_path / "k9.mtx", M @ M.T + 9 * np.eye(9))
    (tmp_path / "map.csv").write_text("0,1,x\n0,2,y\n0,3,z\n1,1,x\n1,2,y\n1,3,z\n")
    case = _case(tmp_path, 'stiffness_file = "k9.mtx"\nstiffness.dof_map = "map.csv"\n'
                 'stiffness.normal = [0, -1]')
    _one_line(*run_cli("run", case, "--out", out)[:3:2],
              "discrete.stiffness_file", "K has 9 dofs but the map lists 2 nodes × 3 dofs = 6")
    # a 3-D matrix (x, y, z per node) offered to the 2-D case
    K, lab = labelled_model(2, 2)
    W.abaqus_matrix_input(tmp_path / "k3_STIF1.mtx", K, lab)
    case = _case(tmp_path, 'stiffness_file = "k3_STIF1.mtx"\n'
                 "stiffness.retained = [21, 22]\nstiffness.normal = [0, -1]")
    _one_line(*run_cli("run", case, "--out", out)[:3:2], "discrete.stiffness_file",
              "3 dofs each", "not reinterpreted")
    # an unlabelled 3-D matrix that says so
    (tmp_path / "k3.mtx").write_text("%%MatrixMarket matrix coordinate real symmetric\n"
                                     "% tangential_dims: 2\n6 6 6\n" + "".join(
                                         f"{i} {i} 1.0\n" for i in range(1, 7)))
    case = _case(tmp_path, 'stiffness_file = "k3.mtx"')
    _one_line(*run_cli("run", case, "--out", out)[:3:2], "tangential_dims = 2",
              "not reinterpreted")
    # not positive definite after condensation
    K, lab = labelled_model(3, 1)
    K[0, 0] = -K[0, 0]
    W.abaqus_matrix_input(tmp_path / "neg_STIF1.mtx", K, lab)
    case = _case(tmp_path, 'stiffness_file = "neg_STIF1.mtx"\n'
                 "stiffness.contact_nodes = [11, 12]\nstiffness.normal = [0, -1]")
    _one_line(*run_cli("run", case, "--out", out)[:3:2], "not positive definite")
    # non-symmetric: both triangles written, and they differ
    K, lab = labelled_model(3, 1)
    K[1, 0] *= 1.5
    (tmp_path / "asym_STIF1.mtx").write_text("".join(
        f"{lab[i][0]},{lab[i][1]}, {lab[j][0]},{lab[j][1]}, {float(K[i, j])!r}\n"
        for i in range(len(lab)) for j in range(len(lab))))
    case = _case(tmp_path, 'stiffness_file = "asym_STIF1.mtx"\n'
                 "stiffness.retained = [13, 21, 22]\nstiffness.normal = [0, -1]")
    _one_line(*run_cli("run", case, "--out", out)[:3:2], "not symmetric")
    # NaN
    np.savez(tmp_path / "nan.npz", K=np.full((4, 4), np.nan))
    case = _case(tmp_path, 'stiffness_file = "nan.npz"')
    _one_line(*run_cli("run", case, "--out", out)[:3:2], "finite")
    # unreadable .mat, and a .mat without the variable
    (tmp_path / "junk.mat").write_bytes(b"MATLAB 5.0 MAT-file" + b"\x01" * 40)
    case = _case(tmp_path, 'stiffness_file = "junk.mat"')
    _one_line(*run_cli("run", case, "--out", out)[:3:2], "junk.mat", "MATLAB")
    W.matlab_v5(tmp_path / "rom.mat", np.eye(4), name="Kred")
    case = _case(tmp_path, 'stiffness_file = "rom.mat"')
    _one_line(*run_cli("run", case, "--out", out)[:3:2], "variables: Kred",
              "keys = {K")
    # an unknown role in the dof map names the key
    (tmp_path / "bad.csv").write_text("0,1,tangent\n")
    case = _case(tmp_path, 'stiffness_file = "k9.mtx"\nstiffness.dof_map = "bad.csv"')
    _one_line(*run_cli("run", case, "--out", out)[:3:2], "discrete.stiffness.dof_map",
              "unknown role 'tangent'")


def test_a_matrix_export_given_as_the_case_file_is_named_for_what_it_is(run_cli, tmp_path):
    K, lab = labelled_model(0, 1)
    files = {"harwell-boeing": W.harwell_boeing(tmp_path / "k.hb", K),
             "Nastran DMIG": W.nastran_dmig_punch(tmp_path / "k.pch", K, lab),
             "Abaqus": W.abaqus_matrix_input(tmp_path / "k_STIF1.mtx", K, lab),
             "Matrix Market": W.matrix_market(tmp_path / "m.mtx", K),
             "MATLAB": W.matlab_v5(tmp_path / "k.mat", K)}
    for word, path in files.items():
        code, _, err = run_cli("run", path, "--out", tmp_path / "o")
        line = _one_line(code, err, "not a")
        assert word.lower() in line.lower() and "TOML" not in line.split("not a")[0], line


# -- end to end: the example case from every format ----------------------------------------------
def _example_export():
    """The example's A, B, C as a labelled 2-D K (nodes 1, 2, normal (0, −1): t1 = x,
    separation +y) with two retained nodes (21, 22) condensing exactly onto it."""
    ex = parse_case_text(EXAMPLE.read_text()).data["discrete"]
    A, B, C = (np.array(ex[k], float) for k in "ABC")
    Kc = np.zeros((4, 4))
    Kc[0::2, 0::2], Kc[1::2, 1::2], Kc[1::2, 0::2], Kc[0::2, 1::2] = A, C, B, B.T
    rng = np.random.default_rng(42)
    Mr = rng.normal(size=(4, 4))
    Krr = Mr @ Mr.T + 4 * np.eye(4)
    Krc = rng.normal(size=(4, 4))
    K = np.block([[Kc + Krc.T @ np.linalg.solve(Krr, Krc), Krc.T], [Krc, Krr]])
    lab = [(1, 1), (1, 2), (2, 1), (2, 2), (21, 1), (21, 2), (22, 1), (22, 2)]
    return 0.5 * (K + K.T), lab


E2E = ("abaqus-matrix-input", "abaqus-coordinate", "calculix-user-element", "ansys-hbmat",
       "matlab-v5", "matlab-v7.3", "nastran-dmig-punch", "matrix-market-csv")


def _case_lines(path: Path, kw: dict) -> str:
    lines = [f'stiffness_file = "{path.name}"', "stiffness.normal = [0, -1]"]
    for k, v in kw.items():
        if k in ("retained", "contact_nodes"):
            lines.append(f"stiffness.{k} = {list(v)}")
        elif k == "dof_map":
            lines.append(f'stiffness.dof_map = "{Path(v).name}"')
        elif k == "format":
            lines.append(f'stiffness.format = "{v}"')
    return "\n".join(lines)


def test_example_case_runs_identically_from_every_export(tmp_path):
    base = slipcycle.run(EXAMPLE)
    K, lab = _example_export()
    for fmt in E2E:
        d = tmp_path / fmt
        d.mkdir()
        path, kw = WRITERS[fmt](d, K, lab, None, [1, 2], [21, 22])
        res = slipcycle.run(_case(d, _case_lines(path, kw)))
        assert res.steady_state == base.steady_state, fmt
        assert res.cycles_run == base.cycles_run, fmt
        assert res.dissipation_per_cycle == pytest.approx(base.dissipation_per_cycle,
                                                          rel=1e-9), fmt


# -- the files shipped in tests/data/fe_exports ---------------------------------------------------
def test_shipped_example_exports_read_to_the_example_blocks():
    """Each file of tests/data/fe_exports (the example's model with two retained nodes, in
    each code's layout; see README.json there) reads to the example's A, B, C."""
    ex = parse_case_text(EXAMPLE.read_text()).data["discrete"]
    index = json.loads((DATA / "README.json").read_text())
    assert len(index["files"]) >= 8
    for name, kw in index["files"].items():
        if "dof_map" in kw:
            kw = {**kw, "dof_map": DATA / kw["dof_map"]}
        rs = read_reduced_stiffness(DATA / name, tangential_dims=1, **kw)
        for k in "ABC":
            np.testing.assert_allclose(getattr(rs, k), np.array(ex[k]), atol=1e-12,
                                       err_msg=f"{name}: {k}")


def write_shipped_exports(directory: Path = DATA) -> None:
    """(Re)write tests/data/fe_exports from the example case (run by hand)."""
    K, lab = _example_export()
    directory.mkdir(parents=True, exist_ok=True)
    ret = {"retained": [21, 22], "frames": {"normal": [0, -1]}}
    writers = {"example_STIF2.mtx": W.abaqus_matrix_input,
               "example_abaqus_substructure.mtx": W.abaqus_user_element,
               "example_calculix_substructure.mtx": W.calculix_user_element,
               "example.sti": W.calculix_matrix_storage, "example.matrix": W.harwell_boeing,
               "example_v5.mat": W.matlab_v5, "example_v73.mat": W.matlab_v73,
               "example.pch": W.nastran_dmig_punch, "example_xyz.mtx": W.matrix_market}
    files = {}
    for name, write in writers.items():
        write(directory / name, K, lab)
        files[name] = dict(ret)
    files["example.matrix"]["format"] = "harwell-boeing"
    files["example_xyz.mtx"]["dof_map"] = "example_xyz.csv"
    index = {"about": "The 2-node example (src/slipcycle/examples/discrete_two_node.toml) "
                      "as a 2-D FE export: contact nodes 1, 2 (dofs 1, 2 = x, y; outward "
                      "normal (0, -1)), retained nodes 21, 22 (condensed out); written by "
                      "tests/fe_export_writers.py (test_fe_exports.write_shipped_exports). "
                      "Each entry: file -> keyword arguments of read_reduced_stiffness "
                      "(dof_map relative to this directory).",
             "files": files}
    (directory / "README.json").write_text(json.dumps(index, indent=1) + "\n")


def test_reduced_stiffness_is_self_validating():
    with pytest.raises(StiffnessError, match="not positive definite"):
        ReducedStiffness(np.eye(2), np.zeros((2, 2)), -np.eye(2))
    with pytest.raises(StiffnessError, match="expected 4×4"):
        ReducedStiffness(np.eye(2), np.zeros((2, 4)), np.eye(2), tangential_dims=2)


# -- the sign convention is that of slipcycle's own 2-D FE reduction -------------------------------
def test_global_export_of_an_fe_block_matches_slipcycle_reduce(tmp_path):
    """The full K of the steel block on a rigid flat (fe_block_nu03.toml; top face held),
    exported with global x, y labels, read with the block's outward normal (0, −1) and
    condensed onto its bottom nodes, equals slipcycle's own reduction (fe.reduction, the
    2-D convention: v along t, w along the inward normal, p compressive) node by node."""
    case = read_case(EXAMPLE.parent / "fe_block_nu03.toml", models=["fe"])
    problem = build_problem(case)
    reduced = reduce_problem(problem)
    body = problem.dofs[problem.contact.body1]
    free = np.setdiff1d(np.arange(problem.ndofs), problem.fixed)
    label = {}
    for node, (ix, iy) in enumerate(zip(body.ux, body.uy, strict=True)):
        label[int(ix)], label[int(iy)] = (node + 1, 1), (node + 1, 2)
    K = problem.K.toarray()[np.ix_(free, free)]
    lab = [label[int(i)] for i in free]
    path = W.abaqus_matrix_input(tmp_path / "block_STIF1.mtx", K, lab)
    contact = problem.contact.nodes1 + 1
    rs = read_reduced_stiffness(path, tangential_dims=1, frames={"normal": [0, -1]},
                                contact_nodes=contact)
    order = np.searchsorted(rs.nodes, contact)      # the FE reduction's node order
    for k in "ABC":
        M = getattr(rs, k)[np.ix_(order, order)]
        np.testing.assert_allclose(M, getattr(reduced, k), rtol=0,
                                   atol=1e-9 * np.abs(reduced.A).max(), err_msg=k)


# -- malformed files: one line naming the file ---------------------------------------------------
def _malformed(tmp: Path):
    K, lab = labelled_model(0, 1)
    hb = W.harwell_boeing(tmp / "k.hb", K, lab).read_text().splitlines()
    yield "complex HB", "k1.hb", "\n".join([hb[0], hb[1], "CSA" + hb[2][3:]] + hb[3:]), \
        "only real assembled"
    yield "truncated HB", "k2.hb", "\n".join(hb[:6]), "file truncated"
    yield "HB mapping too short", "k3.hb", "\n".join(hb), "maps"
    ue = W.calculix_user_element(tmp / "u.mtx", K, lab).read_text().splitlines()
    yield "user element short", "u1.mtx", "\n".join(ue[:-1]), "n(n+1)/2"
    yield "abaqus bad field", "a_STIF1.mtx", "1,1, 1,1, 2.0\n1,2, 1,x, 1.0\n", \
        "not an integer"
    yield "abaqus wrong width", "b_STIF1.mtx", "1,1, 1,1, 2.0\n1,2, 1.0\n1,2,3,4\n", \
        "fields"
    yield "sti with short dof file", "c.sti", "1 1 2.0\n2 2 2.0\n", "lists 1 dofs"
    yield "dmig complex", "d.pch", "DMIG    KAAX           0       6       3\n", "DMIG"
    yield "not a matrix at all", "e.xyz", "hello\n", "unknown stiffness file format"


def test_malformed_exports_are_refused_in_one_line_naming_the_file(tmp_path):
    for what, name, text, words in _malformed(tmp_path):
        path = tmp_path / name
        path.write_text(text)
        if name == "k3.hb":
            path.with_suffix(".mapping").write_text("Matrix Eqn Node DOF\n1 11 UX\n")
        if name == "c.sti":
            path.with_suffix(".dof").write_text("1.1\n")
        with pytest.raises(StiffnessError) as info:
            read_reduced_stiffness(path, frames={"normal": [0, -1]})
        msg = str(info.value)
        assert "\n" not in msg and msg.startswith(name), (what, msg)
        assert words in msg, (what, msg)


def test_dmig_grid_in_a_local_displacement_system_is_refused(tmp_path):
    K, lab = labelled_model(1, 2)
    path = W.nastran_dmig_punch(tmp_path / "m.pch", K, lab)
    with open(path, "a") as fh:
        fh.write(f"GRID    {11:8d}{0:8d}{0.0:8.3f}{0.0:8.3f}{0.0:8.3f}{5:8d}\n")
    with pytest.raises(StiffnessError, match="GRID 11 has displacement coordinate system"):
        read_reduced_stiffness(path, frames={"normal": [0, 0, -1]}, retained=RETAINED)


def test_matlab_v73_without_h5py_is_refused_with_the_remedy(tmp_path, monkeypatch):
    path = W.matlab_v73(tmp_path / "r.mat", np.eye(4))
    monkeypatch.setattr(matlab, "_h5py", lambda: None)
    with pytest.raises(StiffnessError, match="h5py is not installed.*-v7"):
        read_reduced_stiffness(path)


@pytest.mark.parametrize("t", [1, 2], ids=["2-D", "3-D"])
def test_rom_with_a_transformation_L_gives_the_physical_schur_complement(t, tmp_path):
    """A model in generalised coordinates q (u = V q, K_q = Vᵀ K V, f_q = Vᵀ f, as a ROM
    stores K, L = V and its load vector) read through L equals the Schur complement of the
    physical K: S = (L_c K_q⁻¹ L_cᵀ)⁻¹ is the static stiffness of the contact dofs."""
    K, lab = labelled_model(21 + t, t)
    f = np.random.default_rng(5).normal(size=len(lab)) * 1e3
    V = np.random.default_rng(6).normal(size=(len(lab), len(lab))) + 3 * np.eye(len(lab))
    sio.savemat(tmp_path / "rom.mat", {"K": V.T @ K @ V, "L": V, "Fv": (V.T @ f)[:, None],
                                       "dof_labels": np.array(lab, float), "M": np.eye(3)})
    rs = read_reduced_stiffness(tmp_path / "rom.mat", frames={"normal": NORMAL[t]},
                                keys={"L": "L", "loads": "Fv"}, retained=RETAINED)
    ref = reference(K, lab, CONTACT, default_axes(t, NORMAL[t]), f)
    assert_blocks(rs, ref, 1e-8)
    np.testing.assert_allclose(rs.loads["Fv"]["p"], ref["p"], atol=1e-7 * np.abs(f).max())
    np.testing.assert_allclose(rs.loads["Fv"]["q"], ref["q"], atol=1e-7 * np.abs(f).max())
