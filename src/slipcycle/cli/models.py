"""Which package runs which ``model`` of a case file.

Each model package exposes ``run_case(case: Case) -> RunOutputs``: it validates the whole
case (raising :class:`~slipcycle.io.CaseError` before any computation), solves, and returns
the summary, dataset and figures. Imports are lazy so that ``slipcycle --help`` stays fast.
"""

from __future__ import annotations

import importlib

from slipcycle.io import Case, RunOutputs

MODEL_RUNNERS = {
    "halfspace": "slipcycle.halfspace.case:run_case",
    "discrete": "slipcycle.discrete.case:run_case",
    "rods": "slipcycle.rods.case:run_case",
}


def run_model(case: Case) -> RunOutputs:
    """Dispatch ``case`` to its model's ``run_case``."""
    module_name, func = MODEL_RUNNERS[case.model].split(":")
    return getattr(importlib.import_module(module_name), func)(case)
