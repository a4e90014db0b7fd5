"""Random coupled frictional systems shared by the tests and the benchmarks.

The benchmarks import this module through ``sys.path`` (``benchmarks/bench_discrete3d.py``);
the tests import it as a sibling module (pytest puts ``tests/`` on the path).
"""

from __future__ import annotations

import numpy as np


def random_coupled_2d(seed: int, n: int = 2):
    """A random coupled 2-D system and a harmonic load.

    K = M Mᵀ/(2n) + diag(U(1, 2)) with M standard normal is symmetric positive definite;
    A, C are its diagonal blocks and B half of its off-diagonal block, so the coupling is
    strong but the system stays well posed for the friction coefficients drawn.

    Parameters
    ----------
    seed : int
        Seed of :func:`numpy.random.default_rng`; one seed, one system.
    n : int
        Number of contact nodes.

    Returns
    -------
    A, B, C : numpy.ndarray, shape (n, n)
        Tangential, coupling and normal stiffness blocks.
    f : numpy.ndarray, shape (n,)
        Friction coefficients in [0.2, 0.5).
    load : tuple of six numpy.ndarray, shape (n,)
        ``(p0, q0, p1, q1, p_phase, q_phase)`` of :meth:`DiscreteLoad.harmonic
        <slipcycle.discrete.DiscreteLoad.harmonic>`: mean and amplitude of the normal and
        tangential loads, phases in rad.
    """
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(2 * n, 2 * n))
    K = M @ M.T / (2 * n) + np.diag(rng.uniform(1.0, 2.0, 2 * n))
    A, B, C = K[:n, :n], 0.5 * K[n:, :n], K[n:, n:]
    f = rng.uniform(0.2, 0.5, n)
    load = (rng.uniform(0.3, 0.8, n), rng.normal(size=n) * 0.1, rng.uniform(0.3, 0.9, n),
            rng.uniform(0.3, 0.8, n), rng.uniform(0, 6, n), rng.uniform(0, 6, n))
    return A, B, C, f, load


def along_t1(a):
    """Per-node values ``a`` (shape (n,)) as 3-D tangential vectors along t1: shape (2n,),
    (a_1, 0, a_2, 0, ...)."""
    a = np.asarray(a, float)
    z = np.zeros((a.size, 2))
    z[:, 0] = a
    return z.ravel()
