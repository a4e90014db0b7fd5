"""docs/architecture.md stays true: what it names exists, and its tables are the code's.

- the models table is ``registry.MODELS`` (model, case reader, result class and the module
  that defines it);
- every result class of the code (subclasses of ``RunResult``, ``StudyResult`` and their
  common base) is named, and every class, constant and function it names exists;
- every module path, dotted name and import-linter contract id it names exists;
- the package table lists every package and top-level module of ``src/slipcycle`` and
  nothing else; the layer block lists the layers of the ``layers`` contract.

The source is read as text (``ast``), so the test needs none of the optional extras.
"""

from __future__ import annotations

import ast
import importlib
import re
import tomllib
from functools import cache
from pathlib import Path

import pytest

from slipcycle import registry

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "slipcycle"
DOC = ROOT / "docs" / "architecture.md"
TICKS = re.compile(r"`([^`]+)`")
CAMEL = re.compile(r"^[A-Z][A-Za-z0-9]*[a-z][A-Za-z0-9]*$")
CONSTANT = re.compile(r"^[A-Z][A-Z0-9_]{2,}$")
CALL = re.compile(r"^([a-z_][a-z0-9_]*)\(")
DOTTED = re.compile(r"^[a-z_][a-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)+(:[A-Za-z_]\w*)?$")
CONTRACT_ID = re.compile(r"^[a-z]+(-[a-z]+)+$")
FILE = re.compile(r"^[A-Za-z0-9_./-]+(/|\.py|\.toml|\.json|\.md|\.nc|\.png)$")
#: names and modules of the standard library the page uses
STDLIB = {"Path"}
STDLIB_MODULES = {"functools"}


def _text() -> str:
    return DOC.read_text(encoding="utf-8")


def _tokens() -> list[str]:
    """Backticked spans outside fenced code blocks (quotes stripped)."""
    prose = re.sub(r"```.*?```", "", _text(), flags=re.S)
    return [t.strip().strip('"') for t in TICKS.findall(prose)]


@cache
def _index() -> dict:
    """classes (name -> [(file, bases)]), module-level names and function names of src."""
    classes: dict[str, list] = {}
    names: set[str] = set()
    functions: dict[str, set[str]] = {}
    for path in SRC.rglob("*.py"):
        rel = path.relative_to(SRC).as_posix()
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                bases = [b.id if isinstance(b, ast.Name) else getattr(b, "attr", "")
                         for b in node.bases]
                classes.setdefault(node.name, []).append((rel, bases))
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                functions.setdefault(node.name, set()).add(rel)
        for node in tree.body:
            targets = []
            if isinstance(node, ast.Assign):
                targets = [t for t in node.targets if isinstance(t, ast.Name)]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                targets = [node.target]
            names.update(t.id for t in targets)
    return {"classes": classes, "names": names | set(classes), "functions": functions}


def _subclasses(*roots: str) -> set[str]:
    classes = _index()["classes"]
    found = set(roots)
    grew = True
    while grew:
        grew = False
        for name, defs in classes.items():
            if name not in found and any(set(bases) & found for _, bases in defs):
                found.add(name)
                grew = True
    return found - set(roots)


def _table(header_start: str) -> list[list[str]]:
    """Rows (cells) of the markdown table whose header line starts with ``header_start``."""
    lines = _text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header_start))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


def _ticked(cell: str) -> list[str]:
    return TICKS.findall(cell)


def test_models_table_is_the_registry():
    rows = _table("| model | case reader")
    doc = {_ticked(r[0])[0]: r for r in rows}
    assert set(doc) == set(registry.MODELS), "the models table and registry.MODELS differ"
    classes = _index()["classes"]
    for model, entry in registry.MODELS.items():
        _, reader, result, module = doc[model]
        if entry.validator is None:
            assert entry.result is None and result == "none", model
            continue
        assert _ticked(reader)[0] == entry.validator.split(":")[1], (model, reader)
        assert registry.resolve(entry.validator), model
        cls = entry.result.split(":")[1]
        assert _ticked(result) == [cls], (model, result, entry.result)
        result_cls = getattr(importlib.import_module(entry.result.split(":")[0]), cls)
        where = result_cls.__module__.removeprefix("slipcycle.").replace(".", "/") + ".py"
        assert _ticked(module) == [where], (model, module, where)
        assert where in [f for f, _ in classes[cls]]


def test_every_result_class_is_named():
    named = set(_tokens())
    results = {c for c in _subclasses("RunResult", "StudyResult", "_Contract")
               if not c.startswith("_")}
    assert {"HalfspaceResult", "DiscreteResult", "DiscreteResult3D", "RodsResult",
            "FEResult", "LapJointResult", "BasinsResult", "LimitsResult"} <= results
    assert not results - named, f"result classes the page does not name: {results - named}"


def test_every_named_class_constant_and_function_exists():
    index = _index()
    missing = []
    for token in _tokens():
        head = re.split(r"[\s(\[.:,=]", token, maxsplit=1)[0]
        if CAMEL.match(head) or CONSTANT.match(head):
            if head not in index["names"] | STDLIB:
                missing.append(token)
        elif (m := CALL.match(token)) and m.group(1) not in index["functions"]:
            missing.append(token)
    assert not missing, f"names on the page that the code does not define: {missing}"


def _resolves(dotted: str) -> bool:
    name, _, attr = dotted.partition(":")
    parts = name.split(".")
    if parts[0] in STDLIB_MODULES:
        return callable(getattr(importlib.import_module(parts[0]), parts[-1], None))
    if parts[0] != "slipcycle":
        parts = ["slipcycle", *parts]
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for part in parts[i:] + ([attr] if attr else []):
                obj = getattr(obj, part)
        except AttributeError:
            return False
        return True
    return False


def test_every_named_path_and_dotted_name_exists():
    missing = []
    for token in _tokens():
        path, _, func = token.partition(": ")
        if "<" in path or "*" in path or " " in path:
            continue  # a pattern such as cli/cmd_<name>.py
        if FILE.match(path):
            where = next((p for p in (SRC / path, ROOT / path) if p.exists()), None)
            if "/" not in path and not path.endswith(".py"):
                continue  # a file a command writes (summary.json), not one of the tree
            if where is None:
                missing.append(token)
            elif func and func not in _index()["functions"]:
                missing.append(token)
        elif DOTTED.match(token) and not _resolves(token):
            missing.append(token)
    assert not missing, f"paths or names on the page that do not exist: {missing}"


def _contracts() -> list[dict]:
    data = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    return data["tool"]["importlinter"]["contracts"]


def test_every_named_contract_exists():
    ids = {c["id"] for c in _contracts()}
    named = {t for t in _tokens() if CONTRACT_ID.match(t)}
    assert {"models-below-studies", "models-behind-run"} <= named
    assert named <= ids, f"contracts the page names that pyproject.toml lacks: {named - ids}"


def _tree() -> set[str]:
    entries = set()
    for path in SRC.iterdir():
        if path.name.startswith(".") or path.name == "__pycache__":
            continue
        if path.is_dir():
            entries.add(path.name + "/")
        elif path.suffix == ".py":
            entries.add(path.name)
    return entries


def test_package_table_matches_the_tree():
    listed = [_ticked(r[0])[0] for r in _table("| package | job")]
    assert len(listed) == len(set(listed)), "a package is listed twice"
    tree = _tree()
    assert not tree - set(listed), f"packages the page does not list: {tree - set(listed)}"
    assert not set(listed) - tree, f"packages listed that do not exist: {set(listed) - tree}"


def test_layer_block_is_the_layers_contract():
    text = _text()
    section = text[text.index("## Layers"):]
    block = section[section.index("```") + 3:]
    block = block[:block.index("```")].strip("\n")
    doc_layers = [{p.strip() for p in re.split(r"\s{2,}", line.strip())[0].split("|")}
                  for line in block.splitlines()]
    contract = next(c for c in _contracts() if c["id"] == "layers")
    code_layers = [{p.strip().removeprefix("slipcycle.") for p in layer.split("|")}
                   for layer in contract["layers"]]
    assert doc_layers == code_layers


@pytest.mark.parametrize("stale", ["AnalysisStatus", "parse_case(case: Case)",
                                   "only `case.py` modules know", "figures only by `plot`"])
def test_rules_the_code_broke_are_gone(stale):
    """The page once named an alias, a generic reader and rules the code broke."""
    assert stale not in _text()


def test_the_modules_that_parse_toml_are_the_ones_the_page_names():
    text = _text()
    conventions = text[text.index("## Conventions"):]
    rule = conventions[conventions.index("- Solvers take arrays"):]
    rule = rule[:rule.index("\n- ")]
    named = {t.partition(" ")[0] for t in TICKS.findall(rule) if t.endswith(".py")}
    users = set()
    for path in SRC.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        if any(isinstance(n, ast.Import) and any(a.name == "tomllib" for a in n.names)
               for n in ast.walk(tree)):
            users.add(path.relative_to(SRC).as_posix())
    assert "io/case.py" in users
    assert users == named, f"parse TOML: {sorted(users)}; the page names {sorted(named)}"
