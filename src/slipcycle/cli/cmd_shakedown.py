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

A ``model = "discrete3d"`` or ``"lap_joint"`` case: λ2 with separation (nodes open in
part of the cycle), the class reached from every start over ``--lam-points`` load factors
up to ``--lam-max`` (default 1.1 λ2), each start's largest shakedown load factor
bisected to ``--lam-tol`` × lam_max, the λ1 bracket and the class window (where one start
shakes down and another slips). The starts are the case's own and ``--protocols FILE``
(discrete3d), or the assembly protocols of ``[lap_joint.protocols]`` (λ: the service
amplitude in N). Defaults: 9 points, lam_tol 0.01; ``--starts``, ``--seed``, ``--tol``
are for discrete cases, and so are ``--workers``, ``--scheduler`` and ``--resume`` (these
runs go one after another in this process, without a sweep store).

summary.json: ``lambda1``, ``lambda2``, ``lambda3_bracket``, ``lambda4_bracket`` (refined)
and ``lambda3_grid_bracket``, ``lambda4_grid_bracket``, the extreme constraint data, the
runs supporting each bracket (``lambda3_evidence``, ``lambda4_evidence``: the runs at the
final lo and hi), ``refinement`` (trial λ values, number of runs), and the case's own run.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from slipcycle.cli.common import (
    add_common,
    count_option,
    finish_study,
    refuse_sweep_options,
    study_options,
)


def add_parser(sub) -> None:
    p = sub.add_parser("shakedown", help="safe shakedown region and λ1…λ4 of a discrete, "
                                         "discrete3d or lap_joint case",
                       description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file (model = \"discrete\", "
                                              "\"discrete3d\" or \"lap_joint\")")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--lam-max", type=float, default=None, help="largest λ simulated")
    p.add_argument("--lam-points", type=count_option, default=None,
                   help="λ values simulated (default 21; 3-D 9)")
    p.add_argument("--starts", type=count_option, default=None,
                   help="random initial slips per λ (discrete; default 8)")
    p.add_argument("--seed", type=int, default=None, help="random seed (discrete)")
    p.add_argument("--tol", type=float, default=None,
                   help="relative tolerance of λ1 (discrete; default 1e-9)")
    p.add_argument("--lam-tol", type=float, default=None,
                   help="width to which the brackets are bisected, relative to lam_max "
                        "(default 1e-3; 3-D 1e-2)")
    p.add_argument("--protocols", type=Path, default=None,
                   help="TOML file of assembly protocols (discrete3d)")
    add_common(p)
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.io import CaseError, read_case

    case = read_case(args.case, models=["discrete", "discrete3d", "lap_joint"])
    if case.model != "discrete":
        for key, value in (("--starts", args.starts), ("--seed", args.seed),
                           ("--tol", args.tol)):
            if value is not None:
                raise CaseError(key, f"is for discrete cases; a {case.model} case takes "
                                     "--lam-max, --lam-points, --lam-tol"
                                     + (", --protocols" if case.model == "discrete3d"
                                        else ""))
        refuse_sweep_options(args, f"a {case.model} shakedown study", "discrete cases")
        window = {"lam_max": args.lam_max,
                  "lam_points": 9 if args.lam_points is None else args.lam_points,
                  "lam_tol": 1e-2 if args.lam_tol is None else args.lam_tol}
        if case.model == "discrete3d":
            from slipcycle.studies.shakedown3d import shakedown3d_study

            status = shakedown3d_study(case, args.out, protocols=args.protocols, **window)
        else:
            if args.protocols is not None:
                raise CaseError("--protocols", "a lap_joint case names its protocols in "
                                               "[lap_joint.protocols]")
            from slipcycle.joints.lap_joint_shakedown import lap_joint_shakedown_study

            status = lap_joint_shakedown_study(case, args.out, **window)
        return finish_study(status, args, case, ("lambda2", "lambda1_bracket",
                                                 "class_window", "shakedown_limits"))
    if args.protocols is not None:
        raise CaseError("--protocols", "is for discrete3d cases")
    from slipcycle.studies.shakedown import shakedown_study

    status = shakedown_study(
        case, args.out, lam_max=args.lam_max,
        lam_points=21 if args.lam_points is None else args.lam_points,
        starts=8 if args.starts is None else args.starts,
        seed=args.seed or 0, tol=1e-9 if args.tol is None else args.tol,
        lam_tol=1e-3 if args.lam_tol is None else args.lam_tol, **study_options(args))
    return finish_study(status, args, case, ("lambda1", "lambda2", "lambda3_bracket",
                                             "lambda4_bracket", "regime"), unit="runs")
