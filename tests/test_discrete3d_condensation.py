"""The separated nodes condensed out of the 3-D Newton system (``StepSolver``): the
coupling W = K_PP⁻¹ K_PS and the condensed block K̃ of a sequence of slipping sets on one
separated set (the entries of the nodes slipping in both copied from the last set)
against a direct solve; and load steps with slipping and separated nodes together (a
residual of the separated rows within the Newton tolerance left as it is) against the
same steps solved on the whole active block (no condensation), with the residual of
every row within the Newton tolerance.
"""

import numpy as np
from hypothesis import assume, given, settings
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



def _steps(solver, x0, r0, drw, count=4):
    x, r, out = x0, r0, []
    for k in range(count):
        step = solver.solve(x, r, drw * (1.0 + 0.3 * k))
        assert step is not None
        out.append(step)
        x, r = step.x, step.r
    return out


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2 ** 31), n=st.integers(4, 16))
def test_open_nodes_condensed_statically_give_the_steps_of_the_whole_system(seed, n):
    """The nodes that stay open condensed out (K* = K_CC − K_CO K_OO⁻¹ K_OC, the load
    Δr^w_C − K_CO K_OO⁻¹ Δr^w_O, Δx_O recovered): the same node states, the same
    steps within the Newton tolerance, reactions r0 + Δr^w + K Δx of the whole system
    within it, the open nodes' reactions unchanged (zero)."""
    rng = np.random.default_rng(seed)
    system = _system(rng, n)
    x0, r0, drw = _step_state(rng, n)
    tol = 1e-11
    whole = _steps(StepSolver(system, 1.0, rel_tol=tol), x0, r0, drw)
    # the nodes open at the start and at every step's end
    stays = (x0[2 * n:] > 0) & np.all([s.modes == SEPARATED for s in whole], axis=0)
    open_nodes = np.flatnonzero(stays)
    assume(open_nodes.size > 0)
    solver = StepSolver(system, 1.0, rel_tol=tol)
    solver.condense_min_nodes = 1
    solver.condense(open_nodes)
    condensed = _steps(solver, x0, r0, drw)
    assert solver.stats["condensed_steps"] == 4 and "open_fallbacks" not in solver.stats
    scale = np.max(np.abs(np.diag(system.K)))
    x, r = x0, r0
    for a, b in zip(whole, condensed, strict=True):
        assert np.array_equal(a.modes, b.modes)
        assert np.max(np.abs(a.x - b.x)) <= 100 * tol / scale * n
        r_expected = r + b.drw + system.K @ (b.x - x)
        assert np.max(np.abs(b.r - r_expected)) <= 10 * tol * n
        assert np.array_equal(b.r[2 * n:][open_nodes], r0[2 * n:][open_nodes])
        x, r = b.x, b.r


def test_a_condensed_node_that_closes_sends_the_step_to_the_whole_system():
    """A condensed node pressed shut by the step: the condensed step is refused (its
    p − ρ_n w > 0 at the end), the step is solved on the whole system (the same result
    as without condensation) and so is the rest of the path."""
    rng = np.random.default_rng(7)
    n = 12
    system = _system(rng, n)
    x0, r0, drw = _step_state(rng, n)
    open_nodes = np.flatnonzero(x0[2 * n:] > 0)
    j = open_nodes[0]
    drw[2 * n + j] = 10.0 * system.K[2 * n + j, 2 * n + j] * x0[2 * n + j]   # closes j
    whole = StepSolver(system, 1.0).solve(x0, r0, drw)
    solver = StepSolver(system, 1.0)
    solver.condense_min_nodes = 1
    solver.condense(open_nodes)
    step = solver.solve(x0, r0, drw)
    assert whole.modes[j] != SEPARATED
    assert solver.stats["open_fallbacks"] == 1 and solver._open is None
    assert np.array_equal(step.modes, whole.modes)
    assert np.max(np.abs(step.x - whole.x)) <= 1e-9 * np.max(np.abs(whole.x))


def test_a_lap_joint_run_with_its_open_nodes_condensed_gives_the_same_study(monkeypatch):
    """`slipcycle.run` of the shipped lap joint on its unrefined mesh (203 nodes, 70 of
    them open over every steady cycle; the condensation forced on below its size
    threshold): the cycles after the first run condensed, and every protocol's
    dissipation, cycle count and stuck area equal those of the run without it (within
    1e-9: the Newton tolerance)."""
    import slipcycle
    from slipcycle.discrete3d import evolution
    from slipcycle.examples import example_path

    overrides = {"lap_joint.refine": 0, "lap_joint.convergence.coarsening": [],
                 "lap_joint.protocols.names": ["sequential", "simultaneous"],
                 "output.fields": []}
    used = []
    solve = evolution._OpenCondensation.solve

    def counted(self, *args):
        used.append(self.nodes.size)
        return solve(self, *args)

    monkeypatch.setattr(evolution._OpenCondensation, "solve", counted)
    monkeypatch.setattr(evolution.StepSolver, "condense_min_nodes", 16)
    summaries = []
    for flag in (False, True):
        monkeypatch.setattr(evolution.Evolution3D, "condense_open", flag)
        summaries.append(slipcycle.run(example_path("bolted_lap_joint.toml"),
                                       overrides).summary())
    assert len(used) > 1000 and min(used) >= 16
    whole, condensed = summaries
    np.testing.assert_allclose(condensed["protocol_dissipation_per_cycle"],
                               whole["protocol_dissipation_per_cycle"], rtol=1e-9)
    assert condensed["protocol_cycles_run"] == whole["protocol_cycles_run"]
    np.testing.assert_allclose(condensed["protocol_stuck_area"],
                               whole["protocol_stuck_area"], rtol=1e-9)
