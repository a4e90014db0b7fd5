"""``slipcycle basins CASE.toml --out DIR [--grid 201 | --random K | --protocols FILE]``.

Maps the steady state (class and dissipation per cycle) of a discrete case over initial
conditions (Barber 2012, Fig. 3):

- ``--grid n`` (N = 2): an n × n grid of initial slips (v1, v2) at θ = 0 over the box of
  admissible states (or ``--v1 a:b --v2 a:b``); inadmissible starts are marked; the
  box-counting dimension of the class boundaries is reported;
- ``--random K`` (any N): K random admissible initial slip states (``--seed``);
- ``--protocols FILE`` (any N): a TOML file of ``[[protocol]]`` tables, each with
  ``p_w`` and ``q_w`` lists of load states ((S, N) nested lists) visited before cycling.

A ``model = "discrete3d"`` case (isotropic Coulomb cone, any N) takes ``--random K``
(admissible initial slips, two components per node; default 16) or ``--protocols FILE``
(``p_w`` (S, N) and ``q_w`` (S, N, 2) per protocol).

A ``model = "lap_joint"`` case: the map of which assembly protocol of
``[lap_joint.protocols]`` shakes down at which service amplitude (9 amplitudes up to
``--lam`` [N], default 1.1 λ2), each protocol's largest shakedown amplitude bisected, and
the window where one protocol shakes down and another slips (as ``slipcycle shakedown``);
its runs go one after another in this process: no ``--workers``, ``--scheduler``,
``--resume``.

``--lam`` overrides ``loading.lam``. Runs go through the sweep machinery (``DIR/basins.zarr``,
``--resume``, ``--workers``, ``--scheduler``); grid rows run in parallel threads.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from slipcycle.cli.common import (
    add_common,
    count_option,
    finish_study,
    refuse_sweep_options,
    study_options,
)


def add_parser(sub) -> None:
    p = sub.add_parser("basins", help="basins of attraction over initial conditions",
                       description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file (model = \"discrete\", "
                                              "\"discrete3d\" or \"lap_joint\")")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--grid", type=count_option, default=None,
                   help="N = 2: grid points per axis")
    g.add_argument("--random", type=count_option, default=None,
                   help="random initial states")
    g.add_argument("--protocols", type=Path, default=None, help="TOML file of protocols")
    p.add_argument("--v1", default=None, help="grid range a:b of v1 [m]")
    p.add_argument("--v2", default=None, help="grid range a:b of v2 [m]")
    p.add_argument("--lam", type=float, default=None, help="load factor λ (overrides case)")
    p.add_argument("--seed", type=int, default=None, help="random seed (default 0)")
    add_common(p)
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.io import read_case

    case = read_case(args.case, models=["discrete", "discrete3d", "lap_joint"])
    if case.model == "lap_joint":
        from slipcycle.io import CaseError
        from slipcycle.joints.lap_joint_shakedown import lap_joint_shakedown_study

        for key in ("grid", "random", "protocols", "v1", "v2", "seed"):
            if getattr(args, key) is not None:
                raise CaseError(f"--{key}", "a lap_joint case maps its protocols of "
                                            "[lap_joint.protocols] over the service "
                                            "amplitude (--lam: the largest)")
        refuse_sweep_options(args, "a lap_joint basins map",
                             "discrete and discrete3d cases")
        if args.lam is not None and not (math.isfinite(args.lam) and args.lam > 0):
            raise CaseError("--lam", f"must be a service amplitude > 0 N, got {args.lam}")
        status = lap_joint_shakedown_study(case, args.out, lam_max=args.lam)
        return finish_study(status, args, case, ("subjects", "lambda2", "class_window",
                                                 "shakedown_limits"))
    if case.model == "discrete3d":
        from slipcycle.studies.basins3d import basins3d_study

        status = basins3d_study(case, args.out, grid=args.grid, random=args.random,
                                protocols=args.protocols, v1_range=args.v1,
                                v2_range=args.v2, lam=args.lam, seed=args.seed or 0,
                                **study_options(args))
        return finish_study(status, args, case, ("starts", "class_counts", "attractors",
                                                 "both_outcomes"))
    from slipcycle.studies.basins import basins_study

    status = basins_study(case, args.out, grid=args.grid, random=args.random,
                          protocols=args.protocols, v1_range=args.v1, v2_range=args.v2,
                          lam=args.lam, seed=args.seed or 0, **study_options(args))
    return finish_study(status, args, case, ("starts", "class_counts", "both_outcomes",
                                             "lambda1", "lambda2"))
