"""Every profile and control mode through the case-file path, against physics."""

from __future__ import annotations

import numpy as np
import pytest

from slipcycle.halfspace.case import parse_case
from slipcycle.halfspace.model import solve
from slipcycle.halfspace.profiles import sphere
from slipcycle.io import parse_case_text

HEAD = """
model = "halfspace"
[halfspace]
{profile}
friction = 0.5
[loading]
{loading}
[run]
cycles = 4
steps_per_cycle = 400
sliders = 2000
"""
SPHERE = 'profile = "sphere"\nradius = 0.01\nE = [200e9, 200e9]\nnu = [0.3, 0.3]'


def run(profile, loading):
    model = parse_case(parse_case_text(HEAD.format(profile=profile, loading=loading)))
    bed, res = solve(model)
    return model, bed, res


def test_tabulated_profile_reproduces_the_sphere():
    prof = sphere(0.01, 200e9 / (2 * (1 - 0.09)))
    P = np.linspace(0, 150, 3001) ** 1.0
    U = prof.approach(P)
    table = (f"profile = \"tabulated\"\ntable_U = {U.tolist()}\ntable_P = {P.tolist()}\n"
             f"compliance_ratio = {(2 - 0.3) / (2 * 0.7)}")
    loading = "P0 = 100.0\nP1 = 30.0\nQ1 = 25.0\nphase = 1.0"
    _, _, ref = run(SPHERE, loading)
    _, bed, tab = run(table, loading)
    assert bed.size > 2000  # one slider per change of slope
    assert tab.dissipation_per_cycle == pytest.approx(ref.dissipation_per_cycle, rel=5e-3)


def test_flat_punch_has_no_microslip_until_gross_slip():
    """All of a flat punch touches at one level: Q < fP sticks everywhere (W = 0)."""
    punch = 'profile = "flat_punch"\nradius = 0.002\nE = [200e9, 200e9]\nnu = [0.3, 0.3]'
    _, _, res = run(punch, "P0 = 100.0\nQ1 = 45.0")
    assert res.steady and abs(res.dissipation_per_cycle) < 1e-15
    _, _, res = run(punch, "P0 = 100.0\nQ1 = 50.5")
    assert res.gross_slip is not None


def test_power_law_n2_is_the_sphere():
    pl = ('profile = "power_law"\ncoefficient = 50.0\nexponent = 2.0\n'
          'E = [200e9, 200e9]\nnu = [0.3, 0.3]')
    loading = "P0 = 100.0\nQ1 = 30.0"
    _, _, a = run(pl, loading)
    _, _, b = run(SPHERE, loading)
    assert a.dissipation_per_cycle == pytest.approx(b.dissipation_per_cycle, rel=1e-9)


def test_displacement_control_gives_the_same_loop_as_force_control():
    _, _, force = run(SPHERE, "P0 = 100.0\nQ1 = 30.0")
    last = force.cycle == force.cycle.max()
    V_amp = 0.5 * (force.V[last].max() - force.V[last].min())
    V_mid = 0.5 * (force.V[last].max() + force.V[last].min())
    # same start: the force-controlled assembly ends at Q = 30 N, V = V(30 N)
    _, _, disp = run(SPHERE, f"P0 = 100.0\nV0 = {V_mid}\nV1 = {V_amp}")
    assert disp.dissipation_per_cycle == pytest.approx(force.dissipation_per_cycle, rel=2e-3)
    # the loop's Q range is ±30 N; its mean may shift, since the assemblies differ
    Q_last = disp.Q[disp.cycle == disp.cycle.max()]
    assert 0.5 * (Q_last.max() - Q_last.min()) == pytest.approx(30.0, rel=2e-3)


def test_approach_control_matches_force_control():
    model, bed, force = run(SPHERE, "P0 = 100.0\nP1 = 30.0\nQ1 = 20.0\nphase = 0.7")
    U0 = float(bed.approach(np.array([100.0]))[0])
    # a harmonic P is not a harmonic U, so compare with a tabulated U(θ) of the same path
    theta = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    U = bed.approach(100 + 30 * np.cos(theta))
    Q = 20 * np.cos(theta - 0.7)
    loading = (f"theta = {theta.tolist()}\nU = {U.tolist()}\nQ = {Q.tolist()}")
    _, _, app = run(SPHERE, loading)
    assert U0 > 0
    assert app.dissipation_per_cycle == pytest.approx(force.dissipation_per_cycle, rel=5e-3)


def test_cylinder_plane_dissipation_does_not_depend_on_reference_depth():
    base = 'profile = "cylinder"\nradius = 0.02\nE = [200e9, 200e9]\nnu = [0.3, 0.3]'
    loading = "P0 = 1e5\nP1 = 3e4\nQ1 = 2e4\nphase = 1.0"
    _, _, a = run(base, loading)
    _, _, b = run(base + "\nreference_depth = 0.2", loading)
    assert a.dissipation_per_cycle > 0
    assert b.dissipation_per_cycle == pytest.approx(a.dissipation_per_cycle, rel=5e-3)
