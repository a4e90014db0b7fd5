"""Files a command reads and writes (issue 34 item 1, issue 30 item 7).

No command writes over one of its inputs (directly, through a symbolic or hard link, or by
writing results into the directory that holds it); an empty output path is refused; an
input is checked for kind and size before it is read (a device, a FIFO, an oversized
file); the common output options work before and after the command; ``run`` prints a
short summary.
"""

from __future__ import annotations

import json
import os
import stat

import pytest
from tests.conftest import case_text

from slipcycle.io.case import CaseError
from slipcycle.io.files import check_input_file, check_no_overwrite

SPHERE = case_text("halfspace_sphere", run={"steps_per_cycle": 40})
TWO_NODE = case_text("discrete_two_node")


def _listing(path):
    return sorted(str(p.relative_to(path)) for p in path.rglob("*"))


def _one_line_2(code, err):
    assert code == 2, err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err
    return err


def test_reduce_refuses_to_write_its_case_over_the_model_file(run_cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    model = tmp_path / "model.toml"
    model.write_text(case_text("fe_cylinder"))
    before = model.read_bytes()
    code, _, err = run_cli("reduce", "model.toml", "--out", "red.npz", "--case", "model.toml")
    assert "--case" in _one_line_2(code, err) and "model.toml" in err
    assert model.read_bytes() == before and _listing(tmp_path) == ["model.toml"]


@pytest.mark.parametrize("link", ["symlink", "hardlink"])
def test_an_output_reaching_an_input_through_a_link_is_refused(run_cli, tmp_path, monkeypatch,
                                                               link):
    monkeypatch.chdir(tmp_path)
    model = tmp_path / "model.toml"
    model.write_text(case_text("fe_cylinder"))
    (os.symlink if link == "symlink" else os.link)(model, tmp_path / "alias.toml")
    code, _, err = run_cli("reduce", "model.toml", "--out", "red.npz", "--case", "alias.toml")
    assert "--case" in _one_line_2(code, err)
    assert model.read_text() == case_text("fe_cylinder")
    assert not (tmp_path / "red.npz").exists()


def test_results_are_not_written_into_the_directory_that_holds_the_case(run_cli, tmp_path,
                                                                        monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "case.toml").write_text(SPHERE)
    for out in (".", str(tmp_path), "./"):
        code, _, err = run_cli("run", "case.toml", "--out", out)
        assert "--out" in _one_line_2(code, err) and "case.toml" in err
    assert _listing(tmp_path) == ["case.toml"]


def test_a_file_the_case_names_is_an_input_too(run_cli, tmp_path):
    """The stiffness file named in the case may not sit in the output directory."""
    import numpy as np

    data = tmp_path / "data"
    data.mkdir()
    np.savez(data / "K.npz", A=np.array([[1.0, -0.3], [-0.3, 0.8]]),
             B=np.array([[0.1, 0.0], [0.0, 0.1]]), C=np.array([[1.0, 0.2], [0.2, 1.0]]))
    text = TWO_NODE.replace("[discrete]", '[discrete]\nstiffness_file = "data/K.npz"')
    for key in ("A", "B", "C"):
        text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(f"{key} ="))
    (tmp_path / "case.toml").write_text(text + "\n")
    code, _, err = run_cli("run", tmp_path / "case.toml", "--out", data)
    assert "--out" in _one_line_2(code, err) and "discrete.stiffness_file" in err
    assert _listing(data) == ["K.npz"]


@pytest.mark.parametrize("argv", [("run", "case.toml", "--out", ""),
                                  ("run", "case.toml", "--out="),
                                  ("map", "case.toml", "--out", " "),
                                  ("reduce", "case.toml", "--out", "r.npz", "--case", "")])
def test_an_empty_output_path_is_refused(run_cli, tmp_path, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "case.toml").write_text(SPHERE)
    code, _, err = run_cli(*argv)
    assert "must not be empty" in _one_line_2(code, err)
    assert _listing(tmp_path) == ["case.toml"]


def test_a_fifo_case_file_is_refused_without_reading_it(run_cli, tmp_path):
    fifo = tmp_path / "case.toml"
    os.mkfifo(fifo)                       # opening it for reading would block forever
    code, _, err = run_cli("run", fifo, "--out", tmp_path / "o")
    assert "FIFO" in _one_line_2(code, err) and str(fifo) in err


def test_a_device_named_as_stiffness_file_is_refused_before_it_is_read(run_cli, write_case,
                                                                       tmp_path):
    text = TWO_NODE.replace("[discrete]", '[discrete]\nstiffness_file = "/dev/zero"')
    for key in ("A", "B", "C"):
        text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(f"{key} ="))
    code, _, err = run_cli("run", write_case(text + "\n"), "--out", tmp_path / "o")
    assert "discrete.stiffness_file" in _one_line_2(code, err)
    assert "character device" in err and not (tmp_path / "o").exists()


def test_check_input_file_refuses_each_kind_in_one_line(tmp_path, monkeypatch):
    big = tmp_path / "big.mtx"
    with open(big, "wb") as f:            # sparse: 5 GB on paper, nothing on disk
        f.truncate(5 * 10**9)
    empty = tmp_path / "empty.mtx"
    empty.touch()
    os.mkfifo(tmp_path / "pipe")
    cases = {big: "5 GB, larger than the 4 GB", empty: "empty", tmp_path: "directory",
             tmp_path / "pipe": "FIFO", tmp_path / "none": "not found",
             "/dev/null": "character device"}
    for path, words in cases.items():
        with pytest.raises(CaseError) as info:
            check_input_file(path, "key.file")
        assert str(info.value).startswith("key.file: ") and words in str(info.value)
    monkeypatch.setenv("SLIPCYCLE_MEMORY_LIMIT", "100GB")
    assert check_input_file(big, "key.file") == big      # the budget is the limit
    (tmp_path / "ok.txt").write_text("1")
    assert stat.S_ISREG(os.stat(check_input_file(tmp_path / "ok.txt", "k")).st_mode)


def test_check_no_overwrite_allows_distinct_paths(tmp_path):
    (tmp_path / "in.toml").write_text("x")
    check_no_overwrite([("case", tmp_path / "in.toml")],
                       [("--out", tmp_path / "out", "dir"),
                        ("--case", tmp_path / "in2.toml", "file")])
    with pytest.raises(CaseError, match="--out"):
        check_no_overwrite([("case", tmp_path / "in.toml")], [("--out", tmp_path, "dir")])


def test_a_case_file_with_a_byte_order_mark_is_read(run_cli, tmp_path):
    case = tmp_path / "case.toml"
    case.write_bytes(b"\xef\xbb\xbf" + SPHERE.encode())
    code, _, err = run_cli("run", case, "--out", tmp_path / "o", "-q")
    assert code == 0, err


@pytest.mark.parametrize("before,after", [(("-q",), ()), ((), ("-q",)),
                                          (("--quiet", "--no-progress"), ())])
def test_output_options_work_before_and_after_the_command(run_cli, write_case, tmp_path,
                                                          before, after):
    code, out, err = run_cli(*before, "run", write_case(SPHERE), "--out", tmp_path / "o",
                             *after)
    assert code == 0 and out == "" and err == "", err
    assert (tmp_path / "o" / "summary.json").is_file()


def test_progress_and_no_progress_are_refused_together_across_positions(run_cli, write_case,
                                                                        tmp_path):
    code, _, err = run_cli("--progress", "run", write_case(SPHERE), "--out", tmp_path / "o",
                           "--no-progress")
    assert "--no-progress" in _one_line_2(code, err)
    assert not (tmp_path / "o").exists()


def test_verbose_before_the_command_counts_with_verbose_after_it(run_cli, write_case,
                                                                 tmp_path):
    code, _, err = run_cli("-v", "run", write_case(SPHERE), "--out", tmp_path / "o", "-v")
    assert code == 0 and "slipcycle: " in err


def test_run_prints_a_short_summary_without_per_node_lists(run_cli, write_case, tmp_path):
    code, out, err = run_cli("run", write_case(TWO_NODE), "--out", tmp_path / "o")
    assert code == 0, err
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    lines = out.strip().splitlines()
    assert len(lines) <= 6, out
    assert summary["steady_state_class"] in out and "cycles" in out
    assert " J" in out and "dissipation" in out
    assert str(tmp_path / "o") in out
    assert "[" not in out and "dissipation_per_node" not in out


def test_round_off_dissipation_is_printed_as_zero_and_kept_raw_in_result_nc(run_cli,
                                                                            tmp_path):
    """The triangle example's shakedown dissipates 2.7e-17 J (round-off, |D| below
    64 ε F x N = 4.1e-14 J): printed as 0; result.nc keeps the raw per-node values."""
    import xarray as xr

    from slipcycle.examples import example_path

    code, out, err = run_cli("run", example_path("discrete_triangle_protocol"), "--out",
                             tmp_path / "o")
    assert code == 0, err
    assert "dissipation per cycle D = 0 J" in out
    with xr.open_dataset(tmp_path / "o" / "result.nc") as ds:
        per_node = ds["dissipation_per_node"]
        raw = float((per_node.isel(cycle=-1) if "cycle" in per_node.dims else per_node).sum())
    assert raw != 0.0 and abs(raw) < 4e-14


def test_a_resolved_dissipation_is_printed_as_it_is(run_cli, write_case, tmp_path):
    code, out, _ = run_cli("run", write_case(TWO_NODE), "--out", tmp_path / "o")
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert code == 0 and f"D = {summary['dissipation_per_cycle']:.6g} J" in out


def test_a_tabulated_normal_load_needs_no_p0(run_cli, write_case, tmp_path):
    """The docs: a p_table carries the whole normal load (p0 defaults to 0 then); a
    harmonic load without p0 is still refused naming loading.p0."""
    text = TWO_NODE.replace("p0 = [1.0, 1.0]", "theta = [0.0, 3.0]\n"
                            "p_table = [[1.0, 1.0], [1.2, 0.9]]")
    text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(("p1", "p1_phase")))
    code, _, err = run_cli("run", write_case(text + "\n"), "--out", tmp_path / "o", "-q")
    assert code == 0, err
    text = "\n".join(ln for ln in TWO_NODE.splitlines() if not ln.startswith("p0"))
    code, _, err = run_cli("run", write_case(text + "\n", "h.toml"), "--out", tmp_path / "h")
    assert code == 2 and err.startswith("error: loading.p0")
