"""Benchmarks of the coupled discrete solver (issue 3): events per second and wall time to
the steady state for N = 2, 20, 200, 1000, and agreement with a brute-force reference on
N = 2.

The stiffness is FE-like: A, C decaying oscillating Toeplitz matrices (positive definite),
B an odd, decaying coupling kernel as for a punch on a strip; harmonic loads with 100 load
samples per cycle, q^w larger towards the ends so that slip starts at the contact edges.
"""

from __future__ import annotations

import itertools
import time

import numpy as np

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate


def fe_like(n: int):
    i = np.arange(n)
    d = np.abs(i[:, None] - i[None, :])
    A = 2.0 * np.exp(-d / 2.0) * np.cos(0.7 * d) + np.eye(n)
    C = 1.3 * A
    B = 0.3 * np.sign(i[:, None] - i[None, :]) * np.exp(-d / 3.0)
    return A, B, C


def case(n: int):
    A, B, C = fe_like(n)
    system = FrictionalSystem(A, B, C, 0.3)
    x = np.linspace(-1.0, 1.0, n) if n > 1 else np.zeros(1)
    edge = np.abs(x) ** 4
    load = DiscreteLoad.harmonic(np.ones(n), 0.05 * x, 0.2 * np.ones(n), 0.15 + 0.35 * edge,
                                 np.zeros(n), 0.6 * x)
    return system, load


def brute_force_dissipation(system, load, steps, substeps, cycles):
    """Backward-Euler incremental problem, all 4^N node states enumerated (N small)."""
    n = system.n_nodes
    K, f = system.K, system.friction
    combos = np.array(list(itertools.product(range(4), repeat=n)))
    nc = len(combos)
    M = np.zeros((nc, 2 * n, 2 * n))
    Sx = np.zeros_like(M)
    Sr = np.zeros_like(M)
    for j in range(n):
        m = combos[:, j]
        M[m == 0, j, j] = 1
        Sx[m == 0, j, j] = 1
        M[m == 0, n + j, n + j] = 1
        for sel, sg in ((m == 1, 1.0), (m == 2, -1.0)):
            M[sel, j] = sg * K[j] + f[j] * K[n + j]
            Sr[sel, j, j] = -sg
            Sr[sel, j, n + j] = -f[j]
            M[sel, n + j, n + j] = 1
        M[m == 3, j] = K[j]
        Sr[m == 3, j, j] = -1
        M[m == 3, n + j] = K[n + j]
        Sr[m == 3, n + j, n + j] = -1
    Minv = np.linalg.inv(M)
    Px, Pr = Minv @ Sx, Minv @ Sr
    th = np.linspace(0, 2 * np.pi * cycles, steps * substeps * cycles + 1)
    path = np.vstack([np.linspace(0, 1, 50)[:, None] * load(th[:1]), load(th)])
    x = np.zeros(2 * n)
    D = 0.0
    for k, rw in enumerate(path[1:]):
        X = Px @ x + Pr @ rw
        R = rw + X @ K.T
        q, p, dv, w = R[:, :n], R[:, n:], X[:, :n] - x[:n], X[:, n:]
        tol = 1e-9 * np.abs(rw).max()
        ok = np.all((combos != 0) | ((np.abs(q) <= f * p + tol) & (p >= -tol)), axis=1)
        ok &= np.all((combos != 1) | ((dv >= -tol) & (p >= -tol)), axis=1)
        ok &= np.all((combos != 2) | ((dv <= tol) & (p >= -tol)), axis=1)
        ok &= np.all((combos != 3) | (w >= -tol), axis=1)
        g = np.flatnonzero(ok)[0]
        if k >= len(path) - 1 - steps * substeps:
            D -= q[g] @ (X[g, :n] - x[:n])
        x = X[g]
    return D


def benchmarks() -> list[dict]:
    rows = []
    for n in (2, 20, 200, 1000):
        system, load = case(n)
        t0 = time.perf_counter()
        res = simulate(system, load, cycles=50, steps_per_cycle=100, record=False)
        wall = time.perf_counter() - t0
        events = sum(res.events_per_cycle)
        rows.append({"name": f"N={n}: wall time to {res.steady_state} "
                             f"({res.cycles_run} cycles)", "value": float(wall), "unit": "s",
                     **({"target": "< 2", "ok": bool(wall < 2.0 and res.steady_converged)}
                        if n == 200 else {})})
        rows.append({"name": f"N={n}: events per second ({events} events)",
                     "value": float(events / wall), "unit": "1/s"})
        rows.append({"name": f"N={n}: slipping / stuck nodes",
                     "value": float(len(res.slipping_nodes)), "unit":
                     f"of {n} ({len(res.permanently_stuck_nodes)} stuck)"})
    # brute force on N = 2
    system, load = case(2)
    t0 = time.perf_counter()
    res = simulate(system, load, cycles=50, steps_per_cycle=100, tol=1e-12)
    t_ev = time.perf_counter() - t0
    t0 = time.perf_counter()
    d_bf = brute_force_dissipation(system, load, 100, 20, max(res.cycles_run, 3))
    t_bf = time.perf_counter() - t0
    rel = abs(d_bf - res.dissipation_per_cycle) / max(abs(res.dissipation_per_cycle), 1e-300)
    rows.append({"name": "N=2: brute force (4^N, 20 substeps) vs event-driven: rel. diff D",
                 "value": float(rel), "unit": "1", "target": "< 1e-2", "ok": bool(rel < 1e-2)})
    rows.append({"name": "N=2: brute force wall time / event-driven wall time",
                 "value": float(t_bf / t_ev), "unit": "1"})
    return rows


if __name__ == "__main__":
    for r in benchmarks():
        print(r)
