"""Figures named by their plot function (:mod:`slipcycle.figure_task`): the model packages
reach :mod:`slipcycle.plot` only through such names, so every name written in the source
must resolve to a plot function, and a task must survive pickling (the figure worker)."""

from __future__ import annotations

import importlib
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

from slipcycle.figure_task import FigureTask, figure_task

SRC = Path(__file__).resolve().parents[1] / "src" / "slipcycle"
TARGET = re.compile(r"[\"'](slipcycle\.plot\.[a-z0-9_]+):([a-z_][a-z0-9_]*)[\"']")
PREFIX = re.compile(r"[\"'](slipcycle\.plot\.[a-z0-9_]+):[\"']\s*$", re.M)


def _named_targets() -> set[tuple[str, str, str]]:
    """(file, module, function) of every plot function named by string in the source;
    a prefix ``"slipcycle.plot.x:"`` joined with ``+ "name"`` counts too."""
    found = set()
    for path in SRC.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        for module, func in TARGET.findall(text):
            found.add((path.name, module, func))
        for line in text.splitlines():
            m = re.search(r"(\w+) = [\"'](slipcycle\.plot\.[a-z0-9_]+):[\"']", line)
            if m:
                var, module = m.groups()
                for func in re.findall(rf"\b{var} \+ [\"']([a-z_][a-z0-9_]*)[\"']", text):
                    found.add((path.name, module, func))
    return found


def test_every_plot_function_named_in_the_source_exists():
    targets = _named_targets()
    # the model packages name at least the half-space, rods and fe figures this way
    modules = {m for _, m, _ in targets}
    assert {"slipcycle.plot.halfspace", "slipcycle.plot.rods", "slipcycle.plot.fe"} <= modules
    missing = [(f, m, fn) for f, m, fn in sorted(targets)
               if not callable(getattr(importlib.import_module(m), fn, None))]
    assert not missing, f"figure targets that name no plot function: {missing}"


def test_no_model_package_imports_plot():
    """import-linter enforces it (contract models-below-studies); this says where."""
    offenders = []
    for pkg in ("discrete", "discrete3d", "halfspace", "rods", "fe"):
        for path in (SRC / pkg).rglob("*.py"):
            for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if re.match(r"\s*(from slipcycle\.plot\b|from slipcycle import plot\b|"
                            r"import slipcycle\.plot\b|from matplotlib|import matplotlib)",
                            line):
                    offenders.append(f"{pkg}/{path.name}:{n}")
    assert not offenders, offenders


def test_a_task_pickles_and_draws_the_named_function():
    A = np.array([[2.0, -1.0], [-1.0, 2.0]])
    task = figure_task("slipcycle.plot.fe:coupling", A, 0.1 * A, 3.0 * A)
    back = pickle.loads(pickle.dumps(task))
    assert isinstance(back, FigureTask) and back.target == task.target
    fig = back()
    images = [ax.images[0].get_array() for ax in fig.axes if ax.images]
    assert len(images) == 3
    for drawn, M in zip(images, (A, 0.1 * A, 3.0 * A), strict=True):
        np.testing.assert_array_equal(np.asarray(drawn), np.abs(M))


def test_keyword_arguments_reach_the_plot_function():
    task = figure_task("slipcycle.plot.fe:mesh_convergence", [2e-3, 1e-3], [1.0, 1.2],
                       converged=False, title="block")
    fig = task()
    assert fig.axes[0].get_title() == "block\nNOT mesh-converged"
    assert figure_task("slipcycle.plot.fe:mesh_convergence", [2e-3, 1e-3],
                       [1.0, 1.2])().axes[0].get_title() == "not assessed"


@pytest.mark.parametrize("target", ["slipcycle.plot.fe", "slipcycle.plot.fe:", ":coupling",
                                    "coupling"])
def test_a_target_without_module_and_function_is_refused(target):
    with pytest.raises(ValueError, match="package.module:function"):
        figure_task(target)
