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
