"""A figure named by its plot function: what a result's ``figures()`` returns.

A result names each of its figures by the dotted path of the :mod:`slipcycle.plot`
function that draws it and the data it takes (Datasets, arrays, numbers), as
:mod:`slipcycle.registry` names the models: the model packages stand below the figures and
never import :mod:`slipcycle.plot` (contract ``models-below-studies`` in
``pyproject.toml``), and matplotlib is imported only when a figure is drawn. A task is a
frozen dataclass of picklable parts, so the command line's figure worker
(:mod:`slipcycle.cli.figure_worker`) can draw it in another process.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass, field

__all__ = ["FigureTask", "figure_task"]


@dataclass(frozen=True)
class FigureTask:
    """One figure: ``target(*args, **kwargs)`` returns a matplotlib Figure.

    Attributes
    ----------
    target : str
        ``"package.module:function"`` of a plot function, e.g.
        ``"slipcycle.plot.discrete:hysteresis"``.
    args : tuple
        Its positional arguments (picklable for the figure worker).
    kwargs : mapping
        Its keyword arguments.
    """

    target: str
    args: tuple = ()
    kwargs: Mapping = field(default_factory=dict)

    def __post_init__(self):
        module, sep, name = self.target.partition(":")
        if not (sep and module and name):
            raise ValueError(f"figure target must be 'package.module:function', got "
                             f"{self.target!r}")

    @property
    def function(self):
        """The plot function named by :attr:`target` (its module imported on first use)."""
        module, _, name = self.target.partition(":")
        return getattr(importlib.import_module(module), name)

    def __call__(self):
        """Draw the figure.

        Returns
        -------
        matplotlib.figure.Figure
        """
        return self.function(*self.args, **self.kwargs)


def figure_task(target: str, *args, **kwargs) -> FigureTask:
    """``FigureTask(target, args, kwargs)``: the figure ``target(*args, **kwargs)``."""
    return FigureTask(target, args, kwargs)
