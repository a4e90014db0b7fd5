"""The separated nodes condensed out of the 3-D Newton system (``StepSolver``): the
coupling W = K_PP⁻¹ K_PS and the condensed block K̃ of a sequence of slipping sets on one
separated set (the entries of the nodes slipping in both copied from the last set)
against a direct solve; and load steps with slipping and separated nodes together (a
residual of the separated rows within the Newton tolerance left as it is) against the
same steps solved on the whole active block (no condensation), with the residual of
every row within the Newton tolerance.
"""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.linalg import cho_solve

from slipcycle.discrete3d.evolution import Evolution3D, StepSolver, _OpenCondensation
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


def _closing_step(n=12):
    """A step that presses the first open node j shut, its solution on the whole system,
    and a solver that condenses any number of open nodes."""
    rng = np.random.default_rng(7)
    system = _system(rng, n)
    x0, r0, drw = _step_state(rng, n)
    open_nodes = np.flatnonzero(x0[2 * n:] > 0)
    j = open_nodes[0]
    drw[2 * n + j] = 10.0 * system.K[2 * n + j, 2 * n + j] * x0[2 * n + j]
    whole = StepSolver(system, 1.0).solve(x0, r0, drw)
    solver = StepSolver(system, 1.0)
    solver.condense_min_nodes = 1
    return solver, (x0, r0, drw), open_nodes, j, whole


def test_a_condensed_node_that_closes_is_kept_in_the_step_and_after_it():
    """A condensed node pressed shut by the step: the condensed step is refused (its
    p − ρ_n w > 0 at the end), the step is solved again with that node kept (the other
    open nodes condensed: the same result as without condensation), and the following
    steps keep it too."""
    solver, (x0, r0, drw), open_nodes, j, whole = _closing_step()
    solver.condense(open_nodes)
    step = solver.solve(x0, r0, drw)
    assert whole.modes[j] != SEPARATED
    assert solver.stats["open_fallbacks"] == 1
    assert set(solver._open.nodes) == set(open_nodes) - {j}
    assert solver.stats["condensed_steps"] == 1
    assert np.array_equal(step.modes, whole.modes)
    assert np.max(np.abs(step.x - whole.x)) <= 1e-9 * np.max(np.abs(whole.x))


def test_a_lap_joint_run_with_its_open_nodes_condensed_gives_the_same_study(monkeypatch):
    """`slipcycle.run` of the shipped lap joint on its unrefined mesh (203 nodes, 70 of
    them open over every steady cycle; the condensation forced on below its size
    threshold): the assembly and the first cycle condensed per load interval, the later
    cycles over the whole cycle, and every protocol's cycle count and stuck area equal
    those of the run without it, its dissipation within the step control's tolerance
    (1e-4). The condensed steps equal the whole system's within the Newton tolerance
    (the tests above), which moves the instants at which the event location stops (it
    locates an event only as closely as the step control needs): 3.2e-6 relative in D
    of the sequential protocol, measured."""
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
                               whole["protocol_dissipation_per_cycle"], rtol=1e-4)
    assert condensed["protocol_cycles_run"] == whole["protocol_cycles_run"]
    np.testing.assert_allclose(condensed["protocol_stuck_area"],
                               whole["protocol_stuck_area"], rtol=1e-9)


def _follow(system, x0, r_w0, vals, condense, span=True, monkeypatch=None):
    """The states at the samples and every committed step of a path of fixed steps
    (one per load interval, no event location), with or without the open nodes
    condensed per load interval."""
    evo = Evolution3D(system, x0, r_w0, 1.0, adaptive=False)
    evo.locate_events = False
    evo.condense_open = condense
    evo.solver.condense_min_nodes = 1
    evo.solver.force_tol = 1e-11
    if not span:
        monkeypatch.setattr(_OpenCondensation, "max_span", 0)
    evo.step_log = []
    samples = evo.follow(np.zeros(len(vals)), vals, record=True).samples
    return samples, evo.step_log, dict(evo.solver.stats)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2 ** 31), n=st.integers(4, 14), span=st.booleans())
def test_a_path_condensed_per_load_interval_equals_the_whole_systems(seed, n, span):
    """A path along which open nodes close and others open (a tangential load with a
    normal load of changing sign), followed with the nodes open at each interval's
    start and at the end of its whole step condensed out (a node that closes in a step
    kept in it and after it), gives every step of the path on the whole system: the same
    node states, the states within the Newton tolerance. ``span``: the open nodes' load
    maps taken on the basis of the interval's load increment or computed per step."""
    rng = np.random.default_rng(seed)
    system = _system(rng, n)
    x0, r0, drw = _step_state(rng, n)
    r_w0 = r0 - system.K @ x0
    normal = np.zeros(3 * n)
    normal[2 * n:] = rng.normal(size=n)
    t = np.linspace(0.0, 1.0, 9)
    vals = r_w0 + np.outer(t, drw) + np.outer(np.sin(2 * np.pi * t), 0.5 * normal)
    with pytest.MonkeyPatch.context() as mp:
        whole = _follow(system, x0, r_w0, vals, False)
        cond = _follow(system, x0, r_w0, vals, True, span, mp)
    assume(cond[2].get("condensed_steps", 0) > 0)
    scale = np.max(np.abs(np.diag(system.K)))
    assert len(whole[1]) == len(cond[1])
    for a, b in zip(whole[1], cond[1], strict=True):
        assert np.array_equal(a[2], b[2])
        assert np.max(np.abs(a[0] - b[0])) <= 1e3 * 1e-11 / scale * n
    np.testing.assert_array_equal(whole[0]["modes"], cond[0]["modes"])


def test_the_load_maps_of_a_path_span_its_increments_only():
    """The open nodes' load maps kept for a path (:meth:`_OpenCondensation.span`): a
    cycle's increments (multiples of one load vector plus round-off) are mapped through
    the basis, equal to the direct maps K_OO⁻¹ Δr^w_O, Tᵀ Δr^w_O within round-off; an
    increment outside the span is mapped directly (exactly)."""
    rng = np.random.default_rng(3)
    n = 10
    system = _system(rng, n)
    x0, r0, drw = _step_state(rng, n)
    solver = StepSolver(system, 1.0)
    solver.condense_min_nodes = 1
    base = rng.normal(size=3 * n)
    vals = base + np.outer(np.sin(np.linspace(0, 2 * np.pi, 21)), drw)
    solver.condense(np.flatnonzero(x0[2 * n:] > 0), vals)
    cond = solver._open
    assert cond._span[0].shape[0] == 1                   # one direction
    o = cond.o
    for a, b in [(3, 4), (7, 12), (0, 5)]:
        d = (vals[b] - vals[a])[o]
        g, h = cond._maps(d)
        g_direct = cho_solve(cond.cho, d)
        np.testing.assert_allclose(g, g_direct, atol=1e-12 * np.max(np.abs(g_direct)))
        np.testing.assert_allclose(h, cond.Tt @ d, atol=1e-12 * np.max(np.abs(h)))
    other = rng.normal(size=o.size)
    g, h = cond._maps(other)
    np.testing.assert_array_equal(g, cho_solve(cond.cho, other, check_finite=False))


def test_without_a_recondensation_left_a_closing_node_sends_the_path_to_the_whole_system():
    """``recondense_max`` spent: the step that closes a condensed node and the following
    ones are solved on the whole system (the same result as without condensation)."""
    solver, (x0, r0, drw), open_nodes, j, whole = _closing_step()
    solver.recondense_max = 0
    solver.condense(open_nodes)
    step = solver.solve(x0, r0, drw)
    assert solver.stats["open_fallbacks"] == 1 and not solver.condensing
    assert "condensed_steps" not in solver.stats
    assert np.array_equal(step.modes, whole.modes)
    assert np.max(np.abs(step.x - whole.x)) <= 1e-9 * np.max(np.abs(whole.x))
