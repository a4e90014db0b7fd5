"""The pair sampling of the 3-D critical friction (closed-form quadratic over all pairs and
angles at once) gives the answer of the plain loop over pairs and angles with
``numpy.roots`` that it replaced."""

import numpy as np
import pytest

from slipcycle.discrete3d.wellposed import _pairs, critical_friction_3d, radial_matrix


def _loop_pairs(A, B, ratio, ang):
    """The reference: one 2 × 2 matrix pair per (i, k, a1, a2), numpy.roots of its
    determinant polynomial, first strictly smaller root kept."""
    n = B.shape[0]
    best, where, dirs = np.inf, (), ()
    for i in range(n):
        for k in range(i + 1, n):
            for a1 in ang:
                for a2 in ang:
                    M0, M1 = radial_matrix(A, B, ratio, [i, k], [a1, a2])
                    qa = M1[0, 0] * M1[1, 1] - M1[0, 1] * M1[1, 0]
                    qc = M0[0, 0] * M0[1, 1] - M0[0, 1] * M0[1, 0]
                    qb = (M0[0, 0] * M1[1, 1] + M1[0, 0] * M0[1, 1]
                          - M0[0, 1] * M1[1, 0] - M1[0, 1] * M0[1, 0])
                    roots = np.roots([qa, qb, qc])
                    roots = roots[(np.abs(roots.imag) < 1e-12 * (1 + np.abs(roots)))
                                  & (roots.real > 0)].real
                    if roots.size and roots.min() < best:
                        best, where, dirs = float(roots.min()), (i, k), (a1, a2)
    return best, where, dirs


def _system(n, seed, coupling=1.0):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    B = coupling * K[2 * n:, :2 * n]
    return K[:2 * n, :2 * n], B, K[2 * n:, 2 * n:], rng.uniform(0.1, 0.5, n)


@pytest.mark.parametrize("n, seed, coupling", [(2, 0, 1.0), (3, 1, 1.0), (4, 2, 0.3),
                                               (5, 3, 2.0), (3, 4, 1e-3)])
def test_closed_form_pairs_equal_the_loop_with_numpy_roots(n, seed, coupling):
    A, B, _, f = _system(n, seed, coupling)
    ratio = f / f.max()
    ang = np.linspace(0.0, 2 * np.pi, 12, endpoint=False)
    phi, pair, dirs = _pairs(A, B, ratio, ang)
    ref = _loop_pairs(A, B, ratio, ang)
    assert phi == pytest.approx(ref[0], rel=1e-9)
    assert pair == ref[1] and dirs == pytest.approx(ref[2], abs=0)


def test_no_positive_root_reports_none():
    A, B, _, f = _system(3, 5)
    phi, pair, dirs = _pairs(A, np.zeros_like(B), np.ones(3),
                             np.linspace(0, 2 * np.pi, 8, endpoint=False))
    assert phi == np.inf and pair == () and dirs == ()


def test_sixteen_nodes_keep_the_pair_sampling():
    """N ≤ 40 still samples every pair (the method says so) and finds a finite f_crit."""
    A, B, C, f = _system(16, 16)
    res = critical_friction_3d(A, B, C, f)
    assert "pairs" in res.method and np.isfinite(res.f_crit)
