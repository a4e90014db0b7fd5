"""A finished sweep store as an xarray Dataset, sweep errors as case errors, and the
status of a resumable study.

Used by every analysis that runs through the sweep engine (case sweeps, the discrete
basin maps and λ scans), so that their stored outputs read back the same way.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from slipcycle.io import CaseError, RunOutputs
from slipcycle.sweep.core import Axis, SweepError, SweepStore

__all__ = ["store_dataset", "axis_dim", "as_case_error", "StudyStatus"]


@dataclass(frozen=True)
class StudyStatus:
    """How far a resumable study (a sweep, a basin map, a λ scan) got in this call.

    Attributes
    ----------
    outputs : RunOutputs or None
        Summary, Dataset and figures once every cell is done; None while cells are missing.
    cells_done, cells_total : int
        Computed cells of the store, and all of them.
    result : StudyResult or None
        The study's result object once every cell is done (an analysis: basins, λ scans);
        None before, and for a plain case sweep.
    """

    outputs: RunOutputs | None
    cells_done: int
    cells_total: int
    result: object | None = None

    @property
    def complete(self) -> bool:
        return self.outputs is not None


def as_case_error(exc: SweepError) -> CaseError:
    """The :class:`~slipcycle.io.CaseError` of a refused sweep (same key and problem)."""
    return CaseError(exc.key, exc.problem)


def axis_dim(name: str) -> str:
    """The dimension (and coordinate variable) name of the sweep axis ``name``: a CF
    variable name (letters, digits, underscores; CF §2.3), so ``loading.lam`` ->
    ``loading_lam`` and an entry of a list, ``loading.p1[0]``, -> ``loading_p1_0``
    (brackets made the name of the written coordinate invalid)."""
    return re.sub(r"_+$", "", re.sub(r"[^A-Za-z0-9_]", "_", name)) or "axis"


def store_dataset(store: SweepStore, axes: Sequence[Axis], dims: Sequence[str] | None = None,
                  attrs: Mapping[str, Mapping] | None = None):
    """The outputs of a sweep store as an xarray Dataset.

    Parameters
    ----------
    store : SweepStore
        A store whose cells are computed (missing cells read as NaN).
    axes : sequence of Axis
        The sweep axes, in store order.
    dims : sequence of str, optional
        One dimension name per axis (default: :func:`axis_dim` of the axis name).
        Per-cell vectors get a further dimension, ``node`` for ``dissipation_per_node``
        and ``initial_slip``, ``<name>_dim<k>`` otherwise.
    attrs : mapping, optional
        Output name -> attributes, overriding those the task gave with its outputs
        (units, CF flags). A variable nobody described gets none: no unit is guessed.

    Returns
    -------
    xarray.Dataset
        One variable per output over ``dims`` (plus its own dimensions), and ``done``
        (bool over ``dims``: cell computed).
    """
    import xarray as xr  # heavy; only the readers of a finished store need it

    data = store.read()
    described = store.output_attrs
    for name, extra in (attrs or {}).items():
        described[name] = {**described.get(name, {}), **extra}
    dims = list(dims or [axis_dim(a.name) for a in axes])
    coords = {}
    for d, a in zip(dims, axes, strict=True):
        coords[d] = (d, np.asarray(a.values), {"long_name": a.name})
    ds = xr.Dataset(coords=coords)
    for name, arr in data.items():
        extra = [f"{name}_dim{k}" for k in range(arr.ndim - len(dims))]
        if name == "dissipation_per_node" or name == "initial_slip":
            extra = ["node"][:arr.ndim - len(dims)]
        ds[name] = (tuple(dims) + tuple(extra), arr, dict(described.get(name, {})))
    ds["done"] = (tuple(dims), store.done(), {"long_name": "cell computed"})
    return ds
