"""Speed of the 3-D shakedown tools.

Rows: the sampled critical friction of a 3-D system (``critical_friction_3d``, which
samples every node pair up to 40 nodes, in closed form over all pairs and angles) at
16, 25 and 40 nodes (median of 5; target < 1 s each), and λ2 with separation
(``lambda2_open``) of a random 40-node coupled system with open nodes, 24 load samples
(median of 3). Times are wall seconds with one BLAS
thread.

:func:`lap_joint_rows`: λ2 with separation of the 751-node lap joint (the refined mesh
of ``bolted_lap_joint.toml`` with elastic steel bolts, ``bolt_modulus = 210e9``, the
sequential protocol, the case's 20 load samples; issue 33 item 4): CPU time, the peak
memory the program adds, λ2 [N], and its checks: a fresh elastic solution at every
sample (the program's certificate) and by the engine: from the program's safe state at
0.97 λ2 it must shake down. The joint is built in one fresh interpreter, λ2 computed in
another (so that the memory row is the program's, not the FE model's).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

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
    return rows + lap_joint_rows()


_BUILD_CHILD = r"""
import pickle, sys
from slipcycle.io import parse_case_text
from slipcycle.examples import example_path
from slipcycle.joints.lap_joint_case import joint_contact, read_lap_joint_case
from slipcycle.joints.lap_joint_showcase import protocol_subjects
text = example_path("bolted_lap_joint.toml").read_text().replace(
    "friction = 0.3\n", "friction = 0.3\nbolt_modulus = 210e9\n", 1)
lc = read_lap_joint_case(parse_case_text(text))
sub = protocol_subjects(joint_contact(lc.joint), lc.protocols[:1], lc.settings)[0]
run = dict(lc.settings.run)
with open(sys.argv[1], "wb") as fh:
    pickle.dump((sub.system, sub.load, run), fh)
"""

_LAP_JOINT_CHILD = r"""
import json, pickle, resource, sys, time
from slipcycle.discrete3d.shakedown import lambda2_open, safe_start
from slipcycle.discrete3d.steady import simulate3d
with open(sys.argv[1], "rb") as fh:
    system, load, run = pickle.load(fh)
steps = run.pop("steps_per_cycle")
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
c0 = time.process_time()
reg = lambda2_open(system, load, steps)
cpu = time.process_time() - c0
rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
below = load.with_lam(0.97 * reg.lambda2)
res = simulate3d(system, below, record=False, steps_per_cycle=steps,
                 initial_slip=safe_start(system, below, reg, steps), **run)
print(json.dumps({"nodes": system.n_nodes, "cpu": cpu, "added_mb": (rss1 - rss0) / 1024,
                  "lambda2": reg.lambda2, "certified": bool(reg.consistent),
                  "below": res.steady_state, "open": int(reg.open_set[0].sum()),
                  "sets": len({s.tobytes() for s in reg.open_set})}))
"""


def lap_joint_rows() -> list[dict]:
    """λ2 of the 751-node lap joint (module docstring): CPU s, memory, λ2 and its check."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "joint.pkl")
        subprocess.run([sys.executable, "-c", _BUILD_CHILD, path], check=True, env=env)
        out = subprocess.run([sys.executable, "-c", _LAP_JOINT_CHILD, path],
                             capture_output=True, text=True, check=True, env=env)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    name = (f"lambda2_open, lap joint {r['nodes']} nodes ({r['open']} open, {r['sets']} "
            f"contact set(s) over the cycle)")
    return [{"name": f"{name}: CPU", "value": r["cpu"], "unit": "s"},
            {"name": f"{name}: peak memory added", "value": r["added_mb"], "unit": "MB",
             "target": "< 4096", "ok": r["added_mb"] < 4096},
            {"name": f"{name}: lambda2", "value": r["lambda2"], "unit": "N",
             "accuracy": f"certified {r['certified']}; the engine from its safe state at "
                         f"0.97 lambda2: {r['below']}",
             "ok": r["certified"] and r["below"] == "shakedown"}]
