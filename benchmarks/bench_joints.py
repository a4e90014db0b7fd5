"""Bolted lap joint: model build + reduction (``slipcycle.fe.lap_joint``) time and memory,
the whole tightening-order study of the shipped example, and nested refinement.

Rows of :func:`model_rows`: the shipped example's joint (``bolted_lap_joint.toml``: two
bolts, hexahedra with incompatible modes, refined once) and a fine P1 mesh of 4 mm plates
(h = 1 mm, 4 elements through each plate). Each build runs in a fresh interpreter, so that
the peak resident set size (``resource.getrusage``, includes the factorisation's C
allocations) is that of one model; wall and CPU (``time.process_time`` of the child, all
its threads) times are medians over the repeats of each configuration (3 for the example,
1 for the fine mesh). Measured on the shared 2-core development machine: example 30 330
DOF, 751 contact nodes, 2.9 s wall, 0.69 GB.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys

#: (label, LapJoint keyword arguments or "example", repeats, target seconds, target MB)
CONFIGS = [
    ("example (bolted_lap_joint.toml, H8I, refined once)", "example", 3, 30.0, 2048.0),
    ("4 mm plates, P1, h=1mm", {"mesh_size": 0.001, "layers": 4}, 1, 300.0, 8192.0),
]

_CHILD = r"""
import json, resource, sys, time
from slipcycle.fe.lap_joint import LapJoint, lap_joint_model
kwargs = json.loads(sys.argv[1])
if kwargs == "example":
    from slipcycle.examples import example_path
    from slipcycle.io import read_case
    from slipcycle.joints.lap_joint_case import read_lap_joint_case
    joint = read_lap_joint_case(read_case(example_path("bolted_lap_joint"))).joint
else:
    joint = LapJoint(**kwargs)
t0, c0 = time.perf_counter(), time.process_time()
model = lap_joint_model(joint)
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


_REFINE_CHILD = r"""
import json, sys, time
from slipcycle.fe.lap_joint import LapJoint
from slipcycle.joints.lap_joint_case import joint_contact
from slipcycle.joints.lap_joint_study import StudySettings, run_protocol, standard_protocol
t0 = time.perf_counter()
joint = LapJoint(plate_length=0.06, plate_width=0.03, thickness=0.003, overlap=0.03,
                 bolt_diameter=0.0066, washer_diameter=0.012, mesh_size=0.005,
                 element="H8I", refine=int(sys.argv[1]), end_relief=0.004,
                 end_relief_depth=1e-5)
contact = joint_contact(joint)
t1 = time.perf_counter()
settings = StudySettings(preload=5e3, service_amplitude=1e3, friction=0.3,
                         run=dict(cycles=30, steps_per_cycle=20, tol=1e-6, step_tol=1e-4))
sol = run_protocol(contact, standard_protocol("simultaneous", 2), settings).result.solution
print(json.dumps({"nodes": contact.n_nodes, "spacing": contact.spacing,
                  "build": t1 - t0, "solve": time.perf_counter() - t1,
                  "D": sol.dissipation_per_cycle, "cycles": int(sol.cycles_run)}))
"""


def refinement_rows(levels: tuple = (0, 1)) -> list[dict]:
    """Nested refinement of a small H8I joint (the ``NESTED`` case of
    tests/test_lap_joint_study.py, one protocol): contact nodes, spacing, dissipation and
    the wall time of the steady-state solve per level, with the fitted exponent of the
    solve time against the number of contact nodes (one run per level, fresh interpreter).
    """
    import math

    runs = []
    for k in levels:
        out = subprocess.run([sys.executable, "-c", _REFINE_CHILD, str(k)],
                             capture_output=True, text=True, check=True)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    rows = []
    for k, r in zip(levels, runs, strict=True):
        name = (f"small lap joint refine={k}: {r['nodes']} nodes, spacing "
                f"{1e3 * r['spacing']:.3g} mm")
        rows += [{"name": f"{name}: build + reduce", "value": r["build"], "unit": "s"},
                 {"name": f"{name}: steady state ({r['cycles']} cycles)",
                  "value": r["solve"], "unit": "s"},
                 {"name": f"{name}: dissipation per cycle", "value": 1e6 * r["D"],
                  "unit": "uJ"}]
    if len(runs) > 1:
        a, b = runs[0], runs[-1]
        slope = math.log(b["solve"] / a["solve"]) / math.log(b["nodes"] / a["nodes"])
        rows.append({"name": "small lap joint: steady-state time ~ N^p, fitted p",
                     "value": slope, "unit": "1"})
    return rows


def benchmarks() -> list[dict]:
    return model_rows() + study_rows() + refinement_rows()


if __name__ == "__main__":
    for row in benchmarks():
        print(row)
