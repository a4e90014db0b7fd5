"""Sweeps over the keys of a case file (``slipcycle sweep CASE --set key=start:stop:num``).

Each ``--set`` names a dotted key of the case (``loading.lam``, ``discrete.friction``,
``loading.p1[1]`` for one entry of a list) and its values; the sweep runs the case's model
(:func:`slipcycle.cli.models.run_model`, any model: a halfspace case with
``--set loading.Q1=… --set loading.phase=…`` gives a Ŵ map) for every combination and
stores the numeric entries of each ``summary.json`` as one cell of a Zarr store
(:mod:`slipcycle.sweep.core`). ``steady_state`` is stored as an integer code (its meaning
in the ``steady_state_codes`` attribute); wall times are left out so that a sweep is
reproducible bit for bit.
"""

from __future__ import annotations

import copy
import re
from functools import partial

import numpy as np

from slipcycle.io import Case, CaseError
from slipcycle.io.case import parse_case_text
from slipcycle.sweep.core import Axis, SweepError, parse_values

__all__ = ["apply_overrides", "case_task", "parse_set", "validate_cells", "make_task",
           "STEADY_CODES"]

#: integer codes of ``steady_state`` in sweep stores
STEADY_CODES = ("shakedown", "cyclic_slip", "ratcheting", "not_converged", "inadmissible",
                "failed")

_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(\[(\d+)\])?$")

_VALIDATORS = {
    "discrete": "slipcycle.discrete.case:read_discrete_case",
    "halfspace": "slipcycle.halfspace.case:parse_case",
    "rods": "slipcycle.rods.case:parse_case",
}


def parse_set(items: list[str]) -> list[Axis]:
    """``["loading.lam=1:2:41", …]`` → axes. Raises :class:`SweepError` naming the option."""
    axes = []
    seen = set()
    for item in items or []:
        if "=" not in item:
            raise SweepError("--set", f"expected key=start:stop:num or key=a,b,c, got {item!r}")
        key, spec = item.split("=", 1)
        key = key.strip()
        if not key or any(not _KEY.match(p) for p in key.split(".")):
            raise SweepError("--set", f"invalid key {key!r} (dotted name such as loading.lam "
                             "or loading.p1[0])")
        if key in seen:
            raise SweepError(f"--set {key}", "given twice")
        seen.add(key)
        axes.append(Axis(key, tuple(parse_values(spec, key))))
    if not axes:
        raise SweepError("--set", "give at least one --set key=start:stop:num")
    return axes


def apply_overrides(data: dict, params: dict) -> dict:
    """A deep copy of the TOML document ``data`` with dotted keys set to new values.

    Raises
    ------
    CaseError
        If a parent table is missing or an indexed entry does not exist.
    """
    data = copy.deepcopy(data)
    for key, value in params.items():
        parts = key.split(".")
        node = data
        for i, part in enumerate(parts):
            m = _KEY.match(part)
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


def _case_with(case_text: str, case_path, params: dict) -> Case:
    from pathlib import Path

    base = parse_case_text(case_text, Path(case_path) if case_path else None)
    data = apply_overrides(base.data, params)
    return Case(model=data.get("model", base.model), data=data, text=case_text,
                path=base.path)


def validate_cells(case_text: str, case_path, axes: list[Axis], max_checked: int = 256
                   ) -> None:
    """Validate the case with every cell's values (or a spread of ``max_checked`` cells
    including all corners) with the model's reader, before any computation."""
    import importlib
    import itertools

    sizes = [a.size for a in axes]
    cells = list(itertools.product(*(range(s) for s in sizes)))
    if len(cells) > max_checked:
        corners = list(itertools.product(*[(0, s - 1) for s in sizes]))
        step = max(1, len(cells) // max_checked)
        cells = sorted(set(corners) | set(cells[::step]))
    base = parse_case_text(case_text)
    target = _VALIDATORS.get(base.model)
    for cell in cells:
        params = {a.name: a.values[i] for a, i in zip(axes, cell, strict=True)}
        case = _case_with(case_text, case_path, params)
        if target:
            mod, fn = target.split(":")
            try:
                getattr(importlib.import_module(mod), fn)(case)
            except CaseError as exc:
                raise CaseError(exc.key, f"{exc.problem} (with "
                                + ", ".join(f"{k} = {v}" for k, v in params.items())
                                + ")") from None


def summary_numbers(summary: dict) -> dict:
    """Numeric entries of a summary (scalars, fixed-length numeric lists); steady_state as
    its code in :data:`STEADY_CODES`; wall times and metadata left out."""
    out = {}
    for k, v in summary.items():
        if "wall_time" in k or k in ("metadata", "n_nodes"):
            continue
        if k == "steady_state" and isinstance(v, str):
            out[k] = STEADY_CODES.index(v) if v in STEADY_CODES else len(STEADY_CODES) - 1
            continue
        if isinstance(v, bool | int | float | np.number | np.bool_):
            out[k] = float(v) if isinstance(v, float | np.floating) else v
            continue
        if isinstance(v, list | tuple | np.ndarray):
            try:
                arr = np.asarray(v, dtype=float)
            except (TypeError, ValueError):
                continue
            if arr.ndim == 1 and arr.size and k not in ("slipping_nodes",
                                                        "permanently_stuck_nodes",
                                                        "separating_nodes"):
                out[k] = arr
            elif k in ("slipping_nodes", "permanently_stuck_nodes", "separating_nodes"):
                out[f"n_{k}"] = len(v)
    return out


def case_task(params: dict, case_text: str, case_path) -> dict:
    """Run the case with ``params`` applied; return :func:`summary_numbers` of its summary.

    Module-level so that process pools and Dask workers can unpickle it."""
    from slipcycle.cli.models import run_model

    case = _case_with(case_text, case_path, params)
    out = run_model(case)
    return summary_numbers(out.summary)


def make_task(case_text: str, case_path):
    """The picklable task of a case sweep."""
    return partial(case_task, case_text=case_text,
                   case_path=str(case_path) if case_path else None)
