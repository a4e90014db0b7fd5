"""``slipcycle map CASE.toml --out DIR``: rough-surface dissipation map Ŵ(P̂1, Q̂1, φ).

The case names ``model = "halfspace"`` and holds a ``[map]`` table whose keys ``P1_hat``,
``Q1_hat`` and ``phase`` are each a list of values or a table ``{start, stop, num}``; the
optional ``fig7_P1_hat`` (default 0.4) and ``fig7_Q1_hat`` (default [0.2, 0.4, 0.6, 0.8])
select the curves of Barber 2012, Fig. 7, and ``[run]`` may set ``steps_per_cycle`` and
``sliders``. ``[halfspace]`` and ``[loading]`` tables may be present (so a run case can
carry its map) and are not used: Ŵ is dimensionless; W = λ_c γσ f² P0 Ŵ.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from slipcycle.cli.common import StageBar, print_result, progress_enabled

log = logging.getLogger("slipcycle")


def add_parser(sub) -> None:
    p = sub.add_parser("map", help="rough-contact dissipation map W_hat(P1_hat, Q1_hat, phase)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file with a [map] table")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.io import read_case, write_outputs
    from slipcycle.studies.w_hat_map import parse_map_case, w_hat_map_study

    case = read_case(args.case, models=["halfspace"])
    P1, Q1, ph, fig_P1, fig_Q1, settings = parse_map_case(case)
    log.info("computing W_hat on %d x %d x %d = %d points", P1.size, Q1.size, ph.size,
             P1.size * Q1.size * ph.size)
    with StageBar(progress_enabled(args), "W_hat map") as bar:
        outputs = w_hat_map_study(P1, Q1, ph, fig_P1, fig_Q1, settings).to_outputs()
        bar.stage("write")
        write_outputs(args.out, outputs, case.text, case.path)
    print_result(args, outputs.summary, ("grid_points", "wall_time_s", "cubic_law_slope",
                                         "fig7_phase_of_max"))
    return 0
