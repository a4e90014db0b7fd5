"""One engine per physics: the Jenkins bed (return map with moving limits) is written once.

:func:`slipcycle.kernels.jenkins.apply_increment` moves a bed of Jenkins elements by a
common increment and :func:`~slipcycle.kernels.jenkins.solve_tangential_force` finds the
increment for a prescribed total force. The half-space slider bed (``drive_from``, and
through it the Ŵ map) and the rod interfaces (``bed_step``: rings, Jenkins, Iwan) call
them; no model module keeps its own copy of the return map.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import slipcycle
from slipcycle.kernels.jenkins import apply_increment, solve_tangential_force
from slipcycle.rods.kernels import bed_step

SRC = Path(slipcycle.__file__).parent


def _reference_return_map(t, k, cap, dv):
    """Each element on its own: elastic trial, returned to the limit; slip is the rest."""
    t_new = np.clip(t + k * dv, -cap, cap)
    slip = dv - (t_new - t) / k
    return t_new, slip


@settings(max_examples=200, deadline=None)
@given(n=st.integers(1, 12), seed=st.integers(0, 2**31 - 1),
       dv=st.floats(-1e-2, 1e-2, allow_nan=False))
def test_apply_increment_is_the_elementwise_return_map_and_books_half_sum_times_slip(n, seed,
                                                                                    dv):
    rng = np.random.default_rng(seed)
    k = rng.uniform(1e3, 1e6, n)
    cap = rng.uniform(0.0, 10.0, n)
    t = np.clip(rng.normal(0.0, 5.0, n), -cap, cap)
    t_ref, slip_ref = _reference_return_map(t, k, cap, dv)
    d = np.zeros(n)
    z = np.zeros(n)
    slip = np.zeros(n)
    t_work = t.copy()
    q, n_slip, first = apply_increment(t_work, k, k, cap, dv, d, z, slip, 1e-9)
    assert np.all(np.abs(t_work - t_ref) <= 1e-12 * (1 + np.abs(t_ref)))
    np.testing.assert_allclose(z, slip_ref, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(d, 0.5 * (t + t_ref) * slip_ref, rtol=1e-9, atol=1e-15)
    assert abs(q - np.sum(t_work)) <= 1e-12 * (1 + np.abs(t_work).sum())
    slipping = (np.abs(t + k * dv) - cap > 1e-9 * cap) & (cap > 0)
    assert n_slip == slipping.sum()
    assert first == (np.flatnonzero(slipping)[0] if slipping.any() else n)


@settings(max_examples=100, deadline=None)
@given(n=st.integers(1, 10), seed=st.integers(0, 2**31 - 1))
def test_force_step_then_increment_reaches_the_target_force(n, seed):
    rng = np.random.default_rng(seed)
    k = rng.uniform(1e3, 1e6, n)
    cap = rng.uniform(0.1, 10.0, n)
    t = np.clip(rng.normal(0.0, 2.0, n), -cap, cap)
    target = rng.uniform(-0.99, 0.99) * cap.sum()
    dv, _ = solve_tangential_force(t, k, cap, target, 0.0)
    q, _, _ = apply_increment(t, k, k, cap, dv, np.zeros(n), np.zeros(n), np.zeros(n), 0.0)
    assert abs(q - target) <= 1e-10 * cap.sum()


@settings(max_examples=200, deadline=None)
@given(n=st.integers(1, 40), seed=st.integers(0, 2**31 - 1),
       scale=st.floats(1e-16, 1e-6), sign=st.sampled_from([-1.0, 1.0]))
def test_a_tiny_force_on_a_strong_bed_is_reached_relative_to_itself(n, seed, scale, sign):
    """A target force 1e-16 … 1e-6 of the bed's capacity, on a bed carrying forces of
    its own size: the step reaches it to 1e-9 of the target, not to a fraction of the
    capacity (which left a 1e-12 rad twist of the rods unconverged, 2.7 % torque noise)."""
    rng = np.random.default_rng(seed)
    k = rng.uniform(1e3, 1e6, n)
    cap = rng.uniform(10.0, 100.0, n)
    t = np.zeros(n)
    target = sign * scale * cap.sum()
    dv, _ = solve_tangential_force(t, k, cap, target, 0.0)
    q, _, _ = apply_increment(t, k, k, cap, dv, np.zeros(n), np.zeros(n), np.zeros(n), 0.0)
    assert abs(q - target) <= 1e-9 * abs(target)
    # the same force from a bed that already carries a self-equilibrated set of forces
    # of 1e-3 of the target: the tolerance follows the forces summed, not the capacity
    t0 = 1e-3 * abs(target) * np.resize([1.0, -1.0], n)
    t0[-1] -= t0.sum()
    t1 = t0.copy()
    dv, _ = solve_tangential_force(t1, k, cap, target, 0.0)
    q, _, _ = apply_increment(t1, k, k, cap, dv, np.zeros(n), np.zeros(n), np.zeros(n), 0.0)
    assert abs(q - target) <= 1e-9 * abs(target)


def test_rod_bed_step_uses_the_same_return_map():
    """A bed in series with compliance C: the elements end where the shared map puts them."""
    rng = np.random.default_rng(3)
    n = 6
    k = rng.uniform(1e3, 1e5, n)
    cap = rng.uniform(0.5, 2.0, n)
    t = np.zeros(n)
    C = 1e-4
    target = 1.2 * cap.sum()
    work = [np.empty(n + 1) for _ in range(3)]
    d = np.zeros(n)
    T, y = bed_step(t, k, cap, False, target, C, 0.0, *work, d)
    t_ref, slip_ref = _reference_return_map(np.zeros(n), k, cap, y)
    np.testing.assert_allclose(t, t_ref, atol=1e-12)
    np.testing.assert_allclose(d, 0.5 * t_ref * slip_ref, rtol=1e-9, atol=1e-15)
    assert abs(T + y / C - target) <= 1e-9 * target  # bed + series spring balance


def test_no_model_module_writes_its_own_jenkins_return_map():
    """The dissipation booking ½(t_old + t_new)·slip of an elastic bed lives in one kernel."""
    pattern = re.compile(r"0\.5 \* \(told \+ tn\) \* \(")
    homes = sorted(str(p.relative_to(SRC)) for p in SRC.rglob("*.py")
                   if pattern.search(p.read_text()))
    assert homes == ["kernels/jenkins.py"]
    for caller in ("halfspace/kernels.py", "rods/kernels.py"):
        assert "apply_increment(" in (SRC / caller).read_text()
