"""The condensed step solver (active-set Newton with reused factorisations and compiled
node loops) against a plain semismooth Newton method on all 3N unknowns, on random coupled
systems in which nodes stick, slip and separate within one load step; and the compiled
node classification against the array form of the cone's local law."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.discrete3d._kernels import classify_nodes
from slipcycle.discrete3d.cone import node_states, slip_linearisation
from slipcycle.discrete3d.evolution import StepSolver
from slipcycle.discrete3d.model import SEPARATED, SLIP, STICK, FrictionalSystem3D


def _coupled_system(rng, n):
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T / (3 * n) + np.eye(3 * n)
    t = np.arange(2 * n)
    A, B, C = K[np.ix_(t, t)], K[2 * n:, :2 * n], K[2 * n:, 2 * n:]
    return FrictionalSystem3D(A, 0.3 * B, C, rng.uniform(0.2, 0.4, n),
                              accept_ill_posed=True)


def full_newton(system, x0, r0, drw, force_tol, max_iter=100):
    """Semismooth Newton on every unknown of the Alart–Curnier equations (Alart & Curnier
    1991): stuck nodes Δv = 0, closed nodes w = 0, slipping nodes q = f p z/|z|, separated
    nodes q = 0, p = 0; the full 3N × 3N generalised Jacobian is solved densely."""
    n, K, f = system.n_nodes, system.K, system.friction
    rho_t = 0.5 * (np.diag(system.A)[0::2] + np.diag(system.A)[1::2])
    rho_n = np.diag(system.C).copy()
    x = x0.copy()
    for _ in range(max_iter):
        r = r0 + drw + K @ (x - x0)
        dv = (x[:2 * n] - x0[:2 * n]).reshape(n, 2)
        w = x[2 * n:]
        q, p = r[:2 * n].reshape(n, 2), r[2 * n:]
        modes, z, zn = node_states(q, p, dv, w, f, rho_t, rho_n)
        R = np.zeros(3 * n)
        J = np.zeros((3 * n, 3 * n))
        force_rows = []
        for j in range(n):
            tj, nj = [2 * j, 2 * j + 1], 2 * n + j
            if modes[j] == SEPARATED:
                R[tj], R[nj] = q[j], p[j]
                J[tj], J[nj] = K[tj], K[nj]
                force_rows += tj + [nj]
                continue
            R[nj], J[nj, nj] = w[j], 1.0
            if modes[j] == STICK:
                R[tj] = dv[j]
                J[tj, tj] = 1.0
            else:
                phi, nvec = slip_linearisation(z[j:j + 1], zn[j:j + 1], p[j:j + 1],
                                               f[j:j + 1], rho_t[j:j + 1])
                R[tj] = q[j] - f[j] * p[j] * z[j] / zn[j]
                J[tj] = (np.eye(2) - phi[0]) @ K[tj] - f[j] * np.outer(nvec[0], K[nj])
                J[np.ix_(tj, tj)] += rho_t[j] * phi[0]
                force_rows += tj
        disp_rows = np.setdiff1d(np.arange(3 * n), force_rows)
        if (np.max(np.abs(R[force_rows]), initial=0.0) <= force_tol
                and not np.any(R[disp_rows])):
            return x, r, modes
        x = x - np.linalg.solve(J, R)
    raise AssertionError("the reference Newton method did not converge")


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(3, 7))
def test_condensed_solver_agrees_with_full_newton_on_coupled_systems_with_separation(seed, n):
    rng = np.random.default_rng(seed)
    system = _coupled_system(rng, n)
    F = 1.0
    solver = StepSolver(system, F)
    # step 1: from the unloaded state, node 0 pulled off (separates), node 1 sheared hard
    # (slips), the rest pressed with small shear; step 2: a random increment from there
    p1 = rng.uniform(0.5, 1.0, n)
    p1[0] = -0.3
    q1 = rng.normal(scale=0.1, size=(n, 2))
    q1[1] = [0.8, -0.5]
    x, r = np.zeros(3 * n), np.zeros(3 * n)
    seen = set()
    for drw in (np.concatenate([q1.ravel(), p1]),
                np.concatenate([rng.normal(scale=0.3, size=2 * n),
                                rng.normal(scale=0.3, size=n)])):
        step = solver.solve(x, r, drw)
        xr, rr, mr = full_newton(system, x, r, drw, solver.force_tol)
        assert step is not None
        np.testing.assert_array_equal(step.modes, mr)
        np.testing.assert_allclose(step.x, xr, rtol=0, atol=1e-9 * F)
        np.testing.assert_allclose(step.r, rr, rtol=0, atol=1e-9 * F)
        seen |= set(step.modes.tolist())
        x, r = step.x, step.r
    assert {SLIP, SEPARATED} <= seen


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 40))
def test_compiled_classification_is_the_cone_law(seed, n):
    rng = np.random.default_rng(seed)
    x0 = rng.normal(size=3 * n)
    x = x0 + np.where(rng.random(3 * n) < 0.5, 0.0, rng.normal(size=3 * n))
    x[2 * n:] = np.where(rng.random(n) < 0.5, 0.0, np.abs(x[2 * n:]))
    r = rng.normal(size=3 * n)
    f, rho_t, rho_n = rng.uniform(0, 1, n), rng.uniform(0.5, 2, n), rng.uniform(0.5, 2, n)
    modes = np.empty(n, np.int8)
    fix_t, fix_n = np.empty(n, bool), np.empty(n, bool)
    slip, sep = np.empty(n, np.int64), np.empty(n, np.int64)
    count, ns, npp = classify_nodes(x, r, x0, f, rho_t, rho_n, modes, fix_t, fix_n, slip,
                                    sep)
    dv = (x[:2 * n] - x0[:2 * n]).reshape(n, 2)
    ref, _, _ = node_states(r[:2 * n].reshape(n, 2), r[2 * n:], dv, x[2 * n:], f, rho_t,
                            rho_n)
    np.testing.assert_array_equal(modes, ref)
    np.testing.assert_array_equal(fix_t, (ref == STICK) & np.any(dv != 0, axis=1))
    np.testing.assert_array_equal(fix_n, (ref != SEPARATED) & (x[2 * n:] != 0))
    assert count == int(np.sum(fix_t | fix_n))
    np.testing.assert_array_equal(slip[:ns], np.flatnonzero(ref == SLIP))
    np.testing.assert_array_equal(sep[:npp], np.flatnonzero(ref == SEPARATED))


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(8, 30))
def test_separated_nodes_condensed_out_give_the_steps_of_the_whole_active_block(seed, n):
    """Most nodes pulled off, some sheared into slip (the lap joint's open interface):
    the block elimination of the separated rows (one Cholesky of K_PP per separated set)
    reaches the state of the Newton method on the whole active block and of the full
    3N-unknown reference, over three load steps that open, slip and re-close nodes."""
    rng = np.random.default_rng(seed)
    system = _coupled_system(rng, n)
    condensed, whole = StepSolver(system, 1.0), StepSolver(system, 1.0)
    whole.eliminate_separated = False
    off = rng.random(n) < 0.6
    off[0], off[1:3] = True, False
    p1 = np.where(off, -rng.uniform(0.1, 0.5, n), rng.uniform(0.5, 1.0, n))
    q1 = rng.normal(scale=0.1, size=(n, 2))
    q1[1:3] = [[0.9, -0.4], [-0.6, 0.7]]
    steps = (np.concatenate([q1.ravel(), p1]),
             np.concatenate([rng.normal(scale=0.4, size=2 * n), rng.normal(scale=0.2, size=n)]),
             np.concatenate([rng.normal(scale=0.4, size=2 * n), np.abs(p1) + 0.2]))
    x, r = np.zeros(3 * n), np.zeros(3 * n)
    seen = set()
    for drw in steps:
        a, b = condensed.solve(x, r, drw), whole.solve(x, r, drw)
        xr, rr, mr = full_newton(system, x, r, drw, condensed.force_tol)
        assert a is not None and b is not None
        np.testing.assert_array_equal(a.modes, b.modes)
        np.testing.assert_array_equal(a.modes, mr)
        np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-10)
        np.testing.assert_allclose(a.x, xr, rtol=0, atol=1e-9)
        np.testing.assert_allclose(a.r, rr, rtol=0, atol=1e-9)
        seen |= set(a.modes.tolist())
        x, r = a.x, a.r
    assert {SLIP, SEPARATED} <= seen


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), budget=st.sampled_from([0, 10 ** 5, 2 ** 30]))
def test_how_many_active_set_blocks_are_kept_never_changes_a_step(seed, budget):
    """The blocks and factors kept per active set are exact functions of the set: a
    solver that keeps none (budget 0 bytes) and one that keeps a whole cycle's worth
    take bit-identical steps, through states that revisit earlier active sets."""
    rng = np.random.default_rng(seed)
    n = 12
    system = _coupled_system(rng, n)
    ref, probe = StepSolver(system, 1.0), StepSolver(system, 1.0, cache_bytes=budget)
    # a periodic load path: the second period revisits the first period's active sets
    base = np.concatenate([rng.normal(scale=0.3, size=(n, 2)).ravel(),
                           np.where(rng.random(n) < 0.5, -0.3, 0.8)])
    path = [np.cos(2 * np.pi * k / 6) * base for k in range(1, 13)]
    x = np.zeros(3 * n)
    r = np.zeros(3 * n)
    xs, rs = x.copy(), r.copy()
    previous = np.zeros(3 * n)
    for load in path:
        a = ref.solve(x, r, load - previous)
        b = probe.solve(xs, rs, load - previous)
        assert a is not None and b is not None
        np.testing.assert_array_equal(a.x, b.x)
        np.testing.assert_array_equal(a.modes, b.modes)
        x, r, xs, rs, previous = a.x, a.r, b.x, b.r, load
    assert probe._blocks.nbytes <= budget and probe._elims.nbytes <= budget
