"""``slipcycle shakedown CASE.toml --out DIR``: safe region and critical load factors.

For a discrete case (SPEC §2, seed 001 §3): the safe shakedown region
S(λ) = {v : G v ≤ h0 + λ m} (extreme constraint positions), λ2 (largest λ with S(λ)
non-empty, one LP), λ1 (largest λ with all 2N constraints active, redundancy LPs and
bisection), and brackets of λ3 (every node slips in every steady cycle) and λ4 (all nodes
slip or separate at one instant) from simulations over ``--lam-points`` values of λ in
[0, ``--lam-max``] (default 2 λ2) and ``--starts`` random admissible initial slips plus the
case's own initial condition. The simulation runs go through the sweep machinery
(``DIR/scan.zarr``, ``--resume``, ``--workers``, ``--scheduler``).

summary.json: ``lambda1``, ``lambda2``, ``lambda3_bracket``, ``lambda4_bracket``, the
extreme constraint data, the runs supporting each bracket, and the case's own run.
"""

from __future__ import annotations

import argparse
import json
import time
from functools import partial
from pathlib import Path

import numpy as np

from slipcycle.cli.cmd_sweep import add_common, as_case_error


def add_parser(sub) -> None:
    p = sub.add_parser("shakedown", help="safe shakedown region and λ1…λ4 of a discrete case",
                       description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file (model = \"discrete\")")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--lam-max", type=float, default=None, help="largest λ simulated")
    p.add_argument("--lam-points", type=int, default=21, help="λ values simulated")
    p.add_argument("--starts", type=int, default=8, help="random initial slips per λ")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--tol", type=float, default=1e-9, help="relative tolerance of λ1")
    add_common(p)
    p.set_defaults(execute=execute)


def _panels(dc, region, l1, l2, lam_case, seed):
    """Trajectory panels (N = 2): below λ1, between λ1 and λ2 (or the case λ), above λ2."""
    from slipcycle.discrete.shakedown import polygon_vertices, sample_initial_slips
    from slipcycle.discrete.steady import simulate

    lams = []
    if np.isfinite(l1) and l1 > 0:
        lams.append(0.7 * l1)
    if np.isfinite(l2) and l2 > l1:
        lams.append(lam_case if l1 < lam_case < l2 else 0.5 * (l1 + l2))
    if np.isfinite(l2):
        lams.append(1.15 * l2 if l2 > 0 else 0.5)
    run = dc.run
    panels = []
    for lam in lams:
        load = dc.load.with_lam(lam)
        V = sample_initial_slips(dc.system, load, 5, seed=seed)
        P = polygon_vertices(region, lam)
        if len(P) >= 3:                       # one start inside the safe region
            V = np.vstack([V[:4], P.mean(axis=0)[None]])
        traj = []
        for v0 in V:
            res = simulate(dc.system, load, initial_slip=v0, cycles=min(run["cycles"], 30),
                           steps_per_cycle=min(run["steps_per_cycle"], 200), tol=run["tol"])
            v = np.vstack([v0[None], res.x[:, :, :2].reshape(-1, 2)])
            traj.append((v, res.steady_state))
        panels.append({"lam": lam, "trajectories": traj})
    return panels


def execute(args: argparse.Namespace) -> int:
    import xarray as xr

    from slipcycle.discrete.basins import load_discrete_case, run_record
    from slipcycle.discrete.shakedown import (
        constraint_names,
        lambda1,
        lambda2,
        polygon_vertices,
        safe_region,
        simulation_brackets,
    )
    from slipcycle.io import CaseError, RunOutputs, read_case, write_outputs
    from slipcycle.plot import shakedown as plots
    from slipcycle.sweep import Axis, SweepError, run_sweep
    from slipcycle.sweep.case import STEADY_CODES

    case = read_case(args.case, models=["discrete"])
    cpath = str(case.path) if case.path else None
    dc = load_discrete_case(case.text, cpath)
    if args.lam_points < 2:
        raise CaseError("--lam-points", f"must be >= 2, got {args.lam_points}")
    if args.starts < 0:
        raise CaseError("--starts", f"must be >= 0, got {args.starts}")
    if args.lam_max is not None and not (np.isfinite(args.lam_max) and args.lam_max > 0):
        raise CaseError("--lam-max", f"must be a finite number > 0, got {args.lam_max}")
    if not 0 < args.tol < 1:
        raise CaseError("--tol", f"must be in (0, 1), got {args.tol}")
    n = dc.system.n_nodes
    t0 = time.perf_counter()
    region = safe_region(dc.system, dc.load)
    l2, v_last = lambda2(region)
    l1info = lambda1(region, l2, tol=args.tol)
    l1 = l1info["lambda1"]
    t_lp = time.perf_counter() - t0
    lam_case = float(dc.load.p.lam)
    lam_max = args.lam_max or (2.0 * l2 if np.isfinite(l2) and l2 > 0 else
                               max(2.0 * lam_case, 1.0))
    lams = tuple(np.linspace(0.0, lam_max, args.lam_points).tolist())
    axes = [Axis("lam", lams), Axis("start", tuple(range(args.starts + 1)))]
    fn = partial(lam_start_task_ref(), case_text=case.text, case_path=cpath,
                 n_random=args.starts, seed=args.seed)
    try:
        store = run_sweep(fn, axes, Path(args.out) / "scan.zarr",
                          description={"case": case.text, "lams": lams,
                                       "starts": args.starts, "seed": args.seed},
                          resume=args.resume, workers=args.workers, scheduler=args.scheduler,
                          progress=not args.no_progress, stop_after=args.stop_after,
                          desc="λ scan")
    except SweepError as exc:
        raise as_case_error(exc) from None
    done = store.done()
    if not done.all():
        print(f"stopped with {int(done.sum())} of {done.size} runs done; complete it with "
              "--resume", flush=True)
        return 0
    data = store.read()
    cls = data["steady_state"]
    recs = []
    for i, lam in enumerate(lams):
        for s in range(args.starts + 1):
            if cls[i, s] == STEADY_CODES.index("inadmissible"):
                continue
            recs.append((lam, "case" if s == 0 else f"random {s}", {
                "steady_state": STEADY_CODES[int(cls[i, s])],
                "dissipation_per_cycle": float(data["dissipation_per_cycle"][i, s]),
                "n_slipping": int(data["n_slipping"][i, s]),
                "memory_erased": bool(data["memory_erased"][i, s]),
                "cycles_run": int(data["cycles_run"][i, s])}))
    br = simulation_brackets(recs, n)

    def evidence(bracket):
        lo, hi = bracket
        return [r for r in br.runs if r["lam"] in (lo, hi)]

    own = run_record(dc.system, dc.load, initial_slip=dc.initial_slip, protocol=dc.protocol,
                     **{"cycles": dc.run["cycles"], "steps_per_cycle":
                        dc.run["steps_per_cycle"], "tol": dc.run["tol"],
                        "min_cycles": dc.run["min_cycles"]})
    regime = ("below_lambda1" if lam_case < l1 else
              "between_lambda1_and_lambda2" if lam_case <= l2 else "above_lambda2")
    names = constraint_names(n)
    summary = {
        "model": "discrete", "analysis": "shakedown", "n_nodes": n,
        "lambda1": l1, "lambda1_bracket": list(l1info["bracket"]), "lambda2": l2,
        "lambda3_bracket": list(br.lambda3_bracket), "lambda4_bracket": list(br.lambda4_bracket),
        "redundant_above_lambda1": [names[k] for k in l1info["redundant_above"]],
        "extreme_method": region.method,
        "constraints": {"names": names, "G": region.G, "h0": region.h0, "m": region.m,
                        "theta_extreme": region.theta_extreme},
        "last_safe_state": v_last,
        "lam": lam_case, "regime": regime,
        "steady_state": STEADY_CODES[int(own["steady_state"])],
        "dissipation_per_cycle": float(own["dissipation_per_cycle"]),
        "lambda3_evidence": evidence(br.lambda3_bracket),
        "lambda4_evidence": evidence(br.lambda4_bracket),
        "scan": {"lam": list(lams), "starts": args.starts + 1, "seed": args.seed,
                 "store": str(Path(args.out) / "scan.zarr"),
                 "class_counts": {STEADY_CODES[c]: int((cls == c).sum())
                                  for c in np.unique(cls)}},
        "linear_programs": l1info["lps"] + 1, "lp_wall_time_s": t_lp,
    }
    if n == 2:
        summary["safe_region_vertices"] = polygon_vertices(region, lam_case)
    ds = xr.Dataset(
        {"steady_state": (("lam", "start"), cls, {"units": "1",
                                                  "flag_meanings": " ".join(STEADY_CODES)}),
         "dissipation_per_cycle": (("lam", "start"), data["dissipation_per_cycle"],
                                   {"units": "J"}),
         "dissipation_per_node": (("lam", "start", "node"), data["dissipation_per_node"],
                                  {"units": "J"}),
         "n_slipping": (("lam", "start"), data["n_slipping"], {"units": "1"}),
         "memory_erased": (("lam", "start"), data["memory_erased"], {"units": "1"}),
         "initial_slip": (("lam", "start", "node"), data["initial_slip"], {"units": "m"}),
         "G": (("constraint", "node"), region.G, {"units": "N/m"}),
         "h0": (("constraint",), region.h0, {"units": "N"}),
         "m": (("constraint",), region.m, {"units": "N"}),
         "theta_extreme": (("constraint",), region.theta_extreme, {"units": "rad"})},
        coords={"lam": ("lam", np.array(lams), {"units": "1"}),
                "start": ("start", np.arange(args.starts + 1), {"units": "1"})})
    ds.attrs.update({"lambda1": l1, "lambda2": l2 if np.isfinite(l2) else -1.0})
    figures = {"dissipation_vs_lambda": lambda: plots.dissipation_vs_lambda(
        np.array(lams), data["dissipation_per_cycle"], cls, l1, l2, br.lambda3_bracket,
        br.lambda4_bracket)}
    if n == 2 and np.isfinite(l2):
        figures["safe_region_panels"] = lambda: plots.safe_region_panels(
            region, _panels(dc, region, l1, l2, lam_case, args.seed), l1, l2)
    write_outputs(args.out, RunOutputs(summary=summary, dataset=ds, figures=figures),
                  case.text, case.path)
    print(json.dumps({k: summary[k] for k in ("lambda1", "lambda2", "lambda3_bracket",
                                              "lambda4_bracket", "regime")}, indent=2,
                     default=str))
    print(f"results written to {args.out}/")
    return 0


def lam_start_task_ref():
    from slipcycle.discrete.basins import lam_start_task

    return lam_start_task
