"""``slipcycle examples`` for a newcomer (issue 34 item 7): each example is listed with the
command that runs it and a description that ends at a sentence end; every example is
accepted by that command (the FE models that ``run`` refuses are listed under ``reduce``
and reduce), and the demo report's folder gets the user's umask."""

from __future__ import annotations

import os
import re
import shutil
import stat

import pytest

from slipcycle.examples import (
    example_command,
    example_path,
    example_summary,
    example_text,
    list_examples,
)
from slipcycle.io import parse_case_text
from slipcycle.registry import validator


def test_examples_lists_each_example_with_its_command_and_a_whole_sentence(run_cli):
    code, out, err = run_cli("examples")
    assert code == 0 and err == ""
    for name in list_examples():
        line = next(ln for ln in out.splitlines() if ln.startswith(name + " "))
        command = example_command(name)[0]
        assert re.match(rf"{name}\s+{command}\s+\S", line), line
        summary = example_summary(name)
        assert line.endswith(summary)
        comment = " ".join(ln.lstrip("#").strip() for ln in example_text(name).splitlines()
                           if ln.startswith("#"))
        assert comment.startswith(summary)
        # a sentence end, or the whole first comment line (a title without a full stop)
        first = example_text(name).splitlines()[0].lstrip("#").strip()
        assert summary.endswith((".", "?", "!")) or summary == first, summary


def test_fe_examples_that_run_refuses_are_listed_under_reduce():
    assert example_command("fe_cylinder")[0] == "reduce"
    assert example_command("fe_two_blocks")[0] == "reduce"
    assert example_command("halfspace_rough_map")[0] == "map"
    assert example_command("discrete_two_node")[0] == "run"


@pytest.mark.parametrize("name", [n for n in list_examples()
                                  if example_command(n)[0] in ("run", "map")])
def test_every_run_or_map_example_is_accepted_by_its_command(name):
    """The case is read and checked by the reader of the command's model (no solve)."""
    case = parse_case_text(example_text(name), example_path(name))
    read = validator(case.model)
    assert read is not None
    if example_command(name)[0] == "map":
        from slipcycle.studies.w_hat_map import parse_map_case

        read = parse_map_case
    read(case)


@pytest.mark.parametrize("name", ["fe_cylinder", "fe_two_blocks"])
def test_fe_examples_reduce_with_the_listed_command(name, run_cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    shutil.copy(example_path(name), tmp_path)
    argv = example_command(name)
    code, _, err = run_cli(*argv, "-q")
    assert code == 0, err
    assert (tmp_path / argv[argv.index("--out") + 1]).is_file()
    code, _, err = run_cli("run", f"{name}.toml", "--out", "r")
    assert code == 2 and "reduce" in err


def test_demo_report_folder_has_the_users_umask(run_cli, tmp_path, monkeypatch):
    import slipcycle.cli.cmd_demo as demo
    from slipcycle.demo import DEMO_CASES

    # one quick case (an empty mapping is falsy: the command would run them all)
    monkeypatch.setattr(demo, "DEMO_CASES", {"rough_contact": DEMO_CASES["rough_contact"]},
                        raising=False)
    old = os.umask(0o022)
    try:
        code, _, err = run_cli("demo", "--out", tmp_path / "report", "-q")
    finally:
        os.umask(old)
    assert code == 0, err
    assert stat.S_IMODE((tmp_path / "report").stat().st_mode) == 0o755


def test_demo_replaces_its_own_report_and_refuses_a_folder_of_other_files(run_cli, tmp_path,
                                                                          monkeypatch):
    """The demo replaces --out whole: a user's files there were deleted. A folder of other
    files is refused in one line (kept as it was); an earlier report is replaced."""
    import slipcycle.cli.cmd_demo as demo
    from slipcycle.demo import DEMO_CASES

    monkeypatch.setattr(demo, "DEMO_CASES", {"rough_contact": DEMO_CASES["rough_contact"]},
                        raising=False)
    user = tmp_path / "thesis"
    (user / "sub").mkdir(parents=True)
    (user / "thesis.tex").write_text("precious")
    (user / "sub" / "data.csv").write_text("x")
    code, _, err = run_cli("demo", "--out", user, "-q")
    assert code == 2 and "--out" in err and len(err.strip().splitlines()) == 1, err
    assert (user / "thesis.tex").read_text() == "precious"
    assert (user / "sub" / "data.csv").read_text() == "x"
    report = tmp_path / "report"
    assert run_cli("demo", "--out", report, "-q")[0] == 0
    (report / "stale.txt").write_text("left by an older report")
    assert run_cli("demo", "--out", report, "-q")[0] == 0
    assert not (report / "stale.txt").exists() and (report / "report.md").is_file()
