"""The accelerated steady state with its certificate (``slipcycle.coupled.driver``).

A state reached with an accelerator's steps is accepted only after plain cycles from it
reproduce their start within the tolerance; the run reports the method (``acceleration``),
the certified residual, and the estimated distances of the state and of D from plain
cycling's limit. Checked: the certificate on cycle maps whose limit is known in closed
form (an affine contraction), the accelerated runs against plain cycling run to 1e-11 on
FE-reduced blocks, random systems (hypothesis) and a system with two basins, and the run
setting ``accelerate`` through the Python API, the case file and the CLI.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import slid_block
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from test_discrete_steady_jump import _random_case
from test_malformed_inputs import refused_in_one_line
from test_steady_driver import _AffineCycle

import slipcycle
from slipcycle.coupled import RunSettings
from slipcycle.coupled.cycles import CycleHistory
from slipcycle.coupled.driver import (
    ACCELERATIONS,
    STEADY,
    CycleState,
    PlainCycling,
    certificate,
    run_cycles,
)
from slipcycle.discrete import simulate
from slipcycle.discrete.rate import RateProblemError
from slipcycle.discrete.steady import InadmissibleInitialState


class _JumpOnce(PlainCycling):
    """An accelerator that replaces the start after the first cycle by ``target`` and
    calls the state steady right after its checking cycle (whatever its residual)."""

    def __init__(self, target):
        super().__init__()
        self.target, self.jumped = np.asarray(target, float), False

    @property
    def method(self) -> str:
        return "anderson" if self.jumped else "none"

    def judge(self, run):
        return STEADY if self.jumped else None

    def step(self, run):
        if not self.jumped:
            self.jumped = True
            run.restart(self.target)
            run.starts[-1] = self.target.copy()
        return None


def _affine_run(rho, target, cycles=60, tol=1e-8):
    """x → ρ x + (1 − ρ) x* with x* = 1 (every component), from 0."""
    A = np.diag(rho)
    b = (1.0 - np.asarray(rho)) * 1.0
    evo = _AffineCycle(A, b, np.zeros(len(rho)))
    system = SimpleNamespace(n_nodes=len(rho) // 2)
    run = CycleState(system, evo, RunSettings(cycles=cycles, tol=tol),
                     CycleHistory(1.0, False, [evo.x.copy()]), np.zeros(len(rho)), 1.0)
    acc = _JumpOnce(target)
    run_cycles(run, np.zeros(1), np.zeros((1, len(rho))), acc)
    return run, acc


def test_a_jump_to_the_fixed_point_is_certified_by_one_plain_cycle():
    """A jump onto the exact limit: one plain cycle reproduces it (residual 0), and the
    certificate names the method and reports no distance left."""
    run, acc = _affine_run([0.9, 0.5], [1.0, 1.0])
    assert run.state == "steady"
    assert len(run.starts) == 4            # x0, the jump, its checking cycle, one more
    cert = certificate(run, acc)
    assert cert.acceleration == "anderson" and cert.acceleration in ACCELERATIONS
    assert cert.certified_residual == 0.0 and cert.memory_distance == 0.0


@given(rho=st.floats(0.55, 0.98), off=st.floats(1e-6, 1e-2))
@settings(max_examples=40, deadline=None)
def test_a_jump_short_of_the_limit_is_cycled_plainly_until_it_repeats_within_tol(rho, off):
    """A jump that lands ``off`` from the limit of x → ρx + (1 − ρ): plain cycles follow
    until the increment is below the tolerance, and the certificate's distance
    ρ/(1 − ρ)·|Δx| is the exact distance to the limit (a linear map of one rate)."""
    tol = 1e-8
    run, acc = _affine_run([rho, rho], [1.0 - off, 1.0 - off], cycles=2000, tol=tol)
    assert run.state == "steady" and run.residual <= tol
    cert = certificate(run, acc)
    exact = float(np.max(np.abs(run.starts[-1] - 1.0)))
    assert cert.memory_distance == pytest.approx(exact, rel=1e-6)
    # the plain cycles ran from the jump: its distance shrank by ρ per cycle
    k = len(run.starts) - 3
    assert exact == pytest.approx(off * rho ** (k + 1), rel=1e-6)


def test_a_certificate_that_the_cycles_left_cannot_give_is_not_converged():
    run, _ = _affine_run([0.99, 0.99], [0.5, 0.5], cycles=10)
    assert run.state == "not_converged" and run.residual > 1e-8


def test_a_ratcheting_run_has_no_distance_to_a_limit():
    """x → x + drift: ratcheting, whose certificate gives no distance (None in a summary)."""
    evo = _AffineCycle(np.eye(2), [1e-3, 0.0], np.zeros(2))
    run = CycleState(SimpleNamespace(n_nodes=1), evo, RunSettings(cycles=20, tol=1e-8),
                     CycleHistory(1.0, False, [evo.x.copy()]), np.zeros(2), 1.0)
    acc = PlainCycling()
    run_cycles(run, np.zeros(1), np.zeros((1, 2)), acc)
    assert run.state == "ratcheting"
    cert = certificate(run, acc)
    assert cert.acceleration == "none"
    assert cert.memory_distance == cert.dissipation_distance == np.inf


def test_plain_cycling_reports_no_acceleration_and_its_own_creep_distance():
    system, load = _random_case(7, 3, False)
    plain = simulate(system, load, accelerate=False, cycles=400, steps_per_cycle=40,
                     record=False, tol=1e-11)
    cert = plain.certificate
    assert cert.acceleration == "none"
    assert cert.certified_residual == plain.residual <= 1e-11
    assert cert.memory_distance >= cert.certified_residual


def _same(fast, plain, d_rel=1e-6, x_rel=1e-6):
    """Class and node sets identical, D within ``d_rel``, the state (the stuck nodes'
    memory) within ``x_rel`` of the slip scale."""
    assert fast.steady_state == plain.steady_state
    assert fast.slipping_nodes == plain.slipping_nodes
    assert fast.permanently_stuck_nodes == plain.permanently_stuck_nodes
    assert fast.separating_nodes == plain.separating_nodes
    scale = max(abs(plain.dissipation_per_cycle), plain.force_scale * plain.disp_scale)
    assert abs(fast.dissipation_per_cycle - plain.dissipation_per_cycle) <= d_rel * scale
    x_f, x_p = fast.cycle_start_states[-1], plain.cycle_start_states[-1]
    slip_scale = max(plain.disp_scale, float(np.abs(x_p).max()))
    assert np.abs(x_f - x_p).max() <= x_rel * slip_scale


@pytest.fixture(scope="module")
def block_41():
    """The 41-node block from two starts, on the default path (the periodic follower) and
    plainly cycled, all to 1e-11: {start: (accelerated, plain)}. Slid first (pressed
    0.2 µm, pushed 3 µm, pressed to 2 µm) it ends in cyclic slip; loaded monotonically it
    shakes down: two basins of one system."""
    system, load, protocol = slid_block(20)
    kw = dict(cycles=1500, steps_per_cycle=50, record=False, tol=1e-11)
    return {name: (simulate(system, load, protocol=p, **kw),
                   simulate(system, load, protocol=p, accelerate=False, **kw))
            for name, p in (("slid", protocol), ("monotonic", None))}


def test_fe_block_41_default_path_is_certified_and_lands_on_plain_cyclings_limit(block_41):
    """Slid first: the steps, certified, in less than half plain cycling's cycles; class,
    node sets, D and state as plain cycling's (measured 1.1e-9 in D, 8.6e-11 of the slip
    scale; 132 cycles against 362)."""
    fast, plain = block_41["slid"]
    assert fast.certificate.acceleration == "periodic"
    assert fast.certificate.certified_residual <= 1e-11
    assert fast.cycles_run < plain.cycles_run / 2
    _same(fast, plain)


def test_two_basins_each_start_keeps_its_own_steady_state(block_41):
    """The two starts of the 41-node block end in different steady states (cyclic slip,
    shakedown), each accelerated run in that of its own plain run."""
    for fast, plain in block_41.values():
        _same(fast, plain)
    assert [block_41[k][0].steady_state for k in ("slid", "monotonic")] == \
        ["cyclic_slip", "shakedown"]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 100_000), n=st.integers(16, 24), sep=st.booleans())
def test_random_systems_default_path_is_certified_and_matches_plain_cycling(seed, n, sep):
    """Random systems of 16–24 nodes (accelerated by default), both runs to 1e-11."""
    system, load = _random_case(seed, n, sep)
    kw = dict(cycles=400, steps_per_cycle=40, tol=1e-11, record=False)
    try:
        plain = simulate(system, load, accelerate=False, **kw)
    except (InadmissibleInitialState, RateProblemError):
        assume(False)
    assume(plain.steady_state not in ("not_converged", "ratcheting"))
    fast = simulate(system, load, **kw)
    cert = fast.certificate
    assert cert.acceleration in ("none", "periodic")
    assert cert.certified_residual <= 1e-11
    _same(fast, plain)


EXAMPLE = Path(slipcycle.__file__).parent / "examples" / "discrete_two_node.toml"


def test_accelerate_false_in_the_case_file_is_plain_cycling():
    text = EXAMPLE.read_text()
    assert "[run]" in text
    plain = slipcycle.run(text.replace("[run]", "[run]\naccelerate = false"))
    assert plain.summary()["acceleration"] == "none"
    assert plain.case.run["accelerate"] is False


def test_run_accelerate_that_is_not_a_bool_is_refused_in_one_line(tmp_path, monkeypatch,
                                                                   capsys):
    (tmp_path / "case.toml").write_text(
        EXAMPLE.read_text().replace("[run]", "[run]\naccelerate = 1"))
    line = refused_in_one_line(("run", "case.toml", "--out", "o"), tmp_path, monkeypatch,
                               capsys)
    assert "run.accelerate" in line


def test_run_settings_refuse_an_accelerate_that_is_not_a_bool():
    with pytest.raises(TypeError, match="run.accelerate"):
        RunSettings(accelerate="yes")
    assert RunSettings(accelerate=False)["accelerate"] is False
    assert "accelerate" not in RunSettings()        # None: the driver's rule


@pytest.mark.slow
def test_fe_block_401_default_path_at_the_default_tolerance_lands_within_1e6_of_the_limit(
        monkeypatch):
    """401 contact nodes on the default path (slow-mode steps, N ≥ SLOW_MIN_NODES) at the
    default tolerance 1e-8: the steps go on until their remaining distance is below 1e-11
    (SLOW_SETTLED), so D and the state (the 378 stuck nodes' memory) land within 1e-6 of
    plain cycling's limit after 2200 cycles (measured 1.8e-7 and 6.0e-7, in 134 cycles;
    stopping the steps at the tolerance gives 114 cycles and D 9.0e-7 off: 1.0e-4 when
    the residual was measured against the whole load), certified by a plain cycle."""
    from test_discrete_slow_modes import DATA, PLAIN_D_401

    from slipcycle.discrete import steady

    system, load, protocol = slid_block(200)
    kw = dict(cycles=600, steps_per_cycle=50, protocol=protocol, record=False)
    fast = simulate(system, load, **kw)
    cert = fast.certificate
    assert fast.steady_state == "cyclic_slip"
    assert cert.acceleration == "slow_modes" and cert.certified_residual <= 1e-8
    assert fast.cycles_run < 200
    x, plain_x = fast.cycle_start_states[-1], np.load(DATA / "fe_block_401_plain_limit.npy")
    assert np.abs(x - plain_x).max() <= 1e-6 * np.abs(plain_x).max()
    assert fast.dissipation_per_cycle == pytest.approx(PLAIN_D_401, rel=1e-6, abs=0)
    # stopped at the tolerance instead, the steps leave D further off (the reason for the
    # tighter stop)
    monkeypatch.setattr(steady, "SLOW_SETTLED", 1.0)
    loose = simulate(system, load, **kw)
    assert loose.cycles_run < fast.cycles_run
    assert abs(loose.dissipation_per_cycle - PLAIN_D_401) > \
        3 * abs(fast.dissipation_per_cycle - PLAIN_D_401)


@pytest.mark.parametrize("seed", [1, 3])
def test_3d_accelerated_runs_report_their_jumps_and_are_certified(seed):
    """The random coupled 3-D systems of ``test_discrete3d_steady_jump.py``: a run whose
    state the Anderson jumps shaped says so (``anderson``), its last cycle is a plain one
    from that state within the tolerance, and its summary carries the certificate;
    ``accelerate=False`` says ``none``."""
    from test_discrete3d_steady_jump import _random_coupled

    from slipcycle.discrete3d import simulate3d
    from slipcycle.discrete3d.case import solve_model

    system, load = _random_coupled(seed, 8)
    kw = dict(cycles=200, steps_per_cycle=40, step_tol=1e-6, tol=1e-9, record=False)
    acc = simulate3d(system, load, accelerate=True, **kw)
    assert acc.jumps >= 1 and acc.certificate.acceleration == "anderson"
    assert acc.certificate.certified_residual == acc.residual <= 1e-9
    plain = simulate3d(system, load, accelerate=False, **kw)
    assert plain.certificate.acceleration == "none"
    summary = solve_model(system, load, {"cycles": 200, "steps_per_cycle": 40,
                                         "step_tol": 1e-6, "tol": 1e-9,
                                         "accelerate": True}, fields=()).summary()
    assert summary["acceleration"] == "anderson"
    assert summary["certified_residual"] == pytest.approx(acc.residual, rel=1e-12)
    assert summary["units"]["memory_distance"] == "1"
    # the default of the 3-D model is plain cycling (None, and the case file's default)
    default = solve_model(system, load, {"cycles": 200, "steps_per_cycle": 40,
                                         "step_tol": 1e-6, "tol": 1e-9}, fields=())
    assert default.summary()["acceleration"] == "none"
    assert default.solution.solver_stats.jumps == 0
    np.testing.assert_array_equal(default.solution.cycle_start_states,
                                  plain.cycle_start_states)


# --- 3-D: plain cycling by default, Anderson mixing opt-in with a measured bound ---------

def _plain_pair_3d(system, load, *, tol=1e-8, **kw):
    """The 3-D default path at ``tol`` and plain cycling to 1e-11, on the same map."""
    from slipcycle.discrete3d import simulate3d

    kw = dict(record=False, **kw)
    return (simulate3d(system, load, tol=tol, **kw),
            simulate3d(system, load, tol=1e-11, accelerate=False, **kw))


def test_3d_default_path_on_a_100_node_chain_lands_within_1e6_of_plain_cyclings_limit():
    """The FE-like chain of 100 nodes (10 slip, 90 keep their memory), replayed step
    subdivision: the default path (plain cycling, its creep included in the steady-state
    test) at the default tolerance 1e-8 ends within 1e-6 of plain cycling run to 1e-11
    (measured 5.3e-11 in D, 6.0e-9 of the slip scale; 50 cycles against 73), certified
    as plain, its creep estimate above the measured distance."""
    from test_discrete3d_steady_jump import _fe_like

    system, load = _fe_like(100)
    fast, plain = _plain_pair_3d(system, load, steps_per_cycle=40, step_tol=1e-6,
                                 cycles=400, replay=True)
    assert plain.residual <= 1e-11
    cert = fast.certificate
    assert cert.acceleration == "none" and fast.jumps == 0
    _same(fast, plain)
    x, x_p = fast.cycle_start_states[-1], plain.cycle_start_states[-1]
    slip_scale = max(plain.disp_scale, float(np.abs(x_p).max()))
    assert np.abs(x - x_p).max() / slip_scale <= cert.memory_distance


@settings(max_examples=8, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(seed=st.integers(0, 100_000), n=st.integers(6, 10))
def test_3d_random_systems_default_path_matches_plain_cycling_to_1e11(seed, n):
    """Random coupled 3-D systems (random positive definite stiffness, steady pressure,
    a shear rotating over the cycle, large at some nodes only): the default path at 1e-8
    against plain cycling to 1e-11, on the replayed step subdivision: class, node sets,
    D and state within 1e-6."""
    from test_discrete3d_steady_jump import _random_coupled

    system, load = _random_coupled(seed, n)
    fast, plain = _plain_pair_3d(system, load, steps_per_cycle=40, step_tol=1e-6,
                                 cycles=600, replay=True)
    # systems that creep (several cycles), not those that stick from the first cycle on
    assume(plain.steady_state in ("shakedown", "cyclic_slip") and plain.residual <= 1e-11
           and plain.cycles_run >= 4)
    assert fast.certificate.acceleration == "none"
    _same(fast, plain)


def test_3d_two_basins_each_assembly_keeps_its_own_steady_state():
    """A coupled 2-node system whose assembly decides the steady state: tightened plainly
    it shakes down, after a fit-up it slips cyclically. On the default path each start
    ends in the steady state of its own plain cycling to 1e-11."""
    from test_discrete3d_protocol_steps import _A2, _B2, _FIT_UP2, _LOAD2, _PLAIN

    from slipcycle.discrete3d.case import assembly_states
    from slipcycle.discrete3d.model import embed_2d

    system = embed_2d(_A2, _B2, np.eye(2), 0.5)
    ends = []
    for steps in (_PLAIN, _FIT_UP2):
        fast, plain = _plain_pair_3d(system, _LOAD2, steps_per_cycle=100, step_tol=1e-7,
                                     cycles=400, replay=True,
                                     protocol=assembly_states(steps, _LOAD2))
        _same(fast, plain)
        ends.append(fast.steady_state)
    assert ends == ["shakedown", "cyclic_slip"]


def test_3d_anderson_certificate_reports_the_measured_bound_not_its_creep():
    """The opt-in Anderson mixing on the 50-node chain: the certificate's distances are
    at least :data:`ANDERSON_DISTANCE` (the creep of its certifying cycles, about the
    tolerance, cannot see a jump to another member of the set of steady states), and the
    measured distance from plain cycling's limit (1e-11) lies within them."""
    from test_discrete3d_steady_jump import _fe_like

    from slipcycle.discrete3d import simulate3d
    from slipcycle.discrete3d.steady import ANDERSON_DISTANCE

    system, load = _fe_like(50)
    kw = dict(steps_per_cycle=40, step_tol=1e-6, cycles=400, record=False, replay=True)
    acc = simulate3d(system, load, accelerate=True, **kw)
    plain = simulate3d(system, load, accelerate=False, tol=1e-11, **kw)
    cert = acc.certificate
    assert cert.acceleration == "anderson" and acc.jumps >= 1
    assert cert.certified_residual <= 1e-8
    assert cert.memory_distance >= ANDERSON_DISTANCE[0]
    assert cert.dissipation_distance >= ANDERSON_DISTANCE[1]
    x, x_p = acc.cycle_start_states[-1], plain.cycle_start_states[-1]
    slip_scale = max(plain.disp_scale, float(np.abs(x_p).max()))
    assert np.abs(x - x_p).max() / slip_scale <= cert.memory_distance
    d_p = plain.dissipation_per_cycle
    assert abs(acc.dissipation_per_cycle - d_p) / abs(d_p) <= cert.dissipation_distance


def test_a_shakedowns_dissipation_distance_is_measured_against_the_resolved_energy():
    """The two-node example shakes down with D = 3.8e-10 J left by its last creep; its D
    distance was reported relative to that D (10.4, a thousand per cent). Relative to the
    energy the cycling resolves (tol × F × x) it is below the tolerance's order."""
    import slipcycle
    from slipcycle.examples import example_path

    s = slipcycle.run(example_path("discrete_two_node.toml")).summary()
    assert s["steady_state"] == "shakedown"
    assert 0 <= s["dissipation_distance"] <= 1.0
