"""A half-space run warns when its contact is too large for the half-space theory.

Hertz (Johnson 1985, §4.2): a sphere of radius R under P has a = (3PR/(4E*))^{1/3}, a
cylinder under P per length a = (4PR/(πE*))^{1/2}; both theories assume a ≪ R (a profile
slope a/R at the contact edge below about 0.1). A radius given in mm as m, or a modulus in
GPa as Pa, gives a/R ≫ 1 and results that no physical contact has: the summary and the
log say so (the run still completes: the model is defined at any size).
"""

from __future__ import annotations

import json
import logging

import pytest

from slipcycle.halfspace import sphere
from slipcycle.halfspace.case import parse_case
from slipcycle.halfspace.model import solve
from slipcycle.halfspace.profiles import Cylinder2D, slope_warning
from slipcycle.io import parse_case_text

E, NU, R = 200e9, 0.3, 0.01
E_STAR = E / (2 * (1 - NU**2))

CASE = """
model = "halfspace"
[halfspace]
profile = "{profile}"
radius = {R}
E = [{E}, {E}]
nu = [{NU}, {NU}]
friction = 0.5
[loading]
P0 = {P!r}
Q1 = {Q!r}
[run]
cycles = 3
steps_per_cycle = 40
sliders = 200
"""


def _case(profile: str, P: float) -> str:
    return CASE.format(profile=profile, R=R, E=E, NU=NU, P=P, Q=0.25 * P)


def test_edge_slope_is_a_over_R_of_hertz():
    P = 1e5
    a_sphere = (3 * P * R / (4 * E_STAR)) ** (1 / 3)
    assert float(sphere(R, E_STAR).edge_slope(P)) == pytest.approx(a_sphere / R, rel=1e-12)
    a_cyl = (4 * P * R / (3.141592653589793 * E_STAR)) ** 0.5
    assert float(Cylinder2D(R, E_STAR).edge_slope(P)) == pytest.approx(a_cyl / R, rel=1e-12)


@pytest.mark.parametrize("profile,P_small,P_large", [("sphere", 100.0, 1e6),
                                                     ("cylinder", 1e4, 7e7)])
def test_a_contact_large_against_its_radius_is_warned_of(profile, P_small, P_large, caplog):
    for P, warned in ((P_small, False), (P_large, True)):
        model = parse_case(parse_case_text(_case(profile, P)))
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="slipcycle"):
            solve(model, record_last_cycle=False)
        messages = [r.getMessage() for r in caplog.records if "profile slope" in r.getMessage()]
        assert bool(messages) == warned
        assert bool(slope_warning(model.profile, P)) == warned


def test_the_summary_and_the_command_line_carry_the_warning(tmp_path, run_cli):
    case = tmp_path / "large.toml"
    case.write_text(_case("sphere", 1e6))   # a = 4.1 mm on R = 10 mm
    code, _, err = run_cli("run", case, "--out", tmp_path / "out")
    assert code == 0, err
    lines = [ln for ln in err.splitlines() if "profile slope" in ln]
    assert len(lines) == 1 and "0.41" in lines[0]
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert any("profile slope of 0.41" in w for w in s["warnings"])
    case.write_text(_case("sphere", 100.0))
    code, _, err = run_cli("run", case, "--out", tmp_path / "out2")
    assert code == 0 and "profile slope" not in err
    assert "warnings" not in json.loads((tmp_path / "out2" / "summary.json").read_text())
