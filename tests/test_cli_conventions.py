"""Command-line conventions: every command takes --quiet, --verbose, --no-progress and
--progress; results go to stdout, diagnostics through logging to stderr, progress bars to
stderr only on a terminal or when forced; --help is plain text; the shipped examples are
listed and copied by ``slipcycle examples``; ``slipcycle.run(progress=...)`` reaches a
solver that reports progress."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

import slipcycle
from slipcycle.cli.main import COMMANDS, build_parser
from slipcycle.examples import example_text, list_examples

SPHERE = example_text("halfspace_sphere").replace("steps_per_cycle = 400",
                                                  "steps_per_cycle = 40")
REST = re.compile(r"``|:(func|class|meth|mod|data|attr|obj|exc|ref):`")


def _help(*args: str) -> str:
    parser = build_parser()
    sub = parser
    if args:
        sub = next(a for a in parser._subparsers._group_actions
                   if hasattr(a, "choices")).choices[args[0]]
    return sub.format_help()


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_takes_the_output_options(command):
    text = _help(command)
    for option in ("--quiet", "--verbose", "--no-progress", "--progress"):
        assert option in text, f"slipcycle {command} lacks {option}"


@pytest.mark.parametrize("command", [None, *COMMANDS])
def test_help_is_plain_text_without_rest_markup(command):
    text = _help(command) if command else _help()
    assert not REST.search(text), REST.search(text).group(0)


def test_quiet_run_prints_nothing_and_writes_everything(run_cli, write_case, tmp_path):
    code, out, err = run_cli("run", write_case(SPHERE), "--out", tmp_path / "o", "-q")
    assert code == 0 and out == "" and err == ""
    assert {p.name for p in (tmp_path / "o").iterdir()} == {"summary.json", "result.nc",
                                                           "figures"}


def test_results_headline_goes_to_stdout_diagnostics_to_stderr(run_cli, write_case,
                                                               tmp_path):
    code, out, err = run_cli("run", write_case(SPHERE), "--out", tmp_path / "o")
    assert code == 0
    assert out.startswith("halfspace: cyclic_slip after ") and " J\n" in out
    assert err == ""                     # nothing but warnings by default
    code, out_v, err_v = run_cli("run", write_case(SPHERE), "--out", tmp_path / "o2", "-v")
    summary = json.loads(out_v.split("figures/\n", 1)[1])     # -v: every number as well
    assert code == 0 and summary["units"]["dissipation_per_cycle"] == "J"
    lines = err_v.strip().splitlines()
    assert lines and all(ln.startswith("slipcycle: ") for ln in lines), err_v


def test_errors_stay_one_line_after_the_diagnostics_asked_for(run_cli, write_case, tmp_path):
    bad = SPHERE.replace("friction = 0.5", "friction = -0.5")
    code, out, err = run_cli("run", write_case(bad), "--out", tmp_path / "o", "-vv")
    assert code == 2 and out == ""
    *diagnostics, last = err.strip().splitlines()
    assert last.startswith("error: halfspace.friction")
    assert all(ln.startswith("slipcycle: ") for ln in diagnostics)
    code, _, err = run_cli("run", write_case(bad), "--out", tmp_path / "o")
    assert code == 2 and err.startswith("error: halfspace.friction") and err.count("\n") == 1


def test_progress_bar_only_on_a_terminal_unless_forced(run_cli, write_case, tmp_path):
    # stderr is captured (not a terminal): no bar by default
    code, _, err = run_cli("run", write_case(SPHERE), "--out", tmp_path / "a", "-q")
    assert code == 0 and err == ""
    code, _, err = run_cli("run", write_case(SPHERE), "--out", tmp_path / "b", "--progress")
    assert code == 0 and "halfspace: " in err and "%" in err
    code, _, err = run_cli("run", write_case(SPHERE), "--out", tmp_path / "c",
                           "--no-progress")
    assert code == 0 and err == ""


def test_no_progress_and_progress_exclude_each_other(run_cli, write_case, tmp_path):
    code, _, err = run_cli("run", write_case(SPHERE), "--out", tmp_path / "a",
                           "--progress", "--no-progress")
    assert code == 2 and err.count("\n") == 1


def test_examples_lists_every_shipped_case(run_cli):
    code, out, err = run_cli("examples")
    assert code == 0 and err == ""
    listing, footer = out.strip().split("\n\n")          # the table, then how to run
    names = [ln.split()[0] for ln in listing.splitlines()]
    assert names == list_examples() and "halfspace_sphere" in names
    assert "slipcycle examples --copy" in footer


def test_examples_copy_gives_cases_that_run(run_cli, tmp_path):
    code, out, _ = run_cli("examples", "halfspace_sphere", "--copy", tmp_path / "cases")
    assert code == 0 and out.strip() == f"1 example case file copied to {tmp_path / 'cases'}/"
    copied = tmp_path / "cases" / "halfspace_sphere.toml"
    assert copied.read_text() == example_text("halfspace_sphere")
    # a second copy refuses to overwrite the user's edits, in one line
    code, _, err = run_cli("examples", "--copy", tmp_path / "cases")
    assert code == 2 and err.count("\n") == 1 and "--force" in err
    code, _, err = run_cli("examples", "--copy", tmp_path / "cases", "--force")
    assert code == 0
    assert sorted(p.stem for p in (tmp_path / "cases").glob("*.toml")) == list_examples()
    code, _, err = run_cli("examples", "no_such_example")
    assert code == 2 and "no_such_example" in err and err.count("\n") == 1


def test_examples_copy_counts_cases_apart_from_the_data_files_they_read(run_cli, tmp_path):
    """The CalculiX example is one case that reads a mesh deck (.inp): one case file, one
    data file; copying every example counts the .toml files as cases, nothing else."""
    code, out, _ = run_cli("examples", "calculix_block", "--copy", tmp_path / "one")
    assert code == 0
    assert out.strip() == (f"1 example case file and 1 data file they read "
                           f"(calculix_block.inp) copied to {tmp_path / 'one'}/")
    assert sorted(p.name for p in (tmp_path / "one").iterdir()) == [
        "calculix_block.inp", "calculix_block.toml"]
    code, out, _ = run_cli("examples", "--copy", tmp_path / "all")
    files = list((tmp_path / "all").iterdir())
    data = sorted(p.name for p in files if p.suffix != ".toml")
    assert code == 0 and data and len(files) > len(list_examples())
    assert out.strip() == (f"{len(list_examples())} example case files and {len(data)} data "
                           f"files they read ({', '.join(data)}) copied to {tmp_path / 'all'}/")


def test_example_path_is_the_installed_file():
    path = slipcycle.example_path("halfspace_sphere")
    assert path.is_file() and path.suffix == ".toml"
    assert slipcycle.example_path("halfspace_sphere.toml") == path
    with pytest.raises(KeyError, match="halfspace_sphere"):
        slipcycle.example_path("nope")
    res = slipcycle.run(path, overrides={"run.steps_per_cycle": 40})
    assert res.converged


def test_examples_listing_survives_a_closed_pipe():
    proc = subprocess.run(f"{sys.executable} -m slipcycle.cli.main examples | head -1",
                          shell=True, capture_output=True, text=True, timeout=120)
    assert proc.stdout.count("\n") == 1 and proc.stderr == ""


def test_run_hands_the_progress_callback_to_a_solver_that_takes_it(monkeypatch):
    from slipcycle import api, registry

    seen = []

    def solve_case(case, progress=None):
        progress(1, 2)
        progress(2, 2)
        return "solved"

    def solve_without_hook(case):
        return "solved"

    monkeypatch.setattr(registry, "solver", lambda model: solve_case)
    assert api.run(SPHERE, progress=lambda d, t: seen.append((d, t))) == "solved"
    assert seen == [(1, 2), (2, 2)]
    monkeypatch.setattr(registry, "solver", lambda model: solve_without_hook)
    assert api.run(SPHERE, progress=lambda d, t: seen.append((d, t))) == "solved"


def test_diagnostics_use_logging_not_print():
    """Command modules print only results (stdout); diagnostics go through logging."""
    from pathlib import Path

    cli = Path(slipcycle.__file__).parent / "cli"
    for path in sorted(cli.glob("cmd_*.py")):
        text = path.read_text(encoding="utf-8")
        for m in re.finditer(r"print\((.*)", text):
            assert "file=sys.stderr" not in m.group(1), f"{path.name}: {m.group(0)}"
