"""``slipcycle shakedown CASE.toml --out DIR``: safe region and critical load factors.

For a discrete case (Barber 2012): the safe shakedown region
S(λ) = {v : G v ≤ h0 + λ m} (extreme constraint positions), λ2 (largest λ with S(λ)
non-empty, one LP), λ1 (largest λ with all 2N constraints active, redundancy LPs and
bisection), and brackets of λ3 (every node slips in every steady cycle) and λ4 (all nodes
slip or separate at one instant) from simulations over ``--lam-points`` values of λ in
[0, ``--lam-max``] (default 2 λ2) and ``--starts`` random admissible initial slips plus the
case's own initial condition. The simulation runs go through the sweep machinery
(``DIR/scan.zarr``, ``--resume``, ``--workers``, ``--scheduler``). The grid brackets are
then narrowed by bisection in λ to ``--lam-tol`` × lam_max, each trial λ simulated from
the same starts (same seeding rule); trial runs are checkpointed in ``DIR/refine.json``
after every step, so ``--resume`` does not recompute them.

summary.json: ``lambda1``, ``lambda2``, ``lambda3_bracket``, ``lambda4_bracket`` (refined)
and ``lambda3_grid_bracket``, ``lambda4_grid_bracket``, the extreme constraint data, the
runs supporting each bracket (``lambda3_evidence``, ``lambda4_evidence``: the runs at the
final lo and hi), ``refinement`` (trial λ values, number of runs), and the case's own run.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from slipcycle.cli.common import add_common, count_option, finish_study, study_options


def add_parser(sub) -> None:
    p = sub.add_parser("shakedown", help="safe shakedown region and λ1…λ4 of a discrete case",
                       description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file (model = \"discrete\")")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--lam-max", type=float, default=None, help="largest λ simulated")
    p.add_argument("--lam-points", type=count_option, default=21, help="λ values simulated")
    p.add_argument("--starts", type=count_option, default=8,
                   help="random initial slips per λ")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--tol", type=float, default=1e-9, help="relative tolerance of λ1")
    p.add_argument("--lam-tol", type=float, default=1e-3,
                   help="width to which the λ3/λ4 brackets are bisected, relative to "
                        "lam_max (1: no refinement)")
    add_common(p)
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.io import read_case
    from slipcycle.studies.shakedown import shakedown_study

    case = read_case(args.case, models=["discrete"])
    status = shakedown_study(case, args.out, lam_max=args.lam_max, lam_points=args.lam_points,
                             starts=args.starts, seed=args.seed, tol=args.tol,
                             lam_tol=args.lam_tol, **study_options(args))
    return finish_study(status, args, case, ("lambda1", "lambda2", "lambda3_bracket",
                                             "lambda4_bracket", "regime"), unit="runs")
