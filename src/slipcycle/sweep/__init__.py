"""Parameter sweeps that resume and scale out (issue 4).

- :mod:`~slipcycle.sweep.core`  Cartesian grids, Zarr store (one cell per run), resume,
  local process pool / Dask cluster, progress bar

The engine knows no model: the sweeps over the keys of a case file (``slipcycle sweep``)
are :mod:`slipcycle.studies.case_sweep`.
"""

from slipcycle.sweep.core import Axis, CellOutputs, SweepError, SweepStore, run_sweep

__all__ = ["Axis", "CellOutputs", "SweepError", "SweepStore", "run_sweep"]
