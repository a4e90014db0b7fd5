"""``slipcycle basins CASE.toml --out DIR [--grid 201 | --random K | --protocols FILE]``.

Maps the steady state (class and dissipation per cycle) of a discrete case over initial
conditions (seed 001 §3.1, Fig. 3):

- ``--grid n`` (N = 2): an n × n grid of initial slips (v1, v2) at θ = 0 over the box of
  admissible states (or ``--v1 a:b --v2 a:b``); inadmissible starts are marked; the
  box-counting dimension of the class boundaries is reported;
- ``--random K`` (any N): K random admissible initial slip states (``--seed``);
- ``--protocols FILE`` (any N): a TOML file of ``[[protocol]]`` tables, each with
  ``p_w`` and ``q_w`` lists of load states ((S, N) nested lists) visited before cycling.

``--lam`` overrides ``loading.lam``. Runs go through the sweep machinery (``DIR/basins.zarr``,
``--resume``, ``--workers``, ``--scheduler``); grid rows run in parallel threads.
"""

from __future__ import annotations

import argparse
import json
import time
from functools import partial
from pathlib import Path

import numpy as np

from slipcycle.cli.cmd_sweep import add_common, as_case_error, store_dataset
from slipcycle.discrete.sizes import cells_bytes, check_memory, count_option


def add_parser(sub) -> None:
    p = sub.add_parser("basins", help="basins of attraction over initial conditions",
                       description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case", type=Path, help="TOML case file (model = \"discrete\")")
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
    p.add_argument("--seed", type=int, default=0, help="random seed")
    add_common(p)
    p.set_defaults(execute=execute)


#: unit of every numeric summary entry (nested entries by their path)
SUMMARY_UNITS = {
    "lam": "1", "n_nodes": "1", "lambda1": "1", "lambda2": "1", "starts": "1",
    "class_counts": "1", "dissipation_per_cycle.min": "J",
    "dissipation_per_cycle.max": "J", "both_outcomes": "1", "wall_time_s": "s",
    "boundary_box_counting_dimension": "1", "box_counting.dimension": "1",
    "box_counting.sizes": "1", "box_counting.counts": "1",
    "box_counting.boundary_cells": "1", "grid": "1",
}

#: every word of the categorical summary entries
SUMMARY_FLAGS = {"mode": ("grid", "random", "protocols")}

CONVERGED_ATTRS = {"units": "1", "long_name": "the start reached a steady state (shakedown, "
                   "cyclic slip or ratcheting) within run.cycles; false for not_converged, "
                   "inadmissible and failed starts"}


def _range(text, key):
    from slipcycle.io import CaseError

    try:
        a, b = (float(x) for x in text.split(":"))
    except ValueError:
        raise CaseError(key, f"must be a:b, got {text!r}") from None
    if not (np.isfinite(a) and np.isfinite(b) and b > a):
        raise CaseError(key, f"needs finite a < b, got {text!r}")
    return a, b


def _read_protocols(path: Path, n: int) -> list:
    from slipcycle.io import CaseError
    from slipcycle.io.case import Section

    try:
        text = path.read_text()
    except OSError as exc:
        raise CaseError("--protocols", f"cannot read {path}: {exc.strerror}") from None
    import tomllib

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError("--protocols", f"not valid TOML: {exc}") from None
    root = Section(data, "", path.parent)
    out = []
    for ps in root.tables("protocol"):
        p = ps.array("p_w", shape=(None, n))
        q = ps.array("q_w", np.zeros_like(p), shape=(p.shape[0], n))
        ps.finish()
        out.append(np.hstack([q, p]))
    root.finish()
    if not out:
        raise CaseError("protocol", "the protocols file holds no [[protocol]] tables")
    return out


def protocol_task(params, case_text, case_path, protocols, lam):
    """Sweep task: steady state after assembly protocol ``params["index"]``."""
    from slipcycle.discrete.basins import _run_settings, load_discrete_case, run_record

    dc = load_discrete_case(case_text, case_path)
    load = dc.load if lam is None else dc.load.with_lam(lam)
    return run_record(dc.system, load, protocol=np.asarray(protocols[int(params["index"])]),
                      **_run_settings(dc))


def random_task(params, case_text, case_path, V):
    from slipcycle.discrete.basins import _run_settings, load_discrete_case, run_records

    dc = load_discrete_case(case_text, case_path)
    lam = params.get("lam")
    load = dc.load if lam is None else dc.load.with_lam(lam)
    i = int(params["index"])
    out = run_records(dc.system, load, np.asarray(V)[i:i + 1], **_run_settings(dc))
    return {k: v[0] for k, v in out.items()}


def execute(args: argparse.Namespace) -> int:
    from slipcycle.discrete.basins import (
        admissible_box,
        basin_row_task,
        box_counting_dimension,
        load_discrete_case,
    )
    from slipcycle.discrete.shakedown import lambda1, lambda2, safe_region, sample_initial_slips
    from slipcycle.io import CaseError, RunOutputs, read_case, write_outputs
    from slipcycle.plot.shakedown import basin_map
    from slipcycle.sweep import Axis, SweepError, run_sweep
    from slipcycle.sweep.case import STEADY_CODES

    case = read_case(args.case, models=["discrete"])
    cpath = str(case.path) if case.path else None
    dc = load_discrete_case(case.text, cpath)
    n = dc.system.n_nodes
    if args.lam is not None and not (np.isfinite(args.lam) and args.lam >= 0):
        raise CaseError("--lam", f"must be a finite number >= 0, got {args.lam}")
    lam = args.lam if args.lam is not None else float(dc.load.p.lam)
    load = dc.load.with_lam(lam)
    mode = "grid" if args.grid is not None else ("random" if args.random is not None else
                                                 "protocols" if args.protocols else None)
    if mode is None:
        mode = "grid" if n == 2 else "random"
        args.grid = 101 if n == 2 else None
        args.random = None if n == 2 else 64
    if mode == "grid":
        if n != 2:
            raise CaseError("--grid", f"needs a two-node system (this one has {n} nodes); "
                            "use --random or --protocols")
        if args.grid < 2:
            raise CaseError("--grid", f"must be >= 2, got {args.grid}")
        # a grid row is one task returning arrays: per start, the class, D, D_j, counts
        # (8 numbers) held ~4 times (rows, store, Dataset, figure)
        check_memory("--grid", float(args.grid) ** 2 * 8 * (n + 8) * 4,
                     f"{args.grid:g} × {args.grid:g} starts")
        box = admissible_box(dc.system, load)
        if args.v1:
            box[0] = _range(args.v1, "--v1")
        if args.v2:
            box[1] = _range(args.v2, "--v2")
        if not np.all(np.isfinite(box)):
            raise CaseError("loading.lam", f"no slip state is admissible at θ = 0 for λ = "
                            f"{lam:g}; give --v1 and --v2 ranges")
        v1 = np.linspace(box[0, 0], box[0, 1], args.grid)
        v2 = np.linspace(box[1, 0], box[1, 1], args.grid)
        threads = None if (args.workers in (None, 1) and args.scheduler is None) else 1
        workers = 1 if args.workers is None and args.scheduler is None else args.workers
        fn = partial(basin_row_task, case_text=case.text, case_path=cpath,
                     v1=tuple(v1.tolist()), v2=tuple(v2.tolist()), lam=lam, threads=threads)
        axes = [Axis("row", tuple(range(args.grid)))]
        desc = {"mode": "grid", "lam": lam, "v1": v1.tolist(), "v2": v2.tolist()}
    elif mode == "random":
        if args.random < 1:
            raise CaseError("--random", f"must be >= 1, got {args.random}")
        check_memory("--random", cells_bytes(args.random, n) + 8.0 * args.random * n * 8,
                     f"{args.random:g} random starts ({n} nodes)")
        V = sample_initial_slips(dc.system, load, args.random, seed=args.seed)
        if V.shape[0] == 0:
            raise CaseError("loading.lam", f"no slip state is admissible at θ = 0 for λ = "
                            f"{lam:g}")
        fn = partial(random_task, case_text=case.text, case_path=cpath,
                     V=tuple(map(tuple, V.tolist())))
        axes = [Axis("index", tuple(range(V.shape[0])))]
        desc = {"mode": "random", "lam": lam, "V": V.tolist()}
        workers = args.workers
    else:
        protos = _read_protocols(args.protocols, n)
        fn = partial(protocol_task, case_text=case.text, case_path=cpath,
                     protocols=tuple(p.tolist() for p in protos), lam=lam)
        axes = [Axis("index", tuple(range(len(protos))))]
        desc = {"mode": "protocols", "lam": lam, "protocols": [p.tolist() for p in protos]}
        workers = args.workers
    t0 = time.perf_counter()
    try:
        store = run_sweep(fn, axes, Path(args.out) / "basins.zarr",
                          description={"case": case.text, **desc}, resume=args.resume,
                          workers=workers, scheduler=args.scheduler,
                          progress=not args.no_progress, stop_after=args.stop_after,
                          desc="basins")
    except SweepError as exc:
        raise as_case_error(exc) from None
    wall = time.perf_counter() - t0
    done = store.done()
    if not done.all():
        print(f"stopped with {int(done.sum())} of {done.size} cells done; complete it with "
              "--resume", flush=True)
        return 0
    data = store.read()
    region = safe_region(dc.system, dc.load)
    l2 = lambda2(region)[0]
    l1 = lambda1(region, l2)["lambda1"]
    cls = data["steady_state"]
    counts = {STEADY_CODES[c]: int((cls == c).sum()) for c in np.unique(cls)}
    adm = cls != STEADY_CODES.index("inadmissible")
    # reached a steady state (shakedown, cyclic slip or ratcheting) within run.cycles
    converged = np.isin(cls, [STEADY_CODES.index(c) for c in
                              ("shakedown", "cyclic_slip", "ratcheting")])
    D = data["dissipation_per_cycle"]
    summary = {"model": "discrete", "analysis": "basins", "mode": mode, "lam": lam,
               "n_nodes": n, "lambda1": l1, "lambda2": l2, "starts": int(cls.size),
               "class_counts": counts,
               "dissipation_per_cycle": {"min": float(np.nanmin(D[adm])) if adm.any()
                                         else None,
                                         "max": float(np.nanmax(D[adm])) if adm.any()
                                         else None},
               "both_outcomes": bool((cls == 0).any() and (cls == 1).any()),
               "steady_state_codes": list(STEADY_CODES), "wall_time_s": wall,
               "units": dict(SUMMARY_UNITS)}
    figures = {}
    if mode == "grid":
        import xarray as xr

        # boundaries between admissible starts only: the edge of the admissible region
        # is smooth and says nothing about the dynamics
        bc = box_counting_dimension(cls, valid=adm)
        summary["boundary_box_counting_dimension"] = bc["dimension"]
        summary["box_counting"] = bc
        summary["grid"] = [int(args.grid), int(args.grid)]
        ds = xr.Dataset(
            {"steady_state": (("v2", "v1"), cls, {"units": "1", "flag_values": list(range(
                len(STEADY_CODES))), "flag_meanings": " ".join(STEADY_CODES)}),
             "dissipation_per_cycle": (("v2", "v1"), D, {"units": "J"}),
             "dissipation_per_node": (("v2", "v1", "node"), data["dissipation_per_node"],
                                      {"units": "J"}),
             "cycles_run": (("v2", "v1"), data["cycles_run"], {"units": "1"}),
             "n_slipping": (("v2", "v1"), data["n_slipping"], {"units": "1"}),
             "memory_erased": (("v2", "v1"), data["memory_erased"], {"units": "1"}),
             "converged": (("v2", "v1"), converged, CONVERGED_ATTRS)},
            coords={"v1": ("v1", v1, {"units": "m", "long_name": "initial slip of node 0"}),
                    "v2": ("v2", v2, {"units": "m", "long_name": "initial slip of node 1"})})
        figures["basin_map"] = lambda: basin_map(v1, v2, cls, D, region, lam)
    else:
        codes = list(range(len(STEADY_CODES)))
        ds = store_dataset(store, axes, attrs={
            "steady_state": {"units": "1", "flag_values": codes,
                             "flag_meanings": " ".join(STEADY_CODES)},
            "dissipation_per_cycle": {"units": "J"}, "dissipation_per_node": {"units": "J"},
            "cycles_run": {"units": "1"}, "n_slipping": {"units": "1"},
            "memory_erased": {"units": "1"}})
        ds["converged"] = (tuple(ds["steady_state"].dims), converged, CONVERGED_ATTRS)
    write_outputs(args.out, RunOutputs(summary=summary, dataset=ds, figures=figures,
                                       flags=dict(SUMMARY_FLAGS)),
                  case.text, case.path)
    print(json.dumps({k: summary[k] for k in ("starts", "class_counts", "both_outcomes",
                                              "lambda1", "lambda2")}, indent=2))
    print(f"results written to {args.out}/")
    return 0
