"""``slipcycle.run``: one entry point that solves a case of any model.

:func:`run` takes a case in any of its forms (a path to a TOML file, TOML text, the parsed
TOML as a dict, a :class:`~slipcycle.io.Case`, or a validated model object built in
Python) and returns the model's result object (:class:`slipcycle.result.RunResult`):
the same vocabulary for every model, with ``summary()``, ``to_dataset()``, ``figures()``
and ``to_outputs()``. ``slipcycle run``, the case sweeps and the demo report all go
through it.

The models are reached through :mod:`slipcycle.registry` by name (dotted strings), so this
module imports no model package and sits below ``sweep``.
"""

from __future__ import annotations

import copy
import inspect
import json
import math
import os
import re
import tomllib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from slipcycle import registry
from slipcycle.io.case import Case, CaseError, parse_case_text, read_case

if TYPE_CHECKING:  # pragma: no cover
    from slipcycle.result import RunResult

__all__ = ["run", "as_case", "apply_overrides", "toml_text", "takes_workers"]

_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(\[(\d+)\])?$")
_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def run(case: Any, overrides: Mapping[str, Any] | None = None, *,
        progress: Callable[[float, float], None] | None = None,
        workers: int | None = None) -> RunResult:
    """Validate and solve ``case`` with its model; return the model's result object.

    Parameters
    ----------
    case : path, str, dict, Case or model object
        - a :class:`~pathlib.Path` (or a string without ``=`` and newlines) naming a TOML
          case file;
        - TOML text (a string holding ``=`` or a newline);
        - a dict: the parsed TOML document (``{"model": "halfspace", "halfspace": {...},
          ...}``);
        - a :class:`~slipcycle.io.Case`;
        - a validated model object: a
          :class:`~slipcycle.halfspace.HalfspaceModel`, a
          :class:`~slipcycle.discrete.case.DiscreteCase`, a tuple ``(FrictionalSystem,
          load)`` or ``(FrictionalSystem, load, run_settings)``, or a
          :class:`~slipcycle.rods.case.RodsCase` (the types each model registers in
          :mod:`slipcycle.registry`).
    overrides : mapping, optional
        Dotted case keys -> new values, applied before validation (``{"loading.lam":
        1.2, "loading.p1[0]": 0.3}``); for case files, TOML text, dicts and Cases only.
    progress : callable, optional
        ``progress(done, total)``, called by a solver that reports its progress (one
        whose entry point takes a ``progress`` keyword); solvers without such a hook
        ignore it (the command line then shows only the elapsed time).
    workers : int, optional
        Processes for a solver that runs several independent simulations (one whose
        entry point takes a ``workers`` keyword: the protocol runs of a ``lap_joint``
        case; :func:`takes_workers`); the others ignore it. Default: the solver's (1).

    Returns
    -------
    RunResult
        The model's result: ``steady_state``, ``dissipation_per_cycle`` [J or J/m],
        ``cycles_run``, ``residual``, ``converged``, ``message``; ``summary()``,
        ``to_dataset()``, ``figures()``, ``to_outputs()``.

    Raises
    ------
    CaseError
        An invalid case (naming the key), before any computation.
    TypeError
        An object that is no case and no registered model object.
    """
    if isinstance(case, tuple) or not isinstance(case, str | os.PathLike | Mapping | Case):
        first = case[0] if isinstance(case, tuple) and case else case
        found = registry.entry_for_object(first)
        if found is None:
            raise TypeError(f"slipcycle.run takes a case file path, TOML text, a dict, a Case "
                            f"or a model object, not {type(case).__name__}")
        if overrides:
            raise TypeError("overrides apply to case files, TOML text and dicts; build the "
                            "model object with the values wanted instead")
        target = found[1].model_solver
        if target is None:  # entry_for_object finds entries with a model_solver only
            raise TypeError(f"model {found[0]!r} solves no model objects")
        solve = registry.resolve(target)
        extra = _keywords(solve, progress=progress, workers=workers)
        return solve(*case, **extra) if isinstance(case, tuple) else solve(case, **extra)
    c = as_case(case, overrides)
    solve = registry.solver(c.model)
    return solve(c, **_keywords(solve, progress=progress, workers=workers))


def _keywords(solve: Callable[..., Any], **given) -> dict:
    """The keywords of ``given`` that are not None and that ``solve`` takes."""
    try:
        params = inspect.signature(solve).parameters
    except (TypeError, ValueError):
        return {}
    return {k: v for k, v in given.items() if v is not None and k in params}


def takes_workers(model: str) -> bool:
    """Whether the solver of ``model`` runs several simulations in worker processes
    (takes :func:`run`'s ``workers``)."""
    return "workers" in _keywords(registry.solver(model), workers=1)


def as_case(case: Any, overrides: Mapping[str, Any] | None = None) -> Case:
    """A :class:`~slipcycle.io.Case` of a model that :func:`run` solves.

    Parameters
    ----------
    case : path, str, dict or Case
        See :func:`run`.
    overrides : mapping, optional
        Dotted keys -> values (:func:`apply_overrides`), each taken as the case file
        would give it (NumPy values as TOML's numbers and lists).

    Returns
    -------
    Case
        With overrides, its ``text`` is the overridden document (a first comment line
        names the case and the overrides): what a study re-reads and what the outputs
        record as the case run.

    Raises
    ------
    CaseError
        Unreadable file, invalid TOML, or a model :func:`run` does not solve.
    """
    models = list(registry.RUN_MODELS)
    if isinstance(case, Case):
        if case.model not in models:
            parse_case_text(f"model = {json.dumps(case.model)}\n", None, models)
        base = case
    elif isinstance(case, os.PathLike):
        base = read_case(Path(os.fspath(case)), models)
    elif isinstance(case, str):
        base = parse_case_text(case, None, models) if ("\n" in case or "=" in case) \
            else read_case(case, models)
    elif isinstance(case, Mapping):
        base = parse_case_text(toml_text(case), None, models)
    else:
        raise TypeError(f"not a case: {type(case).__name__}")
    if overrides is not None and not isinstance(overrides, Mapping):
        raise TypeError("overrides must be a mapping of dotted keys to values, e.g. "
                        "{'lap_joint.friction': 0.25}, not "
                        f"{type(overrides).__name__} {overrides!r}")
    if not overrides:
        return base
    data = apply_overrides(base.data, dict(overrides))
    # the text is what was run: the studies re-read a case from its text (their worker
    # tasks get text, not dicts), and the provenance of every output records it
    where = f" {json.dumps(str(base.path), ensure_ascii=False)}" if base.path else ""
    head = f"# the case{where} with " + ", ".join(
        f"{k} = {_value(_as_toml(k, v))}" for k, v in overrides.items())
    return Case(model=data.get("model", base.model), data=data,
                text=" ".join(head.splitlines()) + "\n" + toml_text(data), path=base.path)


def apply_overrides(data: dict, params: dict) -> dict:
    """A deep copy of the TOML document ``data`` with dotted keys set to new values.

    Parameters
    ----------
    data : dict
        A parsed case document.
    params : dict
        ``"table.key"`` (or ``"table.key[i]"`` for one entry of a list) -> value.

    Returns
    -------
    dict

    Raises
    ------
    CaseError
        If a parent table is missing or an indexed entry does not exist.
    """
    data = copy.deepcopy(data)
    for key, value in params.items():
        value = _as_toml(key, value)
        parts = key.split(".")
        node = data
        for i, part in enumerate(parts):
            m = _KEY.match(part)
            if m is None:
                raise CaseError(key, "invalid key (dotted name such as loading.lam or "
                                "loading.p1[0])")
            name, idx = m.group(1), m.group(3)
            last = i == len(parts) - 1
            where = ".".join(parts[:i + 1])
            if last and idx is None:
                if not isinstance(node, dict):
                    raise CaseError(key, f"{'.'.join(parts[:i])} is not a table")
                node[name] = value
                break
            if name not in node:
                raise CaseError(where, f"cannot set {key}: [{where}] is not in the case "
                                "file")
            child = node[name]
            if idx is not None:
                if not isinstance(child, list) or int(idx) >= len(child):
                    raise CaseError(where, f"has no entry [{idx}] to set")
                if last:
                    child[int(idx)] = value
                    break
                child = child[int(idx)]
            node = child
    return data


def _as_toml(key: str, value: Any) -> Any:
    """``value`` as the TOML parser gives it back from its text: an override reaches the
    model exactly as the same value written in the case file would (NumPy scalars and
    arrays, tuples and paths become TOML's int, float, list and string; NumPy's int64 is
    no Python int, and a reader would refuse it). A value TOML cannot hold (None, a set)
    is refused naming ``key``."""
    try:
        text = f"v = {_value(value)}\n"
    except CaseError as exc:
        raise CaseError(key, exc.problem) from None
    try:
        return tomllib.loads(text)["v"]
    except (tomllib.TOMLDecodeError, RecursionError):
        raise CaseError(key, f"cannot write {value!r} as a TOML value") from None


# -- a case document as TOML text (the provenance of a case given as a dict) --------------

def _key(k: Any) -> str:
    k = str(k)
    return k if _BARE.match(k) else json.dumps(k, ensure_ascii=False)


def _value(v: Any) -> str:
    if hasattr(v, "tolist") and not isinstance(v, str | bytes):   # NumPy scalars/arrays
        v = v.tolist()
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, os.PathLike):
        return json.dumps(os.fspath(v), ensure_ascii=False)
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise CaseError("case", f"cannot write a {type(v).__name__} as a TOML value")


def _is_table_array(v: Any) -> bool:
    return isinstance(v, list | tuple) and bool(v) and all(isinstance(x, Mapping) for x in v)


def toml_text(data: Mapping, _prefix: tuple[str, ...] = ()) -> str:
    """TOML text of a case document (``tomllib.loads(toml_text(d)) == d``).

    Parameters
    ----------
    data : mapping
        Tables as mappings, arrays of tables as lists of mappings, values as numbers,
        booleans, strings, lists or NumPy arrays.

    Returns
    -------
    str
    """
    lines = [f"{_key(k)} = {_value(v)}" for k, v in data.items()
             if not isinstance(v, Mapping) and not _is_table_array(v)]
    for k, v in data.items():
        name = ".".join(_key(p) for p in (*_prefix, k))
        if isinstance(v, Mapping):
            lines += ["", f"[{name}]", toml_text(v, (*_prefix, k)).rstrip("\n")]
        elif _is_table_array(v):
            for item in v:
                lines += ["", f"[[{name}]]", toml_text(item, (*_prefix, k)).rstrip("\n")]
    return "\n".join(lines).strip("\n") + "\n"

