"""JSON Schemas of slipcycle's files, shipped in ``slipcycle/schemas/``.

- ``summary.schema.json``: every ``summary.json`` (the numbers of a run or an analysis,
  their ``units`` and the ``metadata`` of :func:`slipcycle.io.metadata.provenance`).
- ``case.schema.json``: case files (TOML, read as JSON by editors such as VS Code with
  Even Better TOML or taplo: ``#:schema`` on the first line, or a schema association), one
  branch per ``model``. It names the tables and keys of the shipped example cases with
  their types, so an editor completes them and flags a value of the wrong type; it allows
  further keys (the readers accept optional keys the examples do not use and refuse
  unknown ones themselves, naming the key).

:func:`case_schema` builds the case schema from the example cases (``python -m
slipcycle.io.schema`` rewrites the shipped file after examples change);
:func:`load_schema` reads a shipped schema; :func:`validate` checks a document against
one when the optional ``jsonschema`` package is installed.

Only the standard library is imported at load time.
"""

from __future__ import annotations

import json
import tomllib
from collections.abc import Iterable, Mapping
from importlib import resources
from typing import Any

__all__ = ["SCHEMA_NAMES", "load_schema", "case_schema", "validate", "write_case_schema"]

SCHEMA_NAMES = ("summary", "case")

_BASE = "https://github.com/slipcycle/slipcycle/raw/main/src/slipcycle/schemas/"

_NUMERIC = {"description": "a number, or an array of numbers (one per node or body)",
            "anyOf": [{"type": "number"}, {"type": "array"}]}
_GRID = {"description": "a list of values or a table {start, stop, num}",
         "anyOf": [{"type": "array"}, {"type": "object"}]}


def load_schema(name: str) -> dict:
    """The shipped JSON Schema ``name`` (``"summary"`` or ``"case"``).

    Returns
    -------
    dict
    """
    if name not in SCHEMA_NAMES:
        raise KeyError(f"no schema {name!r}; the schemas are {', '.join(SCHEMA_NAMES)}")
    text = resources.files("slipcycle").joinpath("schemas", f"{name}.schema.json")
    return json.loads(text.read_text(encoding="utf-8"))


def validate(document: Any, name: str) -> None:
    """Check ``document`` against the shipped schema ``name``.

    Raises
    ------
    jsonschema.ValidationError
        If it does not conform.
    ModuleNotFoundError
        If the optional ``jsonschema`` package is not installed.
    """
    import jsonschema

    jsonschema.validate(document, load_schema(name))


def _value_schema(value: Any) -> dict:
    if isinstance(value, bool):
        return {"type": "boolean"}
    if isinstance(value, int | float):
        return dict(_NUMERIC)
    if isinstance(value, str):
        return {"type": "string"}
    if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
        return {"type": "array", "items": _table_schema(value)}
    if isinstance(value, list):
        return {"type": "array"}
    return dict(_GRID)


def _table_schema(tables: Iterable[Mapping]) -> dict:
    """Schema of the tables ``tables`` (the same table in several examples): their keys
    with the types seen, sub-tables recursively; further keys allowed."""
    keys: dict[str, list] = {}
    for table in tables:
        for key, value in table.items():
            keys.setdefault(key, []).append(value)
    props = {}
    for key, values in sorted(keys.items()):
        tables_here = [v for v in values if isinstance(v, dict)]
        # a TOML sub-table is an object of keys; a value that is a grid {start, stop, num}
        # may also be given as a list, so it keeps the grid's two forms
        if tables_here and all(isinstance(v, dict) for v in values) and not all(
                set(v) <= {"start", "stop", "num"} for v in tables_here):
            props[key] = _table_schema(tables_here)
        else:
            kinds = {json.dumps(_value_schema(v), sort_keys=True) for v in values}
            schemas = [json.loads(k) for k in sorted(kinds)]
            props[key] = schemas[0] if len(schemas) == 1 else {"anyOf": schemas}
    return {"type": "object", "properties": props, "additionalProperties": True}


def case_schema(examples: Mapping[str, str]) -> dict:
    """The case-file schema of the example cases ``examples`` (name -> TOML text).

    Returns
    -------
    dict
        A JSON Schema (draft 2020-12) with one ``if model == ... then`` branch per
        ``model``.
    """
    by_model: dict[str, list[dict]] = {}
    for text in examples.values():
        data = tomllib.loads(text)
        by_model.setdefault(str(data.get("model", "")), []).append(data)
    branches = []
    for model, docs in sorted(by_model.items()):
        branch = _table_schema(docs)
        branch["properties"].pop("model", None)
        branch["title"] = f"slipcycle case, model = {model!r}"
        branches.append({"if": {"properties": {"model": {"const": model}}},
                         "then": branch})
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": _BASE + "case.schema.json",
        "title": "slipcycle case file",
        "description": "A slipcycle case file (TOML): 'model' names the model; the tables "
                       "hold its keys. Generated from the shipped example cases.",
        "type": "object",
        "required": ["model"],
        # the readers name an unknown model; the schema checks the models it knows
        "properties": {"model": {"type": "string", "examples": sorted(by_model),
                                 "description": "the model that reads the case"}},
        "allOf": branches,
    }


def write_case_schema() -> str:
    """Rebuild ``schemas/case.schema.json`` from the shipped examples; returns its path."""
    from slipcycle.examples import example_path, example_text, list_examples

    schema = case_schema({n: example_text(n) for n in list_examples()})
    path = example_path(list_examples()[0]).parents[1] / "schemas" / "case.schema.json"
    path.write_text(json.dumps(schema, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    return str(path)


if __name__ == "__main__":  # pragma: no cover
    print(write_case_schema())
