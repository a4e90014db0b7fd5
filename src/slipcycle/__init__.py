"""slipcycle: frictional interfaces under periodic loading.

Subpackages, one per capability:

- :mod:`slipcycle.loading`   periodic loads and assembly protocols
- :mod:`slipcycle.discrete`  coupled discrete frictional systems (Barber; Klarbring)
- :mod:`slipcycle.fe`        static reduction of finite-element models
- :mod:`slipcycle.halfspace` uncoupled half-space contacts, slider beds (Ciavarella; Jäger)
- :mod:`slipcycle.rods`      two rods with a frictional interface
- :mod:`slipcycle.io`        case files and result files
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
