"""The steady-state residual and the 3-D step control follow the service cycle, not the
whole load (issue 32: a preload 1e7 times the service load hid the transient).

Two uncoupled nodes (B = 0, A = k I, C = k_n I): node 0 under a normal preload P and a
tangential load q_a cos θ (and a constant shear Q), node 1 clamped by a preload P_1 from
1 N to 1e10 N and loaded by nothing else. Node 0 is a Jenkins element: it slips whenever
|q| would exceed f P, so its steady cycle slips 4 (q_a − f P)/k and dissipates

    D = 4 f P (q_a − f P) / k        per cycle (q_a > f P),

the independent reference of every test here (Q only shifts the slip). The first cycle
after the assembly can be a transient (D = 3/4 of that, when the assembly left node 0
inside its cone): measured against the clamp's displacement P_1/k (30 m for 3e9 N), its
change passed as steady after one cycle, and the 3-D step control, scaled alike, never
refined the 16 samples of a cycle (D 0.92 % off at every step tolerance).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.cli.main import main
from slipcycle.coupled.cycles import ROUNDOFF, STEP_ROUNDOFF, ResidualScale
from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.discrete.fastcycle import steady_state_fast
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.steady import simulate3d

K, KN, F_COEF = 1e8, 2e8, 0.3
EPS = np.finfo(float).eps


def _closed_form(P: float, qa: float) -> float:
    """D per steady cycle of node 0 [J]."""
    return 4 * F_COEF * P * max(qa - F_COEF * P, 0.0) / K


def _service_disp(qa: float) -> float:
    """u_s: the load varies by 2 q_a over the cycle, over max diag K = k_n [m] (the runs'
    scale is that, or the whole load's where smaller: this bounds it)."""
    return 2 * qa / KN


def _system2():
    return FrictionalSystem(K * np.eye(2), np.zeros((2, 2)), KN * np.eye(2), F_COEF)


def _system3():
    return FrictionalSystem3D(K * np.eye(4), np.zeros((2, 4)), KN * np.eye(2), F_COEF)


def _load2(P, clamp, qa, Q=0.0):
    return DiscreteLoad.harmonic([P, clamp], [Q, 0.0], [0.0, 0.0], [qa, 0.0], [0.0, 0.0],
                                 [0.0, 0.0])


def _load3(P, clamp, qa, Q=0.0):
    return Load3D.harmonic([P, clamp], [Q, 0.0, 0.0, 0.0], None, [qa, 0.0, 0.0, 0.0])


preloads = st.one_of(st.just(1.0), st.just(1e4), st.floats(1.0, 1e4))
clamps = st.one_of(st.just(1.0), st.just(1e10), st.floats(1.0, 1e10))
excess = st.one_of(st.just(0.01), st.just(3.0), st.floats(0.01, 3.0))


@settings(max_examples=40, deadline=None)
@given(P=preloads, clamp=clamps, eps=excess, tol=st.sampled_from([1e-6, 1e-8, 1e-11]))
def test_2d_steady_dissipation_is_the_closed_form_whatever_the_clamp(P, clamp, eps, tol):
    """Assembled from the unloaded state, plain cycling stops at a cycle whose D is the
    closed form to what its residual claims: the start within tol × u_s of the steady
    one moves node 0's slip, hence D, by at most 4 f P tol u_s."""
    qa = F_COEF * P * (1 + eps)
    res = simulate(_system2(), _load2(P, clamp, qa), cycles=20, steps_per_cycle=16, tol=tol)
    D = _closed_form(P, qa)
    assert res.steady_state == "cyclic_slip" and res.residual <= tol
    assert abs(res.dissipation_per_cycle - D) <= 4 * F_COEF * P * tol * _service_disp(qa) \
        + 1e-12 * D
    assert res.slipping_nodes == [0]


@settings(max_examples=25, deadline=None)
@given(P=preloads, clamp=clamps, eps=excess)
def test_compiled_kernel_does_not_stop_on_the_transient_whatever_the_clamp(P, clamp, eps):
    """The compiled 2-D kernel from node 0 at rest in the middle of its cone (q = 0 at
    θ = 0): the first cycle is a transient (it slips only from q = f P on), then the
    closed form; measured against the clamp it stopped after the transient."""
    qa = F_COEF * P * (1 + eps)
    tol = 1e-8
    fast = steady_state_fast(_system2(), _load2(P, clamp, qa), np.array([-qa / K, 0.0]),
                             cycles=20, steps_per_cycle=16, tol=tol)
    D = _closed_form(P, qa)
    assert fast["steady_state"] == "cyclic_slip" and fast["cycles_run"] >= 2
    assert abs(fast["dissipation_per_cycle"] - D) <= 4 * F_COEF * P * tol * \
        _service_disp(qa) + 1e-12 * D


@settings(max_examples=15, deadline=None)
@given(P=preloads, clamp=clamps, eps=excess)
def test_3d_dissipation_converges_with_the_step_tolerance_whatever_the_clamp(P, clamp, eps):
    """The 3-D step control measures its errors against u_s and k_n u_s² (max diag K =
    k_n): each step's energy error estimate is within step_tol k_n u_s², so D is within
    (steps in the cycle) × step_tol × k_n u_s² of the closed form, and the error shrinks
    with step_tol (measured: 7.9e-5 of D at step_tol 1e-6 and 8.7e-8 at 1e-8 for
    q_a = 1.01 f P, at every clamp; scaled to a 1e10 N clamp, the same 9.2e-3 at every
    step_tol)."""
    qa = F_COEF * P * (1 + eps)
    D, energy = _closed_form(P, qa), KN * _service_disp(qa) ** 2
    errors = []
    for step_tol in (1e-6, 1e-8):
        res = simulate3d(_system3(), _load3(P, clamp, qa), cycles=20, steps_per_cycle=16,
                         tol=1e-8, step_tol=step_tol)
        assert res.steady_state == "cyclic_slip"
        err = abs(res.dissipation_per_cycle - D)
        assert err <= res.steps_per_cycle_taken[-1] * step_tol * energy
        errors.append(err)
    assert errors[1] <= errors[0] or errors[1] <= 1e-12 * D


@pytest.mark.parametrize("eps", [0.1, 1.0, 3.0])
@pytest.mark.parametrize("clamp", [1.0, 3e9, 1e10])
def test_3d_dissipation_within_1e_5_at_step_tol_1e_6(eps, clamp):
    """P = 1 kN, q_a = f P (1 + eps): D within 1e-5 of the closed form at step_tol 1e-6
    and 1e-7 at 1e-8 (measured at most 2.1e-6 and 2.8e-8), whatever the clamp. (Closer
    to the threshold, q_a = 1.01 f P, D is a fiftieth of k_n u_s² and its error at 1e-6
    is 7.9e-5 of it: the step control bounds energy errors against k_n u_s².)"""
    P = 1e3
    qa = F_COEF * P * (1 + eps)
    D = _closed_form(P, qa)
    for step_tol, rel in ((1e-6, 1e-5), (1e-8, 1e-7)):
        res = simulate3d(_system3(), _load3(P, clamp, qa), cycles=20, steps_per_cycle=16,
                         tol=1e-8, step_tol=step_tol)
        assert res.dissipation_per_cycle == pytest.approx(D, rel=rel, abs=0)


def test_the_residual_scale_is_the_service_displacement_not_the_clamp():
    """u_s = 2 q_a / k_n for the clamped pair: the clamp (constant) drops out, and the
    transient first cycle (node 0 moves by 3e-8 m, 1e-2 u_s) is not steady."""
    qa = 303.0
    theta, vals = _load2(1e3, 3e9, qa).cycle_samples(16)
    scale = ResidualScale.of(_system2(), vals, 3e9 / K)
    assert scale.service == pytest.approx(_service_disp(qa), rel=1e-12)
    res = simulate(_system2(), _load2(1e3, 3e9, qa), cycles=20, steps_per_cycle=16)
    assert res.cycles_run == 2
    assert res.dissipation_history[0] == pytest.approx(0.75 * _closed_form(1e3, qa))
    assert res.dissipation_per_cycle == pytest.approx(_closed_form(1e3, qa), rel=1e-12)


def test_a_component_that_does_not_change_sets_no_round_off_floor():
    """The floor is the round-off of the components that changed: node 1's slip of 1e6 m
    that stays put sets none; the same slip changed by one ulp sets 1e3 ε × 1e6 m."""
    theta, vals = _load2(1e3, 3e9, 303.0).cycle_samples(16)
    scale = ResidualScale.of(_system2(), vals, 3e9 / K)
    xa = np.array([-3e-8, 1e6, 0.0, 0.0])
    xb = xa.copy()
    xb[0] = -3.1e-8
    small = scale.roundoff(xa, xb)
    assert 0.0 < small < 1e-15
    assert scale.scale(xa, xb, 1e-8) == scale.service
    xb[1] = np.nextafter(1e6, 2e6)
    assert scale.roundoff(xa, xb) >= ROUNDOFF * EPS * 1e6
    assert scale.roundoff(xa, xa) == 0.0


@pytest.mark.parametrize("Q", [1e9, 1e11])
def test_a_state_1e8_times_the_service_displacement_still_converges(Q):
    """A constant shear Q slides node 0 by Q/k during the assembly (10 m and 1000 m,
    up to 1e8 u_s): the round-off of the state, not the service scale, then limits what
    a cycle can resolve; the runs converge all the same, D the closed form (2-D to
    round-off, 3-D within its step control), and the 3-D step scale keeps step_tol ×
    scale above 4 ε |x|."""
    P, qa, tol = 1e3, 606.0, 1e-11
    D = _closed_form(P, qa)
    r2 = simulate(_system2(), _load2(P, 3e9, qa, Q), cycles=30, steps_per_cycle=16, tol=tol)
    assert r2.steady_state == "cyclic_slip" and r2.cycles_run < 30
    assert r2.dissipation_per_cycle == pytest.approx(D, rel=1e-9)
    x_start = -Q / K
    assert r2.cycle_start_states[-1][0] == pytest.approx(x_start, rel=1e-6)
    r3 = simulate3d(_system3(), _load3(P, 3e9, qa, Q), cycles=30, steps_per_cycle=16,
                    tol=tol, step_tol=1e-8)
    assert r3.steady_state == "cyclic_slip" and r3.cycles_run < 30
    assert r3.dissipation_per_cycle == pytest.approx(D, rel=1e-5)
    theta, vals = _load3(P, 3e9, qa, Q).cycle_samples(16)
    scale = ResidualScale.of(_system3(), vals, 3e9 / K)
    step_scale = scale.step_scale(r3.cycle_start_states[0], 1e-8)
    assert 1e-8 * step_scale >= STEP_ROUNDOFF * EPS * abs(x_start) * (1 - 1e-6)
    assert step_scale >= scale.service


@pytest.mark.parametrize("model", ["discrete", "discrete3d"])
def test_a_constant_load_is_steady_after_one_cycle(model):
    """u_s = 0: the residual keeps the whole load's scale and the cycle, in which
    nothing moves, is steady at once: shakedown, D = 0."""
    if model == "discrete":
        res = simulate(_system2(), _load2(1e3, 3e9, 0.0, Q=200.0), cycles=5,
                       steps_per_cycle=16, tol=1e-10)
    else:
        res = simulate3d(_system3(), _load3(1e3, 3e9, 0.0, Q=200.0), cycles=5,
                         steps_per_cycle=16, tol=1e-10, step_tol=1e-6)
    assert res.steady_state == "shakedown" and res.cycles_run == 1
    assert res.residual == 0.0 and res.dissipation_per_cycle == 0.0


def _toml(model: str, clamp: float, qa: float, lam_line: str = "") -> str:
    P = 1e3
    if model == "discrete":
        body = (f'model = "discrete"\n[discrete]\nA = [[{K}, 0.0], [0.0, {K}]]\n'
                f'B = [[0.0, 0.0], [0.0, 0.0]]\nC = [[{KN}, 0.0], [0.0, {KN}]]\n'
                f'friction = {F_COEF}\n[loading]\np0 = [{P}, {clamp}]\nq0 = [0.0, 0.0]\n'
                f'p1 = [0.0, 0.0]\nq1 = [{qa!r}, 0.0]\n{lam_line}')
        run = "[run]\ncycles = 20\nsteps_per_cycle = 16\nsteady_tol = 1e-8\n"
    else:
        body = (f'model = "discrete3d"\n[discrete3d]\nA = {np.diag([K] * 4).tolist()}\n'
                f'B = {np.zeros((2, 4)).tolist()}\nC = [[{KN}, 0.0], [0.0, {KN}]]\n'
                f'friction = {F_COEF}\n[loading]\np0 = [{P}, {clamp}]\n'
                f'q0 = [[0.0, 0.0], [0.0, 0.0]]\np1 = [0.0, 0.0]\n'
                f'q1 = [[{qa!r}, 0.0], [0.0, 0.0]]\n{lam_line}')
        run = ("[run]\ncycles = 20\nsteps_per_cycle = 16\nsteady_tol = 1e-8\n"
               "step_tolerance = 1e-8\n[output]\nfields = []\n")
    return body + run


@pytest.mark.parametrize("model", ["discrete", "discrete3d"])
def test_the_command_line_gives_the_closed_form_under_a_3e9_N_clamp(model, tmp_path):
    """``slipcycle run`` of the clamped pair (q_a = 1.01 f P): summary.json's D is the
    closed form (2-D exact, 3-D within 1e-6 at step_tolerance 1e-8); the 2-D run needs
    its second cycle (the first is the transient it used to stop at)."""
    qa = 303.0
    case = tmp_path / "clamped.toml"
    case.write_text(_toml(model, 3e9, qa), encoding="utf-8")
    out = tmp_path / "out"
    assert main(["run", str(case), "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert s["steady_state"] == "cyclic_slip"
    rel = 1e-12 if model == "discrete" else 1e-6
    assert s["dissipation_per_cycle"] == pytest.approx(_closed_form(1e3, qa), rel=rel)
    if model == "discrete":
        assert s["cycles_run"] == 2


def test_a_sweep_of_the_service_amplitude_gives_the_closed_form_in_every_cell(tmp_path):
    """``slipcycle sweep`` over λ (q_a = λ × 303 N) of the clamped 2-D pair: every cell
    is the closed form, 4 f P (λ q_a − f P)/k (0 below the threshold)."""
    case = tmp_path / "clamped.toml"
    case.write_text(_toml("discrete", 3e9, 303.0, "lam = 1.0\n"), encoding="utf-8")
    out = tmp_path / "sweep"
    lams = [0.5, 1.0, 2.0]
    assert main(["sweep", str(case), "--set", "loading.lam=" + ",".join(map(str, lams)),
                 "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    with xr.open_dataset(out / "result.nc") as ds:
        got = np.asarray(ds["dissipation_per_cycle"].values, float).ravel()
    want = [_closed_form(1e3, lam * 303.0) for lam in lams]
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-20)


def test_the_step_control_errors_quoted_in_docs_discrete3d():
    """docs/discrete3d.md (Step control): under a 3e9 N clamp, q_a = 303 N = 1.01 f P, 16
    samples: D off the closed form by 3.6e-4, 7.9e-5 and 8.7e-8 at step_tol 1e-4, 1e-6
    and 1e-8 (scaled to the clamp, 0.92 % at all three)."""
    D = _closed_form(1e3, 303.0)
    for step_tol, quoted in ((1e-4, 3.6e-4), (1e-6, 7.9e-5), (1e-8, 8.7e-8)):
        res = simulate3d(_system3(), _load3(1e3, 3e9, 303.0), cycles=20, steps_per_cycle=16,
                         tol=1e-8, step_tol=step_tol)
        assert abs(res.dissipation_per_cycle - D) / D == pytest.approx(quoted, rel=0.05)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), big=st.sampled_from([0.0, 1e3, 1e9]),
       tol=st.sampled_from([1e-6, 1e-11]))
def test_the_compiled_kernels_residual_scale_is_the_python_one(seed, big, tol):
    """fastcycle's compiled residual scale (slips of a run in contact, w = 0) equals
    ResidualScale.scale on random coupled 2-D systems and changes of some slips, with
    slips up to 1e9 m (where the round-off floor decides)."""
    from slipcycle.discrete.fastcycle import _residual_scale, _scale_args

    rng = np.random.default_rng(seed)
    n = 4
    M = rng.normal(size=(2 * n, 2 * n))
    Kf = M @ M.T / (2 * n) + np.eye(2 * n)
    system = FrictionalSystem(Kf[:n, :n], 0.3 * Kf[n:, :n], Kf[n:, n:],
                              rng.uniform(0.2, 0.5, n), accept_ill_posed=True)
    load = DiscreteLoad.harmonic(rng.uniform(1, 2, n), rng.normal(size=n),
                                 rng.uniform(0, 0.3, n), rng.uniform(0, 0.6, n),
                                 rng.uniform(0, 6, n), rng.uniform(0, 6, n))
    theta, vals = load.cycle_samples(16)
    va = rng.normal(size=n) * (1.0 + big * (rng.uniform(size=n) < 0.5))
    vb = va + np.where(rng.uniform(size=n) < 0.5, 1e-9 * rng.normal(size=n), 0.0)
    disp = float(np.abs(vals).max()) / system.stiffness_scale()
    scale = ResidualScale.of(system, vals, disp)
    service, qabs, pabs = _scale_args(system, vals, disp)
    got = _residual_scale(system.A, system.B, system.friction, qabs, pabs, va, vb, service,
                          tol)
    want = scale.scale(np.concatenate([va, np.zeros(n)]), np.concatenate([vb, np.zeros(n)]),
                       tol)
    assert got == pytest.approx(want, rel=1e-12)


def _coupled_clamped(clamp: float):
    """The random coupled 5-node 3-D system of test_discrete3d_steady_jump (seed 2) with
    node 0's normal load raised by ``clamp`` [N] (it then stays stuck)."""
    n = 5
    rng = np.random.default_rng(2)
    M = rng.normal(size=(3 * n, 3 * n))
    Kf = M @ M.T / (3 * n) + np.eye(3 * n)
    t = np.arange(2 * n)
    system = FrictionalSystem3D(Kf[np.ix_(t, t)], 0.3 * Kf[2 * n:, :2 * n],
                                Kf[2 * n:, 2 * n:], rng.uniform(0.25, 0.4, n),
                                accept_ill_posed=True)
    amp = 0.05 + 0.5 * (rng.uniform(size=n) < 0.4)
    q1 = np.column_stack([amp, 0.7 * amp]).ravel()
    ph = np.column_stack([np.zeros(n), np.full(n, -np.pi / 2)]).ravel()
    p0 = np.full(n, 2.0)
    p0[0] += clamp
    load = Load3D.harmonic(p0, 0.1 * rng.normal(size=2 * n), 0.3 * rng.uniform(size=n), q1,
                           np.zeros(n), ph)
    return system, load


def test_a_coupled_3d_system_gives_the_same_cycle_under_any_clamp():
    """Node 0 of a coupled 5-node system clamped by 1e4, 1e8 and 1e10 N stays stuck, so
    the steady cycle of the others cannot depend on the clamp: D agrees to 1e-7 (with the
    Newton and event tolerances of the cycles relative to the whole load, D was 4.5e-4
    and 3.1e-2 off at 1e8 and 1e10 N). The Newton solves end far below their tolerance:
    at 1e8 N it is 3.9e-6 m as a displacement, and plain cycling at tol 1e-11 converges
    with cycle changes of 3e-12 m, so the residual's floor needs no term for it."""
    kw = dict(cycles=80, steps_per_cycle=40, tol=1e-11, step_tol=1e-6, accelerate=False,
              record=False)
    runs = {c: simulate3d(*_coupled_clamped(c), **kw) for c in (1e4, 1e8, 1e10)}
    for res in runs.values():
        assert res.steady_state == "cyclic_slip" and res.cycles_run < 80
    for c in (1e8, 1e10):
        assert runs[c].dissipation_per_cycle == pytest.approx(
            runs[1e4].dissipation_per_cycle, rel=1e-7)
    res = runs[1e8]
    system = _coupled_clamped(1e8)[0]
    assert 1e-13 * res.force_scale / system.stiffness_scale() == pytest.approx(3.9e-6,
                                                                                rel=0.05)
    last = np.abs(res.cycle_start_states[-1] - res.cycle_start_states[-2]).max()
    assert last < 1e-11
