"""Brute-force reference for the 3-D discrete model (N ≤ 3): tiny steps, each an exact
convex program solved by Clarabel, against the semismooth-Newton solver with step
control, on random coupled systems including separation.

The reference step freezes the normal reaction in the friction term (semi-explicit in
p, an O(h) approximation of the coupled problem): from x_old it minimises

    ½ xᵀ K x + r^wᵀ x + Σ_j f_j p̃_j |v_j − v_j,old|   subject to  w ≥ 0,

p̃_j = max(p_j,old, 0), a second-order cone program whose optimality conditions are
r = r^w + K x, p ⊥ w ≥ 0 and q_j = −f_j p̃_j s_j with s_j the slip direction (maximum
dissipation). It shares no code with the solver under test (no Newton, no return map,
no step control), only the load samples.
"""

import clarabel
import numpy as np
import pytest
import scipy.sparse as sp

from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.steady import simulate3d


def _reference(system, load, steps_per_cycle, substeps, cycles):
    n = system.n_nodes
    K, f = system.K, system.friction
    _, vals = load.cycle_samples(steps_per_cycle)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-12
    nx = 3 * n
    # variables y = [x (3N), t (N)]; cones: w ≥ 0, (t_j, v_j − v_j,old) ∈ SOC
    P = sp.csc_matrix(np.block([[K, np.zeros((nx, n))], [np.zeros((n, nx + n))]]))
    G = np.zeros((n + 3 * n, nx + n))
    G[np.arange(n), 2 * n + np.arange(n)] = -1.0
    for j in range(n):
        G[n + 3 * j, nx + j] = -1.0
        G[n + 3 * j + 1, 2 * j] = -1.0
        G[n + 3 * j + 2, 2 * j + 1] = -1.0
    G = sp.csc_matrix(G)
    cones = [clarabel.NonnegativeConeT(n)] + [clarabel.SecondOrderConeT(3)] * n

    def step(x_old, p_old, rw):
        b = np.zeros(n + 3 * n)
        b[n + 3 * np.arange(n) + 1] = -x_old[0:2 * n:2]
        b[n + 3 * np.arange(n) + 2] = -x_old[1:2 * n:2]
        c = np.concatenate([rw, f * np.maximum(p_old, 0.0)])
        sol = clarabel.DefaultSolver(P, c, G, b, cones, settings).solve()
        return np.asarray(sol.x)[:nx]

    # assembly: linear from the unloaded state to the load at θ = 0
    x = np.zeros(nx)
    path = [np.zeros(nx) + s * vals[0] for s in np.linspace(0, 1, 4 * substeps + 1)]
    for cycle in range(cycles + 1):
        if cycle:
            path = []
            for k in range(len(vals) - 1):
                for s in np.linspace(0, 1, substeps + 1)[1:]:
                    path.append(vals[k] + s * (vals[k + 1] - vals[k]))
        diss = 0.0
        r = (path[0] if cycle else np.zeros(nx)) + K @ x
        for rw in path[1:] if not cycle else path:
            x_new = step(x, r[2 * n:], rw)
            r_new = rw + K @ x_new
            dv = (x_new[:2 * n] - x[:2 * n]).reshape(n, 2)
            qm = 0.5 * (r[:2 * n] + r_new[:2 * n]).reshape(n, 2)
            diss += -np.sum(qm * dv)
            x, r = x_new, r_new
    return x, diss


def _random_coupled(seed, n):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T / (3 * n) + np.diag(rng.uniform(1.0, 2.0, 3 * n))
    A, B, C = K[:2 * n, :2 * n], 0.5 * K[2 * n:, :2 * n], K[2 * n:, 2 * n:]
    system = FrictionalSystem3D(A, B, C, rng.uniform(0.2, 0.5, n), accept_ill_posed=True)
    load = Load3D.harmonic(rng.uniform(0.3, 0.8, n), rng.normal(size=2 * n) * 0.1,
                           rng.uniform(0.3, 0.9, n), rng.uniform(0.3, 0.8, 2 * n),
                           rng.uniform(0, 6, n), rng.uniform(0, 6, 2 * n))
    return system, load


@pytest.mark.parametrize("seed,n", [(3, 2), pytest.param(11, 3, marks=pytest.mark.slow)])
def test_newton_solver_agrees_with_a_brute_force_cone_program_on_coupled_systems(seed, n):
    """(c) Random coupled systems with opening nodes: after two cycles the state agrees
    within 2 % of the displacement scale and the dissipation of the second cycle within
    2 % (the reference's O(h) error, 40 steps per load interval)."""
    system, load = _random_coupled(seed, n)
    res = simulate3d(system, load, cycles=2, steps_per_cycle=40, tol=1e-14, step_tol=1e-8)
    assert res.cycles_run == 2
    assert res.separating_nodes, "the case must exercise separation"
    x_ref, d_ref = _reference(system, load, 40, 40, 2)
    scale = res.disp_scale
    assert np.max(np.abs(res.cycle_start_states[-1] - x_ref)) <= 0.02 * scale
    assert res.dissipation_history[-1] == pytest.approx(d_ref, rel=0.02)
