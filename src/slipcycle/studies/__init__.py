"""Studies: analyses that run a model many times, above the models.

Each study takes a case or a validated model, runs it over initial conditions, load
factors, maps or meshes (through the sweep engine :mod:`slipcycle.sweep` where it resumes)
and returns a :class:`~slipcycle.result.StudyResult`. The model packages import neither
this package, nor the sweep engine, nor the figures (contract ``models-below-studies`` in
``pyproject.toml``).

- :mod:`~slipcycle.studies.basins`      steady state over initial conditions, 2-D
  (``slipcycle basins``; the runs are :mod:`slipcycle.discrete.basins`)
- :mod:`~slipcycle.studies.basins3d`    the same for ``model = "discrete3d"``
- :mod:`~slipcycle.studies.shakedown`   S(λ), λ1, λ2, λ3/λ4 brackets (``slipcycle shakedown``)
- :mod:`~slipcycle.studies.shakedown3d` λ2 with separation and the shakedown window of
  the starts of a ``discrete3d`` case (``slipcycle shakedown``)
- :mod:`~slipcycle.studies.w_hat_map`   the Ŵ(P̂1, Q̂1, φ) map of a half-space case
  (``slipcycle map``)
- :mod:`~slipcycle.studies.roughness`   which wavelengths of a rough surface matter
  (``slipcycle roughness``)
- :mod:`~slipcycle.studies.limits`      limit frequency of the quasi-static analysis of
  two rods and its regime maps (``slipcycle limits``; the analysis is
  :mod:`slipcycle.rods.limits`)
- :mod:`~slipcycle.studies.common`      the case of a sweep task, assembly protocol files
- :mod:`~slipcycle.studies.case_sweep`  sweeps over the keys of any case
  (``slipcycle sweep``)
"""

import importlib

# each study loads its model, xarray and the sweep engine: loaded on first use
_LAZY = {
    "basins_study": "basins", "BasinsResult": "basins",
    "basins3d_study": "basins3d", "Basins3DResult": "basins3d",
    "shakedown_study": "shakedown", "ShakedownResult": "shakedown",
    "shakedown3d_study": "shakedown3d",
    "parse_map_case": "w_hat_map", "w_hat_map_study": "w_hat_map", "WHatMapResult": "w_hat_map",
    "parse_roughness_case": "roughness", "roughness_study": "roughness",
    "RoughnessResult": "roughness",
    "parse_limits": "limits", "limits_study": "limits", "LimitsResult": "limits",
    "run_case_sweep": "case_sweep",
    "BasinsStudyResult": "common", "read_protocols": "common",
}

__all__ = list(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"slipcycle.studies.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'slipcycle.studies' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
