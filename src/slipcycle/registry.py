"""One registry of the models: name → case reader, solver entry point, commands.

Every model package plugs in here by name. The entries are dotted strings resolved with
:mod:`importlib` on first use, so that this module imports nothing of slipcycle and can sit
below every other layer (``io`` asks it which commands serve a model, ``sweep`` and the
demo run any model through it, the command line lists the models it serves), while
``slipcycle --help`` stays fast.

A model's ``solver`` is ``solve_case(case: Case) -> RunResult``: it validates the whole
case (raising :class:`~slipcycle.io.CaseError` before any computation) and solves it into
the model's result object (:class:`slipcycle.result.RunResult`); its ``model_solver``
solves the validated model objects named in ``model_types`` (built in Python) the same
way. :func:`slipcycle.run` dispatches through both. The ``runner`` is ``run_case(case) ->
RunOutputs`` (``solve_case(case).to_outputs()``), kept for callers of this release. Its
``validator`` reads and checks the case without solving (used by sweeps to check every
cell before the first run).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["ModelEntry", "MODELS", "MODEL_RUNNERS", "MODEL_COMMANDS", "RUN_MODELS",
           "resolve", "runner", "validator", "run_model", "solver", "entry_for_object"]


@dataclass(frozen=True)
class ModelEntry:
    """What slipcycle knows about one ``model = "..."`` of a case file.

    Attributes
    ----------
    runner : str or None
        ``"module:function"`` of ``run_case(case) -> RunOutputs``; None for a model that
        ``slipcycle run`` does not solve.
    validator : str or None
        ``"module:function"`` that reads and checks a case of this model without solving.
    commands : tuple of str
        The ``slipcycle`` commands that take cases of this model.
    solver : str or None
        ``"module:function"`` of ``solve_case(case) -> RunResult`` (validate and solve).
    model_solver : str or None
        ``"module:function"`` solving a validated model object (or the items of a tuple
        of them) into the same result.
    model_types : tuple of str
        ``"module:Class"`` of the model objects ``model_solver`` takes (a tuple is
        matched on the type of its first item).
    result : str or None
        ``"module:Class"`` of the model's result (a :class:`slipcycle.result.RunResult`).
    """

    runner: str | None
    validator: str | None
    commands: tuple[str, ...]
    solver: str | None = None
    model_solver: str | None = None
    model_types: tuple[str, ...] = ()
    result: str | None = None


MODELS: dict[str, ModelEntry] = {
    "halfspace": ModelEntry(
        "slipcycle.halfspace.case:run_case", "slipcycle.halfspace.case:parse_case",
        ("run", "map", "roughness", "sweep"),
        solver="slipcycle.halfspace.case:solve_case",
        model_solver="slipcycle.halfspace.case:solve_model",
        model_types=("slipcycle.halfspace.model:HalfspaceModel",),
        result="slipcycle.halfspace.outputs:HalfspaceResult"),
    "discrete": ModelEntry(
        "slipcycle.discrete.case:run_case", "slipcycle.discrete.case:read_discrete_case",
        ("run", "shakedown", "basins", "sweep"),
        solver="slipcycle.discrete.case:solve_case",
        model_solver="slipcycle.discrete.case:solve_model",
        model_types=("slipcycle.discrete.case:DiscreteCase",
                     "slipcycle.discrete.model:FrictionalSystem"),
        result="slipcycle.discrete.case:DiscreteResult"),
    "discrete3d": ModelEntry(
        "slipcycle.discrete3d.case:run_case",
        "slipcycle.discrete3d.case:read_discrete3d_case", ("run", "sweep", "basins"),
        solver="slipcycle.discrete3d.case:solve_case",
        model_solver="slipcycle.discrete3d.case:solve_model",
        model_types=("slipcycle.discrete3d.case:Discrete3DCase",
                     "slipcycle.discrete3d.model:FrictionalSystem3D"),
        result="slipcycle.discrete3d.case:DiscreteResult3D"),
    "rods": ModelEntry(
        "slipcycle.rods.case:run_case", "slipcycle.rods.case:parse_case",
        ("run", "limits", "sweep"),
        solver="slipcycle.rods.case:solve_case",
        model_solver="slipcycle.rods.case:solve_model",
        model_types=("slipcycle.rods.case:RodsCase",),
        result="slipcycle.rods.case:RodsResult"),
    "fe": ModelEntry(
        "slipcycle.joints.fe_run:run_case", "slipcycle.joints.fe_run:read_fe_case",
        ("run", "reduce", "sweep"),
        solver="slipcycle.joints.fe_run:solve_case",
        result="slipcycle.joints.fe_run:FEResult"),
    "lap_joint": ModelEntry(
        "slipcycle.joints.lap_joint_case:run_case",
        "slipcycle.joints.lap_joint_case:read_lap_joint_case", ("run",),
        solver="slipcycle.joints.lap_joint_case:solve_case",
        model_solver="slipcycle.joints.lap_joint_case:solve_model",
        model_types=("slipcycle.joints.lap_joint_case:LapJointCase",),
        result="slipcycle.joints.lap_joint_result:LapJointResult"),
    # an FE code's export and its mesh -> a discrete3d case (slipcycle.fe_import)
    "fe_import": ModelEntry(None, None, ("reduce",)),
}

#: models that ``slipcycle run`` (and ``sweep``) solve -> their ``run_case``
MODEL_RUNNERS: dict[str, str] = {k: e.runner for k, e in MODELS.items() if e.runner}
#: the models of :data:`MODEL_RUNNERS`, in order
RUN_MODELS: tuple[str, ...] = tuple(MODEL_RUNNERS)
#: which commands serve which model (used to say where a case belongs)
MODEL_COMMANDS: dict[str, tuple[str, ...]] = {k: e.commands for k, e in MODELS.items()}


def resolve(target: str) -> Callable[..., Any]:
    """The function named by ``"package.module:function"``."""
    module_name, func = target.split(":")
    return getattr(importlib.import_module(module_name), func)


def runner(model: str) -> Callable[..., Any]:
    """``run_case`` of ``model`` (KeyError for a model that is not run)."""
    return resolve(MODEL_RUNNERS[model])


def validator(model: str) -> Callable[..., Any] | None:
    """The case reader of ``model`` (None for an unknown model)."""
    entry = MODELS.get(model)
    return resolve(entry.validator) if entry and entry.validator else None


def run_model(case):
    """Solve ``case`` (a :class:`~slipcycle.io.Case`) with its model's ``run_case``.

    Returns
    -------
    RunOutputs
        Summary, Dataset and figures of the run.
    """
    return runner(case.model)(case)


def solver(model: str) -> Callable[..., Any]:
    """``solve_case`` of ``model``: Case -> result object (KeyError if not solved)."""
    target = MODELS[model].solver
    if target is None:
        raise KeyError(model)
    return resolve(target)


def entry_for_object(obj: object) -> tuple[str, ModelEntry] | None:
    """The model whose ``model_types`` hold the type of ``obj`` (or of a base class).

    Types are compared by ``"module:qualified name"``, so nothing is imported.

    Returns
    -------
    (name, ModelEntry) or None
    """
    names = {f"{c.__module__}:{c.__qualname__}" for c in type(obj).__mro__}
    for name, entry in MODELS.items():
        if entry.model_solver and names.intersection(entry.model_types):
            return name, entry
    return None
