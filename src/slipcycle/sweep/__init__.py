"""Parameter sweeps that resume and scale out (issue 4).

- :mod:`~slipcycle.sweep.core`  Cartesian grids, Zarr store (one cell per run), resume,
  local process pool / Dask cluster, progress bar
- :mod:`~slipcycle.sweep.case`  sweeps over the keys of a case file (``slipcycle sweep``)
"""

from slipcycle.sweep.core import Axis, CellOutputs, SweepError, SweepStore, run_sweep

__all__ = ["Axis", "CellOutputs", "SweepError", "SweepStore", "run_sweep"]
