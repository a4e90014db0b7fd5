"""Invariants of the slider bed on random load paths (hypothesis)."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slipcycle.halfspace import FlatPunch, RoughExponential, make_bed, run_history, sphere
from slipcycle.halfspace.bed import lumping_load
from slipcycle.halfspace.kernels import solve_tangential_force

PROFILES = {
    "sphere": lambda: sphere(0.01, 1e11),
    "rough": lambda: RoughExponential(1e-6),
    "punch": lambda: FlatPunch(0.002, 1e11),
}


@st.composite
def closed_paths(draw):
    """A random closed polyline of (P, Q) states inside the friction cone."""
    f = draw(st.floats(0.1, 1.0))
    k = draw(st.integers(2, 6))
    P = np.array(draw(st.lists(st.floats(20.0, 200.0), min_size=k, max_size=k)))
    frac = np.array(draw(st.lists(st.floats(-0.9, 0.9), min_size=k, max_size=k)))
    profile = draw(st.sampled_from(sorted(PROFILES)))
    return f, P, frac * f * P, profile


def _polyline(P, Q, per_segment=30):
    Pc, Qc = np.append(P, P[0]), np.append(Q, Q[0])
    s = np.linspace(0, 1, per_segment + 1)[1:]
    Pp = np.concatenate([Pc[i] + s * (Pc[i + 1] - Pc[i]) for i in range(P.size)])
    Qp = np.concatenate([Qc[i] + s * (Qc[i + 1] - Qc[i]) for i in range(P.size)])
    return Pp, Qp


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(closed_paths())
def test_friction_law_dissipation_sign_and_energy_consistency(path):
    f, P, Q, profile = path
    # the rough law is lumped below the lowest load the history can make slip, derived from
    # the history (a fixed fraction of P_min lets the stick front reach the lumped slider)
    lo = lumping_load(float(P.min()), float(P.max()), min(float(Q.min()), 0.0),
                      max(float(Q.max()), 0.0), f)
    bed = make_bed(PROFILES[profile](), friction=f, compliance_ratio=1.2,
                   P_max=float(P.max()) * 1.01, n_sliders=300,
                   P_lo=lo if profile == "rough" else None)
    Pp, Qp = _polyline(P, Q)
    an = np.linspace(0, Pp[-1], 21)[1:]
    at = np.linspace(0, Qp[-1], 21)[1:]
    res = run_history(bed, an, at, Pp, Qp, max_cycles=4)
    assert res.gross_slip is None
    # |t| ≤ f n for every slider at every recorded instant of the last cycle
    U_last = np.concatenate([[res.U[-1]], res.U[res.cycle == res.cycle.max()]])
    cap = f * bed.normal_stiffness[None] * np.maximum(U_last[:, None] - bed.level[None], 0)
    assert np.all(np.abs(res.last_t) <= cap * (1 + 1e-12) + 1e-15)
    # per-slider and total dissipation per closed cycle are non-negative
    assert res.dissipation_per_cycle >= -1e-12 * max(abs(Qp).max() * 1e-6, 1e-30)
    # global and slider-sum dissipation agree
    W, Ws = res.dissipation_per_cycle, res.slider_sum_dissipation
    assert abs(W - Ws) <= 1e-6 * abs(W) + 1e-18


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 60), st.floats(-0.99, 0.99), st.integers(0, 2**31 - 1))
def test_force_controlled_step_is_exact(n, frac, seed):
    """The step solves Σ clip(t + κΔV, ±c) = Q to rounding, for any state and target."""
    rng = np.random.default_rng(seed)
    cap = rng.uniform(0, 2, n)
    t = rng.uniform(-1, 1, n) * cap * 1.3          # may exceed the new limits (unloading)
    kt = rng.uniform(0.1, 10, n)
    target = frac * cap.sum()
    dv, _ = solve_tangential_force(t, kt, cap, target, rng.normal())
    q = np.clip(t + kt * dv, -cap, cap).sum()
    assert abs(q - target) <= 1e-12 * cap.sum()
