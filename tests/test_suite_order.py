"""The suite's own scheduling (tests/conftest.py): the longest tests run first."""

from __future__ import annotations

import ast
from pathlib import Path

from conftest import LONGEST_FIRST

ROOT = Path(__file__).resolve().parents[1]


def test_every_longest_first_entry_names_a_test_that_exists():
    """A renamed or removed test would silently fall back to its file's place."""
    for nodeid in LONGEST_FIRST:
        path, name = nodeid.split("::")
        tree = ast.parse((ROOT / path).read_text(encoding="utf-8"))
        names = {f.name for f in tree.body if isinstance(f, ast.FunctionDef)}
        assert name in names, nodeid


def test_the_longest_tests_head_the_collection(request):
    """Those collected in this session come first, in the listed order; the others keep
    the order of their files."""
    ids = [item.nodeid for item in request.session.items]
    listed = [i for i in LONGEST_FIRST if i in ids]
    assert ids[:len(listed)] == listed
    rest = ids[len(listed):]
    files = [i.split("::")[0] for i in rest]
    assert files == sorted(files, key=files.index)      # each file's tests stay together
