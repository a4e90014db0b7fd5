"""Static reduction: time and peak memory for 1e4 / 1e5 DOF with ~100 / ~400 contact nodes.

Model: ``block_on_rigid`` (P2, complete contact, uniform mesh), contact nodes 2·elements+1,
height chosen for the DOF target. Each configuration runs in a fresh interpreter so that
the peak resident set size (``resource.getrusage``, includes the solver's C allocations) is
that of the one reduction. Target (issue 6): 1e5 DOF with 400 contact nodes in < 30 s
and < 4 GB.
"""

from __future__ import annotations

import json
import subprocess
import sys

CONFIGS = [(10_000, 50), (10_000, 200), (100_000, 50), (100_000, 200)]  # (DOF, elements)

_CHILD = r"""
import json, resource, sys, time
from slipcycle.fe.builders import block_on_rigid
from slipcycle.fe.reduction import reduce_problem
dofs, el = int(sys.argv[1]), int(sys.argv[2])
h = 1.0 / el
ny = max(1, round((dofs / (2 * (2 * el + 1)) - 1) / 2))
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0 = time.perf_counter()
pr = block_on_rigid(width=1.0, height=ny * h, E=1.0, nu=0.3, elements=el, grading=1.0)
t1 = time.perf_counter()
r = reduce_problem(pr)
t2 = time.perf_counter()
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"ndofs": pr.ndofs, "nodes": r.n, "build": t1 - t0, "reduce": t2 - t1,
                  "peak_mb": peak / 1024, "base_mb": base / 1024}))
"""


def run_one(dofs: int, elements: int) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD, str(dofs), str(elements)],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def benchmarks() -> list[dict]:
    rows = []
    for dofs, el in CONFIGS:
        m = run_one(dofs, el)
        label = f"reduce {m['ndofs']} DOF, {m['nodes']} contact nodes"
        total = m["build"] + m["reduce"]
        big = dofs == 100_000 and el == 200
        rows.append({"name": f"{label}: build+reduce", "value": total, "unit": "s",
                     **({"target": "< 30", "ok": total < 30} if big else {})})
        rows.append({"name": f"{label}: condensation only", "value": m["reduce"], "unit": "s"})
        rows.append({"name": f"{label}: peak RSS", "value": m["peak_mb"], "unit": "MB",
                     **({"target": "< 4096", "ok": m["peak_mb"] < 4096} if big else {})})
    return rows


if __name__ == "__main__":
    for row in benchmarks():
        print(row)
