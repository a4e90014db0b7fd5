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
- :mod:`slipcycle.plot`      figures
- :mod:`slipcycle.cli`       the ``slipcycle`` command
"""

from slipcycle._version import __version__

__all__ = ["__version__"]
