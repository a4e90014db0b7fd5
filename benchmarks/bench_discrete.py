"""Benchmarks of the coupled discrete solver: events per second and wall time to the steady
state for N = 2, 20, 200, 1000, agreement with a brute-force reference on N = 2, and the
scaling of the wall time with N (fitted exponents) for random FE-like systems and for
FE-reduced blocks.

The random stiffness is FE-like: A, C decaying oscillating Toeplitz matrices (positive
definite), B an odd, decaying coupling kernel as for a punch on a strip; harmonic loads
with 100 load samples per cycle, q^w larger towards the ends so that slip starts at the
contact edges.

The FE-reduced blocks are the steel block of ``fe_block_nu03.toml`` (plane strain, complete
contact on a rigid flat, ν = 0.3) reduced by :mod:`slipcycle.fe` with 20, 50, 80, 200
quadratic elements across the contact (41, 101, 161, 401 contact nodes), assembled "slide
first" (pressed 0.2 µm, pushed 3 µm along +t, pressed to 2 µm) and cycled with 50 load
samples per cycle: they creep geometrically to a cyclic-slip orbit (hundreds to thousands
of plain cycles), which the steps of :mod:`slipcycle.discrete.periodic` with its slow-mode
steps (``simulate(slow_modes=True)``: at this tolerance the follower alone leaves the
101-node block unconverged after 600 cycles) reach in tens to about a hundred and fifty.
They run at tolerance 1e-11: their D is small against the state's elastic energy, so
D to 1e-6 needs the state to about 1e-11. Reference dissipations of plain cycling
(``accelerate=False``) were measured once and are stored below. The 401-node block also
runs with the follower alone (``slow_modes=False``; the default path, with the slow-mode
steps, is ``bench_accelerated.py``'s) and plainly, both at the default tolerance: the
follower finds no step there, and its attempts must cost little (target: less than 1.3
times plain cycling's wall time).

The 2000-node row is the same block reduced with 1000 quadratic elements across the
contact (2001 contact nodes), loaded monotonically to θ = 0 and cycled in partial slip
(tangential amplitude 3.15 µm: slip zones at the contact edges, the classical fretting
regime of Cattaneo–Mindlin); the reduction (about a minute) is cached in the temporary
directory (``slipcycle-bench/``) and timed in its own row. With every node slipping at some
instant of the cycle (the slide-first load above) a cycle of this model has over 2000 events
of O(k² + kN) each (k slipping unknowns, Klarbring 1990's rate problem with a dense
reduced stiffness), tens of seconds per cycle.
"""

from __future__ import annotations

import itertools
import pickle
import tempfile
import time
from pathlib import Path

import numpy as np

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.fe.builders import block_on_rigid
from slipcycle.fe.loads import combined_loads
from slipcycle.fe.reduction import reduce_problem

#: dissipation per cycle [J] of plain cycling (accelerate=False, tol=1e-13, 50 samples per
#: cycle) of the slide-first blocks, by contact nodes (measured once; minutes each). 401
#: nodes: one more exact cycle after 2200 plain cycles (145 s), whose increments had
#: reached round-off (3e-18 m); the same value as tests/test_discrete_slow_modes.py
PLAIN_REFERENCE_D = {41: 3.1769966252792746e-07, 101: 1.422803542687334e-07,
                     401: 2.00886690660932e-08}

#: tolerance of the FE-block rows (module docstring)
FE_BLOCK_TOL = 1e-11


def fe_block(elements: int):
    """The slid steel block (module docstring): (system, load, protocol, reduction seconds)."""
    t0 = time.perf_counter()
    r = reduce_problem(block_on_rigid(width=0.04, height=0.02, E=210e9, nu=0.3,
                                      elements=elements, thickness=0.01))
    t_red = time.perf_counter() - t0
    load = DiscreteLoad(*combined_loads(r, {"normal": 2e-6},
                                        {"normal": 0.5e-6, "tangential": 1.5e-6},
                                        {"tangential": np.pi / 2}))
    system = FrictionalSystem(r.A, r.B, r.C, 0.5, accept_ill_posed=True)
    protocol = np.array([np.concatenate(r.combine(normal=a, tangential=t))
                         for a, t in ((0.2e-6, 0.0), (0.2e-6, 3e-6), (2e-6, 3e-6))])
    return system, load, protocol, t_red


#: tangential amplitude [m] of the partial-slip cycle of the 2000-node row (module docstring)
PARTIAL_SLIP_AMPLITUDE = 3.15e-6


def reduced_block(elements: int):
    """The steel block reduced with ``elements`` quadratic elements across the contact,
    cached under the temporary directory: (reduced model, reduction wall time [s], whether
    it came from the cache). The time of a cached model is the one measured when it was
    built."""
    path = Path(tempfile.gettempdir()) / "slipcycle-bench" / f"fe_block_{elements}.pkl"
    if path.exists():
        with path.open("rb") as fh:
            r, t_red = pickle.load(fh)
        return r, t_red, True
    t0 = time.perf_counter()
    r = reduce_problem(block_on_rigid(width=0.04, height=0.02, E=210e9, nu=0.3,
                                      elements=elements, thickness=0.01))
    t_red = time.perf_counter() - t0
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("wb") as fh:
        pickle.dump((r, t_red), fh, protocol=pickle.HIGHEST_PROTOCOL)
    return r, t_red, False


def fe_reduced_2000_rows() -> list[dict]:
    """2001 contact nodes: reduction time, and wall time to the steady state in partial
    slip (target < 30 s), with the time per event and the events per cycle."""
    r, t_red, cached = reduced_block(1000)
    rows = [{"name": "FE block 2001 contact nodes: FE reduction" +
                     (" (cached; time of the first build)" if cached else ""),
             "value": t_red, "unit": "s"}]
    load = DiscreteLoad(*combined_loads(r, {"normal": 2e-6},
                                        {"normal": 0.5e-6,
                                         "tangential": PARTIAL_SLIP_AMPLITUDE},
                                        {"tangential": np.pi / 2}))
    system = FrictionalSystem(r.A, r.B, r.C, 0.5, accept_ill_posed=True)
    t0, c0 = time.perf_counter(), time.process_time()
    res = simulate(system, load, cycles=100, steps_per_cycle=50, record=False)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    events = sum(res.events_per_cycle)
    st = res.solver_stats
    rows.append({"name": f"FE block 2001 contact nodes, partial slip: wall time to "
                         f"{res.steady_state} ({res.cycles_run} cycles, "
                         f"{st['periodic_steps']} periodic steps, "
                         f"{len(res.slipping_nodes)} slipping nodes; CPU {cpu:.1f} s)",
                 "value": wall, "unit": "s", "target": "< 30",
                 "ok": bool(wall < 30.0 and res.steady_converged)})
    rows.append({"name": "FE block 2001 contact nodes: time per event "
                         f"({events / max(res.cycles_run, 1):.0f} events per cycle)",
                 "value": 1e3 * wall / max(events, 1), "unit": "ms"})
    return rows


def default_path_rows(system, load, protocol, ref) -> list[dict]:
    """The 401-node block with the follower alone (exact steps only, default tolerance)
    and plainly cycled: the follower finds no step there (the piece of the cycle map
    changes every cycle), so the same cycles must not cost much more than plain
    cycling's."""
    def timed(accelerate):
        t0 = time.perf_counter()
        res = simulate(system, load, cycles=3000, steps_per_cycle=50, protocol=protocol,
                       record=False, accelerate=accelerate, slow_modes=False)
        return time.perf_counter() - t0, res

    t_def, r_def = timed(None)
    t_plain, r_plain = timed(False)
    st = r_def.solver_stats
    return [{"name": f"FE block 401, follower alone at tol 1e-8 ({r_def.cycles_run} cycles, "
                     f"{st['periodic_steps']} steps, {st['periodic_attempts']} attempts; "
                     f"D {abs(r_def.dissipation_per_cycle - ref) / ref:.1e} off the limit)",
             "value": t_def, "unit": "s"},
            {"name": f"FE block 401, plain cycling at tol 1e-8 ({r_plain.cycles_run} cycles)",
             "value": t_plain, "unit": "s"},
            {"name": "FE block 401: follower alone / plain cycling, wall time",
             "value": t_def / t_plain, "unit": "1", "target": "< 1.3",
             "ok": bool(t_def / t_plain < 1.3)}]


def _fit_exponent(ns, walls) -> float:
    """Slope of log(wall) against log(N) (least squares)."""
    return float(np.polyfit(np.log(ns), np.log(walls), 1)[0])


def scaling_rows() -> list[dict]:
    """Wall time versus N: random FE-like systems and FE-reduced blocks."""
    rows = []
    ns, walls = [], []
    for n in (100, 200, 500, 1000, 2000):
        system, load = case(n)
        t0 = time.perf_counter()
        res = simulate(system, load, cycles=50, steps_per_cycle=100, record=False)
        wall = time.perf_counter() - t0
        events = sum(res.events_per_cycle)
        ns.append(n)
        walls.append(wall)
        row = {"name": f"random FE-like N={n}: wall time to {res.steady_state} "
                       f"({res.cycles_run} cycles, {events} events)",
               "value": wall, "unit": "s"}
        if n == 2000:
            row.update(target="< 5", ok=bool(wall < 5.0 and res.steady_converged))
        rows.append(row)
        rows.append({"name": f"random FE-like N={n}: time per event", "value":
                     1e3 * wall / max(events, 1), "unit": "ms"})
    rows.append({"name": "random FE-like: fitted exponent of wall time ~ N^a (N=100..2000)",
                 "value": _fit_exponent(ns, walls), "unit": "1"})
    ns, walls = [], []
    for elements in (20, 50, 80, 200):
        system, load, protocol, t_red = fe_block(elements)
        n = system.n_nodes
        t0 = time.perf_counter()
        res = simulate(system, load, cycles=600, steps_per_cycle=50, protocol=protocol,
                       record=False, tol=FE_BLOCK_TOL, slow_modes=True)
        wall = time.perf_counter() - t0
        if res.steady_converged:       # the fit is over runs that reached the steady state
            ns.append(n)
            walls.append(wall)
        st = res.solver_stats
        row = {"name": f"FE block {n} contact nodes: wall time to {res.steady_state} at "
                       f"tol {FE_BLOCK_TOL:g} ({res.cycles_run} cycles, "
                       f"{st['periodic_steps']} periodic steps, of which "
                       f"{st['slow_mode_steps']} slow-mode)",
               "value": wall, "unit": "s"}
        if n == 401:
            row.update(target="< 5", ok=bool(wall < 5.0 and res.steady_converged))
        rows.append(row)
        rows.append({"name": f"FE block {n} contact nodes: FE reduction (not timed above)",
                     "value": t_red, "unit": "s"})
        ref = PLAIN_REFERENCE_D.get(n)
        if ref is not None:
            rel = abs(res.dissipation_per_cycle - ref) / ref
            rows.append({"name": f"FE block {n}: D vs plain cycling, relative difference",
                         "value": rel, "unit": "1", "target": "< 1e-6",
                         "ok": bool(rel < 1e-6)})
        if n == 401:
            rows.extend(default_path_rows(system, load, protocol, ref))
        if ref is not None and n <= 101:
            # the scale of that difference: plain cycling stopped at the default tolerance 1e-8
            t0 = time.perf_counter()
            plain = simulate(system, load, cycles=3000, steps_per_cycle=50,
                             protocol=protocol, record=False, accelerate=False)
            wall = time.perf_counter() - t0
            rows.append({"name": f"FE block {n}: plain cycling to the default tolerance "
                                 f"({plain.cycles_run} cycles, {wall:.1f} s), D vs its "
                                 "limit", "unit": "1",
                         "value": abs(plain.dissipation_per_cycle - ref) / ref})
    rows.append({"name": f"FE blocks: fitted exponent of wall time ~ N^a (N={ns[0]}..{ns[-1]}, "
                         "converged runs)", "value": _fit_exponent(ns, walls), "unit": "1"})
    return rows


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
    for n in (2, 20, 200):
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
    return rows + scaling_rows() + fe_reduced_2000_rows()


if __name__ == "__main__":
    for r in benchmarks():
        print(r)
