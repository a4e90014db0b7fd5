"""``slipcycle sweep CASE.toml --set KEY=START:STOP:NUM [--set …] --out DIR``.

Runs the case for every combination of the ``--set`` values (Cartesian product; values
``start:stop:num`` inclusive, or a comma list ``a,b,c``; list entries as ``key[i]``).
Every run's numeric summary is stored as it finishes in ``DIR/sweep.zarr`` (one Zarr chunk
per run); ``--resume`` completes an interrupted sweep, computing only the missing cells.
Runs go to local processes (``--workers``, default all cores) or to an existing Dask
cluster (``--scheduler tcp://host:port``). When every cell is done, ``DIR/summary.json``
and ``DIR/result.nc`` (an xarray Dataset over the sweep axes) are written.

Any model works: a halfspace case with ``--set loading.Q1=… --set loading.phase=…`` gives
a Ŵ map through the same machinery.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np


def add_common(p) -> None:
    """Options shared by the sweep-based commands (sweep, basins, shakedown)."""
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: all cores; 1 = this process)")
    p.add_argument("--scheduler", default=None,
                   help="address of an existing Dask scheduler, e.g. tcp://10.0.0.1:8786")
    p.add_argument("--resume", action="store_true",
                   help="complete an interrupted run from its Zarr store")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--stop-after", type=int, default=None, help=argparse.SUPPRESS)


def add_parser(sub) -> None:
    p = sub.add_parser("sweep", help="parameter sweep of a case file (Zarr store, resumable)",
                       description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUES",
                   help="key=start:stop:num or key=a,b,c (repeat for more axes)")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    add_common(p)
    p.set_defaults(execute=execute)


def as_case_error(exc):
    from slipcycle.io import CaseError

    return CaseError(exc.key, exc.problem)


def store_dataset(store, axes, dims=None):
    """xarray Dataset of a sweep store (dims: one per axis, then ``node``/``i`` for
    per-cell vectors)."""
    import xarray as xr

    data = store.read()
    dims = dims or [a.name.replace(".", "_") for a in axes]
    coords = {}
    for d, a in zip(dims, axes, strict=True):
        coords[d] = (d, np.asarray(a.values), {"long_name": a.name})
    ds = xr.Dataset(coords=coords)
    for name, arr in data.items():
        extra = [f"{name}_dim{k}" for k in range(arr.ndim - len(dims))]
        if name == "dissipation_per_node" or name == "initial_slip":
            extra = ["node"][:arr.ndim - len(dims)]
        units = "J" if "dissipation" in name else ("m" if "slip" in name and
                                                   "n_" not in name else "1")
        ds[name] = (tuple(dims) + tuple(extra), arr, {"units": units})
    ds["done"] = (tuple(dims), store.done(), {"units": "1"})
    return ds


def execute(args: argparse.Namespace) -> int:
    from slipcycle.cli.models import MODEL_RUNNERS
    from slipcycle.io import RunOutputs, read_case, write_outputs
    from slipcycle.sweep import SweepError, run_sweep
    from slipcycle.sweep.case import STEADY_CODES, make_task, parse_set, validate_cells

    case = read_case(args.case, models=list(MODEL_RUNNERS))
    try:
        axes = parse_set(args.sets)
        validate_cells(case.text, case.path, axes)
        store_path = Path(args.out) / "sweep.zarr"
        store = run_sweep(make_task(case.text, case.path), axes, store_path,
                          description={"case": case.text, "command": "sweep"},
                          resume=args.resume, workers=args.workers,
                          scheduler=args.scheduler, progress=not args.no_progress,
                          stop_after=args.stop_after)
    except SweepError as exc:
        raise as_case_error(exc) from None
    done = store.done()
    if not done.all():
        print(f"sweep stopped with {int(done.sum())} of {done.size} runs done; "
              f"complete it with --resume", flush=True)
        return 0
    ds = store_dataset(store, axes)
    data = store.read()
    summary = {"model": case.model, "analysis": "sweep",
               "axes": {a.name: list(a.values) for a in axes},
               "runs": int(done.size), "store": str(store_path),
               "outputs": sorted(data),
               "steady_state_codes": list(STEADY_CODES)}
    if "dissipation_per_cycle" in data:
        d = data["dissipation_per_cycle"]
        summary["dissipation_per_cycle"] = {"min": float(np.nanmin(d)),
                                            "max": float(np.nanmax(d))}
    else:
        summary["dissipation_per_cycle"] = None
    write_outputs(args.out, RunOutputs(summary=summary, dataset=ds), case.text, case.path)
    print(json.dumps({k: summary[k] for k in ("runs", "axes", "dissipation_per_cycle")},
                     indent=2, default=str))
    print(f"results written to {args.out}/")
    return 0
