"""The fast Ŵ map against the original algorithm and the exact Masing law.

``w_hat_map`` skips work that cannot change a value: paths that certainly leave the
friction cone are not driven, the unlumped bed of each P̂1 is built once, the preload (Q = 0
on an unloaded bed) is not driven, and the second cycle stops where its slider forces equal
those of the first at the same step (from a common state the same loads give the same
steps: Melan's theorem for the uncoupled bed, Barber 2012 §4). ``reference=True`` drives
every step of every point as before. The two agree to round-off over the whole domain, and
at constant normal load both give the closed-form Masing Ŵ of the rough law (Barber 2012,
§4.6; the Mindlin–Deresiewicz construction with U = γσ ln P).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.halfspace.wmap import _gross_slip_verdict, w_hat_map, w_hat_point

#: Ŵ of a shakedown point is round-off around 0 (|Ŵ| < 1e-15 in the 50×50×36 map)
ROUND_OFF = 1e-14


def _same(fast, ref):
    fast, ref = np.asarray(fast), np.asarray(ref)
    np.testing.assert_array_equal(np.isnan(fast), np.isnan(ref))
    ok = ~np.isnan(ref)
    assert np.all(np.abs(fast[ok] - ref[ok]) <= 1e-12 * np.abs(ref[ok]) + ROUND_OFF)


def w_hat_masing(q: float) -> float:
    """Ŵ(P̂1 = 0, Q̂1 = q) of the rough law: Masing loops on U = γσ ln P."""
    return -4 * q * math.log(1 - q) - 8 * ((1 - q) * math.log(1 - q) + q)


def test_fast_map_equals_the_reference_algorithm_on_a_grid():
    P1 = np.array([0.0, 0.3, 0.6, 0.9])
    Q1 = np.array([0.01, 0.3, 0.6, 0.95])
    ph = np.linspace(-np.pi, np.pi, 9)
    fast = w_hat_map(P1, Q1, ph)
    ref = w_hat_map(P1, Q1, ph, reference=True)
    assert np.isnan(ref).any() and (~np.isnan(ref)).any()   # both kinds of point
    _same(fast, ref)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.0, 0.999999), st.floats(0.0, 1.0), st.floats(-2 * np.pi, 2 * np.pi),
       st.integers(10, 60), st.integers(16, 90), st.integers(1, 25))
def test_fast_point_equals_the_reference_over_the_whole_domain(P1, Q1, phi, n, steps, asm):
    """Any P̂1, Q̂1, φ and discretisation (steps not a multiple of the chunk included)."""
    kw = {"n_sliders": n, "steps_per_cycle": steps, "assembly_steps": asm}
    _same(w_hat_point(P1, Q1, phi, **kw), w_hat_point(P1, Q1, phi, reference=True, **kw))


@pytest.mark.parametrize("cycles", [1, 3])
def test_other_cycle_counts_take_the_reference_path(cycles):
    fast = w_hat_map([0.4], [0.5], [1.0, -2.0], cycles=cycles)
    _same(fast, w_hat_map([0.4], [0.5], [1.0, -2.0], cycles=cycles, reference=True))


@pytest.mark.parametrize("q", [0.1, 0.3, 0.5, 0.7, 0.9])
def test_fast_map_at_constant_normal_load_is_the_masing_law(q):
    """P̂1 = 0: Ŵ is the Masing value at every phase (the phase only moves the start)."""
    W = w_hat_map([0.0], [q], np.linspace(-np.pi, np.pi, 7))[0, 0]
    np.testing.assert_allclose(W, w_hat_masing(q), rtol=2e-3)


@settings(max_examples=200, deadline=None)
@given(st.floats(0.0, 0.999999), st.floats(0.0, 1.0), st.floats(-2 * np.pi, 2 * np.pi))
def test_gross_slip_verdict_is_the_cone_test_of_the_sampled_path(P1, Q1, phi):
    """1 only if some sample has |Q| ≥ P (f = P0 = 1), 0 only if every sample is inside."""
    steps, asm = 64, 5
    th = 2 * np.pi * np.arange(1, steps + 1) / steps
    P = np.concatenate([np.full(asm, 1 + P1), 1 + P1 * np.cos(th)])
    Q = np.concatenate([Q1 * np.cos(-phi) * np.arange(1, asm + 1) / asm,
                        Q1 * np.cos(th - phi)])
    margin = np.min(P - np.abs(Q))
    verdict = _gross_slip_verdict(P1, Q1, phi, steps, asm)
    if verdict == 1:
        assert margin <= 1e-8
    elif verdict == 0:
        assert margin >= -1e-8
        assert margin > 0 or Q1 == 0
    if abs(margin) > 1e-6:
        assert verdict == (1 if margin < 0 else 0)
        # and the driven bed agrees (gross slip: nan)
        W = w_hat_point(P1, Q1, phi, n_sliders=20, steps_per_cycle=steps,
                        assembly_steps=asm, reference=True)
        assert math.isnan(W) == (margin < 0)
