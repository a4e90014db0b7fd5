"""``slipcycle roughness CASE.toml --out DIR``: rough interface from measured topography.

The case is a half-space case with ``profile = "topography"`` (a ``topography_file`` in any
format SurfaceTopography reads, ``nominal_area``, elastic constants) and harmonic loads; an
optional ``[roughness]`` table sets ``short_cutoffs`` and ``long_cutoffs`` (wavelengths,
m), ``phases``, ``grids`` (BEM grid sizes), ``sliders``, ``rings`` and ``tolerance``. The
study computes the BEM normal law P(U) and its exponential fit (γσ and the load window where
it holds), the dissipation per cycle of the rough joint and its phase dependence, its
convergence in BEM grid and slider count, the cut-off wavelengths that change dissipation and
stiffness by the tolerance (5 %), and the local fretting map of a flat punch of the nominal
area (Barber 2012, §4.6). Needs the ``topo`` extra (``pip install 'slipcycle[topo]'``).
BEM laws are cached (``$SLIPCYCLE_CACHE``, default ``~/.cache/slipcycle/bem``).
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from slipcycle.cli.common import StageBar, print_result, progress_enabled

log = logging.getLogger("slipcycle")


def add_parser(sub) -> None:
    p = sub.add_parser("roughness", help="rough interface from topography: BEM law, "
                       "dissipation, the wavelengths that matter",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file with profile = \"topography\"")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.io import read_case, write_outputs
    from slipcycle.studies.roughness import parse_roughness_case, roughness_study

    case = read_case(args.case, models=["halfspace"])
    with StageBar(progress_enabled(args), "roughness: BEM and slider beds") as bar:
        model, source, settings = parse_roughness_case(case)
        outputs = roughness_study(model, source, settings).to_outputs()
        bar.stage("write")
        write_outputs(args.out, outputs, case.text, case.path)
    print_result(args, outputs.summary, (
        "gamma_sigma", "gamma", "exponential_fit_pressure_range", "dissipation_per_cycle",
        "dissipation_per_area", "short_cutoff_dissipation", "short_cutoff_stiffness",
        "long_cutoff_dissipation", "long_cutoff_stiffness", "fretting_map_total",
        "fretting_map_smooth_dissipation", "wall_time_s"))
    return 0
