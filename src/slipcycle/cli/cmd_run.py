"""``slipcycle run CASE.toml --out DIR``: validate, solve, write results."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_parser(sub) -> None:
    p = sub.add_parser("run", help="run a case file and write summary.json, result.nc, figures/",
                       description=__doc__)
    p.add_argument("case", type=Path, help="TOML case file")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--quiet", action="store_true", help="do not print the summary")
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.api import run
    from slipcycle.io import read_case, write_outputs
    from slipcycle.io.results import to_jsonable
    from slipcycle.registry import RUN_MODELS

    case = read_case(args.case, models=list(RUN_MODELS))
    outputs = run(case).to_outputs()
    write_outputs(args.out, outputs, case.text, case.path)
    if not args.quiet:
        print(json.dumps(to_jsonable(outputs.summary), indent=2))
        print(f"results written to {args.out}/")
    return 0
