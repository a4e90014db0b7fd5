"""``slipcycle sweep CASE.toml --set KEY=START:STOP:NUM [--set …] --out DIR``.

Runs the case for every combination of the ``--set`` values (Cartesian product; values
``start:stop:num`` inclusive, or a comma list ``a,b,c``; list entries as ``key[i]``).
Every run's numeric summary is stored as it finishes in ``DIR/sweep.zarr`` (one Zarr chunk
per run); ``--resume`` completes an interrupted sweep, computing only the missing cells.
Runs go to local processes (``--workers``, default all cores) or to an existing Dask
cluster (``--scheduler tcp://host:port``). When every cell is done, ``DIR/summary.json``
and ``DIR/result.nc`` (an xarray Dataset over the sweep axes) are written.

Any model works: a halfspace case with ``--set loading.Q1=… --set loading.phase=…`` gives
a Ŵ map through the same machinery. Categorical entries (``steady_state``) are stored as
integer codes with CF ``flag_values``/``flag_meanings``, and every entry carries the
``units`` the model gives in its summary.

One sweep at a time may use a store: a second one on the same ``--out`` stops at once.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np


class _Workers(argparse.Action):
    """``--workers N``: a whole number >= 1, refused in one line otherwise."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            n = int(values)
        except ValueError:
            n = 0
        if n < 1:
            # parser.exit, not parser.error: one line, no usage text
            parser.exit(2, f"error: --workers: must be a whole number >= 1, got "
                           f"{values!r}\n")
        setattr(namespace, self.dest, n)


def add_common(p) -> None:
    """Options shared by the sweep-based commands (sweep, basins, shakedown)."""
    p.add_argument("--workers", action=_Workers, default=None, metavar="N",
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


def store_dataset(store, axes, dims=None, attrs=None):
    """xarray Dataset of a sweep store (dims: one per axis, then ``node``/``i`` for
    per-cell vectors).

    Each variable carries the attributes the task gave with its outputs (units, CF flags),
    overridden by ``attrs`` (output name -> attributes) where given; a variable nobody
    described gets none (no unit is guessed).
    """
    import xarray as xr

    data = store.read()
    described = store.output_attrs
    for name, extra in (attrs or {}).items():
        described[name] = {**described.get(name, {}), **extra}
    dims = dims or [a.name.replace(".", "_") for a in axes]
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


def execute(args: argparse.Namespace) -> int:
    from slipcycle.cli.models import MODEL_RUNNERS
    from slipcycle.io import RunOutputs, read_case, write_outputs
    from slipcycle.sweep import SweepError, run_sweep
    from slipcycle.sweep.case import make_task, parse_set, validate_cells
    from slipcycle.sweep.core import lock_store, no_store_to_resume

    case = read_case(args.case, models=list(MODEL_RUNNERS))
    store_path = Path(args.out) / "sweep.zarr"
    try:
        axes = parse_set(args.sets)
        validate_cells(case.text, case.path, axes)
        if args.resume and not store_path.exists():
            raise no_store_to_resume(store_path)
        # held until the outputs are written: a second sweep on --out stops at once
        with lock_store(store_path):
            store = run_sweep(make_task(case.text, case.path), axes, store_path,
                              description={"case": case.text, "command": "sweep",
                                           # codes and units from the model's flags
                                           # (stores of older versions are not resumed)
                                           "store_format": 2},
                              resume=args.resume, workers=args.workers,
                              scheduler=args.scheduler, progress=not args.no_progress,
                              stop_after=args.stop_after)
            done = store.done()
            if not done.all():
                print(f"sweep stopped with {int(done.sum())} of {done.size} runs done; "
                      f"complete it with --resume", flush=True)
                return 0
            summary = _write_results(args, case, store, axes, store_path, RunOutputs,
                                     write_outputs)
    except SweepError as exc:
        raise as_case_error(exc) from None
    print(json.dumps({k: summary[k] for k in ("runs", "axes", "dissipation_per_cycle")},
                     indent=2, default=str))
    print(f"results written to {args.out}/")
    return 0


def _write_results(args, case, store, axes, store_path, RunOutputs, write_outputs):  # noqa: N803
    ds = store_dataset(store, axes)
    data = store.read()
    described = store.output_attrs
    summary = {"model": case.model, "analysis": "sweep",
               "axes": {a.name: list(a.values) for a in axes},
               "runs": int(store.done().size), "store": str(store_path),
               "outputs": sorted(data),
               "flags": {k: v["flag_meanings"].split() for k, v in described.items()
                         if "flag_meanings" in v},
               "units": {k: v["units"] for k, v in described.items() if "units" in v}}
    d = data.get("dissipation_per_cycle")
    if d is not None and d.dtype.kind == "f" and np.isfinite(d).any():
        summary["dissipation_per_cycle"] = {"min": float(np.nanmin(d)),
                                            "max": float(np.nanmax(d))}
    else:
        summary["dissipation_per_cycle"] = None
    write_outputs(args.out, RunOutputs(summary=summary, dataset=ds), case.text, case.path)
    return summary
