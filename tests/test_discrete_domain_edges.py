"""The discrete engines at the edges of their domain: no friction or very little, nodes
open for the whole cycle, load and stiffness scales, one-node closed forms.

References: closed forms derived in each docstring, the frictionless path (a contact
LCP per load sample, no code shared with the engines), and, for the 3-D engine loaded
along t1 only, the exact event-driven 2-D solver.
"""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from random_systems import along_t1, random_coupled_2d

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.discrete.lcp import lemke
from slipcycle.discrete.model import SEPARATED
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import SEPARATED as SEPARATED_3D
from slipcycle.discrete3d.model import embed_2d
from slipcycle.discrete3d.steady import simulate3d


def _both(A, B, C, f, p0, q0, p1, q1, pph, qph, steps=20, step_tol=1e-10, **kw):
    """The exact 2-D solver and the 3-D engine (at ``step_tol``) loaded along t1 on one
    system."""
    n = np.atleast_2d(A).shape[0]
    f = np.broadcast_to(np.asarray(f, float), (n,)).copy()
    r2 = simulate(FrictionalSystem(A, B, C, f, accept_ill_posed=True),
                  DiscreteLoad.harmonic(p0, q0, p1, q1, pph, qph), cycles=60,
                  steps_per_cycle=steps, tol=1e-11, **kw)
    load3 = Load3D.harmonic(p0, along_t1(q0), p1, along_t1(q1), pph, np.repeat(qph, 2))
    r3 = simulate3d(embed_2d(A, B, C, f), load3, cycles=60, steps_per_cycle=steps,
                    tol=1e-11, step_tol=step_tol, **kw)
    return r2, r3


def _frictionless_path_integral(A, B, C, load, steps, sub=200):
    """∮ Σ_j p_j |dv_j| along the frictionless path (f = 0) of the piecewise-linear load
    path through ``steps`` samples, trapezoidal on ``sub`` points per load interval.

    With f = 0 every node in contact carries q = 0, so v = −A⁻¹(q^w + Bᵀw) and
    p = p^w − B A⁻¹ q^w + (C − B A⁻¹ Bᵀ) w, with w ≥ 0, p ≥ 0, wᵀp = 0: an LCP in w
    with the (positive definite) Schur complement, solved by Lemke's method per point.
    """
    n = A.shape[0]
    Ai = np.linalg.inv(A)
    S = C - B @ Ai @ B.T
    _, vals = load.cycle_samples(steps)

    def state(rw):
        qw, pw = rw[:n], rw[n:]
        w = lemke(S, pw - B @ Ai @ qw)
        v = -Ai @ (qw + B.T @ w)
        return v, pw + B @ v + C @ w

    total, prev = 0.0, None
    for k in range(steps):
        for s in np.linspace(0.0, 1.0, sub + 1)[:-1]:
            v, p = state(vals[k] + s * (vals[k + 1] - vals[k]))
            if prev is not None:
                total += 0.5 * (p + prev[1]) @ np.abs(v - prev[0])
            prev = (v, p)
    v, p = state(vals[steps])
    return total + 0.5 * (p + prev[1]) @ np.abs(v - prev[0])


def test_frictionless_node_in_contact_slips_and_never_opens():
    """One node, f = 0: q ≡ 0, so v = −q^w/A and p = p^w − B q^w/A = 1 + 0.5 cos θ −
    0.2 (0.1 + 0.3 cos(θ + 1)) ≥ 0.42 > 0: the node stays in contact all cycle, slips
    every cycle and dissipates nothing. (The 2-D solver opened it at θ = 0 — the apex
    rule took a frictionless node for one at p = 0 — and kept p = 1.45 on it while its
    gap grew to 0.97: "shakedown" with the node separating.)"""
    r2, r3 = _both([[1.0]], [[0.2]], [[1.0]], 0.0, [1.0], [0.1], [0.5], [0.3], [0.0],
                   [1.0], steps=8)
    for res in (r2, r3):
        assert res.separating_nodes == []
        assert res.slipping_nodes == [0]
        assert res.steady_state == "cyclic_slip"
        assert res.dissipation_per_cycle == 0.0          # nothing books without friction
    n = 1
    x, r = r2.x[-1], r2.r[-1]                            # every sample of the last cycle
    assert np.all(x[:, n:] <= r2.disp_scale * 1e-9)      # no gap
    assert np.all(r[:, n:] >= 0.42)


@pytest.mark.parametrize("f", [1e-9, 1e-6, 1e-4])
def test_small_friction_dissipation_is_f_times_the_frictionless_path_integral(f):
    """For f → 0 a slipping node carries q = ∓f p, so D = f ∮ Σ_j p_j |dv_j| + O(f²)
    along the frictionless path (q = 0; :func:`_frictionless_path_integral`). Random
    coupled system 21 with 3 nodes, one of them separating: both engines give D/f
    within 1e-5 + 10 f of the integral (the O(f) term, measured 1.6 f, and the
    trapezoidal rule's error),
    and the 3-D engine loaded along t1 at step_tol 1e-11 gives D and every D_j within
    1e-6 of the exact 2-D solver (measured 4.2e-7, 1.9e-7, 3.5e-8 at f = 1e-9, 1e-6,
    1e-4; before its energy test was scaled by 10 f below f = 0.1, 1.3e-2 off at f = 1e-6
    and 1.7e-3 at 1e-4 at step_tol 1e-10 — a node reversing inside a step moves D by
    O(f), below an energy scale that ignored f; and the 2-D solver, whose friction limits
    were active within 1e-10 of the force scale whatever the cone's width, opened the
    nodes at f = 1e-9 with p > 0 held on them: D/f 1.3e-2 off)."""
    A, B, C, _, (p0, q0, p1, q1, pph, qph) = random_coupled_2d(21, 3)
    r2, r3 = _both(A, B, C, f, p0, q0, p1, q1, pph, qph, steps=20, step_tol=1e-11)
    ref = _frictionless_path_integral(A, B, C,
                                      DiscreteLoad.harmonic(p0, q0, p1, q1, pph, qph), 20)
    assert r2.separating_nodes == r3.separating_nodes == [0]
    for res in (r2, r3):
        assert res.dissipation_per_cycle / f == pytest.approx(ref, rel=1e-5 + 10 * f)
    d2 = r2.dissipation_per_cycle
    assert abs(r3.dissipation_per_cycle - d2) <= 1e-6 * d2
    assert np.max(np.abs(r3.dissipation_per_node - r2.dissipation_per_node)) <= 1e-6 * d2


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2 ** 31 - 1), n=st.integers(1, 3),
       steps=st.sampled_from([4, 5, 8, 20]))
def test_nodes_open_all_cycle_dissipate_nothing(seed, n, steps):
    """Tensile normal loads, p^w ≤ −0.2 at every instant, that keep every node open at
    every load sample of the last cycle (checked; with coupling a node may close): a
    separated node carries p = q = 0, so D_j = −∮ q_j dv_j is exactly 0 at every node
    in both engines — booked as nothing, not as round-off (before: D_j of ±1e-17, and a
    negative D for a "shakedown")."""
    A, B, C, f, (_, q0, p1, q1, pph, qph) = random_coupled_2d(seed, n)
    p0 = -(p1 + 0.2)
    r2, r3 = _both(A, B, C, f, p0, q0, p1, q1, pph, qph, steps=steps)
    assume(np.all(r2.modes[-1][1:] == SEPARATED))
    assert np.all(r3.modes[-1][1:] == SEPARATED_3D)
    for res in (r2, r3):
        assert res.steady_state == "shakedown"
        assert np.all(res.dissipation_per_node == 0.0)
        assert res.dissipation_per_cycle == 0.0


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2 ** 31 - 1), n=st.integers(1, 4),
       steps=st.sampled_from([4, 7, 20, 100]), tensile=st.booleans())
def test_dissipation_of_every_node_is_non_negative(seed, n, steps, tensile):
    """D_j = −∮ q_j dv_j ≥ 0 at every node (q opposes the slip; q = 0 while open),
    with nodes that open in part of the cycle or all of it: no D_j below −1e-12 of the
    energy scale F × displacement scale in either engine."""
    A, B, C, f, (p0, q0, p1, q1, pph, qph) = random_coupled_2d(seed, n)
    if tensile:
        p0 = -p0
    r2, r3 = _both(A, B, C, f, p0, q0, p1, q1, pph, qph, steps=steps)
    for res in (r2, r3):
        scale = res.force_scale * res.disp_scale
        assert np.all(res.dissipation_per_node >= -1e-12 * scale)


@settings(max_examples=20, deadline=None)
@given(force_exp=st.integers(-9, 9), stiff_exp=st.integers(-3, 12),
       ratio=st.floats(0.2, 3.0), f=st.floats(0.05, 0.9))
def test_jenkins_element_dissipation_scales_as_force_squared_over_stiffness(
        force_exp, stiff_exp, ratio, f):
    """One node, A = k, B = 0, constant P, q^w = Q cos θ (the Jenkins element). Loaded
    to q^w = Q at θ = 0 it slips there with q = −f P; on the way back it sticks until
    q^w has fallen by 2 f P and slips again with q = +f P down to −Q, and the same on
    the way up: the loop is a parallelogram of height 2 f P and width 2 (Q − f P)/k, so
    D = 4 f P (Q − f P)/k for Q > f P and D = 0 (shakedown) for Q ≤ f P. With
    P = 10^a N, k = 10^b N/m (a ∈ [−9, 9], b ∈ [−3, 12]) and Q = ratio × f P, both
    engines give D within 1e-9 of it, and the class; the loop is a polygon whose
    corners are located exactly by events (2-D) or by the step control (3-D)."""
    P, k = 10.0 ** force_exp, 10.0 ** stiff_exp
    Q = ratio * f * P
    exact = 4 * f * P * (Q - f * P) / k if Q > f * P else 0.0
    r2, r3 = _both([[k]], [[0.0]], [[k]], f, [P], [0.0], [0.0], [Q], [0.0], [0.0],
                   steps=16)
    for res in (r2, r3):
        assert res.steady_state == ("cyclic_slip" if ratio > 1.0 + 1e-9 else "shakedown")
        assert abs(res.dissipation_per_cycle - exact) <= 1e-9 * 4 * f * P * Q / k


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2 ** 31 - 1), n=st.integers(1, 4),
       f=st.sampled_from([0.0, 1e-12, 1e-9, 1e-7, 1e-5, 3e-3]),
       sign=st.sampled_from([1.0, 0.3, -1.0]))
def test_narrow_friction_cones_keep_the_contact_law_in_the_2d_solver(seed, n, f, sign):
    """Friction cones narrower than the solver's force tolerance (f p ≤ 1e-10 F) or just
    above it, with nodes that open (means scaled by 0.3 or tensile): the rate problem
    always has a solution, an open node carries no normal reaction and a node in
    contact has no gap at every load sample (|w p| ≤ 1e-9 F × displacement scale),
    and D_j ≥ 0. Before: with f = 0 or 1e-9 nodes were opened with p up to 1.45 N held
    on them (the rule "both friction limits active ⇒ at the apex"); with that rule
    confined to p ≈ 0, f = 1e-9 ended in "the rate problem has no solution"."""
    A, B, C, _, (p0, q0, p1, q1, pph, qph) = random_coupled_2d(seed, n)
    res = simulate(FrictionalSystem(A, B, C, f, accept_ill_posed=True),
                   DiscreteLoad.harmonic(sign * p0, q0, p1, q1, pph, qph), cycles=30,
                   steps_per_cycle=16, tol=1e-9)
    x, r = res.x[-1], res.r[-1]
    scale = res.force_scale * res.disp_scale
    assert np.max(np.abs(x[:, n:] * r[:, n:])) <= 1e-9 * scale
    assert np.all(r[:, n:] >= -1e-9 * res.force_scale)
    assert np.all(x[:, n:] >= -1e-9 * res.disp_scale)
    assert np.all(res.dissipation_per_node >= -1e-12 * scale)


def test_lambda2_of_the_triangle_example_separates_shakedown_from_cyclic_slip():
    """Brute force around λ2 (one LP, ``lambda2``) of the shakedown_triangle example
    (Ahn, Bertocchi & Barber 2008): at 0.999 λ2 the LP's safe state lies in S(λ) (S
    shrinks as λ grows), so a run started there never slips (shakedown, D = 0); at
    1.001 λ2 S(λ) is empty and no start shakes down (the LP's state and three random
    admissible starts)."""
    from slipcycle.discrete.shakedown import lambda2, safe_region, sample_initial_slips
    A = np.array([[1.0, 0.247075047227736], [0.247075047227736, 1.0]])
    B = np.array([[-0.41656197222519253, 0.2554683150798821],
                  [0.41714925630544075, -0.11852910240884229]])
    system = FrictionalSystem(A, B, np.eye(2), 0.5)

    def load(lam):
        return DiscreteLoad.harmonic(
            [1.0, 1.0], [0.0, 0.0], [0.20104226346888293, 0.0004598945554328826],
            [0.36807381387725213, 0.452574442452916],
            [3.476172521227298, 3.0127103968364217],
            [6.022577628933113, 1.9935154643203314], lam=lam)

    lam2, v2 = lambda2(safe_region(system, load(1.0)))
    assert lam2 == pytest.approx(1.104, abs=1e-3)     # the example's quoted value
    below = simulate(system, load(0.999 * lam2), cycles=100, steps_per_cycle=400,
                     tol=1e-10, initial_slip=v2)
    assert below.steady_state == "shakedown" and below.dissipation_per_cycle == 0.0
    above = load(1.001 * lam2)
    starts = [v2, *sample_initial_slips(system, above, 3, np.random.default_rng(0))]
    for v0 in starts:
        res = simulate(system, above, cycles=100, steps_per_cycle=400, tol=1e-10,
                       initial_slip=v0)
        assert res.steady_state == "cyclic_slip" and res.dissipation_per_cycle > 0.0
