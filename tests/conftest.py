"""Shared test helpers."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture
def run_cli(capsys):
    """Run the ``slipcycle`` CLI in-process; returns (exit_code, stdout, stderr)."""
    from slipcycle.cli.main import main

    def _run(*argv: str):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:  # argparse errors
            code = exc.code
        out, err = capsys.readouterr()
        return code, out, err

    return _run


@pytest.fixture
def write_case(tmp_path):
    """Write TOML text to a case file in tmp_path and return its path."""

    def _write(text: str, name: str = "case.toml") -> Path:
        path = tmp_path / name
        path.write_text(text)
        return path

    return _write
