"""Outputs users can trust (discrete model, shakedown, basins, reduce): errors that name
the right key, sizes refused with their memory, atomic reduce outputs, units and flags for
every summary entry, figures that do not draw round-off, and identical numbers through
every path (CLI run, Python API, demo)."""

from __future__ import annotations

import argparse
import json
import re
import zipfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slipcycle.discrete.case import SUMMARY_FLAGS, read_discrete_case, run_case
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.shakedown import lambda1, lambda2, safe_region
from slipcycle.discrete.steady import simulate
from slipcycle.io import CaseError, parse_case_text, read_case

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
TRIANGLE = EXAMPLES / "shakedown_triangle.toml"

TWO_NODE = """model = "discrete"
[discrete]
{discrete}
A = [[1.0, -0.3], [-0.3, 0.8]]
B = [[0.4, 0.1], [-0.2, 0.3]]
C = [[1.0, -0.2], [-0.2, 1.0]]
friction = 0.5
[loading]
lam = {lam!r}
p0 = {p0}
q0 = [0.0, 0.0]
p1 = [0.3, 0.2]
p1_phase = [0.0, 1.0]
q1 = {q1}
q1_phase = [0.5, 2.0]
[run]
cycles = {cycles}
steps_per_cycle = {steps}
"""


def _two_node(discrete="initial_slip = [0.0, 0.0]", lam=1.0, p0="[1.0, 1.0]",
              q1="[0.4, 0.5]", cycles=40, steps=64):
    return TWO_NODE.format(discrete=discrete, lam=lam, p0=p0, q1=q1, cycles=cycles,
                           steps=steps)


def _one_line_error(code, err, key):
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"error: {key}: "), lines[0]
    return lines[0]


# -- messages that blame the right key -------------------------------------------------


def test_tensile_p0_is_blamed_on_loading_p0_not_on_initial_slip(write_case, run_cli, tmp_path):
    path = write_case(_two_node(p0="[-1.0, 1.0]"))
    code, _, err = run_cli("run", path, "--out", tmp_path / "o")
    line = _one_line_error(code, err, "loading.p0")
    assert "tensile" in line and "node 0" in line
    assert not (tmp_path / "o").exists()


def test_stiffness_file_with_9_nodes_is_blamed_not_initial_slip(write_case, run_cli, tmp_path):
    A = 2.0 * np.eye(9)
    np.savez(tmp_path / "k9.npz", A=A, B=np.zeros((9, 9)), C=A)
    path = write_case('model = "discrete"\n[discrete]\nstiffness_file = "k9.npz"\n'
                      'friction = 0.5\ninitial_slip = [0.0, 0.0]\n[loading]\np0 = [1.0, 1.0]\n')
    code, _, err = run_cli("run", path, "--out", tmp_path / "o")
    line = _one_line_error(code, err, "discrete.stiffness_file")
    assert "9 contact nodes" in line and "2 values per node" in line


@pytest.mark.parametrize("content", ["zip", "object", "npy"])
def test_corrupt_npz_is_not_a_valid_npz_and_never_suggests_pickles(write_case, run_cli,
                                                                    tmp_path, content):
    bad = tmp_path / "bad.npz"
    if content == "zip":
        bad.write_bytes(b"PK\x03\x04" + b"garbage" * 20)
    elif content == "object":
        np.savez(bad, A=np.array([{"a": 1}], dtype=object))
    else:
        with open(bad, "wb") as fh:
            np.save(fh, np.eye(2))
    path = write_case('model = "discrete"\n[discrete]\nstiffness_file = "bad.npz"\n'
                      'friction = 0.5\n[loading]\np0 = [1.0, 1.0]\n')
    code, _, err = run_cli("run", path, "--out", tmp_path / "o")
    line = _one_line_error(code, err, "discrete.stiffness_file")
    assert "not a valid .npz of arrays A, B, C" in line
    assert "pickle" not in line.lower()
    code, _, err = run_cli("reduce", bad, "--out", tmp_path / "r.npz")
    line = _one_line_error(code, err, "bad.npz")
    assert "not a valid .npz" in line and "pickle" not in line.lower()


@pytest.mark.parametrize("command", ["shakedown", "basins"])
def test_rods_case_in_shakedown_or_basins_names_the_commands_that_serve_it(run_cli, tmp_path,
                                                                           command):
    code, _, err = run_cli(command, EXAMPLES / "rods_spec.toml", "--out", tmp_path / "o")
    line = _one_line_error(code, err, "model")
    assert "unknown" not in line and "slipcycle run" in line


# -- sizes refused up front with their memory ---------------------------------------------


def _memory_refusal(code, err, key):
    line = _one_line_error(code, err, key)
    assert re.search(r"need about [\d.e+]+ [kMGTPE]?B of memory \(limit 4 GB\)", line), line


def test_steps_per_cycle_1e9_is_refused_with_its_memory(write_case, run_cli, tmp_path):
    path = write_case(_two_node(steps="1e9"))
    code, _, err = run_cli("run", path, "--out", tmp_path / "o")
    _memory_refusal(code, err, "run.steps_per_cycle")
    assert not (tmp_path / "o").exists()


def test_huge_cycles_recorded_are_refused_naming_cycles(write_case, run_cli, tmp_path):
    path = write_case(_two_node().replace("steps_per_cycle = 64\n", "").replace(
        "cycles = 40", "cycles = 100000000"))
    code, _, err = run_cli("run", path, "--out", tmp_path / "o")
    _memory_refusal(code, err, "run.cycles")


def test_stiffness_file_of_a_million_nodes_is_refused_before_it_is_loaded(write_case,
                                                                        run_cli, tmp_path):
    # only the .npy header of A: the size is judged without reading the data
    header = np.lib.format.header_data_from_array_1_0(np.zeros((1, 1)))
    header["shape"] = (1_000_000, 1_000_000)
    with zipfile.ZipFile(tmp_path / "huge.npz", "w") as zf, zf.open("A.npy", "w") as fh:
        np.lib.format.write_array_header_1_0(fh, header)
    path = write_case('model = "discrete"\n[discrete]\nstiffness_file = "huge.npz"\n'
                      'friction = 0.5\n[loading]\np0 = 1.0\n')
    code, _, err = run_cli("run", path, "--out", tmp_path / "o")
    _memory_refusal(code, err, "discrete.stiffness_file")


@pytest.mark.parametrize("command, option", [("shakedown", "--lam-points"),
                                             ("shakedown", "--starts"),
                                             ("basins", "--grid"), ("basins", "--random")])
def test_huge_counts_are_refused_naming_the_option(run_cli, tmp_path, command, option):
    code, _, err = run_cli(command, TRIANGLE, "--out", tmp_path / "o", option, "1e9")
    _memory_refusal(code, err, option)
    assert not (tmp_path / "o").exists()


# -- reduce: all outputs or none -----------------------------------------------------------


def test_reduce_case_into_unwritable_place_leaves_no_npz_and_names_the_path(tmp_path):
    from slipcycle.cli import cmd_reduce

    (tmp_path / "afile").write_text("not a directory")
    out = tmp_path / "out.npz"
    args = argparse.Namespace(model=EXAMPLES / "fe_block_nu03.toml", out=out,
                              case=tmp_path / "afile" / "case.toml", dof_order=None,
                              quiet=True)
    with pytest.raises(CaseError) as exc:
        cmd_reduce.execute(args)
    assert exc.value.key == str(tmp_path / "afile" / "case.toml")
    assert "\n" not in str(exc.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_reduce_failing_second_rename_restores_the_previous_outputs(tmp_path, monkeypatch):
    from slipcycle.io import results

    a, b = tmp_path / "a.npz", tmp_path / "sub" / "b.toml"
    a.write_text("old a")
    real = results.os.replace

    def replace(src, dst):
        if Path(dst) == b:
            raise PermissionError(13, "Permission denied")
        return real(src, dst)

    monkeypatch.setattr(results.os, "replace", replace)
    with pytest.raises(CaseError) as exc:
        results.write_together([(a, lambda p: p.write_text("new a")),
                                (b, lambda p: p.write_text("new b"))])
    assert exc.value.key == str(b) and "Permission denied" in exc.value.problem
    assert a.read_text() == "old a"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.npz"]


# -- units and flags -------------------------------------------------------------------------


def _numeric_paths(obj, prefix=""):
    """Dotted paths of every numeric leaf (lists of records by their field names)."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k in ("units", "metadata"):
                continue
            yield from _numeric_paths(v, f"{prefix}{k}.")
    elif isinstance(obj, list | tuple | np.ndarray):
        for v in obj:
            yield from _numeric_paths(v, prefix)
    elif isinstance(obj, bool | int | float | np.number | np.bool_):
        yield prefix[:-1]


def _assert_units_cover(summary):
    units = summary["units"]
    for path in set(_numeric_paths(summary)):
        parts = path.split(".")
        assert any(".".join(parts[:i]) in units for i in range(len(parts), 0, -1)), path


def test_run_summary_gives_a_unit_for_every_numeric_entry_and_flags_for_steady_state():
    out = run_case(parse_case_text(_two_node(cycles=3)))
    _assert_units_cover(out.summary)
    assert out.summary["units"]["dissipation_per_cycle"] == "J"
    assert out.summary["units"]["ratchet_per_cycle"] == "m"
    assert out.flags["steady_state"] == ("shakedown", "cyclic_slip", "ratcheting",
                                         "not_converged")
    assert out.summary["steady_state"] in out.flags["steady_state"]
    assert out.summary["f_crit_method"] in SUMMARY_FLAGS["f_crit_method"]


def test_basins_summary_units_flags_and_converged_mask(run_cli, tmp_path, monkeypatch):
    import slipcycle.io as sio
    from slipcycle.discrete.steady import STEADY_CODES


    seen = {}
    orig = sio.write_outputs

    def spy(out_dir, outputs, *a, **k):
        seen["flags"] = outputs.flags
        return orig(out_dir, outputs, *a, **k)

    monkeypatch.setattr(sio, "write_outputs", spy)
    text = TRIANGLE.read_text().replace("cycles = 60", "cycles = 2")
    case = tmp_path / "tri.toml"
    case.write_text(text)
    code, _, err = run_cli("basins", case, "--grid", "6", "--out", tmp_path / "b",
                           "--workers", "1", "--no-progress")
    assert code == 0, err
    s = json.loads((tmp_path / "b" / "summary.json").read_text())
    _assert_units_cover(s)
    assert seen["flags"]["mode"] == ("grid", "random", "protocols")
    with xr.open_dataset(tmp_path / "b" / "result.nc") as ds:
        cls = ds["steady_state"].values
        conv = ds["converged"].values.astype(bool)
    nc = STEADY_CODES.index("not_converged")
    assert (cls == nc).any(), "2 cycles should leave some starts not converged"
    np.testing.assert_array_equal(conv, np.isin(cls, [0, 1, 2]))


# -- figures ---------------------------------------------------------------------------------


def _triangle_cyclic():
    text = re.sub(r"\[\[discrete\.protocol\]\]\np_w = .*\nq_w = .*\n", "",
                  (EXAMPLES / "discrete_triangle_protocol.toml").read_text())
    text = text.replace("friction = 0.5\n", "friction = 0.5\ninitial_slip = [-0.518, 0.528]\n")
    return run_case(parse_case_text(text.replace("steps_per_cycle = 200", "steps_per_cycle = 64")))


def _offset_texts(fig):
    fig.canvas.draw()
    return [t for ax in fig.axes for t in (ax.xaxis.get_offset_text().get_text(),
                                           ax.yaxis.get_offset_text().get_text()) if t]


def test_hysteresis_says_stuck_and_draws_no_round_off_loop():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    out = _triangle_cyclic()
    ds = out.dataset
    assert out.summary["permanently_stuck_nodes"] == [0]
    np.testing.assert_array_equal(ds["permanently_stuck"].values, [1, 0])
    fig = out.figures["hysteresis"]()
    FigureCanvasAgg(fig)
    ax0, ax1 = fig.axes[:2]
    assert ax0.get_lines() == [] and "stuck" in ax0.get_title()
    assert any("permanently stuck" in t.get_text() for t in ax0.texts)
    assert len(ax1.get_lines()) == 1 and ax1.get_title().startswith("node 1")
    assert _offset_texts(fig) == []
    assert "mm" in ax1.get_xlabel() and "mN" in ax1.get_ylabel()


def test_figures_number_nodes_from_0_like_the_summary_and_have_no_offset_text():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    out = _triangle_cyclic()
    assert out.dataset["node"].values.tolist() == [0, 1]
    for name in ("slip_and_tractions", "v_space"):
        fig = out.figures[name]()
        FigureCanvasAgg(fig)
        assert _offset_texts(fig) == [], name
        text = " ".join([ax.get_xlabel() + ax.get_ylabel() for ax in fig.axes] +
                        [t.get_text() for ax in fig.axes if ax.get_legend()
                         for t in ax.get_legend().get_texts()])
        assert "node 0" in text and "node 2" not in text, name


def test_v_space_zooms_on_a_thin_safe_region():
    out = run_case(parse_case_text(_two_node(cycles=5)))
    fig = out.figures["v_space"]()
    assert len(fig.axes) == 2 and "zoom" in fig.axes[1].get_title()


def test_basin_map_marks_not_converged_starts_with_colour_and_legend():
    from slipcycle.plot.shakedown import CLASS_COLORS, basin_map

    v = np.linspace(0.0, 1e-6, 4)
    cls = np.array([[0, 0, 1, 1], [0, 3, 1, 1], [4, 4, 1, 3], [4, 4, 4, 4]])
    D = np.where(cls < 4, 1e-3, np.nan)
    fig = basin_map(v, v, cls, D)
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "not converged (2)" in legend
    assert CLASS_COLORS[3] not in CLASS_COLORS[:3] + CLASS_COLORS[4:]
    assert any("not converged" in t and "last cycle" in t for t in legend)


# -- the same numbers through every path ----------------------------------------------------


def _triangle_text(lam, p0_scale, q1_scale):
    dc = read_discrete_case(read_case(TRIANGLE))
    lam, p0_scale = float(lam), float(p0_scale)
    text = TRIANGLE.read_text().replace("lam = 1.0", f"lam = {lam!r}")
    text = text.replace("p0 = [1.0, 1.0]", f"p0 = [{p0_scale!r}, {p0_scale!r}]")
    q1 = [float(x) for x in dc.load.q.amplitudes[0] * q1_scale]
    text = re.sub(r"q1 = \[.*\]", f"q1 = [{q1[0]!r}, {q1[1]!r}]", text)
    return text.replace("cycles = 60", "cycles = 25").replace("steps_per_cycle = 100",
                                                              "steps_per_cycle = 48")


def _l1():
    dc = read_discrete_case(read_case(TRIANGLE))
    region = safe_region(dc.system, dc.load)
    return lambda1(region, lambda2(region)[0])["lambda1"]


L1 = _l1()

LOADS = st.one_of(
    # shakedown (small λ), cyclic slip, gross slip (λ far above λ2)
    st.tuples(st.floats(0.0, 3.0), st.just(1.0), st.floats(0.5, 1.5)),
    # separation: a mean pressure so small that p reaches 0 during the cycle
    st.tuples(st.floats(0.5, 1.5), st.floats(0.05, 0.3), st.just(1.0)),
    # λ within 1e-6 of λ1
    st.tuples(st.floats(-1e-6, 1e-6).map(lambda d: L1 * (1 + d)), st.just(1.0),
              st.just(1.0)),
)


@settings(max_examples=6, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(LOADS)
def test_cli_run_and_python_api_give_identical_numbers(tmp_path, run_cli, load):
    lam, p0, q1 = load
    text = _triangle_text(lam, p0, q1)
    path = tmp_path / "c.toml"
    path.write_text(text)
    out = tmp_path / "o"
    code, _, err = run_cli("run", path, "--out", out, "--quiet")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    dc = read_discrete_case(read_case(path))
    assert isinstance(dc.load, DiscreteLoad)
    res = simulate(dc.system, dc.load, protocol=dc.protocol, **dc.run)
    assert s["steady_state"] == res.steady_state
    assert s["cycles_run"] == res.cycles_run
    assert s["dissipation_per_cycle"] == res.dissipation_per_cycle
    assert s["dissipation_per_node"] == res.dissipation_per_node.tolist()
    assert s["slipping_nodes"] == res.slipping_nodes
    assert s["separating_nodes"] == res.separating_nodes
    assert s["residual"] == res.residual


def test_demo_discrete_numbers_equal_run_on_the_same_case_text(run_cli, tmp_path,
                                                                monkeypatch):
    """The demo's discrete_two_node summary is what ``run`` gives on the same text (the
    demo narrowed to that case: the other cases are compared by their own tests)."""
    from slipcycle.cli import cmd_demo

    DEMO_CASES = {"discrete_two_node": cmd_demo.DEMO_CASES["discrete_two_node"]}
    monkeypatch.setattr(cmd_demo, "DEMO_CASES", DEMO_CASES)
    code, _, err = run_cli("demo", "--out", tmp_path / "demo")
    assert code == 0, err
    demo = json.loads((tmp_path / "demo" / "discrete_two_node" / "summary.json").read_text())
    case = tmp_path / "two.toml"
    case.write_text(DEMO_CASES["discrete_two_node"][1].strip() + "\n")
    code, _, err = run_cli("run", case, "--out", tmp_path / "run", "--quiet")
    assert code == 0, err
    run = json.loads((tmp_path / "run" / "summary.json").read_text())
    skip = {"wall_time_s", "metadata"}
    assert {k: v for k, v in demo.items() if k not in skip} == \
        {k: v for k, v in run.items() if k not in skip}
