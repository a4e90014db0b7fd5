"""The accelerated, certified steady state on its targets (issue 32, item 3), each row
with its median wall time and cycles and, beside it, the distances of D and of the state
(the stuck nodes' memory) from plain cycling's limit, so that a speed-up never hides an
accuracy loss.

Systems:

- the slid FE-reduced steel block of 401 contact nodes (2-D, ``bench_discrete.fe_block``,
  50 samples per cycle): the default path (periodic follower and slow-mode steps, N ≥
  ``SLOW_MIN_NODES``) at the default tolerance 1e-8 (target < 5 s) and at 1e-11, and
  plain cycling at 1e-8 (the before). Reference: plain cycling's limit (2200 plain
  cycles, increments at round-off: D ``bench_discrete.PLAIN_REFERENCE_D[401]``, state
  ``tests/data/fe_block_401_plain_limit.npy``);
- the same block of 41 contact nodes (the follower alone), default path and plain
  cycling, both at 1e-11 (reference: plain cycling at 1e-11 of the same run);
- the CalculiX C3D8I block of 121 contact nodes (3-D, ``bench_calculix``, 40 samples per
  cycle, Q/fP ≈ 0.92): the default path (Anderson mixing) against plain cycling of the
  replayed step subdivision, which converges where that of the adaptive one stalls near
  1e-8 (target ≤ 15 cycles).

Distances: D relative to the reference's D; the state as max |x − x_ref| over the
reference's slip scale max(displacement scale, max |x_ref|). The wall times of the
targets are medians of ``REPEATS`` runs (the shared machine's load moves single runs by a
factor of two), the other rows one run each.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_discrete import PLAIN_REFERENCE_D, fe_block  # noqa: E402

from slipcycle.discrete import simulate  # noqa: E402

#: runs whose median wall time a row gives
REPEATS = 3

#: plain cycling's limit of the 401-node block (2200 cycles; tests/data)
PLAIN_LIMIT_401 = HERE.parent / "tests" / "data" / "fe_block_401_plain_limit.npy"


def _median_run(run, repeats: int = REPEATS):
    """(median wall time [s], the last result) of ``repeats`` calls of ``run()``."""
    walls, res = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = run()
        walls.append(time.perf_counter() - t0)
    return statistics.median(walls), res


def _distances(res, d_ref: float, x_ref: np.ndarray) -> tuple[float, float]:
    """(D distance, state distance) of a run from a reference (module docstring)."""
    x = res.cycle_start_states[-1]
    scale = max(res.disp_scale, float(np.abs(x_ref).max()))
    return (abs(res.dissipation_per_cycle - d_ref) / abs(d_ref),
            float(np.abs(x - x_ref).max()) / scale)


def _rows(label: str, wall: float, res, d_ref: float, x_ref: np.ndarray,
          target: dict | None = None) -> list[dict]:
    d_dist, x_dist = _distances(res, d_ref, x_ref)
    cert = res.certificate
    time_row = {"name": f"{label}: wall time to {res.steady_state} ({res.cycles_run} cycles, "
                        f"{cert.acceleration}; certified residual "
                        f"{cert.certified_residual:.1e})", "value": wall, "unit": "s"}
    if target is not None:
        time_row.update(target)
    return [time_row,
            {"name": f"{label}: cycles", "value": float(res.cycles_run), "unit": "1"},
            {"name": f"{label}: D vs plain cycling's limit (estimate "
                     f"{cert.dissipation_distance:.1e})", "value": d_dist, "unit": "1"},
            {"name": f"{label}: state (memory) vs plain cycling's limit (estimate "
                     f"{cert.memory_distance:.1e})", "value": x_dist, "unit": "1"}]


def block_401_rows() -> list[dict]:
    """The 401-node block: default path at 1e-8 (target < 5 s) and 1e-11, plain at 1e-8."""
    system, load, protocol, _ = fe_block(200)
    d_ref, x_ref = PLAIN_REFERENCE_D[401], np.load(PLAIN_LIMIT_401)
    kw = dict(cycles=3000, steps_per_cycle=50, protocol=protocol, record=False)
    rows = []
    wall, res = _median_run(lambda: simulate(system, load, **kw))
    rows += _rows("2-D FE block 401, default path, tol 1e-8", wall, res, d_ref, x_ref,
                  {"target": "< 5", "ok": bool(wall < 5.0 and res.steady_converged)})
    wall, res = _median_run(lambda: simulate(system, load, tol=1e-11, **kw), 1)
    rows += _rows("2-D FE block 401, default path, tol 1e-11 (one run)", wall, res, d_ref,
                  x_ref)
    d_dist, x_dist = _distances(res, d_ref, x_ref)
    rows.append({"name": "2-D FE block 401, default path at 1e-11: D vs the limit",
                 "value": d_dist, "unit": "1", "target": "< 1e-6", "ok": bool(d_dist < 1e-6)})
    wall, res = _median_run(lambda: simulate(system, load, accelerate=False, **kw), 1)
    rows += _rows("2-D FE block 401, plain cycling, tol 1e-8 (one run)", wall, res, d_ref,
                  x_ref)
    return rows


def block_41_rows() -> list[dict]:
    """The 41-node block, default path (follower) against plain cycling, both at 1e-11."""
    system, load, protocol, _ = fe_block(20)
    kw = dict(cycles=3000, steps_per_cycle=50, protocol=protocol, record=False, tol=1e-11)
    wall_p, plain = _median_run(lambda: simulate(system, load, accelerate=False, **kw))
    d_ref, x_ref = plain.dissipation_per_cycle, plain.cycle_start_states[-1]
    wall, res = _median_run(lambda: simulate(system, load, **kw))
    rows = _rows("2-D FE block 41, default path, tol 1e-11", wall, res, d_ref, x_ref)
    rows.append({"name": f"2-D FE block 41, plain cycling, tol 1e-11 ({plain.cycles_run} "
                         "cycles): the reference", "value": wall_p, "unit": "s"})
    return rows


def calculix_rows() -> list[dict]:
    """The 121-node CalculiX block (3-D): default path against plain cycling."""
    from bench_calculix import block_system, reduced_block

    from slipcycle.discrete3d import simulate3d

    system, load = block_system(reduced_block())
    kw = dict(steps_per_cycle=40, record=False)
    # plain cycling of the adaptive map stalls near 1e-8 (the step control's switching,
    # module docstring of slipcycle.discrete3d.steady); that of the replayed map converges
    wall_p, plain = _median_run(lambda: simulate3d(system, load, cycles=400, replay=True,
                                                   accelerate=False, **kw), 1)
    d_ref, x_ref = plain.dissipation_per_cycle, plain.cycle_start_states[-1]
    wall, res = _median_run(lambda: simulate3d(system, load, cycles=200, **kw))
    rows = _rows("3-D CalculiX block 121, default path, tol 1e-8", wall, res, d_ref, x_ref)
    rows[1].update(target="<= 15", ok=bool(res.cycles_run <= 15 and res.steady_converged))
    rows.append({"name": f"3-D CalculiX block 121, plain cycling ({plain.cycles_run} cycles, "
                         f"{plain.steady_state}, residual {plain.residual:.1e}): the "
                         "reference", "value": wall_p, "unit": "s"})
    return rows


def benchmarks() -> list[dict]:
    return block_41_rows() + block_401_rows() + calculix_rows()


if __name__ == "__main__":
    for row in benchmarks():
        print(f"{row['name']:<100} {row['value']:12.4g} {row['unit']}")
