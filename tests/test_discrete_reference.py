"""Event-driven solver against a brute-force reference (issue 3 item 7).

The reference is written here, independently of the solver: the backward-Euler incremental
problem of every small load step is solved by enumerating all 4^N node states (stick,
slip +, slip −, separated), solving the 2N linear equations of each and keeping the one
whose inequalities hold. It converges to the exact solution as the steps shrink (error
O(step) around events, none between), so agreement is checked to a tolerance of 2 % of
the displacement scale and 1 % of the dissipation.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, critical_friction, simulate
from slipcycle.loading import TabulatedLoad


class BruteForce:
    """Backward-Euler incremental quasi-static frictional contact, 4^N enumeration."""

    def __init__(self, A, B, C, f):
        A, B, C = (np.asarray(M, float) for M in (A, B, C))
        n = self.n = A.shape[0]
        self.f = np.broadcast_to(np.asarray(f, float), (n,))
        K = self.K = np.block([[A, B.T], [B, C]])
        combos = self.combos = np.array(list(itertools.product(range(4), repeat=n)))
        nc = len(combos)
        # Equations  M_c x = Sx_c x_old + Sr_c r^w  for each combination c
        M = np.zeros((nc, 2 * n, 2 * n))
        Sx = np.zeros((nc, 2 * n, 2 * n))
        Sr = np.zeros((nc, 2 * n, 2 * n))
        for j in range(n):
            m = combos[:, j]
            st = m == 0
            M[st, j, j] = 1.0
            Sx[st, j, j] = 1.0
            M[st, n + j, n + j] = 1.0
            for sel, sg in ((m == 1, 1.0), (m == 2, -1.0)):
                M[sel, j] = sg * K[j] + self.f[j] * K[n + j]
                Sr[sel, j, j] = -sg
                Sr[sel, j, n + j] = -self.f[j]
                M[sel, n + j, n + j] = 1.0
            se = m == 3
            M[se, j] = K[j]
            Sr[se, j, j] = -1.0
            M[se, n + j] = K[n + j]
            Sr[se, n + j, n + j] = -1.0
        Minv = np.linalg.inv(M)
        self.Px = Minv @ Sx
        self.Pr = Minv @ Sr

    def step(self, x, rw):
        n, f, K, combos = self.n, self.f, self.K, self.combos
        X = self.Px @ x + self.Pr @ rw
        R = rw + X @ K.T
        q, p = R[:, :n], R[:, n:]
        dv, w = X[:, :n] - x[:n], X[:, n:]
        sc = max(np.abs(rw).max(), 1e-300)
        tol, tolx = 1e-9 * sc, 1e-9 * sc / K.diagonal().max()
        st, sp, sn, se = (combos == k for k in range(4))
        ok = np.all(~st | ((np.abs(q) <= f * p + tol) & (p >= -tol)), axis=1)
        ok &= np.all(~sp | ((dv >= -tolx) & (p >= -tol)), axis=1)
        ok &= np.all(~sn | ((dv <= tolx) & (p >= -tol)), axis=1)
        ok &= np.all(~se | (w >= -tolx), axis=1)
        good = np.flatnonzero(ok)
        assert good.size, "brute force: no consistent node states"
        return X[good[0]], q[good[0]]

    def path(self, x0, loads, substeps):
        """Follow loads (S, 2N) linearly with ``substeps`` steps per segment."""
        x = np.array(x0, float)
        out, D = [x.copy()], np.zeros(self.n)
        for k in range(len(loads) - 1):
            for s in range(1, substeps + 1):
                rw = loads[k] + (loads[k + 1] - loads[k]) * s / substeps
                xn, q = self.step(x, rw)
                D -= q * (xn[: self.n] - x[: self.n])
                x = xn
            out.append(x.copy())
        return np.array(out), D


def random_case(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 4))
    G = rng.normal(size=(2 * n, 2 * n))
    K = G @ G.T + 0.5 * np.eye(2 * n)
    A, B, C = K[:n, :n], K[n:, :n], K[n:, n:]
    fc = critical_friction(A, B).f_crit
    f = min(0.8 * fc, rng.uniform(0.1, 1.0))
    system = FrictionalSystem(A, B, C, f)
    th = np.sort(rng.uniform(0, 2 * np.pi, 6))
    th[0] = 0.0
    load = DiscreteLoad(TabulatedLoad(th, rng.normal(size=(6, n)) * 0.6,
                                      np.full(n, rng.uniform(0.3, 1.5))),
                        TabulatedLoad(th, rng.normal(size=(6, n)), np.zeros(n)))
    return system, load


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5, 8])
def test_event_driven_matches_brute_force(seed):
    system, load = random_case(seed)
    n = system.n_nodes
    cycles = 3
    res = simulate(system, load, cycles=cycles, steps_per_cycle=6, min_cycles=cycles)
    vals = load(res.theta)
    vals[-1] = vals[0]
    bf = BruteForce(system.A, system.B, system.C, system.friction)
    xs, _ = bf.path(np.zeros(2 * n), np.vstack([np.zeros(2 * n), vals[0]]), 300)
    x = xs[-1]
    for c in range(cycles):
        xs, D = bf.path(x, vals, 150)
        x = xs[-1]
        err = np.max(np.abs(res.x[c] - xs)) / res.disp_scale
        assert err < 2e-2, f"cycle {c}: state differs by {err:.3g} of the displacement scale"
    d_ref, d = D.sum(), res.dissipation_per_cycle
    assert abs(d - d_ref) <= 1e-2 * max(abs(d_ref), 1e-3 * res.force_scale * res.disp_scale)


def test_brute_force_reference_can_fail():
    """The comparison is not vacuous: a different friction coefficient is detected."""
    system, load = random_case(2)
    other = FrictionalSystem(system.A, system.B, system.C, 0.5 * system.friction)
    a = simulate(system, load, cycles=2, steps_per_cycle=6, min_cycles=2)
    b = simulate(other, load, cycles=2, steps_per_cycle=6, min_cycles=2)
    assert np.max(np.abs(a.x - b.x)) / a.disp_scale > 2e-2
