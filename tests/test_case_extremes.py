"""Values at the ends of what the models compute with are refused in one line naming the
key, exit 2, nothing written; values just inside them run.

- A coefficient of friction is 0 (frictionless) or in [1e-12, 1e12] in every model (one
  check, :func:`slipcycle.io.case.friction_range_problem`): f = 1e-300 hung the 3-D engine
  and gave "more than 700 events on one load segment" in 2-D; f = 1e300 overflowed.
- ``slipcycle reduce`` of an ``fe_import`` model refuses a ``[fe_import.discrete]`` table
  whose written ``discrete3d`` case ``slipcycle run`` would refuse (a tensile mean load,
  1e30 cycles), naming the model file's key, before anything is written; the CalculiX
  export is ccx's own (the shipped deck, run here).
"""

from __future__ import annotations

import shutil

import pytest
from calculix import run_ccx
from conftest import ONE_NODE_3D

from slipcycle.examples import example_path


def _run_edited(tmp_path, run_cli, example: str, old: str, new: str):
    """``slipcycle -q run`` of the shipped ``example`` with ``old`` replaced by ``new``
    once: (exit code, stderr)."""
    text = example_path(example).read_text(encoding="utf-8")
    assert old in text
    case = tmp_path / "c.toml"
    case.write_text(text.replace(old, new, 1))
    code, _, err = run_cli("-q", "run", case, "--out", tmp_path / "out")
    return code, err


def _assert_refused(tmp_path, code: int, err: str, key: str) -> None:
    """One line naming ``key``, exit 2, no output folder."""
    assert code == 2 and err.count("\n") == 1 and err.startswith(f"error: {key}:"), err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("f,ok", [("1e-300", False), ("1e-13", False), ("1e-12", True),
                                  ("0.0", True), ("1e12", True), ("1e13", False)])
def test_friction_of_a_3d_node_is_zero_or_within_1e_12_to_1e12(tmp_path, run_cli, f, ok):
    case = tmp_path / "c.toml"
    case.write_text(ONE_NODE_3D.format(f=f))
    code, _, err = run_cli("-q", "run", case, "--out", tmp_path / "out")
    if ok:
        assert code == 0, err
    else:
        assert code == 2 and err.count("\n") == 1 and "discrete3d.friction" in err
        assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("f", ["1e-300", "1e300"])
def test_friction_of_an_fe_model_out_of_range_is_refused_naming_its_key(tmp_path, run_cli, f):
    code, err = _run_edited(tmp_path, run_cli, "fe_block_nu03", "\nfriction = 0.5\n",
                            f"\nfriction = {f}\n")
    _assert_refused(tmp_path, code, err, "fe.discrete.friction")


@pytest.fixture(scope="module")
def calculix_block(tmp_path_factory):
    """The shipped CalculiX block deck, run by ccx: its .sti and .dof beside the model."""
    work = tmp_path_factory.mktemp("ccx_block")
    deck = example_path("calculix_block").with_suffix(".inp").read_text(encoding="utf-8")
    run_ccx(deck, work, jobname="calculix_block")
    shutil.copy(example_path("calculix_block"), work / "calculix_block.toml")
    return work


@pytest.mark.parametrize("edit,key", [
    (("cycles = 200", "cycles = 1000000000000000000000000000000"), "fe_import.discrete."),
    (("normal = 1.0", "normal = -1.0"), "fe_import.discrete.mean"),
    (("friction = 0.5", "friction = 1e300"), "fe_import.discrete.friction"),
])
def test_reduce_refuses_a_discrete_table_whose_case_run_would_refuse(calculix_block, run_cli,
                                                                     edit, key):
    text = (calculix_block / "calculix_block.toml").read_text(encoding="utf-8")
    assert edit[0] in text
    model = calculix_block / "m.toml"
    model.write_text(text.replace(edit[0], edit[1], 1))
    out = calculix_block / "out"
    code, _, err = run_cli("-q", "reduce", model, "--out", out)
    assert code == 2 and err.count("\n") == 1 and key in err, err
    assert not out.exists()


def test_reduce_writes_a_case_that_runs(calculix_block, run_cli):
    out = calculix_block / "good"
    code, _, err = run_cli("-q", "reduce", calculix_block / "calculix_block.toml",
                           "--out", out)
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["case.toml", "report.txt",
                                                     "stiffness.npz"]


def test_loads_too_far_apart_for_double_precision_are_named_as_the_cause(tmp_path, run_cli):
    """A tangential amplitude of 1e10 m on a 1 µm preload: the 2-D rate problem has no
    solution (the preload is below the round-off of the tangential forces); with f checked
    below f_crit the message names the load sizes, not f (it blamed f_crit before)."""
    code, err = _run_edited(tmp_path, run_cli, "fe_block_nu03", "tangential = 1.5e-6",
                            "tangential = 1e10")
    assert code == 3 and err.count("\n") == 1
    assert "loads of sizes too far apart for double precision" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("example,old,new,key", [
    ("halfspace_sphere", "radius = 0.01", "radius = 1e-300", "halfspace.radius"),
    ("halfspace_rough", "P0 = 1000.0", "P0 = 0.0", "loading.P0"),
    ("halfspace_rough", "P1 = 400.0", "P1 = 1400.0", "loading.P1"),
])
def test_halfspace_loads_and_sizes_out_of_range_blame_their_own_key(tmp_path, run_cli,
                                                                    example, old, new, key):
    """A sphere of radius 1e-300 m overflowed 1/(2R) (an internal error); a rough
    contact whose mean P0 is not compressive blamed the amplitude P1."""
    code, err = _run_edited(tmp_path, run_cli, example, old, new)
    _assert_refused(tmp_path, code, err, key)


def test_a_rough_surface_pressed_below_1e_12_of_its_modulus_is_refused(tmp_path, run_cli):
    """nominal_area = 1e300 m²: the BEM ran 20000 iterations at 7.5e-300 Pa and ended in
    a solver error (exit 3, after numerical warnings)."""
    pytest.importorskip("ContactMechanics")
    code, _, err = run_cli("-q", "examples", "halfspace_topography", "--copy", tmp_path)
    assert code == 0, err
    case = tmp_path / "halfspace_topography.toml"
    text = case.read_text(encoding="utf-8")
    line = next(ln for ln in text.splitlines() if ln.startswith("nominal_area"))
    case.write_text(text.replace(line, "nominal_area = 1e300", 1))
    code, _, err = run_cli("-q", "run", case, "--out", tmp_path / "out")
    assert code == 2 and err.count("\n") == 1
    assert err.startswith("error: halfspace.nominal_area:") and "1e-12 E*" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("old,new,key", [
    ("width = 0.04", "width = 1e-300", "fe.width"),
    ("width = 0.04", "width = 1e300", "fe.width"),
    ("thickness = 0.01", "thickness = 1e-300", "fe.thickness"),
    ("height = 0.02", "height = 1e-300", "fe.height"),
    ("height = 0.02", "height = 200", "fe.height"),      # 5000 times the width
    ("width = 0.04", "width = 1e-9", "fe.height"),       # 2e7 times the width
])
def test_fe_geometry_beyond_double_precision_is_refused_naming_its_key(tmp_path, run_cli,
                                                                      old, new, key):
    """Lengths outside [1e-9, 1e9] m and bodies more slender than 1e-7 … 100 times their
    width: before, numerical warnings filled the output and the message blamed a
    platen tie, the material constants or fe.discrete.friction."""
    code, err = _run_edited(tmp_path, run_cli, "fe_block_nu03", old, new)
    _assert_refused(tmp_path, code, err, key)


@pytest.mark.parametrize("old,new,key", [
    ("cycles = 40", "cycles = 1000000000000000000000000000000", "fe.discrete.cycles"),
    ("steps_per_cycle = 400", "steps_per_cycle = 1000000000000000000000000000000",
     "fe.discrete.steps_per_cycle"),
])
def test_fe_run_counts_beyond_memory_blame_the_count(tmp_path, run_cli, old, new, key):
    """1e30 cycles were refused as fe.convergence.refinements (the mesh study)."""
    code, err = _run_edited(tmp_path, run_cli, "fe_block_nu03", old, new)
    _assert_refused(tmp_path, code, err, key)
