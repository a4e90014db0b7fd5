"""The shakedown / cyclic-slip class of every steady-state run follows the service cycle.

Two uncoupled nodes (B = 0, A = k I, C = k_n I): node 0 under a normal preload P and a
tangential service load F cos θ, node 1 clamped by a preload P_1 up to 1e7 times the
service load and loaded by nothing else. Node 0's steady cycle has the closed form: it
slips 4 (F − f P)/k per cycle while F > f P and dissipates f P times that; the design
value is F = 2 f P, D = 4 (f P)²/k. A preload-scaled threshold (the old rule,
1e-4 × P_1/k) called a slip of 1 % of the design value ``shakedown``; the service-scaled one
(max(100 tol, 1e-9) × the service load's elastic displacement 2F/k) calls it
``cyclic_slip`` in the 2-D and 3-D engines, the compiled 2-D kernel, through
``slipcycle.run`` and the command line, at step tolerances 100× apart.
"""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import slipcycle
from slipcycle.cli.main import main
from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.discrete.fastcycle import steady_state_fast
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.steady import simulate3d
from slipcycle.loading.service import service_slip_tolerance

K, KN, F_COEF, P = 1e8, 2e8, 0.3, 1e3
D_DESIGN = 4 * (F_COEF * P) ** 2 / K


def _slip(eps):
    """Closed-form slip of node 0 per steady cycle at F = f P (1 + eps) [m]."""
    return 4 * max(eps, 0.0) * F_COEF * P / K


def _toml(model, eps, clamp, step_tol=None):
    F = F_COEF * P * (1 + eps)
    if model == "discrete":
        body = (f'model = "discrete"\n[discrete]\nA = [[{K}, 0.0], [0.0, {K}]]\n'
                f'B = [[0.0, 0.0], [0.0, 0.0]]\nC = [[{KN}, 0.0], [0.0, {KN}]]\n'
                f'friction = {F_COEF}\n[loading]\np0 = [{P}, {clamp}]\nq0 = [0.0, 0.0]\n'
                f'p1 = [0.0, 0.0]\nq1 = [{F!r}, 0.0]\n')
    else:
        body = (f'model = "discrete3d"\n[discrete3d]\nA = {np.diag([K] * 4).tolist()}\n'
                f'B = {np.zeros((2, 4)).tolist()}\nC = [[{KN}, 0.0], [0.0, {KN}]]\n'
                f'friction = {F_COEF}\n[loading]\np0 = [{P}, {clamp}]\n'
                f'q0 = [[0.0, 0.0], [0.0, 0.0]]\np1 = [0.0, 0.0]\n'
                f'q1 = [[{F!r}, 0.0], [0.0, 0.0]]\n')
    run = "[run]\ncycles = 20\nsteps_per_cycle = 16\nsteady_tol = 1e-6\n"
    if step_tol is not None:
        run += f"step_tolerance = {step_tol}\n"
    return body + run + ("[output]\nfields = []\n" if model == "discrete3d" else "")


def _system2(f=F_COEF):
    return FrictionalSystem(K * np.eye(2), np.zeros((2, 2)), KN * np.eye(2), f)


def _load2(F, clamp):
    return DiscreteLoad.harmonic([P, clamp], [0.0, 0.0], [0.0, 0.0], [F, 0.0],
                                 [0.0, 0.0], [0.0, 0.0])


def test_the_threshold_is_100_tol_times_the_service_displacement_not_the_preload():
    """u_s = max_s |r^w(θ_s) − r^w(0)| / max diag K: the preload (constant) drops out."""
    samples = np.array([[303.0, 0.0, 1e3, 1e10], [-303.0, 0.0, 1e3, 1e10]])
    assert service_slip_tolerance(1e-6, samples, K, 1e10 / K) == pytest.approx(
        1e-4 * 606.0 / K)
    # a constant load: only round-off counts as stuck
    assert service_slip_tolerance(1e-6, samples[:1], K, 1e2) == pytest.approx(1e-10)


@pytest.mark.parametrize(("model", "step_tol"), [("discrete", None), ("discrete3d", 1e-4),
                                                ("discrete3d", 1e-6)])
def test_one_percent_of_the_design_slip_under_a_huge_preload_is_cyclic_slip(model, step_tol):
    """F = 1.01 f P with P_1 = 1e7 F: slip 4 (F − f P)/k = 1.2e-7 m per cycle, D = 1 % of
    the design value, cyclic slip (the old rule's threshold 1e-4 P_1/k was 1e-3 m)."""
    res = slipcycle.run(_toml(model, 0.01, 3e9, step_tol))
    s = res.summary()
    assert s["steady_state"] == "cyclic_slip"
    assert res.solution.slip_length[0] == pytest.approx(_slip(0.01), rel=1e-6)
    # the 3-D step control measures its error against the service cycle's displacement
    # (measured: D −3.6e-4 off at step_tol 1e-4, −7.9e-5 at 1e-6; scaled to the clamp's
    # 30 m, the 16 samples went unrefined and D was −9.2e-3 off at both)
    rel = 1e-6 if model == "discrete" else 1e-3
    assert s["dissipation_per_cycle"] == pytest.approx(0.01 * D_DESIGN, rel=rel)
    assert _slip(0.01) < 1e-4 * 3e9 / K       # what the old rule called shakedown


@pytest.mark.parametrize("step_tol", [1e-4, 1e-6])
def test_a_run_dissipating_1e_10_of_the_design_value_is_shakedown_to_the_tolerance(step_tol):
    """F = f P (1 + 1e-10): node 0 slips and dissipates 1e-10 of its design values, below
    100 tol of the service displacement: ``shakedown`` in 2-D and 3-D, at step tolerances
    1e-4 and 1e-6 alike. The exact 2-D engine measures that slip (4e-10 of the design
    slip); the 3-D one, whose steps resolve forces to 1e-10 of the load, at most that."""
    r2 = slipcycle.run(_toml("discrete", 1e-10, 3e9))
    r3 = slipcycle.run(_toml("discrete3d", 1e-10, 3e9, step_tol))
    assert 1e-11 < r2.summary()["dissipation_per_cycle"] / D_DESIGN < 1e-9
    assert r2.solution.slip_length[0] == pytest.approx(_slip(1e-10), rel=1e-3)
    for res in (r2, r3):
        assert res.summary()["steady_state"] == "shakedown"
        assert res.summary()["dissipation_per_cycle"] / D_DESIGN < 1e-9
        assert res.solution.slip_length[0] <= res.solution.slip_tolerance


def test_the_command_line_reports_the_service_class(tmp_path):
    """``slipcycle run`` on the 3-D case of 1 % design slip: summary.json says cyclic_slip."""
    case = tmp_path / "clamped.toml"
    case.write_text(_toml("discrete3d", 0.01, 3e9), encoding="utf-8")
    out = tmp_path / "out"
    assert main(["run", str(case), "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["steady_state"] == "cyclic_slip"


@settings(max_examples=25, deadline=None)
@given(eps=st.one_of(st.just(1e-3), st.just(1.0), st.floats(1e-3, 1.0)),
       clamp=st.one_of(st.just(1.0), st.just(1e10), st.floats(1.0, 1e10)),
       tol=st.sampled_from([1e-5, 1e-6, 1e-8]))
def test_2d_engines_agree_on_the_class_whatever_the_preload(eps, clamp, tol):
    """Any slip above 1e-3 of the service load's (F > 1.001 f P) is ``cyclic_slip``, from a
    free node 1 to one clamped 1e10 N (30 million times the service load), in the
    event-driven engine and the compiled kernel alike (node 1 kept in contact, the
    kernel's domain)."""
    F = F_COEF * P * (1 + eps)
    system, load = _system2(), _load2(F, clamp)
    # the start every steady cycle passes through: node 0 at its limit at θ = 0
    start = np.array([(F_COEF * P - F) / K, 0.0])
    res = simulate(system, load, cycles=20, steps_per_cycle=16, tol=tol, initial_slip=start)
    fast = steady_state_fast(system, load, start, cycles=20, steps_per_cycle=16, tol=tol)
    assert res.steady_state == fast["steady_state"] == "cyclic_slip"
    assert res.slip_length[0] == pytest.approx(_slip(eps), rel=1e-6)
    assert res.slipping_nodes == [0]


@settings(max_examples=10, deadline=None)
@given(eps=st.one_of(st.just(-0.5), st.just(0.0), st.floats(-0.5, 0.0)),
       clamp=st.one_of(st.just(0.0), st.just(1e10), st.floats(0.0, 1e10)))
def test_3d_runs_that_never_slip_are_shakedown_whatever_the_preload(eps, clamp):
    """F ≤ f P: no slip at all, ``shakedown`` for any preload of node 1 (the threshold
    never falls below round-off)."""
    F = F_COEF * P * (1 + eps)
    system = FrictionalSystem3D(K * np.eye(4), np.zeros((2, 4)), KN * np.eye(2), F_COEF)
    load = Load3D.harmonic([P, clamp], [0.0] * 4, None, [F, 0.0, 0.0, 0.0])
    res = simulate3d(system, load, cycles=20, steps_per_cycle=16, tol=1e-6, step_tol=1e-6)
    assert res.steady_state == "shakedown"
    assert res.slip_length[0] <= res.slip_tolerance
