"""CalculiX's own frictional contact against slipcycle, side by side (``make bench``).

The block of issue 30: 10 × 10 × 5 mm steel (E = 210 GPa, ν = 0.3), 10 × 10 × 5 C3D8I
hexahedra (726 nodes, the 121 of the bottom face in contact with a rigid flat), top face
pressed down 1 µm and then moved back and forth along x, δ(t) = δ_t sin 2πt, Q/fP ≈ 0.9,
friction f = 0.5. The deck ``benchmarks/calculix/block_friction.inp`` (written by
:func:`block_deck`, checked identical here) runs it in CalculiX 2.20 with
surface-to-surface penalty contact (pressure-overclosure slope 1e16 Pa/m, stick slope
1e15 Pa/m) against a flat of fixed hexahedra for a few cycles; the dissipation of each
cycle is the work of the grip, ∮ F_x dδ, from the reaction totals CalculiX prints. slipcycle
reduces the same mesh (:func:`slipcycle.fe.hex8i.hex8i_stiffness`, the element CalculiX's
C3D8I equals to 1e-10, tests/test_calculix_blocks.py) onto the contact nodes and runs it
to its periodic state.

Rows: CalculiX's wall time and its dissipation in each cycle, slipcycle's wall time
(reduction and run) and D, and the wall-time ratio. Skipped (no rows) without ``ccx``.
"""

from __future__ import annotations

import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DECK = HERE / "calculix" / "block_friction.inp"

E, NU, RHO, FRICTION = 210e9, 0.3, 7800.0, 0.5
SIZE = (0.01, 0.01, 0.005)
DELTA_N = 1e-6              # top face pressed down, m
DELTA_T = 1.6e-6            # tangential amplitude of the top face, m (Q/fP = 0.92)
PENALTY, STICK = 1e16, 1e15  # Pa/m
CYCLES, INCREMENTS = 3, 40  # CalculiX: cycles run, increments per cycle

#: ccx's local vertex order of a hexahedron (bottom counter-clockwise, then the top)
_HEX = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                 [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])


def _grid(n, size, z0=0.0):
    x, y = (np.linspace(0.0, s, k + 1) for s, k in zip(size[:2], n[:2], strict=True))
    z = np.linspace(z0, z0 + size[2], n[2] + 1)
    X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
    pts = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    idx = np.arange(pts.shape[0]).reshape(len(x), len(y), len(z))
    hexes = np.array([[idx[i + a, j + b, k + c] for a, b, c in _HEX]
                      for k in range(n[2]) for j in range(n[1]) for i in range(n[0])])
    return pts, hexes


def block_mesh(n=(10, 10, 5)):
    """Points (m, 3) and hexahedra (e, 8) in ccx's vertex order of the block."""
    return _grid(n, SIZE)


def _lines(ids, per=10):
    ids = [str(int(i)) for i in ids]
    return [", ".join(ids[i:i + per]) for i in range(0, len(ids), per)]


def block_deck(n=(10, 10, 5), cycles=CYCLES, increments=INCREMENTS) -> str:
    """The CalculiX deck: the block (nodes 1.., elements 1..), a flat of fixed C3D8
    below it (z ∈ [−1, 0] mm, its own nodes), surface-to-surface contact, a normal step
    and ``cycles`` tangential cycles of ``increments`` fixed increments."""
    pts, hexes = block_mesh(n)
    fpts, fhex = _grid((n[0], n[1], 1), (SIZE[0], SIZE[1], 1e-3), -1e-3)
    off = pts.shape[0]
    out = ["*HEADING", "slipcycle benchmark: steel block on a rigid flat, frictional cycles",
           "*NODE, NSET=NALL"]
    out += [f"{j + 1}, {x:.17g}, {y:.17g}, {z:.17g}" for j, (x, y, z) in enumerate(pts)]
    out += [f"{off + j + 1}, {x:.17g}, {y:.17g}, {z:.17g}" for j, (x, y, z) in enumerate(fpts)]
    out.append("*ELEMENT, TYPE=C3D8I, ELSET=BLOCK")
    out += [f"{e + 1}, " + ", ".join(str(v + 1) for v in h) for e, h in enumerate(hexes)]
    out.append("*ELEMENT, TYPE=C3D8, ELSET=FLAT")
    ne = hexes.shape[0]
    out += [f"{ne + e + 1}, " + ", ".join(str(off + v + 1) for v in h)
            for e, h in enumerate(fhex)]
    bottom_el = [e + 1 for e in range(n[0] * n[1])]
    out += ["*NSET, NSET=TOP"] + _lines(np.flatnonzero(np.isclose(pts[:, 2], SIZE[2])) + 1)
    out += ["*NSET, NSET=FIXED"] + _lines(off + np.arange(fpts.shape[0]) + 1)
    out += ["*ELSET, ELSET=EBOTTOM"] + _lines(bottom_el)
    out += ["*ELSET, ELSET=EFLAT"] + _lines(ne + np.arange(fhex.shape[0]) + 1)
    out += ["*SURFACE, NAME=SBOTTOM, TYPE=ELEMENT", "EBOTTOM, S1",
            "*SURFACE, NAME=SFLAT, TYPE=ELEMENT", "EFLAT, S2",
            "*MATERIAL, NAME=STEEL", "*ELASTIC", f"{E:.17g}, {NU:.17g}",
            "*DENSITY", f"{RHO:.17g}",
            "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL",
            "*SOLID SECTION, ELSET=FLAT, MATERIAL=STEEL",
            "*SURFACE INTERACTION, NAME=SI",
            "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", f"{PENALTY:.6g}",
            "*FRICTION", f"{FRICTION:g}, {STICK:.6g}",
            "*CONTACT PAIR, INTERACTION=SI, TYPE=SURFACE TO SURFACE", "SBOTTOM, SFLAT"]
    t = np.linspace(0.0, cycles, 4 * cycles * 8 + 1)
    amp = [f"{a:.9g}, {np.sin(2 * np.pi * a):.12g}" for a in t]
    out += ["*AMPLITUDE, NAME=CYCLES"] + amp          # step time (the default)
    out += ["*BOUNDARY", "FIXED, 1, 3", "TOP, 1, 2",
            "*STEP, INC=1000", "*STATIC, DIRECT", "0.25, 1.0",
            "*BOUNDARY", f"TOP, 3, 3, {-DELTA_N:.12g}",
            "*NODE PRINT, NSET=TOP, TOTALS=ONLY", "RF", "*END STEP",
            f"*STEP, INC={10 * cycles * increments}", "*STATIC, DIRECT",
            f"{1.0 / increments:.12g}, {float(cycles):.12g}",
            "*BOUNDARY, AMPLITUDE=CYCLES", f"TOP, 1, 1, {DELTA_T:.12g}",
            "*NODE PRINT, NSET=TOP, TOTALS=ONLY", "RF", "*END STEP"]
    return "\n".join(out) + "\n"


def reduced_block(n=(10, 10, 5)):
    """slipcycle's reduction of the block onto its bottom nodes (top face held), with the
    load cases ``normal`` (top down 1 m) and ``tangential`` (top along x 1 m)."""
    from slipcycle.fe.contact3d import Case3D, condense_contact_3d
    from slipcycle.fe.hex8i import hex8i_stiffness

    pts, hexes = block_mesh(n)
    xyz = pts.T
    dofs = np.arange(3 * pts.shape[0]).reshape(-1, 3)
    bottom = np.flatnonzero(np.isclose(pts[:, 2], 0.0))
    top = np.flatnonzero(np.isclose(pts[:, 2], SIZE[2]))
    fixed = np.zeros((pts.shape[0], 3), bool)
    fixed[top] = True
    cases = []
    for name, move in (("normal", (0.0, 0.0, -1.0)), ("tangential", (1.0, 0.0, 0.0))):
        u = np.zeros((pts.shape[0], 3))
        u[top] = move
        cases.append(Case3D(name, "m", displacement=u))
    return condense_contact_3d(lambda: (hex8i_stiffness(xyz, hexes.T, E, NU), "C3D8I"),
                               dofs, xyz, pairs=np.column_stack([bottom, -np.ones_like(bottom)]),
                               normals=(0.0, 0.0, -1.0),
                               tangents=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), fixed=fixed,
                               cases=cases)


def block_system(red):
    """The reduced block's frictional system and the deck's load: (system, load)."""
    from slipcycle.discrete3d import FrictionalSystem3D, Load3D

    n = red.C.shape[0]
    load = Load3D.harmonic(DELTA_N * red.loads["normal"]["p"],
                           DELTA_N * red.loads["normal"]["q"],
                           DELTA_T * red.loads["tangential"]["p"],
                           DELTA_T * red.loads["tangential"]["q"])
    system = FrictionalSystem3D(red.A, red.B, red.C, np.full(n, FRICTION),
                                accept_ill_posed=True)
    return system, load


def slipcycle_run(red, cycles: int = 200):
    """The periodic state of the reduced block under the deck's load; the result."""
    from slipcycle.discrete3d.case import solve_model

    system, load = block_system(red)
    return solve_model(system, load, {"cycles": cycles, "steps_per_cycle": 40}, fields=())


def q_over_fp(red) -> float:
    """Q/fP of the load with the interface stuck: tangential force amplitude over f times
    the normal force."""
    Q = DELTA_T * abs(red.loads["tangential"]["q"][0::2].sum())
    return Q / (FRICTION * DELTA_N * red.loads["normal"]["p"].sum())


_FORCE = re.compile(r"total force \(fx,fy,fz\) for set TOP and time"
                    r"\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)")


def grip_forces(dat: str) -> tuple[np.ndarray, np.ndarray]:
    """Times (total time) and reaction totals (k, 3), N, of the set TOP in a ``.dat``."""
    hits = _FORCE.findall(dat)
    t = np.array([float(h[0]) for h in hits])
    F = np.array([[float(v) for v in h[1:]] for h in hits])
    return t, F


def cycle_dissipation(t: np.ndarray, fx: np.ndarray, cycles: int = CYCLES) -> np.ndarray:
    """Work of the grip ∮ F_x dδ in each tangential cycle (J): δ(t) = δ_t A(t) with the
    deck's piecewise-linear amplitude A, F_x the reaction on the body (trapezoids)."""
    tab = np.linspace(0.0, cycles, 4 * cycles * 8 + 1)
    s = t - 1.0                                    # step time of the tangential step
    keep = s > -1e-12
    s, f = np.concatenate([[0.0], s[keep]]), np.concatenate([[fx[keep][0]], fx[keep]])
    f[0] = fx[~keep][-1] if np.any(~keep) else 0.0  # end of the normal step
    d = DELTA_T * np.interp(s, tab, np.sin(2 * np.pi * tab))
    work = 0.5 * (f[1:] + f[:-1]) * np.diff(d)
    end = s[1:]
    return np.array([work[(end > k + 1e-9) & (end <= k + 1 + 1e-9)].sum()
                     for k in range(cycles)])


def run_calculix(deck: Path, timeout: float = 3600.0) -> tuple[float, str]:
    """Run ``ccx`` on a copy of the deck in a temporary directory: (wall time s, .dat)."""
    with tempfile.TemporaryDirectory() as tmp:
        job = Path(tmp) / "block"
        shutil.copy(deck, job.with_suffix(".inp"))
        env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_STIFFNESS="1",
                   CCX_NPROC_EQUATION_SOLVER="1")
        t0 = time.perf_counter()
        proc = subprocess.run([shutil.which("ccx"), "-i", "block"], cwd=tmp, env=env,
                              capture_output=True, text=True, timeout=timeout)
        wall = time.perf_counter() - t0
        if proc.returncode != 0 or "Job finished" not in proc.stdout:
            raise RuntimeError(f"ccx failed (exit {proc.returncode}): "
                               f"{proc.stdout[-500:]}")
        return wall, job.with_suffix(".dat").read_text()


def benchmarks() -> list[dict]:
    if shutil.which("ccx") is None:
        print("  bench_calculix: ccx not installed (apt-get install calculix-ccx); no rows",
              file=sys.stderr)
        return []
    if DECK.read_text() != block_deck():
        raise RuntimeError(f"{DECK} differs from block_deck(): rewrite it with "
                           "python benchmarks/bench_calculix.py --write-deck")
    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall_ccx, dat = run_calculix(DECK)
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu_ccx = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
    t, F = grip_forces(dat)
    per_cycle = cycle_dissipation(t, F[:, 0])
    t0, c0 = time.perf_counter(), time.process_time()
    red = reduced_block()
    res = slipcycle_run(red)
    wall_slip, cpu_slip = time.perf_counter() - t0, time.process_time() - c0
    # on a shared machine the wall times include waiting: the CPU times are given too
    rows = [{"name": f"CalculiX {CYCLES} cycles, 121-node block, wall time",
             "value": wall_ccx, "unit": "s"},
            {"name": "CalculiX CPU time", "value": cpu_ccx, "unit": "s"},
            {"name": "CalculiX Q/fP (largest grip force / f P)",
             "value": float(np.abs(F[t > 1.0, 0]).max() / (FRICTION * abs(F[t <= 1.0][-1, 2]))),
             "unit": "1"}]
    rows += [{"name": f"CalculiX dissipation, cycle {k + 1} (work of the grip)",
              "value": float(w), "unit": "J"} for k, w in enumerate(per_cycle)]
    rows += [{"name": f"slipcycle reduce + run to {res.steady_state} ({res.cycles_run} cyc), "
                      "wall", "value": wall_slip, "unit": "s"},
             {"name": "slipcycle dissipation per cycle D (Q/fP = "
                      f"{q_over_fp(red):.2f})", "value": float(res.dissipation_per_cycle),
              "unit": "J"},
             {"name": "slipcycle CPU time", "value": cpu_slip, "unit": "s"},
             {"name": "wall time CalculiX / slipcycle", "value": wall_ccx / wall_slip,
              "unit": "1"},
             {"name": "CPU time CalculiX / slipcycle", "value": cpu_ccx / cpu_slip,
              "unit": "1"}]
    return rows


if __name__ == "__main__":
    if "--write-deck" in sys.argv:
        DECK.write_text(block_deck())
        print(f"wrote {DECK}")
    else:
        for row in benchmarks():
            print(f"{row['name']:<60} {row['value']:12.5g} {row['unit']}")
