"""One physics, every path: case file, Python API, `slipcycle run`, the Ŵ map and the demo.

The rough law dP/dU = P/(γσ) has U = γσ ln P; with constant P and Q = ±Q1 the Masing
construction (as in test_halfspace_closed_forms) gives
Ŵ = −4q ln(1 − q) − 8[(1 − q) ln(1 − q) + q] with q = Q1/(fP): 0.6607 at q = 0.7, 2.9314
at q = 0.9.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import case_text
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from slipcycle.halfspace import RoughExponential, contact_loads, sphere
from slipcycle.halfspace.case import parse_case
from slipcycle.halfspace.model import HalfspaceModel, solve
from slipcycle.halfspace.outputs import package, w_hat
from slipcycle.halfspace.wmap import w_hat_point
from slipcycle.io import parse_case_text


def w_hat_masing(q: float) -> float:
    return -4 * q * math.log(1 - q) - 8 * ((1 - q) * math.log(1 - q) + q)


def test_masing_reference_values_quoted_in_the_docs():
    assert w_hat_masing(0.7) == pytest.approx(0.6607, abs=1e-4)
    assert w_hat_masing(0.9) == pytest.approx(2.9314, abs=1e-4)


ROUGH_RUN = """
model = "halfspace"
[halfspace]
profile = "rough_exponential"
gamma_sigma = 2e-6
compliance_ratio = 1.2
friction = 0.4
[loading]
P0 = 250.0
P1 = 0.0
Q1 = {Q1}
[run]
cycles = 3
steps_per_cycle = 200
sliders = 1000
"""


@pytest.mark.parametrize("q", [0.7, 0.9])
def test_rough_run_through_cli_gives_exact_masing_w_hat(run_cli, write_case, tmp_path, q):
    """The bed of `slipcycle run` covers every stick load, down to P − Q1/f."""
    out = tmp_path / "out"
    code, _, err = run_cli("run", write_case(ROUGH_RUN.format(Q1=q * 0.4 * 250.0)), "--out",
                           out, "--quiet")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["W_hat"] == pytest.approx(w_hat_masing(q), rel=2e-3)


@pytest.mark.parametrize("q", [0.7, 0.97, 0.99])
def test_map_kernel_near_gross_slip_covers_stick_loads_below_a_fixed_floor(q):
    """P − Q1/f falls below 5 % of P for Q̂1 > 0.95; the map must still resolve it."""
    assert w_hat_point(0.0, q, 0.0) == pytest.approx(w_hat_masing(q), rel=2e-3)


def _cycle_inside_cone_margin(P1: float, Q1: float, phi: float) -> float:
    """min over θ of (1 + P̂1 cos θ) − |Q̂1 cos(θ − φ)|: < 0 means gross slip (f = P0 = 1)."""
    th = np.linspace(0, 2 * np.pi, 2001)
    return float(np.min(1 + P1 * np.cos(th) - np.abs(Q1 * np.cos(th - phi))))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.floats(0.0, 0.9), st.floats(0.01, 0.99), st.floats(-np.pi, np.pi))
def test_python_api_w_hat_equals_map_kernel(P1, Q1, phi):
    """Same bed construction, same steady cycle: identical Ŵ (or gross slip in both)."""
    margin = _cycle_inside_cone_margin(P1, Q1, phi)
    assume(abs(margin) > 0.02)   # the sampled cycle and the exact one agree on gross slip
    P0, f = 100.0, 0.5
    model = HalfspaceModel.harmonic(RoughExponential(1e-6), f, 1.2, P0=P0, P1=P1 * P0,
                                    Q1=Q1 * f * P0, phase=phi, steps_per_cycle=64,
                                    n_sliders=150, assembly_steps=20, max_cycles=4)
    _, res = solve(model, record_last_cycle=False)
    kernel = w_hat_point(P1, Q1, phi, n_sliders=150, steps_per_cycle=64)
    if margin < 0:
        assert res.gross_slip is not None and math.isnan(kernel)
        return
    assert res.steady and res.gross_slip is None
    assert w_hat(res.dissipation_per_cycle, model, P0) == pytest.approx(kernel, rel=1e-5,
                                                                       abs=1e-12)


def _halfspace(**loading) -> str:
    """The sphere case with P1, P1_phase, Q0, Q1 and phase set."""
    return case_text("halfspace_sphere", loading=loading,
                     run={"cycles": 4, "steps_per_cycle": 64, "sliders": 300})


@settings(max_examples=10, deadline=None)
@given(st.floats(-2 * np.pi, 2 * np.pi), st.floats(-2 * np.pi, 2 * np.pi),
       st.floats(0.0, 40.0), st.floats(-10.0, 10.0), st.floats(0.0, 20.0))
def test_case_file_and_python_api_mean_the_same_phases(phase, P1_phase, P1, Q0, Q1):
    """phase and P1_phase are lags: P = P0 + P1 cos(θ − P1_phase), Q = Q0 + Q1 cos(θ − phase)."""
    text = _halfspace(P1=P1, P1_phase=P1_phase, Q0=Q0, Q1=Q1, phase=phase)
    from_toml = parse_case(parse_case_text(text))
    normal, tangential = contact_loads(100.0, P1, Q0, Q1, phase, P1_phase)
    th = np.linspace(0, 2 * np.pi, 17)
    np.testing.assert_allclose(from_toml.normal(th)[:, 0], 100.0 + P1 * np.cos(th - P1_phase),
                               atol=1e-12)
    np.testing.assert_allclose(from_toml.tangential(th)[:, 0], Q0 + Q1 * np.cos(th - phase),
                               atol=1e-12)
    np.testing.assert_array_equal(normal(th), from_toml.normal(th))
    np.testing.assert_array_equal(tangential(th), from_toml.tangential(th))
    # and the whole run: identical numbers
    el = from_toml.elasticity
    from_python = HalfspaceModel.harmonic(
        sphere(0.01, el.contact_modulus), 0.5, el.compliance_ratio, P0=100.0, P1=P1,
        P1_phase=P1_phase, Q0=Q0, Q1=Q1, phase=phase, elasticity=el, steps_per_cycle=64,
        max_cycles=4, n_sliders=300, assembly_steps=from_toml.assembly_steps,
        snapshots=from_toml.snapshots, profile_name="sphere")
    a = package(from_toml, *solve(from_toml, record_last_cycle=False)).summary
    b = package(from_python, *solve(from_python, record_last_cycle=False)).summary
    assert a == b


CLI_CASES = {
    "rough_out_of_phase": ROUGH_RUN.format(Q1=30.0).replace("P1 = 0.0", "P1 = 80.0\nphase = 1.3"),
    "sphere_lagging": _halfspace(P1=30.0, P1_phase=0.4, Q0=5.0, Q1=20.0, phase=-1.1),
}


@pytest.mark.parametrize("name", sorted(CLI_CASES))
def test_cli_run_summary_equals_python_api(run_cli, write_case, tmp_path, name):
    text = CLI_CASES[name]
    out = tmp_path / "out"
    code, _, err = run_cli("run", write_case(text), "--out", out, "--quiet")
    assert code == 0, err
    on_disk = json.loads((out / "summary.json").read_text())
    model = parse_case(parse_case_text(text))
    summary = package(model, *solve(model)).summary
    for key, value in summary.items():
        if isinstance(value, float):
            assert on_disk[key] == pytest.approx(value, rel=1e-12, abs=0.0), key
        elif key != "units":
            assert on_disk[key] == value, key
    assert on_disk["units"] == summary["units"]


def test_demo_halfspace_numbers_equal_run_on_the_same_case_text(run_cli, write_case, tmp_path,
                                                                  monkeypatch):
    from slipcycle.cli import cmd_demo

    cases = {k: v for k, v in cmd_demo.DEMO_CASES.items() if 'model = "halfspace"' in v[1]}
    assert len(cases) == 3
    monkeypatch.setattr(cmd_demo, "DEMO_CASES", cases)
    code, _, err = run_cli("demo", "--out", tmp_path / "demo")
    assert code == 0, err
    for name, (_, text) in cases.items():
        out = tmp_path / name
        code, _, err = run_cli("run", write_case(text, f"{name}.toml"), "--out", out, "--quiet")
        assert code == 0, err
        demo = json.loads((tmp_path / "demo" / name / "summary.json").read_text())
        run = json.loads((out / "summary.json").read_text())
        demo.pop("metadata"), run.pop("metadata")
        assert demo == run, name
