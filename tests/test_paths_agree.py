"""Every path a user can take reaches the same model and says what it ran.

- Python overrides (``slipcycle.run(case, overrides)``, ``slipcycle.api.as_case``) reach
  the model exactly as the same values written in the case file: NumPy values are taken
  as TOML's numbers, and the text of the overridden case (what the studies re-read and
  what the outputs record) holds the overrides.
- A sweep's axes are coordinates of ``result.nc`` with the unit of their case key.
- Every ``summary.json`` and ``result.nc`` names its case by the SHA-256 of its text.
- ``--out`` never replaces what belongs to the user (a folder of their own named
  ``figures``, a ``summary.json`` of another tool) and never lies inside the installed
  package.
- The demo report gives the steady-state class of every case in the shared vocabulary.
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import slipcycle
from slipcycle.api import as_case
from slipcycle.errors import CaseError
from slipcycle.examples import example_path, example_text
from slipcycle.io import parse_case_text
from slipcycle.io.metadata import cf_problems

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


def _small_two_node() -> str:
    return example_text("discrete_two_node").replace("steps_per_cycle = 400",
                                                     "steps_per_cycle = 60")


def _small_sphere() -> str:
    return example_text("halfspace_sphere").replace("steps_per_cycle = 400",
                                                    "steps_per_cycle = 40")


# -- Python overrides -------------------------------------------------------------------

def test_overridden_case_text_is_the_case_that_runs():
    """A study re-reads its case from the text (its worker tasks get text): the text of
    an overridden case must hold the overrides, or a study of ``as_case(path,
    {"loading.lam": 0.5})`` silently runs lam = 1."""
    from slipcycle.studies.basins import load_discrete_case

    path = example_path("discrete_two_node")
    case = as_case(path, {"loading.lam": 0.5, "loading.p1[1]": 0.25})
    assert parse_case_text(case.text).data == case.data
    assert case.data["loading"]["lam"] == 0.5 and case.data["loading"]["p1"] == [0.3, 0.25]
    assert "loading.lam = 0.5" in case.text.splitlines()[0]        # said where it came from
    dc = load_discrete_case(case.text, str(path))
    assert float(dc.load.p.lam) == 0.5
    # the original file is what runs without overrides
    assert as_case(path).text == path.read_text(encoding="utf-8")


def test_numpy_override_values_run_as_the_same_values_in_the_case_file(tmp_path):
    """``run.cycles = np.int64(40)`` was refused ("must be an integer") although the same
    40 in the file runs; every NumPy value reaches the model as its TOML number."""
    text = _small_two_node()
    case = tmp_path / "case.toml"
    case.write_text(text)
    edited = tmp_path / "edited.toml"
    edited.write_text(text.replace("lam = 1.0", "lam = 1.3"))
    by_file = slipcycle.run(edited)
    by_override = slipcycle.run(case, {"run.cycles": np.int64(40),
                                       "loading.lam": np.float64(1.3),
                                       "loading.p1": np.array([0.3, 0.2])})
    assert by_override.steady_state == by_file.steady_state
    assert by_override.cycles_run == by_file.cycles_run
    assert math.isclose(by_override.dissipation_per_cycle, by_file.dissipation_per_cycle,
                        rel_tol=1e-9)


@pytest.mark.parametrize("value", [None, {1, 2}])
def test_an_override_value_toml_cannot_hold_is_refused_naming_its_key(value):
    with pytest.raises(CaseError, match=r"^loading\.lam: cannot write"):
        as_case(example_path("discrete_two_node"), {"loading.lam": value})


# -- sweeps -----------------------------------------------------------------------------

def test_sweep_axes_carry_the_unit_of_their_case_key(run_cli, write_case, tmp_path):
    """An integer axis of forces (``loading.Q1=10,20``) was written with units "1" and a
    float axis with none (a CF gap); each axis now has its key's unit, in result.nc and
    in the summary's ``units`` (``axes.<key>``)."""
    case = write_case(_small_sphere())
    code, _, err = run_cli("sweep", case, "--set", "loading.Q1=10,20", "--set",
                           "halfspace.friction=0.5", "--out", tmp_path / "s",
                           "--workers", "1", "-q")
    assert code == 0, err
    with xr.open_dataset(tmp_path / "s" / "result.nc") as ds:
        assert cf_problems(ds) == []
        assert ds["loading_Q1"].attrs["units"] == "N"
        assert ds["halfspace_friction"].attrs["units"] == "1"
    units = json.loads((tmp_path / "s" / "summary.json").read_text())["units"]
    assert units["axes.loading.Q1"] == "N" and units["axes.halfspace.friction"] == "1"


def test_a_sweep_over_a_list_entry_writes_a_valid_cf_coordinate(run_cli, write_case,
                                                                 tmp_path):
    """``--set loading.p1[0]=...`` wrote the coordinate ``loading_p1[0]``, not a CF
    variable name (CF §2.3)."""
    case = write_case(_small_two_node())
    code, _, err = run_cli("sweep", case, "--set", "loading.p1[0]=0.3", "--out",
                           tmp_path / "s", "--workers", "1", "-q")
    assert code == 0, err
    with xr.open_dataset(tmp_path / "s" / "result.nc") as ds:
        assert cf_problems(ds) == []
        axis = ds["loading_p1_0"]
        assert axis.attrs["long_name"] == "loading.p1[0]" and axis.attrs["units"] == "N"
        assert float(axis[0]) == 0.3


def test_line_loads_of_a_plane_contact_are_swept_in_newtons_per_metre():
    from slipcycle.studies.case_sweep import axis_units

    case = as_case(example_path("halfspace_sphere"))
    assert axis_units(case, "loading.P1") == "N"
    plane = as_case(example_path("halfspace_sphere"), {"halfspace.profile": "cylinder"})
    assert axis_units(plane, "loading.P1") == "N/m"
    assert axis_units(case, "loading.phase") == "rad"
    assert axis_units(case, "halfspace.E[0]") == "Pa"
    assert axis_units(case, "halfspace.no_such_key") is None       # never guessed


# -- provenance -------------------------------------------------------------------------

def test_summary_and_result_nc_name_their_case_by_its_hash(run_cli, write_case, tmp_path):
    text = _small_two_node()
    case = write_case(text)
    code, _, err = run_cli("run", case, "--out", tmp_path / "out", "-q")
    assert code == 0, err
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
    meta = json.loads((tmp_path / "out" / "summary.json").read_text())["metadata"]
    assert meta["case_sha256"] == digest and meta["case_file"] == str(case)
    with xr.open_dataset(tmp_path / "out" / "result.nc") as ds:
        assert ds.attrs["case_sha256"] == digest and ds.attrs["case"] == text
        for pkg in ("slipcycle", "numpy", "scipy"):
            assert ds.attrs[f"version_{pkg}"]


def test_a_case_given_as_text_is_named_by_its_hash_in_summary_json(tmp_path):
    """The demo and Python write results of a case that has no file: its summary, which
    leaves the text out, still says which case it was."""
    from slipcycle.io import write_outputs

    text = _small_two_node()
    res = slipcycle.run(text)
    write_outputs(tmp_path / "out", res.to_outputs(), text, None)
    meta = json.loads((tmp_path / "out" / "summary.json").read_text())["metadata"]
    assert meta["case_file"] == ""
    assert meta["case_sha256"] == hashlib.sha256(text.encode("utf-8")).hexdigest()


# -- --out ------------------------------------------------------------------------------

def test_out_inside_the_installed_package_is_refused(run_cli, write_case):
    case = write_case(_small_two_node())
    before = sorted(p.name for p in EXAMPLES.iterdir())
    for out in (EXAMPLES / "results", EXAMPLES.parent):
        code, _, err = run_cli("run", case, "--out", out)
        assert code == 2
        assert err.count("\n") == 1 and "inside the installed slipcycle package" in err
    assert sorted(p.name for p in EXAMPLES.iterdir()) == before
    assert not (EXAMPLES.parent / "summary.json").exists()


def test_a_users_entries_of_the_result_names_are_not_replaced(run_cli, write_case,
                                                              tmp_path):
    """A run replaces figures/ whole: a user's own figures/ folder (and a summary.json of
    another tool) was deleted without a word. Refused before any work, nothing touched;
    an earlier slipcycle result is still replaced."""
    case = write_case(_small_two_node())
    out = tmp_path / "project"
    (out / "figures").mkdir(parents=True)
    (out / "figures" / "sketch.txt").write_text("mine")
    (out / "notes.txt").write_text("notes")
    code, _, err = run_cli("run", case, "--out", out)
    assert code == 2 and err.count("\n") == 1
    assert "figures" in err and str(out) in err
    assert sorted(p.name for p in out.iterdir()) == ["figures", "notes.txt"]
    assert (out / "figures" / "sketch.txt").read_text() == "mine"

    other = tmp_path / "other"
    other.mkdir()
    (other / "summary.json").write_text('{"mine": 1}\n')
    code, _, err = run_cli("run", case, "--out", other)
    assert code == 2 and "summary.json" in err
    assert (other / "summary.json").read_text() == '{"mine": 1}\n'

    (out / "figures" / "sketch.txt").unlink()          # an empty folder holds nothing
    assert run_cli("run", case, "--out", out, "-q")[0] == 0
    assert run_cli("run", case, "--out", out, "-q")[0] == 0    # an earlier result
    assert (out / "notes.txt").read_text() == "notes"


# -- demo -------------------------------------------------------------------------------

def test_demo_report_gives_the_shared_class_and_the_numbers_of_run(tmp_path):
    """The rods summary has no ``steady_state`` of its own: the report showed no class
    for it. Every case now has its ``steady_state_class`` row, and the report's numbers
    are those of ``slipcycle.run`` on the same text."""
    from slipcycle.demo import write_report

    text = example_text("rods_spec")
    report = write_report(tmp_path, {"rods": ("Rods", text)}).read_text()
    rows = {line.split("|")[1].strip(" `"): line.split("|")[2].strip()
            for line in report.splitlines() if line.startswith("| `")}
    res = slipcycle.run(text)
    assert json.loads(rows["steady_state_class"]) == res.steady_state.value
    assert json.loads(rows["cycles_run"]) == res.cycles_run
    assert math.isclose(json.loads(rows["dissipation_per_cycle"]),
                        res.dissipation_per_cycle, rel_tol=1e-9, abs_tol=1e-300)
    written = json.loads((tmp_path / "rods" / "summary.json").read_text())
    assert written["metadata"]["case_sha256"] == hashlib.sha256(
        (text.strip() + "\n").encode("utf-8")).hexdigest()
    assert tomllib.loads(text)["model"] == written["model"]
