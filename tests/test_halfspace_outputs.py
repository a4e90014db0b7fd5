"""What a half-space run reports: stick zones, tractions, gross slip, units, sizes, messages."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.halfspace import ContactElasticity, Cylinder2D, PowerLaw, RoughExponential, sphere
from slipcycle.halfspace.model import HalfspaceModel, solve
from slipcycle.halfspace.outputs import package, permanent_stick

EL = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
PROFILES = {
    "sphere": sphere(0.01, EL.contact_modulus),
    "cylinder": Cylinder2D(0.01, EL.contact_modulus),
    "power_law_n3": PowerLaw(1e3, 3.0, EL.contact_modulus),
    "rough": RoughExponential(1e-6),
}


def _cell_width_at(bed, P):
    j = int(np.searchsorted(bed.edge_load, P))
    return float(np.max(np.diff(bed.edge_load)[max(j - 2, 0):j + 2]))


@settings(max_examples=30, deadline=None)
@given(st.floats(0.01, 0.99), st.sampled_from(sorted(PROFILES)), st.floats(0.1, 1.0))
def test_permanent_stick_load_is_P_minus_Q_amplitude_over_f(ratio, profile, f):
    """Mindlin loading (constant P, Q = ±Q*): P_D = P − Q*/f for any profile, within one
    slider cell, whatever the rounding at the load reversals."""
    P = 100.0
    model = HalfspaceModel.harmonic(PROFILES[profile], f, 1.2, P0=P, Q1=ratio * f * P,
                                    steps_per_cycle=32, max_cycles=3, n_sliders=400,
                                    assembly_steps=10)
    bed, res = solve(model, record_last_cycle=False)
    P_D, _ = permanent_stick(bed, res)
    assert abs(P_D - P * (1 - ratio)) <= _cell_width_at(bed, P * (1 - ratio))


def test_permanent_stick_of_the_mindlin_demo_is_40_N_in_summary_and_figure():
    model = HalfspaceModel.harmonic(PROFILES["sphere"], 0.5, EL.compliance_ratio, P0=100.0,
                                    Q1=30.0, elasticity=EL, steps_per_cycle=400,
                                    max_cycles=3, n_sliders=2000)
    out = package(model, *solve(model))
    assert out.summary["permanent_stick_load"] == pytest.approx(40.0, abs=0.05)
    c = float(PROFILES["sphere"].contact_size(np.array(40.0)))
    assert out.summary["permanent_stick_size"] == pytest.approx(c, rel=1e-3)
    # the figure's dotted line is the same number
    assert float(out.dataset.permanent_stick_size) == out.summary["permanent_stick_size"]


def test_in_phase_loading_without_slip_sticks_everywhere_at_the_smallest_load():
    model = HalfspaceModel.harmonic(PROFILES["sphere"], 0.5, EL.compliance_ratio, P0=100.0,
                                    P1=40.0, Q1=15.0, steps_per_cycle=64, n_sliders=300)
    bed, res = solve(model, record_last_cycle=False)
    assert permanent_stick(bed, res)[0] == pytest.approx(60.0, rel=1e-9)


@pytest.mark.parametrize("steps", [1, 3, 10, 100])
@pytest.mark.parametrize("ratio", [0.05, 0.3, 0.49])
def test_proportional_ramp_below_f_gives_q_equal_Q_over_P_times_p_at_any_step_count(steps,
                                                                                   ratio):
    """Ciavarella–Jäger: Q/P < f applied proportionally slips nowhere, with no trace of the
    first assembly step's contact radius."""
    model = HalfspaceModel.harmonic(PROFILES["sphere"], 0.5, EL.compliance_ratio, P0=100.0,
                                    Q0=ratio * 100.0, elasticity=EL, assembly_steps=steps,
                                    steps_per_cycle=8, max_cycles=2, n_sliders=500)
    bed, res = solve(model)
    ds = package(model, bed, res).dataset
    q, p = ds.shear_traction.values, ds.pressure.values
    assert np.max(np.abs(q - ratio * p)) <= 1e-9 * p.max()
    assert np.all(res.first_slip == bed.size)        # nothing slips, ever


GROSS = open("src/slipcycle/examples/halfspace_sphere.toml").read().replace("Q1 = 30.0",
                                                                        "Q1 = 80.0")


def test_gross_slip_in_assembly_is_a_result_through_slipcycle_run(run_cli, write_case,
                                                                   tmp_path):
    out = tmp_path / "out"
    code, _, err = run_cli("run", write_case(GROSS), "--out", out, "--quiet")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["steady_state"] == "gross_slip"
    g = s["gross_slip"]
    # Q/P = 0.8 > f on the proportional assembly path: gross slip at its first step
    assert g["cycle"] == -1 and g["Q"] / g["P"] == pytest.approx(0.8)
    assert s["dissipation_per_cycle"] is None
    assert {p.name for p in (out / "figures").iterdir()} == {"hysteresis.png", "load_path.png"}


def test_gross_slip_within_a_cycle_reports_angle_and_draws_the_partial_cycle(run_cli,
                                                                            write_case,
                                                                            tmp_path):
    text = GROSS.replace("Q1 = 80.0", "Q1 = 45.0").replace("P1 = 0.0", "P1 = 40.0").replace(
        "phase = 0.0", "phase = 1.0")
    out = tmp_path / "out"
    code, _, err = run_cli("run", write_case(text), "--out", out, "--quiet")
    assert code == 0, err
    g = json.loads((out / "summary.json").read_text())["gross_slip"]
    assert g["cycle"] == 0 and 0 < g["theta"] < 2 * np.pi
    assert abs(g["Q"]) >= 0.5 * g["P"] * (1 - 1e-9)
    assert (out / "figures" / "hysteresis.png").exists()


def test_summary_has_units_for_every_number_and_flags_for_every_word():
    model = HalfspaceModel.harmonic(RoughExponential(1e-6), 0.5, 1.2, P0=100.0, P1=20.0,
                                    Q1=20.0, phase=1.0, steps_per_cycle=32, n_sliders=100)
    for m in (model, HalfspaceModel.harmonic(PROFILES["sphere"], 0.5, EL.compliance_ratio,
                                             P0=100.0, Q1=30.0, elasticity=EL,
                                             steps_per_cycle=32, n_sliders=100),
              HalfspaceModel.harmonic(PROFILES["cylinder"], 0.5, 1.0, P0=100.0, Q1=30.0,
                                      steps_per_cycle=32, n_sliders=100)):
        out = package(m, *solve(m))
        s = out.summary
        for key, value in s.items():
            if isinstance(value, bool) or key == "units":
                continue
            if isinstance(value, int | float):
                assert key in s["units"], key
            if isinstance(value, str) and key != "model":
                assert value in out.flags[key], key
    assert out.summary["units"]["permanent_stick_load"] == "N/m"       # the cylinder
    assert out.summary["units"]["dissipation_per_cycle"] == "J/m"


MAP = """
model = "halfspace"
[map]
P1_hat = [0.0, 0.4]
Q1_hat = [0.1, 0.3]
phase = [0.0, 1.0]
fig7_Q1_hat = [0.2]
[run]
steps_per_cycle = 32
sliders = 20
"""


def test_map_result_has_units_and_long_names_everywhere(run_cli, write_case, tmp_path):
    out = tmp_path / "map"
    code, _, err = run_cli("map", write_case(MAP), "--out", out)
    assert code == 0, err
    with xr.open_dataset(out / "result.nc") as ds:
        for name in ds.variables:
            assert ds[name].attrs.get("units") and ds[name].attrs.get("long_name"), name
    s = json.loads((out / "summary.json").read_text())
    numeric = [k for k, v in s.items() if isinstance(v, int | float | dict) and k != "units"
               and k != "metadata"]
    for k in numeric:
        if isinstance(s[k], dict):
            assert k in s["units"] or all(f"{k}.{kk}" in s["units"] for kk in s[k]), k
        else:
            assert k in s["units"], k


SPHERE = open("src/slipcycle/examples/halfspace_sphere.toml").read()


@pytest.mark.parametrize("cmd,text,key,memory", [
    ("run", SPHERE.replace("steps_per_cycle = 400", "steps_per_cycle = 400\nsliders = 1e7"),
     "run.sliders", "GB"),
    ("run", SPHERE.replace("steps_per_cycle = 400", "steps_per_cycle = 1e9"),
     "run.steps_per_cycle", "TB"),
    ("map", MAP.replace("steps_per_cycle = 32", "steps_per_cycle = 1e9"),
     "run.steps_per_cycle", "GB"),
    ("map", MAP.replace("phase = [0.0, 1.0]", "phase = {start = 0, stop = 1, num = 100000}")
     .replace("P1_hat = [0.0, 0.4]", "P1_hat = {start = 0, stop = 0.5, num = 100000}"),
     "map.P1_hat", "GB"),
], ids=["run-sliders", "run-steps", "map-steps", "map-grid"])
def test_sizes_that_cannot_be_allocated_are_refused_up_front(run_cli, write_case, tmp_path,
                                                             cmd, text, key, memory):
    out = tmp_path / "out"
    code, _, err = run_cli(cmd, write_case(text), "--out", out)
    assert code == 2 and err.startswith(f"error: {key}: ") and err.count("\n") == 1
    assert "memory" in err and memory in err and "limit 4 GB" in err
    assert not out.exists()
    if key == "run.steps_per_cycle" and cmd == "run":   # the example quoted in the docs
        assert err.strip() == ("error: run.steps_per_cycle: 1000000000 steps per cycle need "
                               "about 64.4 TB of memory (limit 4 GB); reduce steps_per_cycle "
                               "(SLIPCYCLE_MEMORY_LIMIT sets the limit)")


BLAME = [
    ("run", SPHERE.replace("[run]", "[[loading.protocol]]\nP = -5.0\n[run]"),
     "loading.protocol[0].P"),
    ("run", SPHERE.replace("radius = 0.01", "radius = 0.01\ngamma_sigma = 1e-6"),
     "halfspace.gamma_sigma"),
    ("run", SPHERE.replace('profile = "sphere"', 'profile = "rough_exponential"')
     .replace("radius = 0.01", "gamma_sigma = 1e-6\ncompliance_ratio = 1.2"),
     "halfspace.E: not used"),
    ("run", MAP, "slipcycle map"),
    ("map", SPHERE, "slipcycle run"),
    ("map", open("src/slipcycle/examples/discrete_two_node.toml").read(), "slipcycle run"),
]


@pytest.mark.parametrize("cmd,text,expected", BLAME,
                         ids=["protocol", "foreign-key", "rough-E", "map-to-run",
                              "run-to-map", "discrete-to-map"])
def test_messages_blame_the_right_key_or_command(run_cli, write_case, tmp_path, cmd, text,
                                                 expected):
    code, _, err = run_cli(cmd, write_case(text), "--out", tmp_path / "out")
    assert code == 2 and err.startswith("error:") and err.count("\n") == 1
    assert expected in err
