"""``slipcycle run CASE.toml --out DIR``: validate, solve, write results.

Writes ``DIR/summary.json`` (the numbers, with their ``units`` and the provenance),
``DIR/result.nc`` (CF-1.10 netCDF of the full histories) and ``DIR/figures/*.png``, then
prints a short summary (steady state, cycles, dissipation per cycle, where the files are;
``--verbose`` adds every number). Only the case's model is imported; the figures are drawn by worker
processes that load matplotlib while the case is solved.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from slipcycle.cli.common import (
    StageBar,
    Timer,
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
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.api import run
    from slipcycle.cli.figure_worker import FigureWorker
    from slipcycle.io import read_case, write_outputs
    from slipcycle.registry import RUN_MODELS

    clock = Timer()
    case = read_case(args.case, models=list(RUN_MODELS))
    log.info("case %s (model %s) read in %s", args.case, case.model, clock)
    # before the solve (and before any thread): matplotlib loads beside the solve
    worker = FigureWorker.start()
    try:
        with StageBar(progress_enabled(args), f"{case.model}: solve") as bar:
            result = run(case, progress=bar.update)
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
