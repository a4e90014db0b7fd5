"""`slipcycle run` / `slipcycle limits` for model = "rods": outputs and refused input."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from conftest import case_text

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "src" / "slipcycle" / "examples"

def _base(interface: str, modes: int, amp: float) -> str:
    """The specification's rods case with the interface, modes and amplitude set."""
    return case_text("rods_spec", rods={"interface": interface, "modes": modes},
                     loading={"rotation_amplitude": amp},
                     run={"steps_per_cycle": 200, "regularisation_points": 10})


def test_spec_example_runs_as_written(run_cli, tmp_path):
    case = tmp_path / "rods.toml"
    shutil.copy(EXAMPLES / "rods_spec.toml", case)
    code, out, err = run_cli("run", case, "--out", tmp_path / "out", "--quiet")
    assert code == 0, err
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    for key in ("omega1", "T_dyn_max", "T_qs_max", "torque_ratio", "dissipation_per_cycle",
                "slip_inception_amplitude_dyn", "slip_inception_amplitude_qs"):
        assert key in s
    assert s["dissipation_per_cycle"] == 0.0 and not s["slipped"]  # far below inception
    assert s["torque_ratio"] == pytest.approx(1.0386, abs=1e-3)  # stuck: 1/(1-...) at 0.3 ω1
    assert (tmp_path / "out" / "result.nc").exists()
    assert (tmp_path / "out" / "figures" / "regularisation.png").exists()
    reg = s["regularisation"]
    assert reg["jenkins"]["slope_microslip"] is None and reg["coulomb"]["slope_microslip"] is None
    assert reg["distributed"]["slope_macroslip"] == pytest.approx(1.0, abs=0.1)
    # Iwan: small-amplitude slope close to 3 + chi
    assert reg["iwan"]["slope_microslip"] == pytest.approx(3 + reg["iwan_fit"]["chi"], abs=0.5)


@pytest.mark.parametrize("interface", ["distributed", "coulomb", "jenkins", "iwan", "welded"])
def test_every_interface_runs_with_slip(run_cli, write_case, tmp_path, interface):
    case = write_case(_base(interface=interface, modes=10, amp=0.02)
                      .replace("regularisation_points = 10", "regularisation = false"))
    code, out, err = run_cli("run", case, "--out", tmp_path / "o", "--quiet")
    assert code == 0, err
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["steady_state_reached"]
    assert abs(s["energy_balance_error"]) < 1e-3
    if interface == "welded":
        assert s["dissipation_per_cycle"] == 0.0
    else:
        assert s["dissipation_per_cycle"] > 0.0
        assert s["T_dyn_max"] <= s["gross_slip_torque"] * (1 + 1e-9)
    # result.nc answers the headline numbers too, in J
    import xarray as xr

    with xr.open_dataset(tmp_path / "o" / "result.nc") as ds:
        for key in ("dissipation_per_cycle", "dissipation_per_cycle_qs"):
            assert float(ds[key]) == s[key] and ds[key].attrs["units"] == "J"


@pytest.mark.parametrize("edit, key", [
    (("friction = 0.3", "friction = -0.1"), "rods.friction"),
    (("L = [0.5, 0.5]", "L = [0.5]"), "rods.L"),
    (("modes = 10", "modes = 0"), "rods.modes"),
    (("interface = \"distributed\"", "interface = \"glue\""), "rods.interface"),
    (("interface_stiffness = 1.0e13\n", ""), "rods.interface_stiffness"),
    (("frequency_ratio = 0.3", "frequency_ratio = 0.3\nfrequency = 100.0"),
     "loading.frequency_ratio"),
    (("damping_ratio = 0.01", "damping_ratio = 0.01\ndampng = 1"), "rods.dampng"),
    (("axial_force = 1.0e4", "axial_force = 0.0"), "rods.axial_force"),
    (("rotation_amplitude = 0.02", "rotation_amplitude = nan"), "loading.rotation_amplitude"),
])
def test_bad_input_refused_with_key(run_cli, write_case, tmp_path, edit, key):
    text = _base(interface="distributed", modes=10, amp=0.02).replace(*edit)
    code, out, err = run_cli("run", write_case(text), "--out", tmp_path / "o")
    assert code == 2
    assert err.startswith(f"error: {key}:"), err
    assert not (tmp_path / "o").exists()


def test_limits_command_small_grid(run_cli, write_case, tmp_path):
    text = _base(interface="distributed", modes=10, amp=0.014) + """
[limits]
frequency_ratio = {start = 0.02, stop = 1.0, num = 8}
amplitude_ratio = [0.5, 1.0, 2.0]
position = [0.3, 0.5]
position_frequencies = 3
"""
    code, out, err = run_cli("limits", write_case(text), "--tolerance", "0.05", "--out",
                             tmp_path / "l")
    assert code == 0, err
    s = json.loads((tmp_path / "l" / "summary.json").read_text())
    assert s["qs_limit_frequency_ratio_status"] == "found"
    assert 0.1 < s["qs_limit_frequency_ratio"] < 0.6
    assert s["map_shape"] == [8, 3]
    for f in ("limit_frequency", "regime_map", "position_map"):
        assert (tmp_path / "l" / "figures" / f"{f}.png").exists()


def test_limits_refuses_bad_tolerance(run_cli, write_case, tmp_path):
    text = _base(interface="distributed", modes=10, amp=0.014)
    code, out, err = run_cli("limits", write_case(text), "--tolerance", "2", "--out",
                             tmp_path / "l")
    assert code == 2 and "--tolerance" in err
