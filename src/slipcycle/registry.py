"""One registry of the models: name → case reader, solver entry point, commands.

Every model package plugs in here by name. The entries are dotted strings resolved with
:mod:`importlib` on first use, so that this module imports nothing of slipcycle and can sit
below every other layer (``io`` asks it which commands serve a model, ``sweep`` and the
demo run any model through it, the command line lists the models it serves), while
``slipcycle --help`` stays fast.

A model's ``runner`` is ``run_case(case: Case) -> RunOutputs``: it validates the whole case
(raising :class:`~slipcycle.io.CaseError` before any computation), solves, and returns the
summary, Dataset and figures. Its ``validator`` reads and checks the case without solving
(used by sweeps to check every cell before the first run).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["ModelEntry", "MODELS", "MODEL_RUNNERS", "MODEL_COMMANDS", "RUN_MODELS",
           "resolve", "runner", "validator", "run_model"]


@dataclass(frozen=True)
class ModelEntry:
    """What slipcycle knows about one ``model = "..."`` of a case file.

    Attributes
    ----------
    runner : str or None
        ``"module:function"`` of ``run_case(case) -> RunOutputs``; None for a model that
        ``slipcycle run`` does not solve (``fe`` is reduced, not run).
    validator : str or None
        ``"module:function"`` that reads and checks a case of this model without solving.
    commands : tuple of str
        The ``slipcycle`` commands that take cases of this model.
    """

    runner: str | None
    validator: str | None
    commands: tuple[str, ...]


MODELS: dict[str, ModelEntry] = {
    "halfspace": ModelEntry("slipcycle.halfspace.case:run_case",
                            "slipcycle.halfspace.case:parse_case", ("run", "map", "sweep")),
    "discrete": ModelEntry("slipcycle.discrete.case:run_case",
                           "slipcycle.discrete.case:read_discrete_case",
                           ("run", "shakedown", "basins", "sweep")),
    "rods": ModelEntry("slipcycle.rods.case:run_case", "slipcycle.rods.case:parse_case",
                       ("run", "limits", "sweep")),
    "fe": ModelEntry(None, "slipcycle.fe.model:build_problem", ("reduce",)),
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
