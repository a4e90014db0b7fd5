"""The package layering of docs/architecture.md holds: a wrong-way import fails here.

The contracts live in ``pyproject.toml`` (``[tool.importlinter]``); import-linter reads
every import, function-local ones included, so no contract can be kept by hiding an import
inside a function.
"""

from __future__ import annotations

import ast
import contextlib
import io
import logging
import os
from pathlib import Path

import pytest

pytest.importorskip("importlinter", reason="needs the test extra")
from importlinter.cli import EXIT_STATUS_SUCCESS, lint_imports  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "slipcycle"


@contextlib.contextmanager
def _logging_kept():
    """Restore the logging state: import-linter configures logging with
    ``disable_existing_loggers``, which silenced the ``slipcycle`` logger (the CLI's -v
    diagnostics) for every later test of the same process."""
    loggers = [lg for lg in logging.root.manager.loggerDict.values()
               if isinstance(lg, logging.Logger)]
    state = [(lg, lg.disabled, lg.level, lg.propagate, list(lg.handlers)) for lg in loggers]
    root = (logging.root.level, list(logging.root.handlers))
    try:
        yield
    finally:
        for lg, disabled, level, propagate, handlers in state:
            lg.disabled, lg.propagate, lg.handlers = disabled, propagate, handlers
            lg.setLevel(level)
        logging.root.handlers = root[1]
        logging.root.setLevel(root[0])


def test_import_contracts_are_kept():
    out = io.StringIO()
    cwd = os.getcwd()
    try:
        os.chdir(ROOT)
        with contextlib.redirect_stdout(out), _logging_kept():
            status = lint_imports(config_filename=str(ROOT / "pyproject.toml"),
                                  no_cache=True, no_logo=True)
    finally:
        os.chdir(cwd)
    assert status == EXIT_STATUS_SUCCESS, ("an import breaks the layering of "
                                           "docs/architecture.md:\n" + out.getvalue())


def _imported_slipcycle_packages(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        else:
            continue
        for name in names:
            parts = name.split(".")
            if parts[0] == "slipcycle" and len(parts) > 1:
                found.add(parts[1])
    return found


def test_no_package_cycles():
    """Top-level packages (and modules) of slipcycle import each other without a cycle."""
    graph: dict[str, set[str]] = {}
    for path in SRC.rglob("*.py"):
        rel = path.relative_to(SRC).parts
        pkg = rel[0].removesuffix(".py")
        graph.setdefault(pkg, set()).update(_imported_slipcycle_packages(path) - {pkg})
    state: dict[str, int] = {}

    def visit(node, stack):
        state[node] = 1
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                cycle = stack[stack.index(nxt):] + [nxt]
                pytest.fail("package cycle: " + " -> ".join(cycle))
            if state.get(nxt) is None:
                visit(nxt, stack + [nxt])
        state[node] = 2

    for node in sorted(graph):
        if state.get(node) is None:
            visit(node, [node])


def test_no_module_cycles_hidden_in_functions():
    """No two modules import each other, directly or around a loop, counting the imports
    inside functions (a function-local import must not be what keeps a cycle apart)."""
    import grimp

    graph = grimp.build_graph("slipcycle")
    state: dict[str, int] = {}

    def visit(node, stack):
        state[node] = 1
        for nxt in sorted(graph.find_modules_directly_imported_by(node)):
            if state.get(nxt) == 1:
                pytest.fail("module cycle: " + " -> ".join(stack[stack.index(nxt):] + [nxt]))
            if state.get(nxt) is None:
                visit(nxt, stack + [nxt])
        state[node] = 2

    for node in sorted(graph.modules):
        if state.get(node) is None:
            visit(node, [node])


def test_command_modules_only_parse_call_and_print():
    """Every analysis lives in the library: the command modules stay short."""
    for path in sorted((SRC / "cli").glob("cmd_*.py")):
        lines = len(path.read_text(encoding="utf-8").splitlines())
        assert lines <= 130, f"{path.name} has {lines} lines"


def test_section_bookkeeping_is_written_only_by_section():
    """The keys a ``Section`` has read (``_used``, which ``finish`` checks) are its own:
    readers mark a key through ``Section.raw`` or ``Section.accept``, never by writing the
    set from outside the class."""
    offenders = []
    for path in sorted(SRC.rglob("*.py")):
        own = path == SRC / "io" / "case.py"
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Attribute) and node.attr == "_used":
                if not (own and isinstance(node.value, ast.Name) and node.value.id == "self"):
                    offenders.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert not offenders, offenders
