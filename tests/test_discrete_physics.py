"""Physics of the discrete model against closed forms and theorems."""

from __future__ import annotations

from itertools import product

import numpy as np
import pytest

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, critical_friction, simulate
from slipcycle.discrete.shakedown import extreme_constraints
from slipcycle.discrete.wellposed import is_p_matrix

# -- Jenkins element (one uncoupled node) ------------------------------------------------


def jenkins(k, P0, Q1, f, P1=0.0, alpha=0.0, steps=64, cycles=20):
    system = FrictionalSystem([[k]], [[0.0]], [[2.0 * k]], f)
    load = DiscreteLoad.harmonic([P0], [0.0], [P1], [Q1], [alpha], [0.0])
    return simulate(system, load, cycles=cycles, steps_per_cycle=steps, tol=1e-12)


@pytest.mark.parametrize("Q1", [0.3, 0.5, 0.9])
def test_jenkins_constant_limit_closed_form(Q1):
    k, P0, f = 2.0, 1.0, 0.4
    res = jenkins(k, P0, Q1, f)
    F = f * P0
    expected = 4 * F * (Q1 - F) / k if Q1 > F else 0.0
    assert res.steady_state == ("cyclic_slip" if Q1 > F else "shakedown")
    assert res.dissipation_per_cycle == pytest.approx(expected, rel=1e-10, abs=1e-14)


def play_operator_dissipation(k, P0, P1, alpha, Q1, f, m=400_000, cycles=4):
    """Reference: the single node's residual u = k v is the play operator of the band
    [−f p − q^w, f p − q^w]; D = Σ f p |Δu| / k over the last cycle (independent code)."""
    th = np.linspace(0, 2 * np.pi * cycles, m * cycles + 1)
    p = P0 + P1 * np.cos(th + alpha)
    qw = Q1 * np.cos(th)
    lo, hi = -f * p - qw, f * p - qw
    u = np.empty_like(th)
    u[0] = np.clip(0.0, lo[0], hi[0])
    for i in range(1, th.size):  # noqa: B007 - sequential by nature
        u[i] = min(max(u[i - 1], lo[i]), hi[i])
    du = np.abs(np.diff(u[-m - 1:]))
    pm = 0.5 * (p[-m - 1:-1] + p[-m:])
    return float(np.sum(f * pm * du) / k)


def test_jenkins_moving_limits_play_operator():
    k, P0, P1, alpha, Q1, f = 1.5, 1.0, 0.5, 1.1, 0.6, 0.5
    ref = play_operator_dissipation(k, P0, P1, alpha, Q1, f, m=20_000)
    res = jenkins(k, P0, Q1, f, P1=P1, alpha=alpha, steps=4000)
    assert res.steady_state == "cyclic_slip"
    assert res.dissipation_per_cycle == pytest.approx(ref, rel=2e-4)
    # in phase with Q1 < f P1 and P0 large: the band always contains a common point
    res0 = jenkins(k, 2.0, 0.2, f, P1=0.5, alpha=0.0, steps=100)
    assert res0.steady_state == "shakedown"
    assert res0.dissipation_per_cycle == pytest.approx(0.0, abs=1e-12)


# -- frictional Melan theorem (uncoupled) ---------------------------------------------------


def test_uncoupled_steady_state_independent_of_initial_condition():
    rng = np.random.default_rng(11)
    n = 3
    G = rng.normal(size=(n, n))
    A = G @ G.T + n * np.eye(n)
    C = 2.0 * np.eye(n) + 0.3
    system = FrictionalSystem(A, np.zeros((n, n)), C, 0.4)
    load = DiscreteLoad.harmonic(np.ones(n), np.zeros(n), [0.2, 0.3, 0.1], [0.6, 0.3, 0.8],
                                 [0.0, 1.0, 2.0], [0.5, 2.5, 4.0])
    r0 = load(np.array([0.0]))[0]
    qw0, pw0 = r0[:n], r0[n:]
    results = []
    # initial slips that put q(0) at chosen fractions of the friction limit
    for t in ([0.0, 0.0, 0.0], [0.9, -0.9, 0.5], [-0.8, 0.7, -0.95]):
        v0 = np.linalg.solve(A, np.array(t) * 0.4 * pw0 - qw0)
        results.append(simulate(system, load, cycles=300, steps_per_cycle=100,
                                initial_slip=v0, tol=1e-11))
    protocol = np.array([np.r_[np.zeros(n), 0.2 * np.ones(n)],
                         np.r_[[0.3, -0.3, 0.1], np.ones(n)]])
    results.append(simulate(system, load, cycles=300, steps_per_cycle=100, protocol=protocol,
                            tol=1e-11))
    ref = results[0]
    assert ref.steady_state == "cyclic_slip"
    for r in results[1:]:
        assert r.steady_state == ref.steady_state
        assert r.slipping_nodes == ref.slipping_nodes
        np.testing.assert_allclose(r.dissipation_per_node, ref.dissipation_per_node,
                                   rtol=1e-6, atol=1e-9)
        # (the residual reactions of permanently stuck nodes may differ: only the
        # dissipation and the slip pattern are unique)


# -- coupled two-node system with a triangular safe region (Ahn et al.) ----------------------

TRI_A = [[1.0, 0.247075047227736], [0.247075047227736, 1.0]]
TRI_B = [[-0.41656197222519253, 0.2554683150798821],
         [0.41714925630544075, -0.11852910240884229]]
TRI_PHASES = [3.476172521227298, 3.0127103968364217, 6.022577628933113, 1.9935154643203314]
TRI_P1 = [0.20104226346888293, 0.0004598945554328826]
TRI_Q1 = [0.36807381387725213, 0.452574442452916]


def triangle_system():
    system = FrictionalSystem(TRI_A, TRI_B, np.eye(2), 0.5)
    load = DiscreteLoad.harmonic([1.0, 1.0], [0.0, 0.0], TRI_P1, TRI_Q1, TRI_PHASES[:2],
                                 TRI_PHASES[2:])
    return system, load


def safe_region_vertices(G, h):
    verts = []
    for a in range(4):
        for b in range(a + 1, 4):
            M = G[[a, b]]
            if abs(np.linalg.det(M)) > 1e-9:
                p = np.linalg.solve(M, h[[a, b]])
                if np.all(G @ p >= h - 1e-9):
                    verts.append(p)
    return np.unique(np.round(np.array(verts), 10), axis=0)


def test_triangular_safe_region_history_dependence():
    system, load = triangle_system()
    G, h = extreme_constraints(system, load, steps=4000)
    verts = safe_region_vertices(G, h)
    active = {k for k in range(4) if any(abs(G[k] @ v - h[k]) < 1e-8 for v in verts)}
    assert len(verts) == 3 and active == {1, 2, 3}, "the safe region must be a triangle"
    inside = verts.mean(axis=0)
    a = simulate(system, load, cycles=60, steps_per_cycle=200, initial_slip=inside)
    assert a.steady_state == "shakedown"
    assert a.dissipation_per_cycle == pytest.approx(0.0, abs=1e-12)
    b = simulate(system, load, cycles=60, steps_per_cycle=200, initial_slip=[-0.518, 0.528])
    assert b.steady_state == "cyclic_slip"
    assert b.slipping_nodes == [1] and b.permanently_stuck_nodes == [0]
    assert b.dissipation_per_cycle > 1e-3
    assert b.energy_balance_error < 1e-9


# -- well-posedness -------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
def test_f_crit_is_where_p_property_fails(seed):
    rng = np.random.default_rng(seed)
    n = 2 + seed % 2
    G = rng.normal(size=(2 * n, 2 * n))
    K = G @ G.T + 0.3 * np.eye(2 * n)
    A, B = K[:n, :n], K[n:, :n]
    fc = critical_friction(A, B)
    assert fc.method == "exact" and np.isfinite(fc.f_crit)
    assert fc.lower_bound <= fc.f_crit
    signs = [np.diag(s) for s in product((1.0, -1.0), repeat=n)]
    assert all(is_p_matrix(A + 0.999 * fc.f_crit * S @ B) for S in signs)
    assert not all(is_p_matrix(A + 1.001 * fc.f_crit * S @ B) for S in signs)


def test_f_crit_bound_brackets_exact_value():
    rng = np.random.default_rng(7)
    n = 6
    G = rng.normal(size=(2 * n, 2 * n))
    K = G @ G.T + 1.0 * np.eye(2 * n)
    A, B = K[:n, :n], K[n:, :n]
    exact = critical_friction(A, B)
    bound = critical_friction(A, B, exact_max_nodes=0)
    assert bound.method == "bound"
    assert bound.lower_bound <= exact.f_crit * (1 + 1e-12)
    assert bound.f_crit >= exact.f_crit * (1 - 1e-12)
    assert critical_friction(A, np.zeros((n, n))).f_crit == np.inf


def test_assembly_protocol_order_matters_and_is_reproducible():
    system, load = triangle_system()
    # states r^w = [q1, q2, p1, p2]: clamp one node, shear the other, then clamp both
    bolt1_first = np.array([[0.0, 0.3, 1.0, 0.1], [0.0, 0.0, 1.0, 1.0]])
    bolt2_first = np.array([[0.3, 0.0, 0.1, 1.0], [0.0, 0.0, 1.0, 1.0]])
    a = simulate(system, load, cycles=5, steps_per_cycle=50, protocol=bolt1_first)
    a2 = simulate(system, load, cycles=5, steps_per_cycle=50, protocol=bolt1_first)
    b = simulate(system, load, cycles=5, steps_per_cycle=50, protocol=bolt2_first)
    np.testing.assert_array_equal(a.x, a2.x)
    assert np.max(np.abs(a.initial_state - b.initial_state)) > 1e-3
