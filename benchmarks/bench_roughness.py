"""Rough-interface benchmarks: BEM normal law of a topography and the roughness study.

Targets (this 2-core machine): the 24-load BEM law of the example surface on a 128² grid in
under 15 s (256²: under 60 s); a cached rerun of ``slipcycle roughness`` on the example in
under 10 s; the slider bed of the 400-point table under 0.5 s per run.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


def _row(name, value, unit, target):
    return {"name": name, "value": value, "unit": unit, "target": target,
            "ok": bool(value <= target)}


def benchmarks() -> list[dict]:
    from slipcycle.halfspace.model import solve
    from slipcycle.halfspace.topography import bem_normal_law, read_surface, resample
    from slipcycle.io import read_case
    from slipcycle.studies.roughness import parse_roughness_case, roughness_study

    rows = []
    with tempfile.TemporaryDirectory() as cache:
        os.environ["SLIPCYCLE_CACHE"] = cache
        case = read_case(EXAMPLES / "halfspace_topography.toml")
        t0 = time.perf_counter()
        model, source, settings = parse_roughness_case(case)   # base BEM law, 128²
        rows.append(_row("BEM law 128², 24 loads (example surface, uncached)",
                         time.perf_counter() - t0, "s", 15.0))
        surface = resample(read_surface(source.path), 256)
        t0 = time.perf_counter()
        bem_normal_law(surface, source.contact_modulus, source.pressures(7e7))
        rows.append(_row("BEM law 256², 24 loads", time.perf_counter() - t0, "s", 60.0))
        t = []
        for _ in range(3):
            t0 = time.perf_counter()
            solve(model, record_last_cycle=False)
            t.append(time.perf_counter() - t0)
        rows.append(_row("slider bed, 400-point table, 4 cycles × 200 steps (median of 3)",
                         float(np.median(t)), "s", 0.5))
        roughness_study(model, source, settings)                # fills the cache
        t0 = time.perf_counter()
        roughness_study(model, source, settings)
        rows.append(_row("roughness study of the example, cached BEM laws",
                         time.perf_counter() - t0, "s", 10.0))
        os.environ.pop("SLIPCYCLE_CACHE", None)
    return rows


if __name__ == "__main__":  # pragma: no cover
    for r in benchmarks():
        print(f"{r['name']}: {r['value']:.3g} {r['unit']} (target {r['target']}, "
              f"{'ok' if r['ok'] else 'MISSED'})")
