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
integer codes with CF ``flag_values``/``flag_meanings``, every entry carries the
``units`` the model gives in its summary, and every axis is a coordinate with the unit of
its case key (``loading_Q1`` in N; ``loading.p1[0]`` becomes ``loading_p1_0``).

One sweep at a time may use a store: a second one on the same ``--out`` stops at once.
Ctrl-C stops a sweep at once (exit code 130) with every finished run stored, and says how
to complete it (``--resume``). A run that stops with an input or solver error is stored as
failed (its message in the ``error`` output) and the sweep goes on; the summary counts the
failed runs and gives the first message.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from slipcycle.cli.common import add_common, finish_study, log, study_options


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


def execute(args: argparse.Namespace) -> int:
    from slipcycle.io import read_case, write_outputs
    from slipcycle.registry import RUN_MODELS
    from slipcycle.studies.case_sweep import run_case_sweep
    from slipcycle.sweep.core import SweepInterrupted

    case = read_case(args.case, models=list(RUN_MODELS))
    try:
        status = run_case_sweep(
            case, args.sets, args.out, **study_options(args),
            write=lambda out: write_outputs(args.out, out, case.text, case.path))
    except SweepInterrupted as exc:
        # main prints the line (commands write no diagnostics themselves) and exits 130
        raise KeyboardInterrupt(interrupted_line(exc, args)) from None
    if status.complete and status.outputs.summary.get("failed_runs"):
        s = status.outputs.summary
        log.warning("%d of %d runs failed (stored as failed, message in the 'error' "
                    "output); first: %s", s["failed_runs"], s["runs"], s["first_failure"])
    return finish_study(status, args, case, ("runs", "failed_runs", "first_failure", "axes",
                                             "dissipation_per_cycle"),
                        what="sweep stopped", unit="runs", write=False)


def interrupted_line(exc, args: argparse.Namespace) -> str:
    """The one line of a sweep stopped by Ctrl-C: how far it got, how to go on."""
    if not exc.done:
        return (f"interrupted: sweep stopped before any of its {exc.total} runs finished "
                "(nothing stored); run it again to start it")
    return (f"interrupted: sweep stopped with {exc.done} of {exc.total} runs stored in "
            f"{exc.path}; complete it with the same command and --resume")
