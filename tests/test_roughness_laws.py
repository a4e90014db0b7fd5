"""Normal laws from data: the exponential fit, the convex table, files of P(U), and the
local fretting map of a flat punch (no BEM needed here)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.halfspace import RoughExponential
from slipcycle.halfspace.loads import contact_loads
from slipcycle.halfspace.model import HalfspaceModel, solve
from slipcycle.halfspace.profiles import FlatPunch
from slipcycle.halfspace.topography import (
    BEMLaw,
    convex_minorant,
    fit_exponential,
    read_table_file,
    smooth_table,
)
from slipcycle.studies.roughness import cutoff_within, local_dissipation, punch_rings


def synthetic_law(gamma_sigma, P_knee, decades_exp, noise, seed=0):
    """Hertz-like below P_knee (U ∝ P^(2/3), matched in value and slope), exponential for
    ``decades_exp`` decades above it, then stiffening (saturation) beyond."""
    P = np.geomspace(P_knee / 100, P_knee * 10 ** (decades_exp + 1), 60)
    x = np.log(P / P_knee)
    top = np.log(10) * decades_exp
    # local γσ = dU/dln P: (2/3)U-like growth below, constant, then falling above
    g = np.where(x < 0, gamma_sigma * np.exp(2 * x / 3),
                 np.where(x <= top, gamma_sigma, gamma_sigma * np.exp(-(x - top))))
    U = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]) * np.diff(x))])
    rng = np.random.default_rng(seed)
    return P, U + noise * gamma_sigma * rng.standard_normal(U.size)


@settings(max_examples=15, deadline=None)
@given(gs=st.floats(1e-9, 1e-4), decades=st.floats(1.0, 4.0), seed=st.integers(0, 100))
def test_fit_recovers_gamma_sigma_of_an_exponential_law_to_one_percent(gs, decades, seed):
    P, U = synthetic_law(gs, 1e3, decades, noise=1e-4, seed=seed)
    fit = fit_exponential(P, U, tolerance=0.1)
    assert fit.gamma_sigma == pytest.approx(gs, rel=0.01)
    lo, hi = fit.load_range
    # the window lies in the exponential part, spans most of it, nothing outside the band
    assert lo >= 1e3 * 10 ** -0.2 and hi <= 1e3 * 10 ** (decades + 0.2)
    assert fit.decades >= 0.8 * decades
    assert fit.max_deviation <= 0.1


def test_fit_of_a_law_nowhere_exponential_reports_no_window():
    P = np.geomspace(1, 1e4, 30)
    U = P ** (2 / 3)                       # Hertz: local γσ = (2/3)U grows everywhere
    fit = fit_exponential(P, U, tolerance=0.02)
    assert np.isnan(fit.gamma_sigma) and not fit.in_range.any()


def _law(P, U):
    return BEMLaw(P, U, U.max() - U, np.zeros_like(P), float(U.max()), 1e11, (8, 8),
                  (1e-3, 1e-3), 1e-6)


def test_dense_table_is_convex_and_reproduces_the_exponential_law():
    gs = 4e-7
    p = np.geomspace(1e5, 1e8, 25)
    U = gs * np.log(p / p[0]) + 1e-6
    table = smooth_table(_law(p, U), 1e-4, 500)
    slopes = table.slopes
    assert np.all(np.diff(slopes) >= 0) and np.all(slopes > 0)
    assert table.P[0] == 0.0 and table.U[0] == 0.0
    # compliance between table points is that of the law, C = γσ/P (to O((ΔP/P)²))
    mid = 0.5 * (table.P[1:] + table.P[:-1])
    mid = mid[mid > 0.1 * table.P[-1]]
    np.testing.assert_allclose(table.compliance(mid) * mid, gs, rtol=1e-3)


def test_convex_minorant_removes_a_dent_and_keeps_hull_points():
    U = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    P = np.array([0.0, 1.0, 3.5, 4.0, 8.0])   # (2, 3.5) lies above the chord (1, 1)-(3, 4)
    Uh, Ph = convex_minorant(U, P)
    np.testing.assert_array_equal(Uh, [0, 1, 3, 4])
    assert np.all(np.diff(np.diff(Ph) / np.diff(Uh)) >= 0)


def test_table_files_csv_and_netcdf_read_the_same_law(tmp_path):
    U = np.array([0.0, 1e-6, 2e-6, 3e-6])
    P = np.array([0.0, 1.0, 3.0, 6.0])
    csv = tmp_path / "law.csv"
    csv.write_text("U,P,comment\n" + "".join(f"{u},{p},0\n" for u, p in zip(U, P, strict=True)))
    nc = tmp_path / "law.nc"
    xr.Dataset({"U": ("k", U), "P": ("k", P)}).to_netcdf(nc)
    for path in (csv, nc):
        u, p = read_table_file(path)
        np.testing.assert_array_equal(u, U)
        np.testing.assert_array_equal(p, P)


def test_punch_ring_factors_integrate_to_the_load():
    r, area, c = punch_rings(2e-3, 40)
    assert np.sum(c * area) == pytest.approx(1.0, rel=1e-12)
    assert np.sum(area) == pytest.approx(np.pi * 4e-6, rel=1e-12)
    # ring averages of P/(2πa√(a²−r²)) grow towards the rim
    assert np.all(np.diff(c) > 0)


def test_fretting_map_of_exponential_law_totals_the_joint_dissipation():
    """Tractions of the stuck flat punch are proportional to the loads, so every ring sees
    the same P̂1, Q̂1, φ and dissipates λ_c γσ f² p0 Ŵ per unit area (Barber 2011, §4.6):
    the map integrates to the rough joint's W = λ_c γσ f² P0 Ŵ."""
    gs, f, lam = 5e-7, 0.5, 1.1
    normal, tangential = contact_loads(5000.0, 2000.0, 0.0, 1000.0, np.pi / 2)
    run = dict(steps_per_cycle=100, max_cycles=3, n_sliders=200, assembly_steps=20)
    A = 1e-4
    r, area, c = punch_rings(np.sqrt(A / np.pi), 6)
    W_ring, steady = local_dissipation(RoughExponential(gs), normal, tangential, c,
                                       friction=f, compliance_ratio=lam, **run)
    joint = HalfspaceModel(profile=RoughExponential(gs), elasticity=None, friction=f,
                           compliance_ratio=lam, normal=normal, tangential=tangential, **run)
    W_joint = solve(joint, record_last_cycle=False)[1].dissipation_per_cycle
    assert steady.all()
    assert np.sum(W_ring * area) == pytest.approx(W_joint, rel=1e-6)
    # per unit area, W/p0 is the same on every ring
    np.testing.assert_allclose(W_ring / (c * 5000.0), W_joint / 5000.0, rtol=1e-6)
    # the smooth flat punch sticks: no dissipation (a complete contact)
    punch = HalfspaceModel(profile=FlatPunch(np.sqrt(A / np.pi), 1.1e11), elasticity=None,
                           friction=f, compliance_ratio=lam, normal=normal,
                           tangential=tangential, **run)
    assert abs(solve(punch, record_last_cycle=False)[1].dissipation_per_cycle) < 1e-12 * W_joint


def test_cutoff_crossing_is_interpolated_in_log_wavelength():
    lam = np.array([1.0, 2.0, 4.0, 8.0])
    ratio = np.array([1.0, 1.02, 1.08, 1.5])
    # |dev| goes 0.02 → 0.08 between λ = 2 and 4: 0.05 at the log-midpoint, √8
    assert cutoff_within(lam, ratio, 0.05, short=True) == pytest.approx(np.sqrt(8.0))
    assert cutoff_within(lam, np.ones(4), 0.05, short=True) == 8.0
    assert np.isnan(cutoff_within(lam, ratio, 0.05, short=False))
    assert cutoff_within(lam, ratio[::-1], 0.05, short=False) == pytest.approx(np.sqrt(8.0))


def test_table_of_an_exponential_law_dissipates_as_the_exponential_law():
    """The dense convex table fed to the slider bed reproduces W = λ_c γσ f² P0 Ŵ of the
    exponential law (Barber 2011, §4.6) it samples, to 1 %."""
    gs, A, f, lam = 4e-7, 1e-4, 0.5, 1.15
    p = np.geomspace(1.75e4, 1.75e7, 30)           # three decades up to 1.25 P_max/A
    law = _law(p, gs * np.log(p / p[0]) + 2e-6)
    normal, tangential = contact_loads(1000.0, 400.0, 0.0, 200.0, np.pi / 2)
    run = dict(steps_per_cycle=200, max_cycles=3, n_sliders=1000, assembly_steps=20)
    W = []
    for profile in (smooth_table(law, A, 1000), RoughExponential(gs)):
        m = HalfspaceModel(profile=profile, elasticity=None, friction=f, compliance_ratio=lam,
                           normal=normal, tangential=tangential, **run)
        W.append(solve(m, record_last_cycle=False)[1].dissipation_per_cycle)
    assert W[0] == pytest.approx(W[1], rel=0.01)
