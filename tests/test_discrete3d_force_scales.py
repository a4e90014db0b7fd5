"""The 3-D engine across the scales of the loads: a service load far below the preload,
and every load scaled by a common factor.

References: positive homogeneity of rate-independent friction with linear elasticity
(loads × λ → state × λ, dissipation × λ²), and the elastic limit: a service load far
below what friction holds shakes down. Before the Newton tolerance of an active set had a
floor at the round-off of the terms of its rows, a service load 1e-8 of the preload (or a
preload 1e6 times the service load) ended in "no solution the Newton method can find".
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_lap_joint_study import FAST, SMALL, synthetic_joint

import slipcycle.discrete3d.evolution as ev
from slipcycle.cli.main import main
from slipcycle.joints.lap_joint_study import StudySettings, lap_joint_study, standard_protocol

JOINT = synthetic_joint(4)
PROTOCOL = [standard_protocol("sequential", 3)]
RUN = {**FAST, "cycles": 8}


def _study(preload, service):
    settings = StudySettings(preload=preload, service_amplitude=service, friction=0.3,
                             run=RUN)
    return lap_joint_study(JOINT, PROTOCOL, settings, fields=())


@settings(max_examples=10, deadline=None)
@given(preload=st.floats(1e3, 1e10), ratio_exp=st.floats(6.0, 12.0))
def test_a_service_load_far_below_the_preload_shakes_down(preload, ratio_exp):
    """Service 1e-6 … 1e-12 of the preload, preload 1 kN … 10 GN: the run reaches its
    steady state, and it is a shakedown (the service load is far below what the
    preloaded interface holds)."""
    res = _study(preload, preload * 10.0 ** -ratio_exp)
    assert res.mesh.steady_state.tolist() == [["shakedown"]]
    assert np.all(np.isfinite(res.mesh.dissipation))


def test_without_the_round_off_floor_such_a_run_fails(monkeypatch):
    """The floor is what makes the case above run: without it the Newton iteration is
    asked for a residual below the round-off of the preload's forces."""
    monkeypatch.setattr(ev.StepSolver, "roundoff_ulps", 0.0)
    with pytest.raises(ev.IncrementalSolverError):
        _study(1e4, 1e-4)


@settings(max_examples=8, deadline=None)
@given(scale_exp=st.floats(-6.0, 6.0))
def test_scaling_every_load_scales_the_state_and_the_dissipation_by_its_square(scale_exp):
    """Loads × λ (preload and service): the cycle starts × λ, D × λ², the classes and
    cycles the same (λ from 1e-6 to 1e6; the tolerances are relative to the loads). The
    service load makes the interface slip (D well above its round-off)."""
    lam = 10.0 ** scale_exp
    base, scaled = _study(1e4, 3000.0), _study(1e4 * lam, 3000.0 * lam)
    assert scaled.mesh.steady_state.tolist() == base.mesh.steady_state.tolist()
    a, b = base.runs[0].solution, scaled.runs[0].solution
    assert b.cycles_run == a.cycles_run
    d = a.dissipation_per_cycle
    assert d > 1e-6
    assert b.dissipation_per_cycle / lam ** 2 == pytest.approx(d, rel=1e-6)
    x0, x1 = a.cycle_start_states[-1], b.cycle_start_states[-1] / lam
    assert np.max(np.abs(x1 - x0)) <= 1e-6 * np.max(np.abs(x0))


def test_the_command_line_runs_a_lap_joint_whose_service_load_is_1e_8_of_its_preload(
        tmp_path):
    """The shipped small joint (10 kN per bolt) under a 0.1 mN service load through
    ``slipcycle run``: every protocol shakes down, on both meshes."""
    text = SMALL.replace("service_amplitude = 2e3", "service_amplitude = 1e-4")
    assert text != SMALL
    (tmp_path / "lap.toml").write_text(text)
    assert main(["run", str(tmp_path / "lap.toml"), "--out", str(tmp_path / "out"),
                 "-q"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert set(summary["protocol_steady_state"]) == {"shakedown"}
    assert np.all(np.isfinite(np.asarray(summary["mesh_dissipation"], float)))
