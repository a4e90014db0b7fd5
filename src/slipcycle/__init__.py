"""slipcycle: frictional interfaces under periodic loading.

Subpackages, one per capability:

- :mod:`slipcycle.loading`   periodic loads and assembly protocols
- :mod:`slipcycle.discrete`  coupled discrete frictional systems (Barber; Klarbring)
- :mod:`slipcycle.fe`        static reduction of finite-element models
- :mod:`slipcycle.halfspace` uncoupled half-space contacts, slider beds (Ciavarella; Jäger)
- :mod:`slipcycle.rods`      two rods with a frictional interface
- :mod:`slipcycle.io`        case files and result files
- :mod:`slipcycle.sweep`     parallel evaluation over parameter grids
- :mod:`slipcycle.kernels`   compiled kernels shared by several models (the Jenkins bed)
- :mod:`slipcycle.registry`  model name -> reader, solver, serving commands
- :mod:`slipcycle.api`       :func:`run`: any case (path, TOML text, dict, model) -> result
- :mod:`slipcycle.result`    the result contract shared by every model (:class:`RunResult`)
- :mod:`slipcycle.plot`      figures
- :mod:`slipcycle.examples`  the example case files shipped with the package
- :mod:`slipcycle.cli`       the ``slipcycle`` command

``import slipcycle`` is cheap: :func:`run`, the result types and the example helpers load
on first use, so the command line starts without NumPy until a command needs it.
"""

from typing import TYPE_CHECKING

from slipcycle._version import __version__

if TYPE_CHECKING:  # pragma: no cover - for type checkers; loaded lazily at run time
    from slipcycle.api import run
    from slipcycle.examples import example_path, list_examples
    from slipcycle.result import RunResult, SteadyState, StudyResult

__all__ = ["__version__", "run", "RunResult", "StudyResult", "SteadyState", "example_path",
           "list_examples"]

#: public names loaded on first use, so that ``import slipcycle`` stays cheap
_LAZY = {"run": "slipcycle.api", "RunResult": "slipcycle.result",
         "StudyResult": "slipcycle.result", "SteadyState": "slipcycle.result",
         "example_path": "slipcycle.examples", "list_examples": "slipcycle.examples"}


def __getattr__(name: str):
    """The names of :data:`_LAZY` (``slipcycle.run``, ...) on first use."""
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'slipcycle' has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *_LAZY])
