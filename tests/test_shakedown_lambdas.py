"""Safe region and λ1, λ2 against independent computations (issue 4, SPEC §2)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slipcycle.discrete import DiscreteLoad, FrictionalSystem
from slipcycle.discrete.case import read_discrete_case
from slipcycle.discrete.shakedown import (
    lambda1,
    lambda2,
    polygon_vertices,
    redundant_constraints,
    safe_region,
)
from slipcycle.io import read_case
from slipcycle.loading import TabulatedLoad
from slipcycle.plot.discrete import extreme_constraints

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def triangle_case():
    dc = read_discrete_case(read_case(EXAMPLES / "shakedown_triangle.toml"))
    return dc.system, dc.load


def spec_case():
    dc = read_discrete_case(read_case(EXAMPLES / "discrete_two_node.toml"))
    return dc.system, dc.load


# --- independent N = 2 reference: sampled extremes + hand-written line intersections ----
def ref_lines(system, load, lam, steps=40000):
    """Lines a·v ≥ c at their extreme positions, by dense sampling of the cycle."""
    G, h = extreme_constraints(system, load.with_lam(lam), steps=steps)
    return G, h


def ref_vertices(G, h, tol=1e-12):
    verts = []
    for i in range(4):
        for j in range(i + 1, 4):
            (a, b), (c, d) = G[i], G[j]
            det = a * d - b * c
            if abs(det) < 1e-14:
                continue
            x = (h[i] * d - b * h[j]) / det          # Cramer's rule
            y = (a * h[j] - c * h[i]) / det
            if all(G[k, 0] * x + G[k, 1] * y >= h[k] - tol for k in range(4)):
                verts.append((x, y, {i, j}))
    return verts


def ref_n_edges(system, load, lam):
    verts = ref_vertices(*ref_lines(system, load, lam))
    if not verts:
        return 0
    edges = 0
    for k in range(4):
        on = {(round(x, 12), round(y, 12)) for x, y, s in verts if k in s}
        edges += len(on) >= 2
    return edges


def ref_bisect(pred, lo, hi, tol=1e-7):
    """Largest λ in [lo, hi] with pred(λ) true (pred true at lo, false at hi)."""
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if pred(mid) else (lo, mid)
    return lo


@pytest.mark.parametrize("make", [triangle_case, spec_case])
def test_lambda2_and_lambda1_match_hand_intersections(make):
    system, load = make()
    region = safe_region(system, load)
    assert region.method == "exact_single_harmonic"
    l2, v = lambda2(region)
    l1 = lambda1(region, l2)["lambda1"]
    ref2 = ref_bisect(lambda lam: len(ref_vertices(*ref_lines(system, load, lam))) > 0,
                      0.0, 3.0)
    ref1 = ref_bisect(lambda lam: ref_n_edges(system, load, lam) == 4, 0.0, ref2)
    assert l2 == pytest.approx(ref2, abs=2e-5)
    assert l1 == pytest.approx(ref1, abs=2e-5)
    assert 0 < l1 < l2
    # the LP's last safe state lies in S(λ2) and S(λ2 (1 + 1e-6)) is empty
    assert region.contains(v, l2, tol=1e-9)
    assert redundant_constraints(region, l2 * (1 + 1e-6)) is None


def test_extremes_match_sampling_and_polygon():
    system, load = triangle_case()
    region = safe_region(system, load)
    for lam in (0.3, 1.0):
        Gp, hp = extreme_constraints(system, load.with_lam(lam), steps=40000)
        # plot convention: G_p v ≥ h_p; ours: G v ≤ h
        np.testing.assert_allclose(-Gp, region.G, atol=1e-14)
        np.testing.assert_allclose(-hp, region.h(lam), atol=1e-8)
    P = polygon_vertices(region, 1.0)
    assert len(P) == 3                               # triangle between λ1 and λ2
    assert len(polygon_vertices(region, 0.5)) == 4   # quadrilateral below λ1


def test_uncoupled_lambda1_equals_lambda2():
    """B = 0: all 2N constraints stay active until S vanishes (frictional Melan)."""
    rng = np.random.default_rng(3)
    M = rng.standard_normal((3, 3))
    A = M @ M.T + 3 * np.eye(3)
    system = FrictionalSystem(A, np.zeros((3, 3)), np.eye(3) * 2, 0.4)
    load = DiscreteLoad.harmonic(np.ones(3), np.zeros(3), [0.2, 0.1, 0.3],
                                 [0.3, 0.5, 0.2], [0.0, 1.0, 2.0], [0.3, 2.0, 4.0])
    region = safe_region(system, load)
    l2 = lambda2(region)[0]
    l1 = lambda1(region, l2)["lambda1"]
    assert np.isfinite(l2) and l2 > 0
    assert l1 == pytest.approx(l2, rel=1e-6)


def test_several_harmonics_refined_and_tabulated_breakpoints():
    system, _ = triangle_case()
    p1 = [[0.2, 0.05], [0.1, 0.02]]
    q1 = [[0.3, 0.4], [0.15, -0.2]]
    load = DiscreteLoad.harmonic([1.0, 1.0], [0.0, 0.0], p1, q1, [[0.0, 1.0], [2.0, 0.5]],
                                 [[0.3, 1.2], [1.0, 2.0]])
    region = safe_region(system, load)
    assert region.method == "harmonic_refined"
    Gp, hp = extreme_constraints(system, load, steps=400000)
    np.testing.assert_allclose(-hp, region.h(1.0), atol=1e-9)
    assert np.all(-hp >= region.h(1.0) - 1e-13)      # refined minimum is below samples
    th = np.array([0.0, 1.0, 2.5, 4.0])
    tab = DiscreteLoad(TabulatedLoad(th, [[0.1, 0.0], [-0.2, 0.1], [0.05, -0.1],
                                          [0.0, 0.05]], [1.0, 1.0]),
                       TabulatedLoad(th, [[0.3, -0.2], [0.0, 0.4], [-0.3, 0.0],
                                          [0.1, -0.1]], [0.0, 0.0]))
    region = safe_region(system, tab)
    assert region.method == "breakpoints"
    Gp, hp = extreme_constraints(system, tab, steps=100000)
    # sampling can only miss the knots: it is never below the exact extreme, and close
    assert np.all(-hp >= region.h(1.0) - 1e-13)
    np.testing.assert_allclose(-hp, region.h(1.0), atol=1e-4)
    # at the knots themselves the sampled and exact values coincide
    c1 = tab(th) @ np.array([[1, 0, 0.5, 0], [-1, 0, 0.5, 0], [0, 1, 0, 0.5],
                             [0, -1, 0, 0.5]]).T
    np.testing.assert_allclose(c1.min(axis=0), region.h(1.0), atol=1e-14)


def test_mean_load_infeasible_and_no_periodic_load():
    system, _ = triangle_case()
    const = DiscreteLoad.harmonic([1.0, 1.0], [0.1, 0.0])
    region = safe_region(system, const)
    assert lambda2(region)[0] == np.inf
    bad = DiscreteLoad.harmonic([1.0, 1.0], [5.0, 0.0], [0.1, 0.1], [0.1, 0.1])
    assert lambda2(safe_region(system, bad))[0] == -np.inf
