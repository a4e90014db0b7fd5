"""3-D shakedown with separation: λ2 with the contact sets of the elastic solution, its
polygonal-LP bracket, the engine's verdict on either side, and λ1 over starts."""

import numpy as np
import pytest

from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.separation import closed_rows, elastic_reactions
from slipcycle.discrete3d.shakedown import (
    is_safe_open,
    lambda1_bracket,
    lambda2_open,
    lambda2_polygonal,
    lambda2_socp,
    safe_start,
    shakedown_limit,
)
from slipcycle.discrete3d.steady import simulate3d


def small(n=5, seed=1, coupled=True, p_low=-0.3):
    """A random SPD system; normal preloads in [p_low, 1] × 10 N (negative: open)."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * n * np.eye(3 * n)
    if not coupled:
        K[:2 * n, 2 * n:] = 0.0
        K[2 * n:, :2 * n] = 0.0
    system = FrictionalSystem3D(K[:2 * n, :2 * n], K[2 * n:, :2 * n], K[2 * n:, 2 * n:],
                                0.3, accept_ill_posed=True)
    p0 = rng.uniform(p_low, 1.0, n) * 10
    p1 = 3 * rng.normal(size=(1, n))
    q0 = rng.normal(size=2 * n)
    load = Load3D.harmonic(p0, q0, p1, 2 * rng.normal(size=(1, 2 * n)))
    return system, load


def test_condensed_rows_reproduce_the_elastic_solution_with_open_nodes():
    system, load = small()
    rng = np.random.default_rng(3)
    is_open = np.array([True, False, True, False, False])
    r, v = 10 * rng.normal(size=15), 1e-2 * rng.normal(size=10)
    c, R_load, R_slip, W_load, W_slip = closed_rows(system, is_open)
    reac, x = elastic_reactions(system, r, v, is_open)
    n = 5
    want = np.concatenate([reac[:2 * n].reshape(n, 2)[c].reshape(-1), reac[2 * n:][c]])
    np.testing.assert_allclose(R_load @ r + R_slip @ v, want, atol=1e-10 * np.abs(want).max())
    np.testing.assert_allclose(W_load @ r + W_slip @ v, x[2 * n:][is_open], rtol=1e-10)
    # the open nodes carry no force
    assert np.abs(reac.reshape(-1)[[0, 1, 4, 5, 10, 12]]).max() < 1e-10 * np.abs(r).max()


def test_no_open_node_gives_the_all_closed_cone_program():
    system, load = small(p_low=0.8)
    res = lambda2_open(system, load, 24)
    assert not res.open_set.any() and res.consistent
    ref = lambda2_socp(system, load, 24)
    assert res.lambda2 == pytest.approx(ref.lambda2, rel=1e-6)


def test_all_closed_program_is_infeasible_where_nodes_open_but_separation_is_not():
    system, load = small(coupled=False)
    assert lambda2_socp(system, load, 24).lambda2 == 0.0
    res = lambda2_open(system, load, 24)
    assert res.feasible and res.consistent and res.lambda2 > 0.1
    assert res.open_set[:, 0].all()          # node 0 is open throughout
    assert is_safe_open(system, load.with_lam(res.lambda2 * (1 - 1e-6)), res.safe_slip, 24)


@pytest.mark.parametrize("coupled", [False, True])
def test_polygonal_lps_bracket_the_cone_program_and_close_as_k_squared(coupled):
    system, load = small(coupled=coupled)
    res = lambda2_open(system, load, 24)
    widths = []
    for k in (16, 64, 256):
        lo, hi = lambda2_polygonal(system, load, res.open_set, k, 24)
        assert lo <= res.lambda2 * (1 + 1e-7) and res.lambda2 <= hi * (1 + 1e-7)
        widths.append((hi - lo) / res.lambda2)
    assert widths[-1] < 1e-3
    if coupled:                              # cone-limited: the bracket shrinks ~ k⁻²
        assert widths[1] < widths[0] / 8 and widths[2] < widths[1] / 8


def test_safe_state_is_certified_and_stops_being_safe_above_lambda2():
    system, load = small()
    res = lambda2_open(system, load, 24)
    assert res.consistent
    assert is_safe_open(system, load.with_lam(res.lambda2 * (1 - 1e-6)), res.safe_slip, 24)
    assert not is_safe_open(system, load.with_lam(res.lambda2 * 1.05), res.safe_slip, 24)


def test_uncoupled_lambda2_converges_to_the_engines_shakedown_limit():
    """B = 0: Melan makes λ2 the limit for every start; the sampled program converges to
    it at second order in the sample spacing (the contact change of node 1 lies between
    samples), and the 3-D engine shakes down just below it and slips just above."""
    system, load = small(coupled=False)
    lam = [lambda2_open(system, load, s).lambda2 for s in (24, 96, 384)]
    assert abs(lam[1] - lam[2]) < abs(lam[0] - lam[2]) / 8
    below = simulate3d(system, load.with_lam(0.97 * lam[2]), steps_per_cycle=96, cycles=300)
    above = simulate3d(system, load.with_lam(1.05 * lam[2]), steps_per_cycle=96, cycles=300)
    assert below.steady_state == "shakedown"
    assert above.steady_state != "shakedown" and above.dissipation_per_cycle > 0


def test_coupled_safe_start_shakes_down_below_lambda2():
    system, load = small()
    res = lambda2_open(system, load, 96)
    ld = load.with_lam(0.97 * res.lambda2)
    run = simulate3d(system, ld, steps_per_cycle=96, cycles=300,
                     initial_slip=safe_start(system, ld, res, 96))
    assert run.steady_state == "shakedown"


def test_shakedown_limit_bisects_a_threshold():
    lo, hi = shakedown_limit(lambda lam: lam < 0.3141, 1.0, rtol=1e-3)
    assert lo < 0.3141 <= hi and hi - lo <= 1e-3


def test_uncoupled_lambda1_bracket_contains_lambda2():
    """Melan (B = 0): every start shakes down below λ2, so λ1 = λ2."""
    system, load = small(coupled=False)
    res = lambda2_open(system, load, 96)
    # two assembly paths: the mean load first, or a tangential push first
    push = load.with_lam(0.0)(np.zeros(1))
    push[:, :10] += 5.0
    br = lambda1_bracket(system, load, 1.1 * res.lambda2, rtol=0.02, steps_per_cycle=96,
                         protocols=[load.with_lam(0.0)(np.zeros(1)), push], cycles=300)
    assert br.limits.shape == (2, 2)
    assert br.lower <= res.lambda2 * 1.01 and br.upper >= res.lambda2 * 0.99


def test_cone_program_ties_each_contact_set_once_and_each_sample_row_is_sparse():
    """The program scales to FE joints: the slip response of a contact set is one dense
    block (its closed reactions and open gaps per slip), however many samples share the
    set; every sample's cone or gap row touches λ and one entry of that response. Three
    distinct sets over 24 samples: three blocks, and the optimum is the one the polygonal
    LPs bracket."""
    from slipcycle.discrete3d.shakedown import _open_rows

    system, load = small()
    res = lambda2_open(system, load, 24)
    theta, _ = load.cycle_samples(24)
    r0, r1 = load.split_lam(theta[:-1])
    rows = _open_rows(system, r0, r1, res.open_set)
    distinct = {s.tobytes() for s in res.open_set}
    assert len(distinct) == 3
    n = system.n_nodes
    # one tie row per live entry of each distinct set's response (3 per closed node,
    # 1 per open node, at most)
    assert rows.A_tie.shape[0] <= 3 * n * len(distinct)
    assert rows.n_vars == 2 * n + 1 + rows.A_tie.shape[0]
    assert rows.G_cone.getnnz(axis=1).max() <= 2 and rows.G_gap.getnnz(axis=1).max() <= 2
    closed = (~res.open_set).sum()
    assert rows.G_cone.shape[0] == 3 * closed and rows.G_gap.shape[0] == res.open_set.sum()
    lo, hi = lambda2_polygonal(system, load, res.open_set, 256, 24)
    assert lo <= res.lambda2 * (1 + 1e-7) and res.lambda2 <= hi * (1 + 1e-7)


def test_contact_set_that_cycles_is_refused_at_once(monkeypatch):
    """A node pressed by the load (free, it would penetrate) but stuck at a slip that
    pulls it off (p < 0 when closed) has no contact state: the active-set iteration
    meets a set twice and stops with an error after a few solves, instead of 4 N + 10."""
    import slipcycle.discrete3d.separation as separation
    from slipcycle.errors import SolverError

    k, b, c = 2.0, 1.0, 2.0
    K = np.array([[k, 0, b], [0, k, 0], [b, 0, c]])
    system = FrictionalSystem3D(K[:2, :2], K[2:, :2], K[2:, 2:], 0.3, accept_ill_posed=True)
    r = np.array([0.0, 0.0, 1.0])
    slip = np.array([-2.0 / b, 0.0])
    # both states are wrong: closed it pulls, open it penetrates
    assert (elastic_reactions(system, r, slip, np.array([False]))[0][2] < 0
            and elastic_reactions(system, r, slip, np.array([True]))[1][2] < 0)
    solves = []
    real = separation.elastic_reactions
    monkeypatch.setattr(separation, "elastic_reactions",
                        lambda *a: solves.append(1) or real(*a))
    with pytest.raises(SolverError, match="did not settle"):
        separation.elastic_open_set(system, r, slip)
    assert len(solves) <= 4
