"""Bolted lap joint: model build + reduction (``slipcycle.fe.lap_joint``) time and memory.

Rows of :func:`model_rows`: the example joint (``slipcycle.fe.lap_joint.EXAMPLE``, two M8
bolts, h = 2 mm at the interface) and a fine mesh of it (h = 1 mm, 4 elements through each
plate). Each build runs in a fresh interpreter, so that the peak resident set size
(``resource.getrusage``, includes SuperLU's C allocations) is that of one model; wall and
CPU (``time.process_time`` of the child, all its threads) times are medians over the
repeats of each configuration (3 for the example, 1 for the fine mesh). Measured on the
shared 2-core development machine (wall inflated by other jobs): example 11 772 DOF, 529
contact nodes, 4.4–8.4 s CPU, 17–40 s wall, 0.55 GB; fine 66 630 DOF, 1 895 nodes,
144 s CPU (user + sys), 7.7 GB.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys

#: (label, LapJoint keyword arguments, repeats, target seconds, target MB)
CONFIGS = [
    ("example h=2mm", {}, 3, 30.0, 2048.0),
    ("fine h=1mm", {"mesh_size": 0.001, "layers": 4}, 1, 300.0, 8192.0),
]

_CHILD = r"""
import json, resource, sys, time
from slipcycle.fe.lap_joint import LapJoint, lap_joint_model
kwargs = json.loads(sys.argv[1])
t0, c0 = time.perf_counter(), time.process_time()
model = lap_joint_model(LapJoint(**kwargs))
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"wall": wall, "cpu": cpu, "peak_mb": peak / 1024,
                  "nodes": model.n_nodes, "dofs": model.description["dofs"],
                  "reduce": model.description["reduction_s"]}))
"""


def run_one(kwargs: dict) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(kwargs)],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def model_rows() -> list[dict]:
    """Build + reduction of the example lap joint and of a fine mesh of it."""
    rows = []
    for label, kwargs, repeats, t_target, mb_target in CONFIGS:
        runs = [run_one(kwargs) for _ in range(repeats)]
        wall = statistics.median(r["wall"] for r in runs)
        cpu = statistics.median(r["cpu"] for r in runs)
        peak = max(r["peak_mb"] for r in runs)
        name = f"lap joint {label}, {runs[0]['dofs']} DOF, {runs[0]['nodes']} nodes"
        rows.append({"name": f"{name}: wall", "value": wall, "unit": "s",
                     "target": f"< {t_target:g}", "ok": wall < t_target})
        rows.append({"name": f"{name}: CPU", "value": cpu, "unit": "s"})
        rows.append({"name": f"{name}: peak RSS", "value": peak, "unit": "MB",
                     "target": f"< {mb_target:g}", "ok": peak < mb_target})
    return rows


_STUDY_CHILD = r"""
import json, sys, time
from slipcycle.api import run
from slipcycle.examples import example_path
t0, c0 = time.perf_counter(), time.process_time()
res = run(example_path("bolted_lap_joint"))
s = res.summary()
print(json.dumps({"wall": time.perf_counter() - t0, "cpu": time.process_time() - c0,
                  "nodes": s["n_nodes"], "protocols": len(s["protocols"]),
                  "meshes": len(s["mesh_spacing"])}))
"""


def study_rows(repeats: int = 1) -> list[dict]:
    """The whole tightening-order study of the shipped example ``bolted_lap_joint.toml``
    (build and reduce every mesh, run every protocol on each): target < 5 minutes.

    Run in a fresh interpreter (import and Numba compilation included); the median of
    ``repeats`` runs, wall and CPU (``time.process_time``, all threads).
    """
    runs = []
    for _ in range(repeats):
        out = subprocess.run([sys.executable, "-c", _STUDY_CHILD], capture_output=True,
                             text=True, check=True)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    wall = statistics.median(r["wall"] for r in runs)
    cpu = statistics.median(r["cpu"] for r in runs)
    r = runs[0]
    name = (f"lap joint tightening-order study (example: {r['protocols']} protocols, "
            f"{r['meshes']} meshes, {r['nodes']} nodes)")
    return [{"name": f"{name}: wall", "value": wall, "unit": "s", "target": "< 300",
             "ok": wall < 300.0},
            {"name": f"{name}: CPU", "value": cpu, "unit": "s"}]


def benchmarks() -> list[dict]:
    return model_rows() + study_rows()


if __name__ == "__main__":
    for row in benchmarks():
        print(row)
