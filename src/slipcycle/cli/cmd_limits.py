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
position map); ``[loading].frequency_ratio`` may then be omitted.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


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


def _axis(sec, key, default, **bounds):
    """A grid axis; values given as a list are sorted."""
    vals = sec.grid(key, default, max_num=10000, **bounds)
    return vals if isinstance(sec.data.get(key, default), dict) else np.sort(vals)


def parse_limits(case, tolerance: float):
    from slipcycle.io import CaseError
    from slipcycle.rods.case import parse_case

    if not (0.0 < tolerance < 1.0):
        raise CaseError("--tolerance", f"must be in (0, 1), got {tolerance:g}")
    load = case.data.get("loading")
    if isinstance(load, dict) and "frequency_ratio" not in load and "frequency" not in load:
        load["frequency_ratio"] = 1.0  # the sweep sets the frequency
    sec = case.section("limits", required=False)
    ratios = _axis(sec, "frequency_ratio", {"start": 0.01, "stop": 3.0, "num": 40},
                   gt=0.0, le=1e3, geometric=True)
    amps = _axis(sec, "amplitude_ratio", {"start": 0.3, "stop": 3.0, "num": 20},
                 gt=0.0, le=1e4, geometric=True)
    pos = _axis(sec, "position", {"start": 0.1, "stop": 0.9, "num": 9}, gt=0.0, le=0.999)
    npf = sec.int("position_frequencies", 20, ge=2, le=1000)
    rc = parse_case(case)
    return rc, ratios, amps, pos, npf


def execute(args: argparse.Namespace) -> int:
    import xarray as xr

    from slipcycle.io import RunOutputs, read_case, write_outputs
    from slipcycle.plot import rods as plots
    from slipcycle.rods.interfaces import iwan_bed, make_bed
    from slipcycle.rods.limits import Study, limit_frequency, position_map, regime_map
    from slipcycle.rods.modal import modal_basis

    case = read_case(args.case, models=["rods"])
    rc, ratios, amps, pos, npf = parse_limits(case, args.tolerance)
    rods, exc = rc.rods, rc.exc
    if rods.interface == "iwan":
        bed = iwan_bed(rods, exc.axial_force, rc.rings)[0]
    else:
        bed = make_bed(rods, exc.axial_force, rc.rings)
    basis = modal_basis(rods, rc.modes, rc.static_correction)
    study = Study(rods, exc, bed, basis, rc.steps_per_cycle, min(rc.cycles, 150),
                  max(rc.steady_tol, 1e-5))
    t0 = time.perf_counter()
    lim = limit_frequency(study, args.tolerance, ratios, progress=True)
    t1 = time.perf_counter()
    maps = None
    pmap = None
    if not args.no_maps:
        maps = regime_map(study, ratios, amps, progress=True)
        t2 = time.perf_counter()
        pr = np.geomspace(ratios.min(), ratios.max(), npf)
        pmap = position_map(study, pos, pr, progress=True)
        t3 = time.perf_counter()
    summary = {
        "model": "rods",
        "analysis": "limits",
        "tolerance": args.tolerance,
        "interface": rods.interface,
        "omega1": study.omega1,
        "rotation_amplitude": exc.rotation_amplitude,
        "qs_limit_frequency_ratio": lim["qs_limit_frequency_ratio"],
        "qs_limit_frequency_ratio_status": lim["qs_limit_frequency_ratio_status"],
        "qs_limit_frequency": lim["qs_limit_frequency_ratio"] * study.omega1,
        "qs_limit_frequency_ratio_dissipation": lim["qs_limit_frequency_ratio_dissipation"],
        "qs_limit_frequency_ratio_dissipation_status":
            lim["qs_limit_frequency_ratio_dissipation_status"],
        "dissipation_per_cycle": None,
        "sweep_points_not_converged": int(np.sum(~lim["converged"])),
        "wall_time_sweep_s": t1 - t0,
    }
    ds = xr.Dataset(
        {"torque_ratio": ("frequency_ratio", lim["torque_ratio"], {"units": "1"}),
         "dissipation_ratio": ("frequency_ratio", lim["dissipation_ratio"], {"units": "1"}),
         "converged": ("frequency_ratio", lim["converged"].astype("i1"), {"units": "1"})},
        coords={"frequency_ratio": ("frequency_ratio", ratios, {"units": "1"})})
    figures = {"limit_frequency": lambda: plots.limit_curve(lim, args.tolerance)}
    if maps is not None:
        summary.update({
            "map_shape": list(maps["torque_ratio"].shape),
            "map_points_not_converged": int(np.sum(~maps["converged"])),
            "wall_time_map_s": t2 - t1,
            "wall_time_position_map_s": t3 - t2,
            "theta_gross": maps["theta_gross"],
            "resonances_frequency_ratio": maps["resonances"],
            "position_omega1": pmap["omega1"],
        })
        ds = ds.assign_coords(map_frequency_ratio=("map_frequency_ratio", ratios),
                              amplitude_ratio=("amplitude_ratio", amps, {"units": "1"}),
                              position=("position", pos, {"units": "1"}),
                              position_frequency_ratio=("position_frequency_ratio",
                                                        pmap["ratios"]))
        dims = ("map_frequency_ratio", "amplitude_ratio")
        ds["map_torque_ratio"] = (dims, maps["torque_ratio"], {"units": "1"})
        ds["map_dissipation_ratio"] = (dims, maps["dissipation_ratio"], {"units": "1"})
        pd = ("position", "position_frequency_ratio")
        ds["position_torque_ratio"] = (pd, pmap["torque_ratio"], {"units": "1"})
        ds["position_dissipation_ratio"] = (pd, pmap["dissipation_ratio"], {"units": "1"})
        figures["regime_map"] = lambda: plots.regime_map(maps, args.tolerance)
        figures["position_map"] = lambda: plots.position_map(pmap, args.tolerance)
    write_outputs(args.out, RunOutputs(summary=summary, dataset=ds, figures=figures),
                  case.text, case.path)
    print(json.dumps({k: summary[k] for k in ("omega1", "qs_limit_frequency_ratio",
                                              "qs_limit_frequency_ratio_status",
                                              "qs_limit_frequency_ratio_dissipation")},
                     indent=2))
    print(f"results written to {args.out}/")
    return 0
