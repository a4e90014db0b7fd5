"""``slipcycle run CASE.toml --out DIR``: validate, solve, write results.

Writes ``DIR/summary.json`` (the numbers, with their ``units`` and the provenance),
``DIR/result.nc`` (CF-1.10 netCDF of the full histories) and ``DIR/figures/*.png``, then
prints a short summary (steady state, cycles, dissipation per cycle, where the files are;
``--verbose`` adds every number). Only the case's model is imported; the figures are drawn by worker
processes that load matplotlib while the case is solved. A case whose model runs several
independent simulations (the protocol runs of a ``lap_joint`` case) runs them in
``--workers`` processes (default: every core); the numbers do not depend on it.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from slipcycle.cli.common import (
    StageBar,
    Timer,
    Workers,
    dissipation_resolution,
    print_run_summary,
    progress_enabled,
)

log = logging.getLogger("slipcycle")


def add_parser(sub) -> None:
    p = sub.add_parser("run", help="run a case file and write summary.json, result.nc, figures/",
                       description=__doc__)
    p.add_argument("case", type=Path, help="TOML case file")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--workers", action=Workers, default=None, metavar="N",
                   help="processes for the protocol runs of a lap_joint case (default: "
                        "all cores; 1 = this process)")
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.api import run, takes_workers
    from slipcycle.cli.figure_worker import FigureWorker
    from slipcycle.io import CaseError, read_case, write_outputs
    from slipcycle.registry import RUN_MODELS

    clock = Timer()
    case = read_case(args.case, models=list(RUN_MODELS))
    log.info("case %s (model %s) read in %s", args.case, case.model, clock)
    workers = args.workers
    if not takes_workers(case.model):
        if workers is not None and workers != 1:   # one process is what it gets anyway
            raise CaseError("--workers", f"a {case.model} case is one simulation; "
                                         "--workers is for lap_joint cases (their "
                                         "protocol runs)")
    elif workers is None:
        from slipcycle.sweep.core import usable_cores

        workers = usable_cores()
    # before the solve (and before any thread): matplotlib loads beside the solve
    worker = FigureWorker.start()
    try:
        with StageBar(progress_enabled(args), f"{case.model}: solve") as bar:
            result = run(case, progress=bar.update, workers=workers)
            log.info("solved in %s", clock)
            bar.stage(f"{case.model}: write")
            outputs = result.to_outputs()
            write_outputs(args.out, outputs, case.text, case.path,
                          draw=worker.draw if worker is not None else None)
    finally:
        if worker is not None:
            worker.close()
    log.info("results written in %s", clock)
    print_run_summary(args, outputs.summary, dissipation_resolution(result))
    return 0
