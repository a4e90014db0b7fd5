"""What a sweep stores means what the model says: codes from its flags, units from its
summary, the same numbers as ``slipcycle run`` (issue "Trustworthy outputs")."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.studies.case_sweep import summary_numbers

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"

WORD = st.text(alphabet="abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=12)


@settings(max_examples=40, deadline=None)
@given(words=st.lists(WORD, min_size=1, max_size=8, unique=True), data=st.data())
def test_flag_code_is_the_position_of_the_word_in_the_models_flags(words, data):
    word = data.draw(st.sampled_from(words))
    out = summary_numbers({"steady_state": word}, {"steady_state": tuple(words)})
    code = int(out["steady_state"])
    meanings = out.attrs["steady_state"]["flag_meanings"].split()
    assert meanings == words and meanings[code] == word
    assert out.attrs["steady_state"]["flag_values"] == list(range(len(words)))


def test_a_word_the_model_does_not_list_is_an_error_not_a_code():
    with pytest.raises(ValueError, match="steady_state"):
        summary_numbers({"steady_state": "steady"}, {"steady_state": ("shakedown", "failed")})


def test_words_without_flags_are_stored_as_text():
    out = summary_numbers({"steady_state": "steady", "dissipation_per_cycle": 1.5})
    assert out["steady_state"] == "steady" and "steady_state" not in out.attrs


def test_units_come_from_the_summary_and_are_never_guessed():
    summary = {"dissipation_per_cycle": 2.0, "dissipation_relative_difference": 1e-3,
               "contact_modulus": 1e11, "permanent_stick_load": 40.0, "slip": 1e-6,
               "slipping_nodes": [0, 2], "wall_time_s": 0.1,
               "units": {"dissipation_per_cycle": "J", "contact_modulus": "Pa",
                         "dissipation_relative_difference": "1"}}
    out = summary_numbers(summary)
    assert out.attrs["dissipation_per_cycle"]["units"] == "J"
    assert out.attrs["dissipation_relative_difference"]["units"] == "1"
    assert out.attrs["contact_modulus"]["units"] == "Pa"
    # the model gives no unit: none is invented from the name
    assert "units" not in out.attrs.get("permanent_stick_load", {})
    assert "units" not in out.attrs.get("slip", {})
    assert out["n_slipping_nodes"] == 2 and "wall_time_s" not in out


def _small(name: str) -> str:
    text = (EXAMPLES / name).read_text()
    return (text.replace("cycles = 3", "cycles = 2").replace("cycles = 40  ", "cycles = 8  ")
            .replace("steps_per_cycle = 400", "steps_per_cycle = 60")
            .replace("modes = 50", "modes = 6"))


CASES = {
    "halfspace_sphere": ("halfspace_sphere.toml", "loading.Q1=30.0"),
    "discrete_two_node": ("discrete_two_node.toml", "loading.lam=1.0"),
    "rods": ("rods_spec.toml", "loading.frequency_ratio=0.3"),
}


def _same_number(a, b) -> bool:
    if b is None:
        return bool(np.all(np.isnan(np.asarray(a, float))))
    return np.array_equal(np.asarray(a, float), np.asarray(b, float))


@pytest.mark.parametrize("name", sorted(CASES))
def test_one_cell_sweep_gives_the_numbers_flags_and_units_of_run(name, run_cli,
                                                                  write_case, tmp_path):
    """Cross-path: ``slipcycle sweep`` with one cell stores exactly the summary of
    ``slipcycle run`` on the same case, each categorical entry decoding to the run's
    word, each entry with the run's unit (and none where the run gives none)."""
    file, setting = CASES[name]
    case = write_case(_small(file))
    code, _, err = run_cli("run", case, "--out", tmp_path / "run")
    assert code == 0, err
    code, _, err = run_cli("sweep", case, "--set", setting, "--out", tmp_path / "sweep",
                           "--workers", "1", "--no-progress")
    assert code == 0, err
    run = json.loads((tmp_path / "run" / "summary.json").read_text())
    units = run.get("units", {})
    with xr.open_dataset(tmp_path / "sweep" / "result.nc") as ds:
        stored = [v for v in ds.data_vars if v != "done"]
        for key in stored:
            var = ds[key]
            cell = var.values.reshape(var.shape[1:] if var.ndim > 1 else ())
            if key.startswith("n_") and key[2:] in run and isinstance(run[key[2:]], list):
                assert int(cell) == len(run[key[2:]]), key
                continue
            want = run[key]
            if "flag_meanings" in var.attrs:
                assert var.attrs["flag_meanings"].split()[int(cell)] == want, key
                assert list(var.attrs["flag_values"]) == list(
                    range(len(var.attrs["flag_meanings"].split())))
            elif isinstance(want, str):
                assert str(cell) == want, key
            else:
                assert _same_number(cell, want), (key, cell, want)
                assert var.attrs.get("units") == units.get(key), key
        # every number of the run is in the sweep
        numeric = [k for k, v in run.items() if "wall_time" not in k and k != "n_nodes"
                   and (isinstance(v, bool | int | float) or (
                       isinstance(v, list) and v and all(isinstance(x, int | float)
                                                         for x in v)))]
        missing = [k for k in numeric if k not in stored and f"n_{k}" not in stored]
        assert not missing
        if "steady_state" in run:
            assert "steady_state" in stored
    summary = json.loads((tmp_path / "sweep" / "summary.json").read_text())
    for key, unit in summary["units"].items():
        assert key.startswith(("n_", "axes.")) or units.get(key) == unit, key


def test_converged_halfspace_cells_are_not_stored_as_failed(run_cli, write_case, tmp_path):
    """The regression of the issue: a converged half-space run decodes to its own word
    in the store and in result.nc."""
    import zarr

    case = write_case(_small("halfspace_sphere.toml"))
    out = tmp_path / "s"
    code, _, err = run_cli("sweep", case, "--set", "loading.Q1=10.0,20.0", "--out", out,
                           "--workers", "1", "--no-progress")
    assert code == 0, err
    arr = zarr.open_group(str(out / "sweep.zarr"), mode="r")["steady_state"]
    with xr.open_dataset(out / "result.nc") as ds:
        for meanings, codes in ((arr.attrs.get("flag_meanings"), arr[...]),
                                (ds["steady_state"].attrs.get("flag_meanings"),
                                 ds["steady_state"].values)):
            words = [meanings.split()[int(c)] if meanings else str(c) for c in codes.ravel()]
            assert "failed" not in words and all(w == words[0] for w in words)
            assert words[0] in ("steady", "shakedown", "cyclic_slip")
        assert ds["dissipation_relative_difference"].attrs.get("units") in (None, "1")
        assert ds["contact_modulus"].attrs.get("units") in (None, "Pa")
        assert not math.isnan(float(ds["dissipation_per_cycle"][0]))
