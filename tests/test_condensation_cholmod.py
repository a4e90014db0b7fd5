"""The CHOLMOD path of the condensation engine against the SuperLU path.

:func:`slipcycle.condensation.schur_complement` factorises K once with CHOLMOD's
supernodal Cholesky (``cvxopt``, the ``cholmod`` extra) when it is installed, and with SuperLU
otherwise. Both must give the same Schur complement S = K_bb − K_bi K_ii⁻¹ K_ib and
load reactions r = K_bi K_ii⁻¹ f_i − f_b to round-off (here 1e-10 relative), on a 3-D
finite-element model and on random sparse SPD matrices (also when S is only semidefinite:
a body held by its boundary alone, which the boundary shift of the CHOLMOD path is for),
and must refuse a singular, nearly singular or indefinite interior with the same
one-line SingularModelError.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import slipcycle.condensation as cond
from slipcycle.condensation import SingularModelError, schur_complement

pytest.importorskip("cvxopt")
pytest.importorskip("pymetis")


def _superlu(monkeypatch, K, ni, F):
    """schur_complement as on an install without cvxopt."""
    with monkeypatch.context() as m:
        m.setattr(cond, "_cvxopt_cholmod", lambda: None)
        return schur_complement(K, ni, F)


def _cholmod(monkeypatch, K, ni, F):
    """schur_complement through CHOLMOD, failing the test if it fell back to SuperLU."""
    calls = []
    real = cond._schur_cholmod

    def spy(*args):
        out = real(*args)
        calls.append(out is not None)
        return out

    with monkeypatch.context() as m:
        m.setattr(cond, "_schur_cholmod", spy)
        out = schur_complement(K, ni, F)
    assert calls == [True], "the CHOLMOD path did not produce the result"
    return out


def _rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def _random_model(seed: int, n_int: int, n_bnd: int, grounded: bool, m: int):
    """A sparse SPD K (interior first) from a random connected spring network.

    Graph Laplacian of random springs (a path through every node keeps it connected)
    plus, with ``grounded``, springs to the ground at a few interior nodes; without
    them only the boundary holds the network and S is singular (semidefinite).
    """
    rng = np.random.default_rng(seed)
    n = n_int + n_bnd
    walk = rng.permutation(n)
    i = np.concatenate([walk[:-1], rng.integers(0, n, 3 * n)])
    j = np.concatenate([walk[1:], rng.integers(0, n, 3 * n)])
    keep = i != j
    i, j = i[keep], j[keep]
    k = rng.uniform(0.1, 10.0, i.size) * 10.0 ** rng.uniform(-2, 2, i.size)
    A = sp.coo_matrix((k, (i, j)), shape=(n, n))
    A = (A + A.T).tocsr()
    K = sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A
    if grounded:
        g = np.zeros(n)
        g[rng.choice(n_int, size=max(1, n_int // 10), replace=False)] = rng.uniform(1, 5)
        K = K + sp.diags(g)
    F = rng.standard_normal((n, m))
    return sp.csr_matrix(K), F


@pytest.fixture(scope="module")
def block_model():
    """K' (interior first, 3 N contact dofs last) and the loads of a small P1 3-D block."""
    import slipcycle.fe.contact3d as c3
    from slipcycle.fe.solid3d import Block3D, block_on_rigid_3d

    captured = {}
    real = c3.schur_complement

    def capture(K, n, F, block=128):
        captured.update(K=K.copy(), ni=n, F=F.copy())
        return real(K, n, F, block=block)

    mp = pytest.MonkeyPatch()
    mp.setattr(c3, "schur_complement", capture)
    try:
        block_on_rigid_3d(Block3D(width_x=0.02, width_y=0.02, height=0.01, E=200e9,
                                  nu=0.3, contact_x=0.006, contact_y=0.006, elements=6,
                                  element="P1", radius=0.05))
    finally:
        mp.undo()
    return captured


def test_cholmod_and_superlu_give_the_same_schur_complement_of_a_3d_block(
        block_model, monkeypatch):
    K, ni, F = block_model["K"], block_model["ni"], block_model["F"]
    assert K.shape[0] - ni == 3 * 49 and F.shape[1] == 3
    S1, r1 = _cholmod(monkeypatch, K, ni, F)
    S2, r2 = _superlu(monkeypatch, K, ni, F)
    assert _rel(S1, S2) < 1e-10
    assert max(_rel(r1[:, k], r2[:, k]) for k in range(F.shape[1])) < 1e-10
    assert np.array_equal(S1, S1.T)
    assert np.linalg.eigvalsh(S1).min() > 0.0


def test_getfactor_fallback_gives_the_same_schur_complement_as_the_supernode_read(
        block_model, monkeypatch):
    """Should the supernodes not read as expected, the public cholmod.getfactor is used."""
    K, ni, F = block_model["K"], block_model["ni"], block_model["F"]
    tails = []
    real = cond._supernodal_tail

    def spy(*args):
        out = real(*args)
        tails.append(out)
        return out

    monkeypatch.setattr(cond, "_supernodal_tail", spy)
    S1, r1 = schur_complement(K, ni, F)
    assert len(tails) == 1 and tails[0] is not None, "the supernodes were not read in place"
    monkeypatch.setattr(cond, "_supernodal_tail", lambda *args: None)
    S2, r2 = _cholmod(monkeypatch, K, ni, F)
    assert _rel(S2, S1) < 1e-12 and _rel(r2, r1) < 1e-12


def test_cholmod_path_leaves_cvxopt_cholmod_options_as_they_were(block_model):
    from cvxopt import cholmod

    K, ni, F = block_model["K"], block_model["ni"], block_model["F"]
    before = dict(cholmod.options)
    cholmod.options["supernodal"] = 1
    try:
        schur_complement(K, ni, F)
        assert cholmod.options == {"supernodal": 1}
    finally:
        cholmod.options.clear()
        cholmod.options.update(before)


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**32 - 1), n_int=st.integers(1, 120), n_bnd=st.integers(1, 30),
       grounded=st.booleans(), m=st.integers(0, 3))
def test_cholmod_and_superlu_agree_on_random_sparse_spd_matrices(
        monkeypatch, seed, n_int, n_bnd, grounded, m):
    K, F = _random_model(seed, n_int, n_bnd, grounded, m)
    S1, r1 = _cholmod(monkeypatch, K, n_int, F)
    S2, r2 = _superlu(monkeypatch, K, n_int, F)
    assert S1.shape == (n_bnd, n_bnd) and r1.shape == (n_bnd, m)
    # relative to K_bb ⪰ S: with one interior node and no ground, S = 0 up to round-off
    scale = np.linalg.norm(K[n_int:, n_int:].toarray())
    assert np.linalg.norm(S1 - S2) <= 1e-10 * scale
    for k in range(m):
        assert np.linalg.norm(r1[:, k] - r2[:, k]) <= 1e-10 * max(
            np.linalg.norm(r2[:, k]), np.linalg.norm(F[:, k]))
    if not grounded:  # only the boundary holds the network: S is a Laplacian, S·1 = 0
        assert np.abs(S1.sum(axis=1)).max() <= 1e-10 * scale


def _chain(n_int: int, n_bnd: int) -> sp.csr_matrix:
    """Unit springs in a chain 0-1-…-(n−1), the boundary (last nodes) at one end."""
    n = n_int + n_bnd
    main = np.full(n, 2.0)
    main[[0, -1]] = 1.0
    return sp.diags([main, -np.ones(n - 1), -np.ones(n - 1)], [0, -1, 1], format="csr")


def _floating(kind: str) -> tuple[sp.csr_matrix, int]:
    """A model whose interior is singular, nearly singular or indefinite.

    A chain of 40 interior nodes held by 4 boundary nodes, with a negative stiffness in
    the chain (indefinite), or with a free pair of interior nodes joined by a unit spring
    (its rigid motion makes K_ii exactly singular), held to the ground by 1e-15 (nearly
    singular).
    """
    chain = _chain(40, 4).tolil()
    if kind == "indefinite":
        chain[10, 10] = -5.0
        return chain.tocsr(), 40
    pair = sp.lil_matrix(np.array([[1.0, -1.0], [-1.0, 1.0]]))
    if kind == "nearly singular":
        pair[0, 0] += 1e-15
    K = sp.block_diag([pair, chain], format="csr")   # interior: the pair, then 40 nodes
    return K, 42


def _message(exc: BaseException) -> str:
    return re.sub(r"[-+]?\d+\.\d+e[-+]\d+", "<number>", str(exc))


@pytest.mark.parametrize("kind", ["singular", "nearly singular", "indefinite"])
def test_singular_or_indefinite_interior_is_refused_the_same_way_on_both_paths(
        monkeypatch, kind):
    K, ni = _floating(kind)
    F = np.ones((K.shape[0], 1))
    with pytest.raises(SingularModelError) as via_superlu:
        _superlu(monkeypatch, K, ni, F)
    calls = []
    real = cond._schur_cholmod

    def spy(*args):
        calls.append("raised")
        out = real(*args)
        calls[-1] = "declined" if out is None else "returned"
        return out

    monkeypatch.setattr(cond, "_schur_cholmod", spy)
    with pytest.raises(SingularModelError) as via_cholmod:
        schur_complement(K, ni, F)
    # a tiny positive pivot is caught on the Cholesky pivots; a zero or negative one
    # stops CHOLMOD, and SuperLU then names the fault
    assert calls == ["raised" if kind == "nearly singular" else "declined"]
    assert "\n" not in str(via_cholmod.value)
    assert _message(via_cholmod.value) == _message(via_superlu.value)
    expected = {"singular": "some body or part of a body is not supported",
                "nearly singular": "(nearly) singular",
                "indefinite": "not positive definite (a negative pivot"}[kind]
    assert expected in str(via_cholmod.value)
