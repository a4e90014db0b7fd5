"""Two-rod model (issue 5): one steady-state frequency point with slip and the regime map.

* one point: distributed interface, 100 rings, 50 modes per rod, 400 steps per cycle,
  Θa in microslip at Ω/ω1 = 0.5, equal steel rods (examples/rods_limits_equal.toml);
* the 40 × 20 regime map (Ω/ω1 ∈ [0.01, 3] × Θa/Θg ∈ [0.3, 3]) of the same system.
Target (issue 5): the map in under 5 minutes.
"""

from __future__ import annotations

import time


def benchmarks() -> list[dict]:
    import numpy as np

    from slipcycle.rods.interfaces import distributed_bed
    from slipcycle.rods.limits import Study, regime_map
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
    study = Study(rods, exc, bed, basis, 400, 150, 1e-5)
    t0 = time.perf_counter()
    m = regime_map(study, np.geomspace(0.01, 3.0, 40), np.geomspace(0.3, 3.0, 20),
                   progress=False)
    t_map = time.perf_counter() - t0
    return [
        {"name": f"rods: one steady point with slip ({res.cycles} cycles)", "value": t_point,
         "unit": "s"},
        {"name": "rods: 40x20 regime map", "value": t_map, "unit": "s", "target": "< 300",
         "ok": t_map < 300},
        {"name": "rods: map points not converged", "value": float(np.sum(~m["converged"])),
         "unit": "points"},
    ]
