"""``slipcycle limits CASE.toml --tolerance 0.05 --out DIR``: limits of quasi-static analysis.

The case names ``model = "rods"`` (see docs/rods.md). The command sweeps Ω/ω1 at the case
amplitude and finds ``qs_limit_frequency_ratio``, the frequency ratio below which the
quasi-static and dynamic maximum interface torques agree within the tolerance (and,
separately, ``qs_limit_frequency_ratio_dissipation`` for the dissipation per cycle). It then
draws the regime maps: torque and dissipation ratios over Ω/ω1 × Θa/Θg (Θg: amplitude at
which a stuck interface would carry the gross-slip torque) and over Ω/ω1 × L1/(L1 + L2).
An optional ``[limits]`` table sets the axes: ``frequency_ratio``, ``amplitude_ratio``
(each a list or ``{start, stop, num}``, geometric), ``position`` (list or
``{start, stop, num}``, linear) and ``position_frequencies`` (number of Ω/ω1 values of the
position map); ``[loading].frequency_ratio`` may then be omitted. Every point uses the
interface law and numerical settings of ``slipcycle run`` for the same case.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from slipcycle.cli.common import print_result, progress_enabled


def add_parser(sub) -> None:
    p = sub.add_parser("limits", help="limit frequency of the quasi-static analysis and regime "
                       "maps (rods)", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file with model = \"rods\"")
    p.add_argument("--tolerance", type=float, default=0.05,
                   help="relative tolerance ε on T_dyn/T_qs (default 0.05)")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--no-maps", action="store_true", help="only the 1-D frequency sweep")
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.io import read_case, write_outputs
    from slipcycle.studies.limits import limits_study, parse_limits

    case = read_case(args.case, models=["rods"])
    lc = parse_limits(case, args.tolerance, maps=not args.no_maps)
    out = limits_study(lc, maps=not args.no_maps, progress=progress_enabled(args)).to_outputs()
    write_outputs(args.out, out, case.text, case.path)
    print_result(args, out.summary, (
        "omega1", "qs_limit_frequency_ratio", "qs_limit_frequency_ratio_status",
        "qs_limit_frequency_ratio_dissipation", "poles_frequency_ratio"))
    return 0
