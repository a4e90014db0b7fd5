"""Speed of the 3-D shakedown tools.

Rows: the sampled critical friction of a 3-D system (``critical_friction_3d``, which
samples every node pair up to 40 nodes, in closed form over all pairs and angles) at
16, 25 and 40 nodes (median of 5; target < 1 s each), and λ2 with separation
(``lambda2_open``) of a random 40-node coupled system with open nodes, 24 load samples
(median of 3). Times are wall seconds with one BLAS
thread.
"""

from __future__ import annotations

import time

import numpy as np
from threadpoolctl import threadpool_limits

from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.shakedown import lambda2_open
from slipcycle.discrete3d.wellposed import critical_friction_3d


def _system(n: int, seed: int):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    return K[:2 * n, :2 * n], K[2 * n:, :2 * n], K[2 * n:, 2 * n:], rng


def _median(func, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        func()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def benchmarks() -> list[dict]:
    rows = []
    with threadpool_limits(1, user_api="blas"):
        for n in (16, 25, 40):
            A, B, C, _ = _system(n, n)
            t = _median(lambda A=A, B=B, C=C, n=n: critical_friction_3d(
                A, B, C, np.full(n, 0.3)), 5)
            rows.append({"name": f"critical_friction_3d, {n} nodes (pairs sampled)",
                         "value": t, "unit": "s", "target": "< 1", "ok": t < 1})
        n = 40
        A, B, C, rng = _system(n, 7)
        system = FrictionalSystem3D(A, B, C, 0.3, accept_ill_posed=True)
        load = Load3D.harmonic(rng.uniform(-0.3, 1.0, n) * 10, rng.normal(size=2 * n),
                               3 * rng.normal(size=(1, n)), 2 * rng.normal(size=(1, 2 * n)))
        t = _median(lambda: lambda2_open(system, load, 24), 3)
        rows.append({"name": "lambda2_open, 40 nodes with open nodes, 24 samples",
                     "value": t, "unit": "s"})
    return rows
