"""Observed order and Richardson extrapolation of mesh sequences against closed forms."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.errors import InputError
from slipcycle.joints.convergence import MeshConvergence, mesh_convergence


def _sequence(c, k, p, spacing):
    return [c + k * h**p for h in spacing]


def test_power_law_sequence_recovers_order_and_limit_exactly():
    h = [0.1, 0.05, 0.025]
    mc = mesh_convergence(h, _sequence(2.0, 3.0, 2.0, h))
    assert mc.observed_order == pytest.approx(2.0, rel=1e-12)
    assert mc.extrapolated == pytest.approx(2.0, rel=1e-12)
    assert mc.relative_error == pytest.approx(3.0 * 0.025**2 / 2.0, rel=1e-9)
    assert mc.converged


def test_uniform_ratio_order_is_log_of_difference_ratio():
    # p = ln[(f2 - f1)/(f3 - f2)] / ln r for a constant ratio r (Roache 1998, ch. 5)
    h, f = [4.0, 2.0, 1.0], [10.0, 7.0, 5.5]
    mc = mesh_convergence(h, f)
    assert mc.observed_order == pytest.approx(math.log(3.0 / 1.5) / math.log(2.0))
    assert mc.extrapolated == pytest.approx(5.5 - 1.5 / (2.0 - 1.0))


@settings(max_examples=200, deadline=None)
@given(p=st.floats(0.5, 4.0), c=st.floats(0.1, 10.0), k=st.floats(-5.0, 5.0),
       r1=st.floats(1.3, 4.0), r2=st.floats(1.3, 4.0), h1=st.floats(1e-4, 1e-1))
def test_any_order_and_non_uniform_ratios_are_recovered(p, c, k, r1, r2, h1):
    h = [h1, h1 / r1, h1 / (r1 * r2)]
    f = _sequence(c, k, p, h)
    if abs(f[1] - f[0]) < 1e-9 * c or abs(f[2] - f[1]) < 1e-9 * c:
        return  # differences at round-off: the order is not measurable
    mc = mesh_convergence(h, f)
    assert mc.observed_order == pytest.approx(p, rel=1e-6, abs=1e-6)
    assert mc.extrapolated == pytest.approx(c, rel=1e-8, abs=1e-10)


@settings(max_examples=100, deadline=None)
@given(p=st.floats(0.5, 4.0), r=st.floats(1.5, 4.0), noise=st.floats(-1e-3, 1e-3))
def test_noise_moves_order_and_limit_within_first_order_bounds(p, r, noise):
    # a relative perturbation ε of the finest value changes the limit by O(ε f/(rᵖ − 1))
    h = [1.0, 1.0 / r, 1.0 / r**2]
    f = _sequence(1.0, 1.0, p, h)
    f[-1] *= 1.0 + noise
    mc = mesh_convergence(h, f)
    assert mc.observed_order is not None
    assert mc.extrapolated == pytest.approx(1.0, abs=20 * abs(noise) * r**p / (r**p - 1)
                                            + 1e-12)


def test_more_than_three_meshes_uses_the_last_three():
    h = [1.0, 0.5, 0.25, 0.125]
    f = [50.0] + _sequence(1.0, 1.0, 1.5, h[1:])  # a wild coarse mesh outside the fit
    f[0] = f[1] + 1.0  # keep it monotone
    mc = mesh_convergence(h, f)
    assert mc.observed_order == pytest.approx(1.5)
    assert mc.extrapolated == pytest.approx(1.0)


def test_two_meshes_assume_first_order_and_say_so():
    mc = mesh_convergence([0.2, 0.1], [1.2, 1.1])
    assert mc.observed_order is None and mc.order_assumed
    assert mc.extrapolated == pytest.approx(1.0)  # c + k h exactly
    assert mc.relative_error == pytest.approx(0.1)
    assert not mc.converged and "first order assumed" in mc.message
    assert mesh_convergence([0.2, 0.1], [1.002, 1.001], rtol=0.01).converged


def test_non_monotone_sequence_is_not_converged():
    mc = mesh_convergence([1.0, 0.5, 0.25], [1.0, 1.2, 1.1])
    assert not mc.converged
    assert mc.observed_order is None and mc.extrapolated is None
    assert "not monotone" in mc.message


def test_growing_differences_are_diverging():
    mc = mesh_convergence([1.0, 0.5, 0.25], [1.0, 2.0, 4.0])
    assert not mc.converged and mc.observed_order == pytest.approx(-1.0)
    assert mc.extrapolated is None and "grow" in mc.message


@pytest.mark.parametrize("n_nodes", [(41, 101, 161), (41, 81, 161), (101, 201, 401)])
def test_dissipation_falling_like_spacing_is_not_converged(n_nodes):
    # a fixed slip zone a at the edge, resolved by one element: W ∝ h → 0 (W = k h)
    length, k = 0.04, 2e-4
    h = [length / (n - 1) for n in n_nodes]
    mc = mesh_convergence(h, [k * x for x in h], rtol=0.05)
    assert mc.observed_order == pytest.approx(1.0, abs=1e-9)
    assert abs(mc.extrapolated) < 1e-12 * k  # limit zero: a discretisation effect
    assert not mc.converged and mc.relative_error == math.inf
    assert "vanishes under refinement" in mc.message


def test_identical_values_are_converged():
    mc = mesh_convergence([1.0, 0.5, 0.25], [3.0, 3.0, 3.0])
    assert mc.converged and mc.relative_error == 0.0 and mc.extrapolated == 3.0


def test_summary_is_flat_with_units():
    mc = mesh_convergence([0.1, 0.05, 0.025], [1.4, 1.1, 1.025], unit="J/m")
    s = mc.summary("dissipation_")
    assert s["dissipation_mesh_converged"] is True  # p = 2, error 0.025 ≤ 0.05
    assert s["dissipation_observed_order"] == pytest.approx(2.0)
    assert s["dissipation_extrapolated"] == pytest.approx(1.0)
    assert s["units"]["dissipation_extrapolated"] == "J/m"
    assert s["units"]["dissipation_mesh_spacing"] == "m"
    assert all(not isinstance(v, dict) for k, v in s.items() if k != "units")
    assert isinstance(mc, MeshConvergence)


@pytest.mark.parametrize("spacing, values", [
    ([0.1], [1.0]), ([0.1, 0.2], [1.0, 2.0]), ([0.1, 0.05], [1.0]),
    ([0.1, -0.05], [1.0, 2.0]), ([0.1, 0.05], [1.0, math.nan])])
def test_bad_sequences_raise_input_error(spacing, values):
    with pytest.raises(InputError):
        mesh_convergence(spacing, values)


@pytest.mark.parametrize("h", [[0.00282, 0.00251], [1.0, 0.9, 0.5], [1.0, 0.5, 0.45]])
def test_meshes_too_close_are_never_called_converged(h):
    """Refinement ratios below 1.3 (Celik et al. 2008): even values that agree to 0.1 %
    give no verdict of convergence, no order and no error estimate, which would look
    precise."""
    f = _sequence(1.0, 0.01, 1.0, h)
    mc = mesh_convergence(h, f)
    assert not mc.converged
    assert "too close" in mc.message and "1.3" in mc.message
    assert mc.extrapolated is None and mc.relative_error is None and mc.observed_order is None
    h2 = [h[0] * 2.0 ** -k for k in range(len(h))]
    assert mesh_convergence(h2, _sequence(1.0, 0.01, 1.0, h2)).converged   # ratio 2
