"""Damaged or misdeclared FE exports are refused for what they are (issue 34).

Each file of the corpus is one of the shipped exports (tests/data/fe_exports, the two-node
example with retained nodes 21, 22) cut short, missing its labelling file, complex, holding
one triangle where its header declares a full matrix, or not a regular file at all. Every
one must end as one line naming the file and the real problem, exit code 2, no traceback,
no NumPy warning and nothing written: through the Python API, ``slipcycle run`` of a case
naming the file, and ``slipcycle reduce``.
"""

from __future__ import annotations

import json
import os
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slipcycle.io.matrices import StiffnessError, read_reduced_stiffness

DATA = Path(__file__).resolve().parent / "data" / "fe_exports"
EXAMPLE = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples" / \
    "discrete_two_node.toml"
KWARGS = json.loads((DATA / "README.json").read_text())["files"]


def _lines(name: str) -> list[str]:
    return (DATA / name).read_text().splitlines(keepends=True)


def _abaqus(d: Path, keep) -> tuple[Path, str]:
    path = d / "example_STIF2.mtx"
    path.write_text("".join(keep(_lines("example_STIF2.mtx"))))
    return path, "example_STIF2.mtx"


def _dmig(d: Path, keep) -> tuple[Path, str]:
    path = d / "example.pch"
    path.write_text("".join(keep(_lines("example.pch"))))
    return path, "example.pch"


def _sti_without_dof(d: Path):
    shutil.copy(DATA / "example.sti", d / "example.sti")
    return d / "example.sti", "example.sti"


def _hb_without_mapping(d: Path):
    shutil.copy(DATA / "example.matrix", d / "example.matrix")
    return d / "example.matrix", "example.matrix"


def _hb_rua_triangle(d: Path):
    lines = _lines("example.matrix")
    lines[2] = "RUA" + lines[2][3:]                 # the same lower triangle, declared full
    (d / "example.matrix").write_text("".join(lines))
    shutil.copy(DATA / "example.mapping", d / "example.mapping")
    return d / "example.matrix", "example.matrix"


def _dmig_ifo1_triangle(d: Path):
    def square(lines):
        h = lines[1]                                # DMIG* KAAX 0 6 2: IFO 6 -> 1 (square)
        lines[1] = h[:40] + h[40:56].replace("6", "1") + h[56:]
        return lines
    return _dmig(d, square)


def _complex_matrix_market(d: Path):
    path = d / "k.mtx"
    path.write_text("%%MatrixMarket matrix coordinate complex symmetric\n4 4 4\n"
                    + "".join(f"{i} {i} 2.0 0.5\n" for i in range(1, 5)))
    return path, "k.mtx"


def _fifo(d: Path):
    path = d / "k.mtx"
    os.mkfifo(path)
    return path, "k.mtx"


def _ten_gigabytes(d: Path):
    path = d / "example_STIF2.mtx"
    with open(path, "wb") as fh:                    # sparse: no disk used
        fh.truncate(10 * 1024 ** 3)
    return path, "example_STIF2.mtx"


def _is_row(node_dof: str):
    return lambda ln: ln.startswith(node_dof)


#: id -> (writer(d) -> (path, README entry), words the one line must hold)
CORPUS = {
    "abaqus_cut_inside_a_row": (lambda d: _abaqus(d, lambda ls: ls[:-1]),
                                ["no diagonal entry", "node 22 dof 2", "truncated"]),
    "abaqus_cut_at_a_row_end": (
        lambda d: _abaqus(d, lambda ls: [ln for ln in ls if not _is_row("22,2,")(ln)]),
        ["last node 22 has dof(s) 1 only", "truncated"]),
    "abaqus_cut_inside_a_line": (
        lambda d: _abaqus(d, lambda ls: ls[:-1] + ["22,2, 22,"]),
        ["3 fields where the other lines have 5", "truncated"]),
    "sti_without_its_dof_file": (_sti_without_dof, ["example.dof is missing"]),
    "hbmat_without_its_mapping": (_hb_without_mapping, ["example.mapping is missing"]),
    "dmig_cut_inside_a_column": (lambda d: _dmig(d, lambda ls: ls[:-1]),
                                 ["no diagonal entry", "node 22 dof 2", "truncated"]),
    "dmig_cut_at_a_column_end": (lambda d: _dmig(d, lambda ls: ls[:-9]),
                                 ["last node 22 has dof(s) 1 only", "truncated"]),
    "dmig_cut_inside_a_card": (lambda d: _dmig(d, lambda ls: ls[:-1] + [ls[-1][:20]]),
                               ["truncated"]),
    "complex_matrix_market": (_complex_matrix_market, ["complex", "a stiffness is real"]),
    "hb_declared_rua_holding_a_triangle": (_hb_rua_triangle,
                                           ["declared RUA", "one triangle only"]),
    "dmig_ifo_1_holding_a_triangle": (_dmig_ifo1_triangle,
                                      ["declared IFO = 1", "one triangle only"]),
    "a_fifo": (_fifo, ["FIFO"]),
    "a_10_gb_file": (_ten_gigabytes, ["10.7 GB", "larger than"]),
}


def _kwargs(entry: str) -> dict:
    kw = dict(KWARGS.get(entry, {"frames": {"normal": [0, -1]}}))
    kw.pop("format", None) if entry != "example.matrix" else None
    return kw


@pytest.mark.parametrize("case", sorted(CORPUS))
def test_python_api_refuses_in_one_line_naming_the_file_without_warnings(case, tmp_path):
    write, words = CORPUS[case]
    path, entry = write(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")              # no NumPy ComplexWarning or the like
        with pytest.raises(StiffnessError) as err:
            read_reduced_stiffness(path, tangential_dims=1, **_kwargs(entry))
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith((path.name, str(path))), msg
    for w in words:
        assert w in msg, msg


def test_dev_zero_is_refused_before_it_is_read():
    with pytest.raises(StiffnessError, match=r"^/dev/zero: is a character device"):
        read_reduced_stiffness("/dev/zero", format="matrix-market")


def _case_lines(path: Path, entry: str) -> str:
    kw = _kwargs(entry)
    lines = [f'stiffness_file = "{path}"', "stiffness.normal = [0, -1]"]
    if "retained" in kw:
        lines.append(f"stiffness.retained = {kw['retained']}")
    if entry == "example.matrix":
        lines.append('stiffness.format = "harwell-boeing"')
    return "\n".join(lines) + "\n"


def _one_line(code, out, err, *words) -> str:
    assert code == 2, (out, err)
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert not out.strip(), out                     # nothing else on the terminal
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


@pytest.mark.parametrize("case", sorted(CORPUS) + ["dev_zero"])
def test_run_of_a_case_naming_the_file_exits_2_in_one_line_writing_nothing(case, run_cli,
                                                                           tmp_path):
    files = tmp_path / "files"
    files.mkdir()
    if case == "dev_zero":
        path, entry, words = Path("/dev/zero"), "", ["character device"]
    else:
        write, words = CORPUS[case]
        path, entry = write(files)
    text = EXAMPLE.read_text()
    text = text[:text.index("A = [[")] + _case_lines(path, entry) + text[text.index("friction"):]
    case_file = tmp_path / "case.toml"
    case_file.write_text(text)
    before = sorted(p.name for p in tmp_path.rglob("*"))
    code, out, err = run_cli("run", case_file, "--out", tmp_path / "out")
    line = _one_line(code, out, err, "discrete.stiffness_file", *words)
    assert path.name in line
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


#: files ``slipcycle reduce FILE`` takes without a case (Abaqus, Matrix Market, any path)
REDUCE = [c for c in sorted(CORPUS) if c.startswith(("abaqus", "complex", "a_"))]


@pytest.mark.parametrize("case", REDUCE)
def test_reduce_of_the_file_exits_2_in_one_line_writing_nothing(case, run_cli, tmp_path):
    files = tmp_path / "files"
    files.mkdir()
    write, words = CORPUS[case]
    path, _ = write(files)
    out = tmp_path / "reduced.npz"
    code, stdout, err = run_cli("reduce", path, "--out", out)
    line = _one_line(code, stdout, err, *words)
    assert path.name in line
    assert not out.exists()


def test_a_condensation_that_is_not_the_schur_complement_is_caught(monkeypatch):
    """The reduction of a full K is checked against the equilibrium of K itself: a
    condensation engine that returned the uncondensed block K_bb (what CalculiX's
    substructure export holds) is refused in one line."""
    from slipcycle.io.fe_formats import dofmap

    def uncondensed(K, ni, F=None, block=128):
        Kd = K.toarray()
        R = np.zeros((K.shape[0] - ni, 0 if F is None else F.shape[1]))
        return Kd[ni:, ni:], R

    kw = _kwargs("example.sti")
    ok = read_reduced_stiffness(DATA / "example.sti", tangential_dims=1, **kw)
    monkeypatch.setattr(dofmap, "schur_complement", uncondensed)
    with pytest.raises(StiffnessError) as err:
        read_reduced_stiffness(DATA / "example.sti", tangential_dims=1, **kw)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("example.sti")
    assert "not its Schur complement" in msg
    assert ok.C.shape == (2, 2)


TEXT_EXPORTS = ["example_STIF2.mtx", "example.sti", "example.matrix", "example.pch",
                "example_abaqus_substructure.mtx", "example_calculix_substructure.mtx",
                "example_xyz.mtx"]


@pytest.mark.parametrize("name", TEXT_EXPORTS)
@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(where=st.floats(0.0, 1.0))
def test_an_export_cut_anywhere_is_refused_or_reads_the_same(name, where, tmp_path):
    """Cut at any byte, a shipped export is refused in one line naming the file (or the
    node a cut removed), never with another exception, a warning or a crash (SciPy's own
    Matrix Market reader dies on ``3.66E``); it is read only when cut inside its last
    line, where a number cut short cannot be told from a shorter number."""
    data = (DATA / name).read_bytes()
    kw = dict(KWARGS[name])
    if "dof_map" in kw:
        kw["dof_map"] = DATA / kw["dof_map"]
    full = read_reduced_stiffness(DATA / name, tangential_dims=1, **kw)
    d = tmp_path / f"cut{abs(hash(where))}"
    d.mkdir(exist_ok=True)
    for side in (".dof", ".mapping"):
        if (DATA / name).with_suffix(side).exists():
            shutil.copy((DATA / name).with_suffix(side), (d / name).with_suffix(side))
    cut = int(where * (len(data) - 1))
    (d / name).write_bytes(data[:cut])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            red = read_reduced_stiffness(d / name, tangential_dims=1, **kw)
    except StiffnessError as exc:
        msg = str(exc)
        assert "\n" not in msg and name in msg, msg
        return
    assert b"\n" not in data[cut:].rstrip(b"\r\n"), "a cut before the last line was read"
    assert red.C.shape == full.C.shape


@pytest.mark.parametrize(("name", "code"), [("job.sti", "calculix"), ("k.hbmat", "harwell-boeing"),
                                            ("k.mat", "matlab"), ("k.pch", "nastran-dmig")])
def test_reduce_of_a_bare_export_names_the_route_that_takes_it(run_cli, tmp_path, name, code):
    """``slipcycle reduce`` imports bare ``.mtx``/``.npz`` files only: another code's export
    given bare is refused in one line naming the model-file route (it used to be read as a
    TOML model and blamed on its syntax), and nothing is written."""
    export = tmp_path / name
    export.write_text("1 1 1.0\n")
    code_, out, err = run_cli("reduce", export, "--out", tmp_path / "red.npz")
    assert code_ == 2
    assert len(err.strip().splitlines()) == 1
    assert code in err and 'model = "fe_import"' in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_an_unknown_export_format_names_the_case_files_format_key(tmp_path):
    from slipcycle.io.fe_formats import StiffnessError, detect_format

    path = tmp_path / "k.xyz"
    path.write_text("no header here\n")
    with pytest.raises(StiffnessError, match="stiffness table's `format` key"):
        detect_format(path)
