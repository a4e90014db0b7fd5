"""BEM normal laws of rough surfaces against closed forms (slipcycle.halfspace.topography).

References: Westergaard (1939) and Johnson, Greenwood & Higginson (1985) for the wavy
surface h cos(2πx/λ) on an elastic half-space: complete contact at p* = π E* h/λ, contact
width 2a with p̄/p* = sin²(πa/λ), and mean gap ḡ/h = 1 − ψ + ψ ln ψ with ψ = p̄/p* (from
the Westergaard displacements integrated over a period).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("ContactMechanics")
pytest.importorskip("SurfaceTopography")

from slipcycle.halfspace.topography import (  # noqa: E402
    SurfaceMap,
    bem_normal_law,
    cached_bem_normal_law,
    filter_surface,
    fit_exponential,
    read_surface,
    resample,
    synthetic_surface,
)

E_STAR = 1.0e11
LAM = 1.0e-3
H = 1.0e-6


def wavy(n: int = 128) -> SurfaceMap:
    x = np.arange(n) * LAM / n
    return SurfaceMap(np.tile(H * np.cos(2 * np.pi * x / LAM)[:, None], (1, 4)),
                      (LAM, 4 * LAM / n))


def test_wavy_surface_follows_westergaard_mean_gap_and_contact_width():
    p_star = np.pi * E_STAR * H / LAM
    psi = np.array([0.05, 0.3, 0.7])
    law = bem_normal_law(wavy(), E_STAR, psi * p_star)
    gap_ref = H * (1 - psi + psi * np.log(psi))
    np.testing.assert_allclose(law.mean_gap, gap_ref, atol=2e-3 * H)
    np.testing.assert_allclose(law.approach, H - gap_ref, atol=2e-3 * H)
    width_ref = 2 * np.arcsin(np.sqrt(psi)) / np.pi
    # contact width resolved to the grid: within two pixels of 128
    np.testing.assert_allclose(law.contact_fraction, width_ref, atol=2.5 / 128)
    assert law.first_touch_gap == pytest.approx(H, rel=1e-12)


def test_wavy_surface_closes_at_johnson_full_contact_pressure():
    p_star = np.pi * E_STAR * H / LAM
    law = bem_normal_law(wavy(), E_STAR, np.array([0.95, 1.05]) * p_star)
    assert law.contact_fraction[0] < 0.95
    assert law.contact_fraction[1] == 1.0
    assert law.mean_gap[1] == pytest.approx(0.0, abs=1e-6 * H)


def test_filtered_surface_law_converges_in_bem_grid():
    """A surface without wavelengths below L/8 on grids 64 and 128 (8 and 16 pixels per
    shortest wavelength): stiffness within 1 %, mean gap within 1 % of σ. (The approach
    is measured from the highest grid point, whose height depends on the grid; only its
    differences enter the dissipation.)"""
    topo = synthetic_surface(64, 1e-3, hurst=0.8, rms_height=1e-6, long_cutoff=2.5e-4,
                             seed=3)
    s = filter_surface(SurfaceMap(np.array(topo.heights()), topo.physical_sizes),
                       short_cutoff=1e-3 / 8)
    p = np.geomspace(3e6, 1e8, 8)
    coarse = bem_normal_law(resample(s, 64), 1.1e11, p)
    fine = bem_normal_law(resample(s, 128), 1.1e11, p)
    np.testing.assert_allclose(coarse.stiffness(p[1:-1]), fine.stiffness(p[1:-1]), rtol=0.01)
    np.testing.assert_allclose(coarse.mean_gap, fine.mean_gap, atol=0.01 * s.rms_height)


def test_fourier_resampling_is_exact_for_band_limited_surfaces():
    topo = synthetic_surface(32, 1e-3, hurst=0.7, rms_height=1e-6, short_cutoff=1e-3 / 8,
                             seed=5)
    s = SurfaceMap(np.array(topo.heights()), topo.physical_sizes)
    back = resample(resample(s, 64), 32)
    np.testing.assert_allclose(back.heights, s.heights, atol=1e-12 * s.rms_height + 1e-20)
    assert resample(s, 64).rms_height == pytest.approx(s.rms_height, rel=1e-12)


def test_bem_law_is_cached_by_surface_and_parameters(tmp_path):
    s = wavy(32)
    p = np.array([0.2, 0.5]) * np.pi * E_STAR * H / LAM
    law, path, hit = cached_bem_normal_law(s, E_STAR, p, directory=tmp_path)
    assert not hit and path is not None and path.is_file()
    again, path2, hit2 = cached_bem_normal_law(s, E_STAR, p, directory=tmp_path)
    assert hit2 and path2 == path
    np.testing.assert_array_equal(again.approach, law.approach)
    _, path3, hit3 = cached_bem_normal_law(s, 2 * E_STAR, p, directory=tmp_path)
    assert not hit3 and path3 != path


def test_rough_surface_is_exponential_over_a_window_with_gamma_of_order_one():
    """Persson/Akarapu: dP/dU ≈ P/(γσ) with γ of order one at moderate loads."""
    topo = synthetic_surface(64, 1e-3, hurst=0.8, rms_height=1e-6, short_cutoff=1e-3 / 16,
                             long_cutoff=2.5e-4, seed=1)
    s = SurfaceMap(np.array(topo.heights()), topo.physical_sizes)
    law = bem_normal_law(s, 1.1e11, np.geomspace(1e6, 3e8, 14))
    fit = fit_exponential(law.pressure, law.approach, 0.1)
    assert 0.2 < fit.gamma_sigma / s.rms_height < 1.0
    assert fit.decades > 0.5


@settings(max_examples=10, deadline=None)
@given(cut=st.floats(2.0 / 32, 1.0), seed=st.integers(0, 50))
def test_short_and_long_filters_split_the_surface(cut, seed):
    """Removing wavelengths below λ and, separately, above λ splits the map into two parts
    that add up to it (every Fourier component is in exactly one)."""
    rng = np.random.default_rng(seed)
    s = SurfaceMap(rng.standard_normal((32, 32)) * 1e-6, (1e-3, 1e-3))
    # both filters cut at the same value, set off the grid's wavelengths L/|k| so that a
    # component at λ = L/10 cannot fall on either side by rounding (0.1·L ≠ L/10 in floats)
    lam = cut * 1e-3 * (1 - 1e-12)
    low = filter_surface(s, short_cutoff=lam)
    high = filter_surface(s, long_cutoff=lam)
    np.testing.assert_allclose(low.heights + high.heights, s.heights, atol=1e-18)
    assert low.rms_height**2 + high.rms_height**2 == pytest.approx(s.rms_height**2,
                                                                   rel=1e-9)


def test_non_periodic_scan_in_micrometres_is_read_in_metres_and_mirror_stitched(tmp_path):
    from SurfaceTopography import Topography

    h = np.random.default_rng(0).standard_normal((16, 12))
    Topography(h, (16.0, 12.0), periodic=False, unit="µm").to_netcdf(str(tmp_path / "s.nc"))
    s = read_surface(tmp_path / "s.nc")
    assert not s.periodic and s.grid == (32, 24)
    assert s.size == pytest.approx((32e-6, 24e-6))
    # mirror images keep the heights: the map holds the detrended scan, in metres
    assert s.heights.max() < 10e-6 and s.rms_height == pytest.approx(
        np.std(s.heights[:16, :12]), rel=0.2)
