"""Speed of the 3-D discrete model (isotropic Coulomb cone).

Rows: the time per cycle of a 2000-node system (6000 dofs, dense FE-like K; the first
three cycles, a measurement), its full run to the steady state (issue 32's target: at
most 50 cycles of 100 load samples in 5 s of solver time), the CalculiX block of 121
contact nodes to its steady state (target 1.5 s, :func:`calculix_block_rows`), and the
costs per load-step solve and per Newton iteration against N (100 … 2000) with the
fitted exponents. Each target row carries where its time goes (cycles, load steps per
sample, Newton iterations per solve, µs per iteration: :func:`run_counters`) and its D
against the same run at a tighter tolerance, so that a speed-up cannot hide an accuracy
loss. Times are CPU seconds (one BLAS thread; medians of 3 runs for the target rows),
the quiet-machine estimate on a shared machine; the wall times are kept beside them
(``wall_s``). The full run to the steady state
(``discrete3d_2000_nodes_to_steady_state``) is always run, with the steady-state class,
the cycles run, the jumps of the
accelerated cycle loop (``simulate3d``: reduced rank extrapolation, then Anderson mixing
of every cycle of the pattern) and the cycles run on the frozen subdivision of the step
control (``replay``, whose fixed point is accepted after a replay with every error
estimate checked); plain cycling of this system creeps toward its periodic state by a
factor of about 0.987 per cycle at the end (the nodes at the edges of the slip zones).

The FE-like system is the 2-D benchmark's ``fe_like`` (bench_discrete.py) with two
tangential directions per node: A = A₁ ⊗ [[1, 0.1], [0.1, 1]], B couples the normal
reactions to the t1 slips as in 2-D, C = 1.3 A₁. Loads: constant pressure with a small
harmonic part, a tangential load rotating (elliptically) with an amplitude that grows
toward the edges, so that the edges slip and the interior sticks (fretting-like).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.steady import simulate3d


def fe_like_3d(n: int):
    """Dense SPD A (2N×2N), B (N×2N), C (N×N) of an FE-like chain of N contact nodes."""
    i = np.arange(n)
    d = np.abs(i[:, None] - i[None, :])
    A1 = 2.0 * np.exp(-d / 2.0) * np.cos(0.7 * d) + np.eye(n)
    A = np.kron(A1, np.array([[1.0, 0.1], [0.1, 1.0]]))
    B = np.zeros((n, 2 * n))
    B[:, 0::2] = 0.3 * np.sign(i[:, None] - i[None, :]) * np.exp(-d / 3.0)
    return A, B, 1.3 * A1


def case(n: int):
    A, B, C = fe_like_3d(n)
    x = np.linspace(-1.0, 1.0, n) if n > 1 else np.zeros(1)
    coords = np.column_stack([x, np.zeros(n), np.zeros(n)])
    system = FrictionalSystem3D(A, B, C, 0.3, coordinates=coords)
    edge = np.abs(x) ** 8
    amp = 0.1 + 0.4 * edge
    q1 = np.column_stack([amp, 0.6 * amp]).ravel()
    ph = np.column_stack([np.zeros(n), np.full(n, -np.pi / 2)]).ravel()
    load = Load3D.harmonic(np.ones(n), np.column_stack([0.05 * x, np.zeros(n)]).ravel(),
                           0.2 * np.ones(n), q1, np.zeros(n), ph)
    return system, load


def steady_time(n: int, cycles: int = 50, steps: int = 100, step_tol: float = 1e-4,
                accelerate: bool = True, replay: bool = True):
    """(wall, CPU) seconds of a run to the steady state (at most ``cycles``) and its result.

    CPU time (``time.process_time``, one BLAS thread) is the quiet-machine estimate on a
    shared machine, where the wall time is inflated by the other processes."""
    system, load = case(n)
    t0, c0 = time.perf_counter(), time.process_time()
    res = simulate3d(system, load, cycles=cycles, steps_per_cycle=steps, tol=1e-6,
                     step_tol=step_tol, record=False, accelerate=accelerate,
                     replay=replay)
    return time.perf_counter() - t0, time.process_time() - c0, res


def step_cost(n: int, steps: int = 100, step_tol: float = 1e-4
              ) -> tuple[float, float, float]:
    """(wall, CPU) seconds per load-step solve (Newton solves of one cycle and its
    assembly), and CPU seconds per Newton iteration."""
    wall, cpu, res = steady_time(n, cycles=1, steps=steps, step_tol=step_tol)
    solves = max(1, res.solver_stats["solves"])
    return wall / solves, cpu / solves, cpu / max(1, res.solver_stats["newton_iterations"])


def where_time_goes(n: int, cycles: int = 3, steps: int = 100,
                    step_tol: float = 1e-4) -> dict:
    """Where the time of ``cycles`` cycles of the N-node chain goes: Newton solves per
    load sample (steps of the step control, rejected ones and event locations
    included), Newton iterations per solve, CPU seconds per iteration and per solve,
    factorisations per solve, steps split at a contact event."""
    wall, cpu, res = steady_time(n, cycles=cycles, steps=steps, step_tol=step_tol)
    st = res.solver_stats
    samples = steps * max(res.cycles_run, 1)
    solves, its = max(st["solves"], 1), max(st["newton_iterations"], 1)
    return {"n": n, "cycles": res.cycles_run, "cpu_s": cpu, "wall_s": wall,
            "solves_per_sample": solves / samples, "iterations_per_solve": its / solves,
            "cpu_per_iteration_s": cpu / its, "cpu_per_solve_s": cpu / solves,
            "factorisations_per_solve": st["factorisations"] / solves}


def event_rows(seeds: range = range(30), steps: int = 100) -> list[dict]:
    """The 2-D limit with separating and re-closing nodes (issue 32, item 1): random
    coupled 2-node systems loaded along t1 only, the 3-D engine against the exact 2-D
    solver, worst relative error of D and of every D_j over the systems with a
    separating node, with the event location (the target 1e-6) and without it."""
    from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
    from slipcycle.discrete3d.evolution import Evolution3D
    from slipcycle.discrete3d.model import embed_2d

    # the random systems of tests/test_discrete3d_events.py (one generator for both)
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from random_systems import along_t1, random_coupled_2d

    worst = {True: 0.0, False: 0.0}
    count = 0
    for seed in seeds:
        A, B, C, f, (p0, q0, p1, q1, pph, qph) = random_coupled_2d(seed)
        r2 = simulate(FrictionalSystem(A, B, C, f),
                      DiscreteLoad.harmonic(p0, q0, p1, q1, pph, qph), cycles=60,
                      steps_per_cycle=steps, tol=1e-11)
        if not r2.separating_nodes:
            continue
        count += 1
        load3 = Load3D.harmonic(p0, along_t1(q0), p1, along_t1(q1), pph, np.repeat(qph, 2))
        for locate in (True, False):
            Evolution3D.locate_events = locate
            try:
                r3 = simulate3d(embed_2d(A, B, C, f), load3, cycles=60,
                                steps_per_cycle=steps, tol=1e-11, step_tol=1e-8)
            finally:
                Evolution3D.locate_events = True
            d2 = r2.dissipation_per_cycle
            err = max(abs(r3.dissipation_per_cycle - d2), float(np.max(np.abs(
                r3.dissipation_per_node - r2.dissipation_per_node)))) / d2
            worst[locate] = max(worst[locate], err)
    return [{"name": f"discrete3d_2d_limit_separating_D_error ({count} systems)",
             "value": worst[True], "unit": "rel", "target": 1e-6,
             "ok": worst[True] <= 1e-6},
            {"name": "discrete3d_2d_limit_separating_D_error_without_event_location",
             "value": worst[False], "unit": "rel", "target": None}]


def benchmarks() -> list[dict]:
    # small dense solves: one BLAS thread avoids contention on a shared 2-core machine
    with threadpool_limits(limits=1, user_api="blas"):
        return event_rows() + _rows() + calculix_block_rows()


def _rows() -> list[dict]:
    rows = []
    sizes = [100, 200, 500, 1000, 2000]
    step_cost(20)           # loads the compiled kernels, kept out of the first row
    costs = [step_cost(n) for n in sizes]
    for n, (wall, cpu, per_it) in zip(sizes, costs, strict=True):
        rows.append({"name": f"discrete3d_step_cost_N{n}", "value": cpu, "unit": "CPU s/step",
                     "target": None, "wall_s": wall})
        rows.append({"name": f"discrete3d_iteration_cost_N{n}", "value": per_it,
                     "unit": "CPU s/iteration", "target": None})
    slope = float(np.polyfit(np.log(sizes), np.log([c[1] for c in costs]), 1)[0])
    rows.append({"name": "discrete3d_step_cost_exponent", "value": slope, "unit": "1",
                 "target": 2.0, "ok": slope <= 2.0})
    slope = float(np.polyfit(np.log(sizes), np.log([c[2] for c in costs]), 1)[0])
    rows.append({"name": "discrete3d_iteration_cost_exponent", "value": slope, "unit": "1",
                 "target": None})
    # time per cycle from the first three cycles (assembly and the transient's extra
    # refinements included: an upper bound); a measurement only, the target is the full
    # run below (5 s for at most 50 cycles)
    for n in (500, 2000):
        w = where_time_goes(n)
        for key in ("solves_per_sample", "iterations_per_solve", "cpu_per_iteration_s",
                    "factorisations_per_solve"):
            rows.append({"name": f"discrete3d_chain_N{n}_{key}", "value": w[key],
                         "unit": "1" if not key.startswith("cpu") else "CPU s",
                         "target": None})
    wall, cpu, res = steady_time(2000, cycles=3)
    per_cycle = cpu / max(res.cycles_run, 1)
    rows.append({"name": "discrete3d_2000_nodes_time_per_cycle", "value": per_cycle,
                 "unit": "CPU s", "target": None,
                 "wall_s": wall / max(res.cycles_run, 1),
                 "steady_state": res.steady_state, "cycles_run": res.cycles_run,
                 "slipping_nodes": len(res.slipping_nodes)})
    # the full run to the steady state (≤ 50 cycles of 100 samples): solver time (CPU,
    # median of 3) against issue 32's target 5 s (24 s before), D against step_tol 1e-5
    cpu, wall, res = _median_runs(lambda: steady_time(2000, cycles=50)[2], 3)
    c = run_counters(res, cpu, 100)
    ref = steady_time(2000, cycles=50, step_tol=1e-5)[2]
    d_err = abs(res.dissipation_per_cycle - ref.dissipation_per_cycle) / abs(
        ref.dissipation_per_cycle)
    rows.append({"name": "discrete3d_2000_nodes_to_steady_state", "value": cpu,
                 "unit": "CPU s", "target": 5.0,
                 "ok": bool(cpu <= 5.0 and res.steady_converged), "wall_s": wall,
                 "steady_state": res.steady_state, "residual": res.residual,
                 "jumps": res.jumps, "jumps_undone": res.jumps_undone,
                 "replayed_cycles": res.replayed_cycles, **c})
    for key, unit in (("cycles", "1"), ("steps_per_sample", "1"),
                      ("iterations_per_solve", "1"), ("us_per_iteration", "us")):
        rows.append({"name": f"discrete3d_2000_nodes_to_steady_state: {key}",
                     "value": c[key], "unit": unit, "target": None})
    rows.append({"name": "discrete3d_2000_nodes_to_steady_state: D vs step_tol 1e-5",
                 "value": d_err, "unit": "rel", "target": None})
    return rows


def run_counters(res, cpu: float, steps: int) -> dict:
    """The counters of a run to the steady state (issue 32: where the time goes): cycles,
    load steps per load sample in the last cycle, Newton iterations per solve, CPU µs
    per Newton iteration (the run's CPU time over its iterations)."""
    its = max(res.solver_stats["newton_iterations"], 1)
    return {"cycles": int(res.cycles_run),
            "steps_per_sample": res.steps_per_cycle_taken[-1] / steps,
            "iterations_per_solve": its / max(res.solver_stats["solves"], 1),
            "us_per_iteration": 1e6 * cpu / its}


def _median_runs(run, repeats: int) -> tuple[float, float, object]:
    """Median (CPU, wall) seconds of ``repeats`` calls of ``run()`` and the last result."""
    cpus, walls = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        res = run()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return float(np.median(cpus)), float(np.median(walls)), res


def calculix_block_rows(repeats: int = 3) -> list[dict]:
    """The CalculiX C3D8I block of 121 contact nodes (``bench_calculix``; f = 0.5,
    Q/fP ≈ 0.93, 40 samples per cycle, step_tol 1e-7) to its steady state: the solver
    time (median CPU of ``repeats`` runs, the reduction excluded) against the target
    1.5 s of issue 32 (15.6 s before), with the counters of :func:`run_counters`, and
    its D against the same run at a tight tolerance (step_tol 1e-9, tol 1e-10). The
    default path is plain cycling (about 250 cycles at tol 1e-8 against the service
    cycle's scale), hence up to 600 cycles."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_calculix import block_system, reduced_block

    system, load = block_system(reduced_block())

    def run(step_tol=1e-7, tol=1e-8):
        return simulate3d(system, load, cycles=600, steps_per_cycle=40, tol=tol,
                          step_tol=step_tol, record=False)

    run()                   # compiled kernels loaded outside the timing
    cpu, wall, res = _median_runs(run, repeats)
    ref = run(1e-9, 1e-10)
    d_err = abs(res.dissipation_per_cycle - ref.dissipation_per_cycle) / abs(
        ref.dissipation_per_cycle)
    c = run_counters(res, cpu, 40)
    name = "discrete3d_calculix_block_121_to_steady_state"
    rows = [{"name": name, "value": cpu, "unit": "CPU s", "target": 1.5,
             "ok": bool(cpu <= 1.5 and res.steady_converged), "wall_s": wall,
             "steady_state": res.steady_state, **c}]
    for key, unit in (("cycles", "1"), ("steps_per_sample", "1"),
                      ("iterations_per_solve", "1"), ("us_per_iteration", "us")):
        rows.append({"name": f"{name}: {key}", "value": c[key], "unit": unit,
                     "target": None})
    rows.append({"name": f"{name}: D vs step_tol 1e-9 reference", "value": d_err,
                 "unit": "rel", "target": None})
    return rows


if __name__ == "__main__":  # pragma: no cover
    for row in benchmarks():
        print(row)
