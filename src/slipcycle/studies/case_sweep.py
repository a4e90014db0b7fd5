"""Sweeps over the keys of a case file (``slipcycle sweep CASE --set key=start:stop:num``).

Each ``--set`` names a dotted key of the case (``loading.lam``, ``discrete.friction``,
``loading.p1[1]`` for one entry of a list) and its values; the sweep runs the case's model
(:func:`slipcycle.run`, any model: a halfspace case with
``--set loading.Q1=… --set loading.phase=…`` gives a Ŵ map) for every combination and
stores the numeric entries of each ``summary.json`` as one cell of a Zarr store
(:mod:`slipcycle.sweep.core`). What the entries mean comes from the model's own result
description (:class:`slipcycle.io.RunOutputs`): a categorical entry listed in its ``flags``
is stored as the integer position of its word, with CF ``flag_values``/``flag_meanings``;
one the model gives no words for is stored as text (never as a code that could be
wrong); every entry carries the ``units`` of the summary's ``units`` map, and none where
the model gives none. Wall times are left out so that a sweep is reproducible bit for
bit.

A cell whose run stops with a user-facing error (:class:`~slipcycle.errors.InputError`,
:class:`~slipcycle.errors.SolverError`: a friction of zero, an amplitude too small to
solve) does not stop the sweep: it is stored as failed (``steady_state_class`` = the code
of ``failed``, its message in the text output ``error``, other outputs NaN) and the
summary counts the failed runs. A bug still stops the sweep, finished cells kept.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from functools import partial
from pathlib import Path

import numpy as np

from slipcycle import registry
from slipcycle.api import apply_overrides, as_case, run
from slipcycle.errors import InputError, SolverError
from slipcycle.io import Case, CaseError, RunOutputs
from slipcycle.io.case import parse_case_text
from slipcycle.result import STEADY_STATES
from slipcycle.sweep.core import (
    Axis,
    CellOutputs,
    SweepError,
    SweepStore,
    check_size,
    lock_store,
    no_store_to_resume,
    parse_values,
    run_sweep,
)
from slipcycle.sweep.dataset import StudyStatus, as_case_error, store_dataset

__all__ = ["apply_overrides", "case_task", "parse_set", "validate_cells", "make_task",
           "summary_numbers", "sweep_outputs", "run_case_sweep", "StudyStatus",
           "failed_cell"]

_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(\[(\d+)\])?$")

#: the stored output of a failed run's class, and of its message
CLASS, ERROR = "steady_state_class", "error"


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
        values = parse_values(spec, key)
        distinct: set = set()
        # hashing, not pairwise comparison: an axis may have 10^6 values (1 == 1.0)
        twice = sorted({repr(v) for v in values if v in distinct or distinct.add(v)})
        if twice:
            # two cells with one coordinate: the store could not tell them apart
            raise SweepError(f"--set {key}", f"value {', '.join(twice)} given more than "
                             "once; each value of a sweep axis must be distinct")
        axes.append(Axis(key, tuple(values)))
    if not axes:
        raise SweepError("--set", "give at least one --set key=start:stop:num")
    check_size([a.size for a in axes], "--set")
    return axes


def _case_with(case_text: str, case_path, params: dict) -> Case:
    """The case of one cell: the same override path as ``slipcycle.run(case, params)``
    (:func:`slipcycle.api.as_case`), so a cell is the case file edited to its values."""
    base = parse_case_text(case_text, Path(case_path) if case_path else None)
    return as_case(base, params)


def validate_cells(case_text: str, case_path, axes: list[Axis], max_checked: int = 256
                   ) -> None:
    """Validate the case with every cell's values (or a spread of ``max_checked`` cells
    including all corners) with the model's reader, before any computation."""
    import itertools

    sizes = [a.size for a in axes]
    total = math.prod(sizes)
    if total <= max_checked:
        cells = list(itertools.product(*(range(s) for s in sizes)))
    else:
        # every corner and an even spread, without listing the whole grid
        corners = set(itertools.product(*[(0, s - 1) for s in sizes]))
        step = max(1, total // max_checked)
        spread = zip(*np.unravel_index(np.arange(0, total, step), sizes), strict=True)
        cells = sorted(corners | {tuple(int(i) for i in c) for c in spread})
    base = parse_case_text(case_text)
    read = registry.validator(base.model)
    for cell in cells:
        params = {a.name: a.values[i] for a, i in zip(axes, cell, strict=True)}
        case = _case_with(case_text, case_path, params)
        if read is not None:
            try:
                read(case)
            except CaseError as exc:
                raise CaseError(exc.key, f"{exc.problem} (with "
                                + ", ".join(f"{k} = {v}" for k, v in params.items())
                                + ")") from None


_COUNTED = ("slipping_nodes", "permanently_stuck_nodes", "separating_nodes")


def summary_numbers(summary: dict, flags: Mapping[str, tuple] | None = None
                    ) -> CellOutputs:
    """The entries of a summary that a sweep stores, with their attributes.

    Parameters
    ----------
    summary : dict
        A model's summary (``RunOutputs.summary``); its ``units`` map gives the unit of
        each numeric entry.
    flags : mapping, optional
        ``RunOutputs.flags``: categorical entry -> every word it can take.

    Returns
    -------
    CellOutputs
        Scalars and fixed-size numeric lists (nested: tables such as protocol × bolt) as
        numbers; a categorical entry listed in
        ``flags`` as the position of its word (attributes ``flag_values``,
        ``flag_meanings``); any other text entry as text; lists of node indices as their
        count ``n_<key>``. ``attrs[name]["units"]`` is the summary's unit of the entry,
        absent where the model gives none. Wall times, metadata, ``model`` and
        ``n_nodes`` are left out.

    Raises
    ------
    ValueError
        If a categorical entry holds a word its ``flags`` do not list (a model defect:
        storing it would give a wrong code).
    """
    flags = dict(flags or {})
    units = summary.get("units") if isinstance(summary.get("units"), Mapping) else {}
    out, attrs = {}, {}
    for k, v in summary.items():
        if "wall_time" in k or k in ("metadata", "n_nodes", "units", "model"):
            continue
        if isinstance(v, str):
            words = flags.get(k)
            if words is None:
                out[k] = v
                continue
            words = tuple(str(w) for w in words)
            if v not in words:
                raise ValueError(f"summary entry {k!r} is {v!r}, not one of the words the "
                                 f"model lists for it: {', '.join(words)}")
            if any(len(w.split()) != 1 for w in words):
                raise ValueError(f"the words of {k!r} must be single blank-free words "
                                 f"(CF flag_meanings), got {words}")
            out[k] = np.int64(words.index(v))
            attrs[k] = {"flag_values": list(range(len(words))),
                        "flag_meanings": " ".join(words)}
            continue
        if k in _COUNTED and isinstance(v, list | tuple | np.ndarray):
            out[f"n_{k}"] = len(v)
            attrs[f"n_{k}"] = {"units": "1", "long_name": f"number of {k.replace('_', ' ')}"}
            continue
        if isinstance(v, bool | int | float | np.number | np.bool_):
            out[k] = float(v) if isinstance(v, float | np.floating) else v
        elif isinstance(v, list | tuple | np.ndarray):
            try:
                arr = np.asarray(v, dtype=float)
            except (TypeError, ValueError):
                continue
            if not arr.size:
                continue
            out[k] = arr
        else:
            continue
        if k in units and units[k] is not None:
            attrs.setdefault(k, {})["units"] = str(units[k])
    return CellOutputs(out, attrs)


def failed_cell(exc: BaseException) -> CellOutputs:
    """The outputs of a cell whose run stopped with ``exc``: the ``failed`` class code and
    the error's one-line message (every other output is NaN in the store)."""
    message = " ".join(str(exc).split()) or type(exc).__name__
    return CellOutputs({CLASS: np.int64(STEADY_STATES.index("failed")), ERROR: message},
                       {CLASS: {"flag_values": list(range(len(STEADY_STATES))),
                                "flag_meanings": " ".join(STEADY_STATES)}})


def case_task(params: dict, case_text: str, case_path) -> dict:
    """Run the case with ``params`` applied; return :func:`summary_numbers` of its summary,
    or :func:`failed_cell` if the run stops with an input or solver error.

    Module-level so that process pools and Dask workers can unpickle it."""
    try:
        result = run(_case_with(case_text, case_path, params))
    except (InputError, SolverError) as exc:
        return failed_cell(exc)
    return summary_numbers(result.summary(), result.flags)


def make_task(case_text: str, case_path):
    """The picklable task of a case sweep."""
    return partial(case_task, case_text=case_text,
                   case_path=str(case_path) if case_path else None)


#: the unit of a case key by its last name (the same meaning in every model;
#: README, docs/*.md): a sweep axis is a coordinate of ``result.nc`` and needs its unit
_KEY_UNITS = {
    **dict.fromkeys(("friction", "nu", "lam", "compliance_ratio", "frequency_ratio",
                     "damping_ratio", "grading", "rtol", "steady_tol", "difference_tol",
                     "step_tolerance", "lam_tol", "exponent", "iwan_chi", "iwan_beta",
                     "amplitude_ratio"), "1"),
    **dict.fromkeys(("cycles", "steps_per_cycle", "sliders", "modes", "rings", "elements",
                     "refine", "bolt_count", "bem_grid", "assembly_steps", "lam_points",
                     "f_crit_exact_max_nodes"), "1"),
    **dict.fromkeys(("E", "bolt_modulus", "contact_modulus"), "Pa"),
    **dict.fromkeys(("radius", "L", "height", "width", "thickness", "contact_width",
                     "gamma_sigma", "bolt_diameter", "washer_diameter", "mesh_size",
                     "overlap", "plate_length", "plate_width", "end_relief",
                     "end_relief_depth", "reference_depth", "coordinates", "initial_slip",
                     "U0", "U1", "V0", "V1"), "m"),
    **dict.fromkeys(("phase", "p1_phase", "q1_phase", "P1_phase", "rotation_amplitude"),
                    "rad"),
    **dict.fromkeys(("p0", "q0", "p1", "q1", "axial_force", "preload",
                     "service_amplitude"), "N"),
    **dict.fromkeys(("A", "B", "C"), "N/m"),
    "density": "kg m-3", "area": "m2", "nominal_area": "m2", "interface_stiffness": "N m-3",
}


def axis_units(case: Case, key: str) -> str | None:
    """The unit of the case key ``key`` (a sweep axis, ``loading.Q1``, ``loading.p1[0]``),
    or None where slipcycle does not know it (then none is written: no unit is guessed).

    The half-space loads of a plane contact (``profile = "cylinder"``) are line loads
    [N/m], as in its summary.
    """
    m = _KEY.match(key.split(".")[-1])
    name = m.group(1) if m else ""
    if case.model == "halfspace" and name in ("P0", "P1", "Q0", "Q1"):
        table = case.data.get("halfspace")
        plane = isinstance(table, Mapping) and table.get("profile") == "cylinder"
        return "N/m" if plane else "N"
    return _KEY_UNITS.get(name)


def sweep_outputs(case: Case, store: SweepStore, axes: list[Axis], store_path) -> RunOutputs:
    """Summary and Dataset of a finished case sweep.

    Returns
    -------
    RunOutputs
        ``summary``: ``model``, ``analysis`` ("sweep"), ``axes`` (name -> values),
        ``runs``, ``failed_runs`` (runs stopped by an input or solver error) and
        ``first_failure`` (the message of the first in grid order, with its values, or
        None), ``store``, ``outputs`` (names), ``flags`` and ``units`` of the stored
        outputs and of the axes (``axes.<key>``, :func:`axis_units`),
        ``dissipation_per_cycle`` ({min, max} over the cells [J], or None);
        ``dataset``: :func:`~slipcycle.sweep.dataset.store_dataset`, each axis coordinate
        with its unit.
    """
    ds = store_dataset(store, axes)
    axis_unit = {a.name: axis_units(case, a.name) for a in axes}
    for a, dim in zip(axes, ds["done"].dims, strict=True):
        if axis_unit[a.name] is not None:   # an integer axis would otherwise read as "1"
            ds[dim].attrs["units"] = axis_unit[a.name]
    data = store.read()
    described = store.output_attrs
    errors = data.get(ERROR, np.full(store.shape, ""))
    failed = [idx for idx in np.ndindex(*store.shape) if errors[idx]]
    first = None
    if failed:
        first = f"{errors[failed[0]]} (with " + ", ".join(
            f"{a.name} = {a.values[i]}" for a, i in zip(axes, failed[0], strict=True)) + ")"
    summary = {"model": case.model, "analysis": "sweep",
               "axes": {a.name: list(a.values) for a in axes},
               "runs": int(store.done().size), "failed_runs": len(failed),
               "first_failure": first, "store": str(store_path),
               "outputs": sorted(data),
               "flags": {k: v["flag_meanings"].split() for k, v in described.items()
                         if "flag_meanings" in v},
               "units": {**{k: v["units"] for k, v in described.items() if "units" in v},
                         **{f"axes.{k}": u for k, u in axis_unit.items() if u is not None}}}
    d = data.get("dissipation_per_cycle")
    if d is not None and d.dtype.kind == "f" and np.isfinite(d).any():
        summary["dissipation_per_cycle"] = {"min": float(np.nanmin(d)),
                                            "max": float(np.nanmax(d))}
    else:
        summary["dissipation_per_cycle"] = None
    return RunOutputs(summary=summary, dataset=ds)


def run_case_sweep(case: Case, sets: list[str], out, *, resume: bool = False,
                   workers: int | None = None, scheduler=None, progress: bool = True,
                   stop_after: int | None = None, write=None) -> StudyStatus:
    """Run ``case`` for every combination of the ``sets`` values into ``out/sweep.zarr``.

    Parameters
    ----------
    case : Case
        A case of any model that :func:`slipcycle.run` solves.
    sets : list of str
        ``"key=start:stop:num"`` or ``"key=a,b,c"`` (dotted case keys, ``key[i]`` for a
        list entry); one sweep axis each, Cartesian product.
    out : path
        Output directory; the store is ``out/sweep.zarr``.
    resume : bool
        Complete an interrupted sweep (its store must exist).
    workers, scheduler, progress, stop_after
        See :func:`~slipcycle.sweep.core.run_sweep`.
    write : callable, optional
        ``write(outputs)``, called with the finished results while the store is still
        locked (so that a second sweep on ``out`` stops at once until they are written).

    Returns
    -------
    StudyStatus
        ``outputs`` (see :func:`sweep_outputs`) once every cell is done.

    Raises
    ------
    CaseError
        A refused option or cell, before any computation.
    """
    store_path = Path(out) / "sweep.zarr"
    try:
        axes = parse_set(sets)
        validate_cells(case.text, case.path, axes)
        if resume and not store_path.exists():
            raise no_store_to_resume(store_path)
        # held until the outputs are written: a second sweep on --out stops at once
        with lock_store(store_path):
            store = run_sweep(make_task(case.text, case.path), axes, store_path,
                              description={"case": case.text, "command": "sweep",
                                           # codes and units from the model's flags
                                           # (stores of older versions are not resumed)
                                           "store_format": 2},
                              resume=resume, workers=workers, scheduler=scheduler,
                              progress=progress, stop_after=stop_after)
            done = store.done()
            if not done.all():
                return StudyStatus(None, int(done.sum()), int(done.size))
            outputs = sweep_outputs(case, store, axes, store_path)
            if write is not None:
                write(outputs)
    except SweepError as exc:
        raise as_case_error(exc) from None
    return StudyStatus(outputs, int(done.size), int(done.size))
