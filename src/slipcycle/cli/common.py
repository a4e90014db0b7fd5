"""Options shared by the commands that run through the sweep engine (sweep, basins,
shakedown)."""

from __future__ import annotations

import argparse


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


def finish_study(status, args: argparse.Namespace, case, keys: tuple[str, ...], *,
                 what: str = "stopped", unit: str = "cells", write: bool = True) -> int:
    """End a resumable command: report progress if it stopped early; otherwise write its
    outputs (unless the study wrote them itself), print the ``keys`` of its summary as JSON
    and where the results went. Returns the exit code (0)."""
    import json

    from slipcycle.io import write_outputs

    if not status.complete:
        print(f"{what} with {status.cells_done} of {status.cells_total} {unit} done; "
              "complete it with --resume", flush=True)
        return 0
    if write:
        write_outputs(args.out, status.outputs, case.text, case.path)
    summary = status.outputs.summary
    print(json.dumps({k: summary[k] for k in keys}, indent=2, default=str))
    print(f"results written to {args.out}/")
    return 0


def study_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of the library's resumable studies from the common options."""
    return {"workers": args.workers, "scheduler": args.scheduler, "resume": args.resume,
            "progress": not args.no_progress, "stop_after": args.stop_after}
