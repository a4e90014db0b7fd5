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
- :mod:`slipcycle.cli`       the ``slipcycle`` command
"""

from slipcycle._version import __version__

__all__ = ["__version__", "run", "RunResult", "SteadyState"]

#: public names loaded on first use, so that ``import slipcycle`` stays cheap
_LAZY = {"run": "slipcycle.api", "RunResult": "slipcycle.result",
         "SteadyState": "slipcycle.result"}


def __getattr__(name: str):
    """``slipcycle.run``, ``slipcycle.RunResult``, ``slipcycle.SteadyState`` on first use."""
    if name == "run":
        from slipcycle.api import run

        return run
    if name in ("RunResult", "SteadyState"):
        from slipcycle import result

        return getattr(result, name)
    raise AttributeError(f"module 'slipcycle' has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *_LAZY])
