"""The compiled loops of the 3-D step solver against independent references: the LU
solve with LAPACK's getrf factors against the system it solves, the Newton matrix of the
active rows against finite differences of their residual, the step bookkeeping and the
step-doubling estimates against their array definitions, the event crossings against the
array form of the rule."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg.lapack import dgetrf

from slipcycle.discrete3d._kernels import (
    active_residual,
    book_step,
    doubling_error,
    event_crossings,
    lu_solve,
    slip_jacobian,
)
from slipcycle.discrete3d.cone import slip_linearisation


@settings(max_examples=30, deadline=None)
@given(m=st.integers(1, 40), seed=st.integers(0, 2 ** 31))
def test_lu_solve_with_the_getrf_factors_solves_the_system(m, seed):
    rng = np.random.default_rng(seed)
    J = rng.normal(size=(m, m)) + m * np.eye(m)      # well conditioned, pivoting used
    J[[0, -1]] = J[[-1, 0]]
    b = rng.normal(size=m)
    lu, piv, info = dgetrf(J.copy())
    assert info == 0
    x = lu_solve(np.asfortranarray(lu), piv, b)
    # backward stable: the residual is round-off of |J| |x|
    assert np.max(np.abs(J @ x - b)) <= 1e-12 * np.max(np.abs(J)) * np.max(np.abs(x)) * m


def _active_rows(rng, ns, npp):
    """A random SPD K restricted to the active rows V (the slip unknowns, the separated
    ones, then the slipping nodes' normal rows) and columns U, with a state in which every
    slipping node slips (|z| > f p) and every separated one stays open."""
    m = 2 * ns + 3 * npp
    M = rng.normal(size=(m + ns, m + ns))
    K = M @ M.T / (m + ns) + np.eye(m + ns)
    KVU = np.ascontiguousarray(K[:, :m])
    fS, rhoS = rng.uniform(0.2, 0.5, ns), rng.uniform(1.0, 2.0, ns)
    rhoP = rng.uniform(1.0, 2.0, npp)
    v0S = rng.normal(size=(ns, 2))
    xU = np.concatenate([v0S.ravel() + 0.3 * rng.normal(size=2 * ns),
                         np.tile([0.0, 0.0, 1.0], npp) * rng.uniform(0.5, 1.0, 3 * npp)])
    rV = np.concatenate([rng.normal(size=2 * ns) * 3.0, np.zeros(3 * npp),
                         rng.uniform(1.0, 2.0, ns)])
    return KVU, fS, rhoS, rhoP, v0S, xU, rV


def _residual(KVU, fS, rhoS, rhoP, v0S, xU0, rV0, xU, ns, npp):
    m = xU.size
    R = np.empty(m)
    rV = rV0 + KVU @ (xU - xU0)
    active_residual(xU, rV, v0S, fS, rhoS, rhoP, ns, npp, R, np.empty((ns, 2)),
                    np.empty(ns))
    return R


@settings(max_examples=25, deadline=None)
@given(ns=st.integers(1, 5), npp=st.integers(0, 3), seed=st.integers(0, 2 ** 31))
def test_newton_matrix_is_the_derivative_of_the_active_residual(ns, npp, seed):
    rng = np.random.default_rng(seed)
    KVU, fS, rhoS, rhoP, v0S, xU, rV = _active_rows(rng, ns, npp)
    m = xU.size
    R, zs, zsn = np.empty(m), np.empty((ns, 2)), np.empty(ns)
    active_residual(xU, rV, v0S, fS, rhoS, rhoP, ns, npp, R, zs, zsn)
    phi, nvec = slip_linearisation(zs, zsn, rV[m:], fS, rhoS)
    J = slip_jacobian(KVU, ns, npp, np.ascontiguousarray(phi), np.ascontiguousarray(nvec),
                      fS, rhoS)
    h = 1e-6
    fd = np.empty((m, m))
    for c in range(m):
        e = np.zeros(m)
        e[c] = h
        fd[:, c] = (_residual(KVU, fS, rhoS, rhoP, v0S, xU, rV, xU + e, ns, npp)
                    - _residual(KVU, fS, rhoS, rhoP, v0S, xU, rV, xU - e, ns, npp)) / (2 * h)
    # central differences: error O(h²) times the curvature of the disk projection
    np.testing.assert_allclose(J, fd, atol=1e-6 * max(1.0, np.max(np.abs(fd))))


@settings(max_examples=25, deadline=None)
@given(n=st.integers(1, 12), seed=st.integers(0, 2 ** 31))
def test_step_bookkeeping_is_the_trapezoidal_rule_of_its_definition(n, seed):
    rng = np.random.default_rng(seed)
    x0, r0, x1, r1, drw = (rng.normal(size=3 * n) for _ in range(5))
    modes = rng.integers(0, 3, n).astype(np.int8)
    f = np.full(n, 0.5)
    diss, slip_len = np.zeros(n), np.zeros(n)
    sep, slipped = np.zeros(n, bool), np.zeros(n, bool)
    work, normal_work, none_stuck = book_step(x0, r0, x1, r1, drw, modes, f, diss, slip_len,
                                              sep, slipped)
    dv = (x1[:2 * n] - x0[:2 * n]).reshape(n, 2)
    qm = 0.5 * (r0[:2 * n] + r1[:2 * n]).reshape(n, 2)
    np.testing.assert_allclose(diss, -np.sum(qm * dv, axis=1), rtol=1e-12, atol=1e-14)
    # a frictionless node's q is round-off: it books nothing
    free = np.zeros(n)
    book_step(x0, r0, x1, r1, drw, modes, np.zeros(n), free, np.zeros(n), np.zeros(n, bool),
              np.zeros(n, bool))
    assert np.all(free == 0.0)
    assert abs(work - 0.5 * (x0 + x1) @ drw) <= 1e-12 * np.sum(np.abs(0.5 * (x0 + x1) * drw))
    nw = 0.5 * (r0[2 * n:] + r1[2 * n:]) @ (x1[2 * n:] - x0[2 * n:])
    assert abs(normal_work - nw) <= 1e-12 * (1.0 + abs(nw)) * n
    np.testing.assert_allclose(slip_len, np.where(modes == 1, np.hypot(*dv.T), 0.0),
                               rtol=1e-12)
    assert np.array_equal(sep, modes == 2) and np.array_equal(slipped, modes == 1)
    assert none_stuck == bool(np.all(modes != 0))
    err, d_full, d_half = doubling_error(x0, r0, x1, r1, drw, drw, x1, r1, n)
    assert err == 0.0                      # the full step and the second half agree
    assert abs(d_full - np.sum(diss)) <= 1e-12 * (1.0 + np.sum(np.abs(diss)))


@settings(max_examples=50, deadline=None)
@given(n=st.integers(1, 10), stops=st.booleans(), seed=st.integers(0, 2 ** 31))
def test_event_crossings_follow_the_array_form_of_the_rule(n, stops, seed):
    rng = np.random.default_rng(seed)
    g0, g1 = rng.normal(size=2 * n), rng.normal(size=2 * n)
    g0[rng.random(2 * n) < 0.2] = 0.0            # at the event already
    tol = 1e-3
    cross = (np.abs(g0) > tol) & (np.abs(g1) > tol) & ((g0 > 0) != (g1 > 0))
    cross[n:] &= stops & (g0[:n] > tol) & (g1[:n] > tol) & (g0[n:] < 0)
    assert np.array_equal(event_crossings(g0, g1, stops, tol), np.flatnonzero(cross))
