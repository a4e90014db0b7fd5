"""The accelerated cycle loop of ``simulate3d`` (reduced rank extrapolation of the
start-of-cycle state once the slip pattern repeats, validated by the next cycle) against
plain cycling run to a much tighter tolerance: the same steady-state class, the same
dissipation per cycle and per node within the cycling tolerance, the same slipping,
stuck and separating nodes (the same member of the set of steady states), on random
coupled systems and on an FE-like chain whose plain cycling creeps slowly."""

import numpy as np
import pytest

from slipcycle.discrete3d import steady as steady3d
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.steady import _anderson, simulate3d

TOL = 1e-7          # cycling tolerance of the accelerated runs
REF_TOL = 1e-11     # plain cycling, the reference


def _random_coupled(seed, n):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T / (3 * n) + np.eye(3 * n)
    t = np.arange(2 * n)
    system = FrictionalSystem3D(K[np.ix_(t, t)], 0.3 * K[2 * n:, :2 * n], K[2 * n:, 2 * n:],
                                rng.uniform(0.25, 0.4, n), accept_ill_posed=True)
    # steady pressure, mean shear, and rotating shear large at some nodes only: those slip,
    # the rest stick with a memory of the history
    amp = 0.05 + 0.5 * (rng.uniform(size=n) < 0.4)
    q1 = np.column_stack([amp, 0.7 * amp]).ravel()
    ph = np.column_stack([np.zeros(n), np.full(n, -np.pi / 2)]).ravel()
    load = Load3D.harmonic(np.full(n, 2.0), 0.1 * rng.normal(size=2 * n),
                           0.3 * rng.uniform(size=n), q1, np.zeros(n), ph)
    return system, load


def _fe_like(n):
    """The benchmark's FE-like chain (benchmarks/bench_discrete3d.py): edges slip, the
    interior sticks, and plain cycling approaches the periodic state slowly."""
    i = np.arange(n)
    d = np.abs(i[:, None] - i[None, :])
    A1 = 2.0 * np.exp(-d / 2.0) * np.cos(0.7 * d) + np.eye(n)
    A = np.kron(A1, np.array([[1.0, 0.1], [0.1, 1.0]]))
    B = np.zeros((n, 2 * n))
    B[:, 0::2] = 0.3 * np.sign(i[:, None] - i[None, :]) * np.exp(-d / 3.0)
    x = np.linspace(-1.0, 1.0, n)
    system = FrictionalSystem3D(A, B, 1.3 * A1, 0.3)
    amp = 0.1 + 0.4 * np.abs(x) ** 8
    q1 = np.column_stack([amp, 0.6 * amp]).ravel()
    ph = np.column_stack([np.zeros(n), np.full(n, -np.pi / 2)]).ravel()
    load = Load3D.harmonic(np.ones(n), np.column_stack([0.05 * x, np.zeros(n)]).ravel(),
                           0.2 * np.ones(n), q1, np.zeros(n), ph)
    return system, load


def _assert_same_steady_state(acc, ref, tol=TOL):
    assert ref.steady_converged
    assert acc.steady_state == ref.steady_state
    assert acc.slipping_nodes == ref.slipping_nodes
    assert acc.permanently_stuck_nodes == ref.permanently_stuck_nodes
    assert acc.separating_nodes == ref.separating_nodes
    # the accepted state is within tol of a fixed point; the distance to it is then at
    # most tol / (1 − ρ) (ρ the contraction of the cycle map): a margin of 100
    e_scale = ref.force_scale * ref.disp_scale
    assert abs(acc.dissipation_per_cycle - ref.dissipation_per_cycle) <= 100 * tol * e_scale
    assert np.max(np.abs(acc.dissipation_per_node - ref.dissipation_per_node)) \
        <= 100 * tol * e_scale
    assert np.max(np.abs(acc.cycle_start_states[-1] - ref.cycle_start_states[-1])) \
        <= 100 * tol * max(ref.disp_scale, np.max(np.abs(ref.cycle_start_states[-1])))


def _pair(system, load, cycles_ref, steps=40, step_tol=1e-6, tol=TOL, ref_tol=REF_TOL):
    kw = dict(steps_per_cycle=steps, step_tol=step_tol, record=False)
    acc = simulate3d(system, load, cycles=cycles_ref, tol=tol, accelerate=True, **kw)
    ref = simulate3d(system, load, cycles=cycles_ref, tol=ref_tol, accelerate=False, **kw)
    return acc, ref


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_accelerated_random_coupled_systems_reach_plain_cyclings_steady_state(seed):
    system, load = _random_coupled(seed, 8)
    acc, ref = _pair(system, load, 200)
    _assert_same_steady_state(acc, ref)
    assert acc.cycles_run <= ref.cycles_run


def test_accelerated_fe_like_chain_jumps_and_matches_plain_cycling():
    # the cycling tolerance stays above the step control's (its refinement decisions
    # make the discretised cycle map only piecewise smooth at that level)
    system, load = _fe_like(50)
    acc, ref = _pair(system, load, 150, steps=40, step_tol=1e-6, tol=1e-6, ref_tol=1e-9)
    _assert_same_steady_state(acc, ref, tol=1e-6)
    assert acc.steady_state == "cyclic_slip"
    assert acc.permanently_stuck_nodes          # a memory the jump had to keep
    assert acc.jumps >= 1 and acc.jumps_undone == 0
    # far fewer cycles than plain cycling needs for the same tolerance
    plain = simulate3d(system, load, cycles=150, tol=1e-6, accelerate=False,
                       steps_per_cycle=40, step_tol=1e-6, record=False)
    assert plain.steady_state == "cyclic_slip"
    assert acc.cycles_run < plain.cycles_run


def test_accelerate_false_is_plain_cycling():
    """Without acceleration no state is replaced: the run equals one whose cycles are
    chained by hand, each starting where the previous ended."""
    system, load = _fe_like(20)
    kw = dict(steps_per_cycle=20, step_tol=1e-5, record=False)
    res = simulate3d(system, load, cycles=3, tol=1e-14, accelerate=False, **kw)
    assert res.jumps == 0 and res.cycles_run == 3
    one = simulate3d(system, load, cycles=1, tol=1e-14, **kw)
    np.testing.assert_array_equal(res.cycle_start_states[:2], one.cycle_start_states)


def test_rre_is_exact_for_a_linear_contraction_and_keeps_unmoved_components():
    """For x_{i+1} = T x_i + b with the error in k eigen-directions, k + 1 differences
    give the fixed point exactly; components that never move are left as they are."""
    rng = np.random.default_rng(3)
    m, k = 12, 3
    Q, _ = np.linalg.qr(rng.normal(size=(m - 2, m - 2)))
    lam = np.array([0.97, 0.9, -0.5] + [0.0] * (m - 5))
    T = Q @ np.diag(lam) @ Q.T
    b = rng.normal(size=m - 2)
    x_fix = np.linalg.solve(np.eye(m - 2) - T, b)
    e0 = Q[:, :3] @ rng.normal(size=3)
    xs = [x_fix + e0]
    for _ in range(k + 1):
        xs.append(T @ xs[-1] + b)
    frozen = np.array([0.123, -4.5])                # a stuck node's slip: never moves
    states = np.array([np.concatenate([frozen, x]) for x in xs])
    x_star = _anderson(states[:-1], states[1:])   # a plain sequence: reduced rank
    assert np.array_equal(x_star[:2], frozen)
    np.testing.assert_allclose(x_star[2:], x_fix, atol=1e-9 * np.max(np.abs(x_fix)))


def test_anderson_mixing_of_jumped_starts_is_exact_for_a_linear_map():
    """Anderson mixing uses pairs (x_i, P(x_i)) whose starts need not follow one another
    (the starts of jumped cycles): for an affine P whose error lies in k directions,
    k + 1 pairs from arbitrary starts in that subspace give the fixed point exactly
    (GMRES on the linear map); a component no pair moves is left as it is."""
    rng = np.random.default_rng(7)
    m, k = 10, 4
    lam = np.array([0.995, 0.98, 0.9, -0.6])             # slow creep modes and a fast one
    V = np.linalg.qr(rng.normal(size=(m, m)))[0][:, :k]
    T = V @ np.diag(lam) @ V.T                           # acts on span(V) only
    x_fix = rng.normal(size=m)

    def P(x):
        return x_fix + T @ (x - x_fix)

    starts = [x_fix + V @ rng.normal(size=k) for _ in range(k + 1)]  # jumped, unrelated
    frozen = np.array([7.0])
    X = np.array([np.concatenate([frozen, x]) for x in starts])
    F = np.array([np.concatenate([frozen, P(x)]) for x in starts])
    x_star = _anderson(X, F)
    assert x_star[0] == frozen[0]
    np.testing.assert_allclose(x_star[1:], x_fix, atol=1e-9 * np.max(np.abs(x_fix)))
    # with one pair too few the mixing is not exact: the test can fail
    x_short = _anderson(X[1:], F[1:])
    assert np.max(np.abs(x_short[1:] - x_fix)) > 1e-6


def test_mixing_on_a_200_node_chain_keeps_the_member_plain_cycling_reaches():
    """The benchmark's FE-like chain at 200 nodes (18 slip, 182 keep their memory): the
    accelerated run (22 cycles) and plain cycling (90 cycles), both to 1e-9, end with the
    same slipping and stuck nodes, the same dissipation (measured 1e-9 relative) and start
    states within 1e-6 of the largest slip (measured; plain cycling's own remaining
    distance to its limit is of that order, its last contraction being slow)."""
    system, load = _fe_like(200)
    kw = dict(steps_per_cycle=100, step_tol=1e-4, tol=1e-9, record=False, cycles=400)
    acc = simulate3d(system, load, accelerate=True, **kw)
    ref = simulate3d(system, load, accelerate=False, **kw)
    assert acc.steady_state == ref.steady_state == "cyclic_slip"
    assert acc.jumps >= 1 and acc.cycles_run < ref.cycles_run / 2
    assert acc.slipping_nodes == ref.slipping_nodes
    assert acc.permanently_stuck_nodes == ref.permanently_stuck_nodes
    assert acc.dissipation_per_cycle == pytest.approx(ref.dissipation_per_cycle, rel=1e-7)
    x_ref = ref.cycle_start_states[-1]
    assert np.max(np.abs(acc.cycle_start_states[-1] - x_ref)) <= 1e-5 * np.max(np.abs(x_ref))


def test_plain_cycling_of_the_chain_stops_within_the_rest_of_its_creep(monkeypatch):
    """50-node chain, plain cycling at tolerance 1e-7 against plain cycling to 1e-11: the
    increments shrink by 0.63 per cycle, so the rest of the creep is 1.7 times the last
    increment. With that distance in the steady-state test the run stops after 28 cycles
    with its start state 2.6e-7 of the largest slip from the limit and D 2.8e-9 off; with
    the last increment alone after 27 cycles, 4.1e-7 and 4.4e-9 off (26 cycles, 6.4e-7
    and 7.0e-9 with the residual measured against the whole load)."""
    system, load = _fe_like(50)
    kw = dict(steps_per_cycle=40, step_tol=1e-6, record=False, accelerate=False,
              cycles=600)
    ref = simulate3d(system, load, tol=1e-11, **kw)
    x_ref = ref.cycle_start_states[-1]

    def errors(run):
        return (np.abs(run.cycle_start_states[-1] - x_ref).max() / np.abs(x_ref).max(),
                abs(run.dissipation_per_cycle / ref.dissipation_per_cycle - 1))

    run = simulate3d(system, load, tol=1e-7, **kw)
    monkeypatch.setattr(steady3d, "creep_distance", lambda starts, residual, xscale: residual)
    alone = simulate3d(system, load, tol=1e-7, **kw)
    assert (run.cycles_run, alone.cycles_run) == (28, 27)
    x_err, d_err = errors(run)
    x_alone, d_alone = errors(alone)
    assert x_err == pytest.approx(2.6e-7, rel=0.05) and d_err == pytest.approx(2.8e-9, rel=0.05)
    assert x_alone == pytest.approx(4.1e-7, rel=0.05)
    assert d_alone == pytest.approx(4.4e-9, rel=0.05)
