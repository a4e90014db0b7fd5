"""The separated nodes condensed out of the 3-D Newton system (``StepSolver``): the
coupling W = K_PP⁻¹ K_PS and the condensed block K̃ of a sequence of slipping sets on one
separated set (the entries of the nodes slipping in both copied from the last set)
against a direct solve; and load steps with slipping and separated nodes together (a
residual of the separated rows within the Newton tolerance left as it is) against the
same steps solved on the whole active block (no condensation), with the residual of
every row within the Newton tolerance.
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.discrete3d.evolution import StepSolver
from slipcycle.discrete3d.model import SEPARATED, SLIP, FrictionalSystem3D


def _system(rng, n, f=0.1):
    """A random coupled system: K symmetric positive definite, diagonally dominant (so
    that a small f is well below the critical friction coefficient)."""
    M = rng.normal(size=(3 * n, 3 * n))
    K = 0.1 * M @ M.T / (3 * n) + np.eye(3 * n)
    K = 0.5 * (K + K.T)
    return FrictionalSystem3D(K[:2 * n, :2 * n], K[2 * n:, :2 * n], K[2 * n:, 2 * n:], f,
                              accept_ill_posed=True)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2 ** 31), n=st.integers(3, 14))
def test_condensed_blocks_of_a_sequence_of_slipping_sets_equal_a_direct_solve(seed, n):
    """W of a sequence of slipping sets on one separated set (nodes added, removed, the
    same set again), its columns of the nodes slipping in the last set too copied from
    it, equals K_PP⁻¹ K_PS solved directly, and the condensed block
    K̃ = K_{VS,S} − K_{VS,P} W too (round-off of the triangular solves)."""
    rng = np.random.default_rng(seed)
    solver = StepSolver(_system(rng, n), 1.0)
    nodes = rng.permutation(n)
    P = np.sort(nodes[: max(1, n // 3)])
    rest = nodes[max(1, n // 3):]
    K = solver.K
    for _ in range(5):
        S = np.sort(rng.choice(rest, size=rng.integers(1, rest.size + 1), replace=False))
        block = solver._active_block(S, P)
        key, U, V, KVU = block[:4]
        cho, W, Kt, KSP = solver._separated_block(key, KVU, S.size, P.size)
        s, m = 2 * S.size, U.size
        Sdofs, Pdofs = U[:s], U[s:]
        W_ref = np.linalg.solve(K[np.ix_(Pdofs, Pdofs)], K[np.ix_(Pdofs, Sdofs)])
        VS = np.concatenate([V[:s], V[m:]])
        Kt_ref = K[np.ix_(VS, Sdofs)] - K[np.ix_(VS, Pdofs)] @ W_ref
        assert np.allclose(W, W_ref, rtol=0.0, atol=1e-12 * np.max(np.abs(W_ref)) + 1e-300)
        assert np.allclose(Kt, Kt_ref, rtol=0.0, atol=1e-12 * np.max(np.abs(K)))


def _step_state(rng, n):
    """A start state with about a third of the nodes open (w > 0, reactions zero) and a
    load increment that keeps them open and makes the closed ones slip."""
    x0 = np.zeros(3 * n)
    open_ = rng.random(n) < 0.35
    open_[0], open_[-1] = True, False
    x0[2 * n:][open_] = rng.uniform(0.5, 1.0, open_.sum())
    # reactions: zero at the open nodes, the others pressed (p = 1); the load is then
    # r0 − K x0, which the step solver does not need
    r0 = np.zeros(3 * n)
    r0[2 * n:][~open_] = 1.0
    drw = np.zeros(3 * n)
    drw[: 2 * n] = rng.normal(size=2 * n)                  # tangential: slip
    drw[2 * n:] = np.where(open_, -0.05, 0.05)             # open stay open
    return x0, r0, drw


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2 ** 31), n=st.integers(4, 14))
def test_condensed_steps_agree_with_the_whole_active_block(seed, n):
    """Load steps with slipping and separated nodes: the condensed Newton system (a
    residual of the separated rows within the tolerance left as it is)
    gives the step of the Newton method on the whole active block within the Newton
    tolerance, and the reactions of the step are r0 + Δr^w + K Δx, zero at open nodes,
    within it too."""
    rng = np.random.default_rng(seed)
    system = _system(rng, n)
    x0, r0, drw = _step_state(rng, n)
    tol = 1e-11
    steps = []
    for eliminate in (True, False):
        solver = StepSolver(system, 1.0, rel_tol=tol)
        solver.eliminate_separated = eliminate
        x, r, out = x0, r0, []
        for k in range(4):                              # several steps: cached sets reused
            step = solver.solve(x, r, drw * (1.0 + 0.3 * k))
            assert step is not None
            out.append(step)
            x, r = step.x, step.r
        steps.append(out)
    for a, b in zip(*steps, strict=True):
        assert np.array_equal(a.modes, b.modes)
        scale = np.max(np.abs(np.diag(system.K)))
        assert np.max(np.abs(a.x - b.x)) <= 100 * tol / scale * n
    x = x0
    r = r0
    for step in steps[0]:
        r_expected = r + step.drw + system.K @ (step.x - x)
        assert np.max(np.abs(step.r - r_expected)) <= 10 * tol * n
        sep = step.modes == SEPARATED
        n_ = system.n_nodes
        assert np.max(np.abs(step.r[2 * n_:][sep]), initial=0.0) <= 10 * tol
        x, r = step.x, step.r
    assert any(np.any(s.modes == SLIP) and np.any(s.modes == SEPARATED) for s in steps[0])

