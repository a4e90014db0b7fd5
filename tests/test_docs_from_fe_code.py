"""docs/from_fe_code.md: its CalculiX worked example runs as written (real ``ccx``) and
every number the page quotes is what the commands produce."""

from __future__ import annotations

import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from calculix import require_ccx  # noqa: E402

PAGE = Path(__file__).resolve().parents[1] / "docs" / "from_fe_code.md"


def _console(text: str) -> list[tuple[str, list[str]]]:
    """(command, expected output lines) of the page's ``console`` block."""
    block = re.search(r"```console\n(.*?)```", text, re.S).group(1)
    out: list[tuple[str, list[str]]] = []
    for line in block.splitlines():
        if line.startswith("$ "):
            out.append((line[2:], []))
        elif line.strip():
            out[-1][1].append(line)
    return out


def _sci(x: float, digits: int) -> str:
    """``x`` as the page writes it: 4.42e-4 (no leading zero in the exponent)."""
    return f"{x:.{digits}e}".replace("e-0", "e-").replace("e+0", "e")


def _run(command: str, run_cli) -> str:
    argv = shlex.split(command)
    if argv[0] == "ccx":
        proc = subprocess.run([require_ccx(), *argv[1:]], capture_output=True, text=True,
                              timeout=120)
        assert proc.returncode == 0 and "Job finished" in proc.stdout, proc.stdout[-2000:]
        return ""
    assert argv[0] == "slipcycle", command
    code, out, err = run_cli(*argv[1:])
    assert code == 0, (command, err)
    return out


def test_calculix_worked_example_runs_and_quotes_its_numbers(tmp_path, run_cli, monkeypatch):
    require_ccx()
    text = PAGE.read_text(encoding="utf-8")
    deck = re.search(r"```text\n(\*MATERIAL.*?)```", text, re.S).group(1)
    shipped = (PAGE.parents[1] / "src" / "slipcycle" / "examples" / "calculix_block.inp")
    assert deck in shipped.read_text(), "the deck quoted is not the shipped deck's end"
    monkeypatch.chdir(tmp_path)
    commands = _console(text)
    assert [c for c, _ in commands] == [
        "slipcycle examples calculix_block --copy work", "cd work", "ccx -i calculix_block",
        "slipcycle reduce calculix_block.toml --out block",
        "slipcycle run block/case.toml --out block_run"]
    for command, expected in commands:
        if command.startswith("cd "):
            monkeypatch.chdir(Path.cwd() / command[3:])
            continue
        out = _run(command, run_cli)
        if command.startswith("slipcycle reduce"):
            assert out.splitlines() == expected
    report = json.loads(Path("block/report.txt").read_text())
    body = report["bodies"][0]
    assert f"{body['rows']} rows of `calculix_block.sti` ({body['mesh_nodes']} nodes × 3)" \
        in text and body["rows"] == 3 * body["mesh_nodes"]
    assert f"{body['elements']['hexahedron']} hexahedra" in text
    assert f"{report['contact_nodes']} contact nodes with a total area of " \
           f"{_sci(report['contact_area_m2'], 1)} m²" in text
    data = np.load("block/stiffness.npz")
    names = [str(n) for n in data["load_cases"]]
    P = data["p_w"][names.index("normal")].sum()
    Q = abs(data["q_w"][names.index("tangential")][0::2].sum())
    assert f"P = {P:.0f} N" in text and f"tangential force of {Q:.0f} N" in text
    model = (Path("calculix_block.toml")).read_text()
    amplitude = float(re.search(r"^tangential = ([0-9.]+)", model, re.M).group(1))
    friction = float(re.search(r"^friction = ([0-9.]+)", model, re.M).group(1))
    assert f"amplitude {amplitude:g}" in text
    assert f"Q/fP = {amplitude * Q / (friction * P):.2f}" in text
    summary = json.loads(Path("block_run/summary.json").read_text())
    assert summary["steady_state"] == "cyclic_slip" and "**cyclic slip**" in text
    assert summary["converged"]
    assert f"D = {_sci(summary['dissipation_per_cycle'], 2)} J" in text
    assert Path("block_run/fields/interface.pvd").is_file()


def test_quoted_error_lines_are_what_reduce_says(tmp_path, run_cli, monkeypatch):
    require_ccx()
    text = PAGE.read_text(encoding="utf-8")
    quoted = re.findall(r"^error: .*$", text, re.M)
    assert len(quoted) == 2
    monkeypatch.chdir(tmp_path)
    run_cli("examples", "calculix_block", "--copy", ".")
    _run("ccx -i calculix_block", run_cli)
    base = Path("calculix_block.toml").read_text()
    edits = [('nodes = "TOP"\ndisplacement = [0.0, 0.0, -1.0e-6]',
              'nodes = "TOPP"\ndisplacement = [0.0, 0.0, -1.0e-6]'),
             ('nodes = "TOP"\ndisplacement = [1.0e-6, 0.0, 0.0]',
              'nodes = "BOTTOM"\ndisplacement = [1.0e-6, 0.0, 0.0]')]
    for line, (old, new) in zip(quoted, edits, strict=True):
        assert base.count(old) == 1
        Path("m.toml").write_text(base.replace(old, new))
        code, _, err = run_cli("reduce", "m.toml", "--out", "out")
        assert code == 2 and err.strip() == line
