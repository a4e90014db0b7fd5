"""Three-dimensional contact reduction: time and peak memory, ~2e5 DOF with ~1000 contact nodes.

Model: :func:`slipcycle.fe.solid3d.block_on_rigid_3d` with linear tetrahedra (P1), a
uniform 31 × 31-element contact face (1 mm elements, 1024 contact nodes) on a rigid flat,
the block 60 × 60 × 40 mm graded by 1.05 (209,952 DOF; a slender 32 × 32 × 65-node column
of the same size is much slower: nested dissection then cuts it into many full
cross-sections); and a smaller sphere on a flat block
(:func:`slipcycle.fe.sphere3d.sphere_on_block`, two bodies). The condensation
(:func:`slipcycle.condensation.schur_complement`) is one supernodal Cholesky factorisation
by CHOLMOD (``cvxopt``, the ``fe`` extra) with the contact DOFs last, S read off the
trailing block of the factor; without ``cvxopt`` it is SuperLU's LU (the child's JSON line
names the one installed). Each configuration runs in a fresh interpreter so that the peak
resident set size (``resource.getrusage``, includes the solver's C allocations) is that of
the one reduction; wall and CPU (user + system) time are both reported, as the wall time
depends on the load of the machine. Target: 2e5 DOF with 1000 contact nodes in < 60 s and
< 8 GB.
"""

from __future__ import annotations

import json
import subprocess
import sys

_CHILD = r"""
import json, resource, sys, time
kind = sys.argv[1]
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0, c0 = time.perf_counter(), time.process_time()
if kind == "block":
    from slipcycle.fe.solid3d import Block3D, block_on_rigid_3d
    el, width, height, grading = (int(sys.argv[2]), float(sys.argv[3]),
                                  float(sys.argv[4]), float(sys.argv[5]))
    h = 1e-3
    b = Block3D(width_x=width, width_y=width, height=height, E=200e9, nu=0.3,
                contact_x=el * h, contact_y=el * h, elements=el, grading=grading,
                element="P1")
    red = block_on_rigid_3d(b)
else:
    from slipcycle.fe.sphere3d import SphereOnBlock, sphere_on_block
    h = float(sys.argv[2])
    m = SphereOnBlock(R=0.01, E=200e9, nu=0.3, contact_radius=7e-4, h_contact=h,
                      h_far=1e-3, radius_body=5e-3, cap_height=5e-3, block_height=5e-3)
    red, _ = sphere_on_block(m)
t1, c1 = time.perf_counter(), time.process_time()
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
ndofs = int(red.source.split(" dofs")[0].split(", ")[-1])
from slipcycle.condensation import cholmod_available
print(json.dumps({"ndofs": ndofs, "nodes": int(red.C.shape[0]), "wall": t1 - t0,
                  "cpu": c1 - c0, "peak_mb": peak / 1024, "base_mb": base / 1024,
                  "method": "CHOLMOD" if cholmod_available() else "SuperLU",
                  "source": red.source[-120:]}))
"""

#: a 54 × 54 × 24-node graded block (209,952 DOF, 1024 contact nodes), and the sphere
CONFIGS = [("block", "31", "0.06", "0.04", "1.05"), ("sphere", "1e-4")]


def run_one(*args: str) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD, *args], capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def benchmarks() -> list[dict]:
    rows = []
    for args in CONFIGS:
        m = run_one(*args)
        label = f"3-D {args[0]}, {m['ndofs']} DOF, {m['nodes']} contact nodes"
        big = args[0] == "block"
        rows.append({"name": f"{label}: build+reduce wall", "value": m["wall"], "unit": "s",
                     **({"target": "< 60", "ok": m["wall"] < 60} if big else {})})
        rows.append({"name": f"{label}: build+reduce CPU", "value": m["cpu"], "unit": "s",
                     **({"target": "< 60", "ok": m["cpu"] < 60} if big else {})})
        rows.append({"name": f"{label}: peak RSS", "value": m["peak_mb"], "unit": "MB",
                     **({"target": "< 8192", "ok": m["peak_mb"] < 8192} if big else {})})
    return rows


if __name__ == "__main__":
    for row in benchmarks():
        print(row)
