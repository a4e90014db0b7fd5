"""Incremental updates of the rate solver against from-scratch references.

The rate solver keeps the inverse of the mode system and the rows of K of its unknowns
current by bordering / Schur-complement removal and swap-delete of rows (Golub & Van Loan,
*Matrix Computations*, §2.1.4); after any sequence of mode changes its rates must equal a
dense solve of the full 2N × 2N rate equations for that mode set. The compiled event scan
must pick the same event as the direct evaluation of every event function.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.discrete import FrictionalSystem
from slipcycle.discrete.evolution import _scan_events
from slipcycle.discrete.model import SEPARATED, SLIP_NEG, SLIP_POS, STICK
from slipcycle.discrete.rate import RateSolver


def _system(seed: int, n: int) -> FrictionalSystem:
    rng = np.random.default_rng(seed)
    G = rng.normal(size=(2 * n, 2 * n))
    K = G @ G.T + 2.0 * n * np.eye(2 * n)      # diagonally dominant: every mode set regular
    return FrictionalSystem(K[:n, :n], K[n:, :n], K[n:, n:], 0.2, accept_ill_posed=True)


def _dense_rates(system: FrictionalSystem, modes: np.ndarray, rw: np.ndarray):
    """ẋ, ṙ from the 2N × 2N equations of the mode set (independent of the solver)."""
    n, K, f = system.n_nodes, system.K, system.friction
    M = np.zeros((2 * n, 2 * n))
    b = np.zeros(2 * n)
    for j in range(n):
        m = modes[j]
        if m == STICK:
            M[j, j] = 1.0
            M[n + j, n + j] = 1.0
        elif m in (SLIP_POS, SLIP_NEG):
            s = 1.0 if m == SLIP_POS else -1.0           # f ṗ ± q̇ = 0, ẇ = 0
            M[j] = s * K[j] + f[j] * K[n + j]
            b[j] = -(s * rw[j] + f[j] * rw[n + j])
            M[n + j, n + j] = 1.0
        else:                                            # q̇ = ṗ = 0
            M[j] = K[j]
            b[j] = -rw[j]
            M[n + j] = K[n + j]
            b[n + j] = -rw[n + j]
    xd = np.linalg.solve(M, b)
    return xd, rw + K @ xd


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 14), steps=st.integers(1, 60))
def test_incremental_mode_updates_equal_a_dense_solve(seed, n, steps):
    """Random walks over mode sets (single and block changes, including many updates in a
    row): rates equal the dense solve to 1e-9 relative at every step."""
    system = _system(seed, n)
    solver = RateSolver(system, 1e-12)
    rng = np.random.default_rng(seed + 7)
    modes = np.zeros(n, np.int8)
    for _ in range(steps):
        k = rng.integers(1, max(2, n // 3) + 1)
        modes = modes.copy()
        modes[rng.choice(n, size=min(k, n), replace=False)] = rng.integers(0, 4, size=min(k, n))
        rw = rng.normal(size=2 * n)
        got = solver.rates(modes, rw)
        assert got is not None
        xd, rd = _dense_rates(system, modes, rw)
        scale = np.abs(xd).max() + 1e-300
        np.testing.assert_allclose(got[0], xd, rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(got[1], rd, rtol=0, atol=1e-9 * np.abs(rd).max() + 1e-12)


def _scan_reference(f, q, p, w, qd, pd, wd, modes, tol, dtol, remaining):
    """Every event function evaluated directly; the first event, ties to the lowest
    (kind, node)."""
    n = f.size
    best = (remaining, -1, -1)
    for kind in range(4):
        for j in range(n):
            m = modes[j]
            if kind <= 1 and m == STICK:
                s = 1.0 if kind == 0 else -1.0
                g, gd, thr = f[j] * p[j] + s * q[j], f[j] * pd[j] + s * qd[j], tol
            elif kind == 2 and m != SEPARATED:
                g, gd, thr = p[j], pd[j], tol
            elif kind == 3 and m == SEPARATED:
                g, gd, thr = w[j], wd[j], dtol
            else:
                continue
            if g > thr and gd < 0 and g / -gd < best[0]:
                best = (g / -gd, kind, j)
    return best


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 30), ties=st.booleans())
def test_event_scan_finds_the_first_event(seed, n, ties):
    rng = np.random.default_rng(seed)
    f = rng.uniform(0.1, 0.8, n)
    q, p, w = rng.normal(size=n), rng.uniform(0.0, 2.0, n), rng.uniform(0.0, 1.0, n)
    qd, pd, wd = rng.normal(size=n), rng.normal(size=n), rng.normal(size=n)
    if ties:   # the same time for several nodes: the lowest (kind, node) wins
        p[:] = 1.0
        pd[:] = -1.0
        q[:] = 0.0
        qd[:] = 0.0
    modes = rng.integers(0, 4, n).astype(np.int8)
    ref = _scan_reference(f, q, p, w, qd, pd, wd, modes, 1e-12, 1e-12, 0.7)
    dt, kind, j, _ = _scan_events(f, q, p, w, qd, pd, wd, modes, 1e-12, 1e-12, 0.7)
    assert (kind, j) == (ref[1], ref[2])
    assert dt == ref[0]


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 40), steps=st.integers(20, 300))
def test_single_node_events_update_in_place_without_refactorizing(seed, n, steps):
    """The usual event changes one node (stick ↔ slip): the inverse is bordered or reduced
    in place, O(k²), through every size from 0 to N (its buffer grows by doubling), with no
    factorization after the first; rates equal the dense solve to 1e-9 relative."""
    system = _system(seed, n)
    solver = RateSolver(system, 1e-12)
    rng = np.random.default_rng(seed + 11)
    modes = np.zeros(n, np.int8)
    solver.rates(modes, rng.normal(size=2 * n))
    for _ in range(min(steps, 390)):        # below the refresh after 400 updates
        j = rng.integers(n)
        modes = modes.copy()
        modes[j] = STICK if modes[j] != STICK else rng.choice([SLIP_POS, SLIP_NEG])
        rw = rng.normal(size=2 * n)
        got = solver.rates(modes, rw)
        xd, rd = _dense_rates(system, modes, rw)
        np.testing.assert_allclose(got[0], xd, rtol=0, atol=1e-9 * (np.abs(xd).max() + 1e-300))
        np.testing.assert_allclose(got[1], rd, rtol=0, atol=1e-9 * np.abs(rd).max() + 1e-12)
    assert solver.stats["factorizations"] == 1


def test_node_at_the_apex_of_its_friction_limit_may_open():
    """A node in contact with q = 0 and a pressure between the force tolerance and
    tolerance/f sits on both sides of its friction limit (f p ± q ≤ tol), i.e. at the
    apex. A load rate that pulls it open must open it (ẇ = 1/k_n per unit pull) instead of
    leaving the rate problem without a solution (seen as Lemke's ray termination on a
    random 6-node system, seed 38096, with f = 0.58 f_crit)."""
    system = FrictionalSystem(np.array([[2.0]]), np.array([[0.0]]), np.array([[4.0]]), 0.3)
    tol = 1e-9
    solver = RateSolver(system, tol)
    x = np.zeros(2)
    r = np.array([0.0, 1.5 * tol])          # p above tol, f p below it
    modes, xd, rd = solver.solve(x, r, np.array([0.0, -1.0]), np.array([STICK], np.int8))
    assert modes[0] == SEPARATED
    assert xd[1] == 0.25
    assert rd[1] == 0.0


def _critical_state(rng, n: int, f: float, tol: float):
    """A state (x, r) with every kind of node: stuck inside its cone, stuck at q = −f p or
    q = +f p, in contact at p = 0, separated with a gap, separated with the gap closed."""
    x = np.zeros(2 * n)
    r = np.zeros(2 * n)
    for j in range(n):
        kind = rng.integers(6)
        p = rng.uniform(0.5, 2.0)
        x[j] = rng.normal()
        if kind == 0:
            r[j], r[n + j] = rng.uniform(-0.5, 0.5) * f * p, p
        elif kind in (1, 2):
            r[j], r[n + j] = (-f * p if kind == 1 else f * p), p
        elif kind == 3:
            r[j], r[n + j] = 0.0, 0.0
        elif kind == 4:
            x[n + j] = rng.uniform(0.1, 1.0)
        # kind 5: separated at w = 0 (q = p = 0 and no gap): in contact at p = 0
    return x, r


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 12))
def test_compiled_pivoting_solves_the_rate_problem_as_lemkes_method_does(seed, n):
    """At states with nodes on every kind of inequality (friction limits both ways, p = 0,
    open gaps) and random load rates, the compiled block pivoting returns rates that keep
    every active inequality (complementarity: a slipping node slips the way its friction
    force allows and keeps q = ∓f p, a stuck node at a limit does not cross it, a node at
    p = 0 does not pull, an open node carries nothing) and that equal those of Lemke's
    method on the LCP of the critical nodes (unique for this P-matrix system)."""
    system = _system(seed, n)
    rng = np.random.default_rng(seed + 3)
    f = float(system.friction[0])
    solver = RateSolver(system, 1e-12)
    x, r = _critical_state(rng, n, f, 1e-12)
    rw = rng.normal(size=2 * n)
    guess = rng.integers(0, 4, n).astype(np.int8)
    modes, xd, rd = solver.solve(x, r, rw, guess)
    K = system.K
    scale = np.abs(rw).max() + np.abs(K).max() * np.abs(xd).max()
    tol = 1e-9 * scale
    np.testing.assert_allclose(rd, rw + K @ xd, rtol=0, atol=tol)
    q, p, w = r[:n], r[n:], x[n:]
    qd, pd, vd, wd = rd[:n], rd[n:], xd[:n], xd[n:]
    for j in range(n):
        m = modes[j]
        if m == SEPARATED:
            assert abs(qd[j]) <= tol and abs(pd[j]) <= tol
            if w[j] == 0:
                assert wd[j] >= -tol
            continue
        assert abs(wd[j]) <= tol and w[j] == 0            # in contact
        if p[j] <= 1e-12:
            assert pd[j] >= -tol                          # does not pull at p = 0
        if m == STICK:
            assert vd[j] == 0
            if f * p[j] + q[j] <= 1e-12:
                assert f * pd[j] + qd[j] >= -tol
            if f * p[j] - q[j] <= 1e-12:
                assert f * pd[j] - qd[j] >= -tol
        elif m == SLIP_POS:
            assert vd[j] >= -tol and abs(f * pd[j] + qd[j]) <= tol
        else:
            assert vd[j] <= tol and abs(f * pd[j] - qd[j]) <= tol
    flags = solver.flags(x, r)
    rate_tol = 1e-9 * float(np.abs(rw).max()) + 1e-300
    _, xd_lemke, rd_lemke = solver._lemke(x, r, rw, flags, rate_tol)
    np.testing.assert_allclose(xd, xd_lemke, rtol=0, atol=1e-7 * (np.abs(xd).max() + 1e-300))
    np.testing.assert_allclose(rd, rd_lemke, rtol=0, atol=1e-7 * scale)
