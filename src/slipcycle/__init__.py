"""slipcycle: frictional interfaces under periodic loading.

Subpackages follow the specification (SPEC.md):

- :mod:`slipcycle.loading`   periodic loads and assembly protocols (SPEC §1)
- :mod:`slipcycle.discrete`  coupled discrete frictional systems (SPEC §2)
- :mod:`slipcycle.fe`        static reduction of finite-element models (SPEC §3)
- :mod:`slipcycle.halfspace` uncoupled half-space contacts, slider beds (SPEC §4)
- :mod:`slipcycle.rods`      two rods with a frictional interface (SPEC §5)
- :mod:`slipcycle.io`        case files and result files (SPEC §6)
- :mod:`slipcycle.sweep`     parallel evaluation over parameter grids
- :mod:`slipcycle.plot`      figures
- :mod:`slipcycle.cli`       the ``slipcycle`` command
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("slipcycle")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
