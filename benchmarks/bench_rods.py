"""Two-rod model: one steady-state point with slip and the regime map of the limits case.

* one point: distributed interface, 100 rings, 50 modes per rod, 400 steps per cycle,
  Θa in microslip at Ω/ω1 = 0.5, equal steel rods (example ``rods_limits_equal``);
* the 40 × 20 regime map (Ω/ω1 ∈ [0.01, 3] × Θa/Θg ∈ [0.3, 3]) of that case, exactly as
  ``slipcycle limits`` computes it: median of 3 runs, per-point cost, points marked not
  converged;
* wall time against map size (10 × 5, 20 × 10, 40 × 20) with the fitted exponent;
* agreement of the default solver (cycling, then Newton on the periodic problem where
  cycling is slow, rods/periodic.py) with plain cycling on a 20 × 10 map: largest relative
  difference of T_dyn/T_qs and D_dyn/D_qs over the points both converge, and the points
  each marks not converged.
Target (issue "Speed a user feels"): the 40 × 20 map in under 30 s.
"""

from __future__ import annotations

import functools
import math
import time


def _case():
    from slipcycle.examples import example_path
    from slipcycle.io.case import read_case
    from slipcycle.studies.limits import parse_limits

    return parse_limits(read_case(example_path("rods_limits_equal")), 0.05)


def _map(lc, ratios, factors, method="newton"):
    """Wall time and result of `regime_map` of a fresh study (no cached loops)."""
    import slipcycle.rods.limits as limits
    from slipcycle.rods.modal import steady_state

    saved = limits.steady_state
    # the method under test, everything else exactly as `slipcycle limits`
    limits.steady_state = functools.partial(steady_state, method=method)
    try:
        study, _ = limits.make_study(lc.rc)
        t0, c0 = time.perf_counter(), time.process_time()
        m = limits.regime_map(study, ratios, factors, progress=False)
        m["cpu_s"] = time.process_time() - c0  # the wall time of an idle machine, nearly
        return time.perf_counter() - t0, m
    finally:
        limits.steady_state = saved


def benchmarks() -> list[dict]:
    import numpy as np

    from slipcycle.rods.interfaces import distributed_bed
    from slipcycle.rods.modal import modal_basis, steady_state
    from slipcycle.rods.model import Excitation, Rod, TwoRods
    from slipcycle.rods.welded import omega1

    r = Rod(0.5, 0.01, 200e9, 0.3, 7850.0)
    rods = TwoRods(r, r, 0.3, "distributed", 1e13, 0.01)
    bed = distributed_bed(rods, 100)
    basis = modal_basis(rods, 50)
    w1 = omega1(rods)
    exc = Excitation(0.016, 0.5 * w1, 1e4)
    steady_state(rods, exc.with_(frequency=0.3 * w1), bed, basis, 400)  # JIT warm-up
    t0 = time.perf_counter()
    res = steady_state(rods, exc, bed, basis, 400)
    t_point = time.perf_counter() - t0

    lc = _case()
    _map(lc, lc.ratios[::20], lc.amplitude_ratios[::10])  # warm-up (JIT)
    times, cpus, m = [], [], None
    for _ in range(3):
        t, m = _map(lc, lc.ratios, lc.amplitude_ratios)
        times.append(t)
        cpus.append(m["cpu_s"])
    t_map = float(np.median(times))
    cpu_map = float(np.median(cpus))
    points = m["torque_ratio"].size
    marked = int(np.sum(~m["converged"] & ~m["pole"]))

    sizes, walls = [], []
    for step in (4, 2):
        t, _ = _map(lc, lc.ratios[::step], lc.amplitude_ratios[::step])
        sizes.append(lc.ratios[::step].size * lc.amplitude_ratios[::step].size)
        walls.append(t)
    sizes.append(points)
    walls.append(t_map)
    slope = float(np.polyfit(np.log(sizes), np.log(walls), 1)[0])

    sub = (lc.ratios[::2], lc.amplitude_ratios[::2])
    t_new, a = _map(lc, *sub)
    t_cyc, b = _map(lc, *sub, method="cycling")
    both = a["converged"] & b["converged"]
    diffs = []
    for key in ("torque_ratio", "dissipation_ratio"):
        x, y = a[key][both], b[key][both]
        ok = np.isfinite(x) & np.isfinite(y)
        diffs.append(float(np.max(np.abs(x[ok] - y[ok]) / np.maximum(np.abs(y[ok]), 1e-300)))
                     if ok.any() else math.nan)
    return [
        {"name": f"rods: one steady point with slip ({res.cycles} cycles)", "value": t_point,
         "unit": "s"},
        {"name": "rods: 40x20 regime map (median of 3)", "value": t_map, "unit": "s",
         "target": "< 30", "ok": t_map < 30},
        {"name": "rods: 40x20 regime map, CPU time (median of 3)", "value": cpu_map,
         "unit": "s", "target": "< 30", "ok": cpu_map < 30},
        {"name": "rods: map cost per point", "value": 1e3 * t_map / points, "unit": "ms"},
        {"name": "rods: map points marked not converged", "value": float(marked),
         "unit": "points"},
        {"name": "rods: map wall time ~ points^p, fitted p (50-800 pts)", "value": slope,
         "unit": "1"},
        {"name": f"rods: 20x10 map, default solver ({int(np.sum(~a['converged']))} marked)",
         "value": t_new, "unit": "s"},
        {"name": f"rods: 20x10 map, plain cycling ({int(np.sum(~b['converged']))} marked)",
         "value": t_cyc, "unit": "s"},
        {"name": "rods: max rel. diff. torque ratio, default vs cycling", "value": diffs[0],
         "unit": "1", "target": "<= 1e-5", "ok": bool(diffs[0] <= 1e-5)},
        {"name": "rods: max rel. diff. dissipation ratio, default vs cycling",
         "value": diffs[1], "unit": "1", "target": "<= 1e-5", "ok": bool(diffs[1] <= 1e-5)},
    ]
