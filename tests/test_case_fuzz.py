"""Defects found by mutation fuzzing of the shipped example cases through every command.

Each mutation that ended in a traceback, an internal error (exit 4), a hang, or a run that
silently accepted nonsense is kept here: the case is refused before any computation with
one line on stderr naming the key (exit code 2) and no output written.
"""

from __future__ import annotations

import tomllib

import pytest

from slipcycle.examples import example_text


def _toml(value) -> str:
    """``value`` as a TOML inline value (numbers, strings, nested lists)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, str):
        return f'"{value}"'
    return repr(value)


def _mutated(example: str, changes: dict) -> str:
    """The example's text with ``table.key = value`` lines set (added when absent); the
    other lines, comments included, are kept as written."""
    doc = tomllib.loads(example_text(example))
    text = example_text(example)
    for dotted, value in changes.items():
        table, key = dotted.rsplit(".", 1)
        lines = text.splitlines()
        start = next(i for i, ln in enumerate(lines)
                     if ln.split("#")[0].strip() == f"[{table}]")
        end = next((i for i in range(start + 1, len(lines))
                    if lines[i].startswith("[")), len(lines))
        new = f"{key} = {_toml(value)}"
        if key in doc[table]:   # one-line assignments only (the keys changed here)
            i = next(i for i in range(start + 1, end) if lines[i].split("=")[0].strip() == key)
            lines[i] = new
        else:
            lines.insert(start + 1, new)
        text = "\n".join(lines) + "\n"
    assert tomllib.loads(text)  # still TOML
    return text


def _refused(run_cli, tmp_path, command: list[str], text: str, key: str) -> str:
    case = tmp_path / "case.toml"
    case.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    code, stdout, err = run_cli(command[0], case, "--out", out, *command[1:])
    lines = err.strip().splitlines()
    assert code == 2, (code, err)
    assert len(lines) == 1, err
    assert lines[0].startswith(f"error: {key}:"), lines[0]
    assert not out.exists()
    return lines[0]


# -- discrete3d [run]: the checks of the 2-D reader were missing --------------------------

@pytest.mark.parametrize("changes, key, words", [
    # one load sample per cycle sees a constant load: "shakedown, D = 0" whatever the load
    ({"run.steps_per_cycle": 1}, "run.steps_per_cycle", ">= 4"),
    ({"run.steps_per_cycle": 3}, "run.steps_per_cycle", ">= 4"),
    # min_cycles above cycles: stopped at cycles and called a steady cycle "not converged"
    ({"run.min_cycles": 50}, "run.min_cycles", "<= cycles (40)"),
    # an internal "Maximum allowed size exceeded" (exit 4), or minutes of allocation
    ({"run.steps_per_cycle": 10**30}, "run.steps_per_cycle", "memory"),
    ({"run.steps_per_cycle": 100_000_000}, "run.steps_per_cycle", "memory"),
])
def test_discrete3d_run_settings_that_cannot_give_a_cycle_are_refused(run_cli, tmp_path,
                                                                      changes, key, words):
    line = _refused(run_cli, tmp_path, ["run"], _mutated("discrete3d_three_node", changes),
                    key)
    assert words in line


def test_discrete3d_basins_refuses_one_step_per_cycle_as_run_does(run_cli, tmp_path):
    text = _mutated("discrete3d_three_node", {"run.steps_per_cycle": 2})
    _refused(run_cli, tmp_path, ["basins", "--random", "2", "--workers", "1"], text,
             "run.steps_per_cycle")


# -- loads whose elastic energy overflows double precision ---------------------------------

@pytest.mark.parametrize("example, changes, key", [
    # 3-D: OverflowError in the step control (exit 4)
    ("discrete3d_three_node", {"loading.lam": 1e300}, "loading.lam"),
    ("discrete3d_three_node", {"loading.p0": [1e300, 1.2, 1.0]}, "loading.p0"),
    ("discrete3d_three_node", {"loading.p1": [1e300, 0.0, 0.2]}, "loading.p1"),
    # 2-D: "shakedown" with overflow warnings and no energy balance
    ("discrete_two_node", {"loading.p1": [1e300, 0.2]}, "loading.p1"),
    ("discrete_two_node", {"loading.p0": [1e160, 1e160]}, "loading.p0"),
    ("discrete_two_node", {"loading.lam": 1e300}, "loading.lam"),
])
def test_loads_whose_energy_overflows_are_refused_naming_the_largest_load_key(
        run_cli, tmp_path, example, changes, key):
    line = _refused(run_cli, tmp_path, ["run"], _mutated(example, changes), key)
    assert "energy" in line and "units" in line


def test_large_but_representable_loads_still_run_with_a_balanced_energy(run_cli, tmp_path):
    # 1e12 N on a 1 N/m system: 1e24 J, far inside double precision; must run as before
    case = tmp_path / "case.toml"
    case.write_text(_mutated("discrete_two_node", {"loading.lam": 1e12, "loading.p0":
                                                   [1e12, 1e12], "loading.q0": [0.0, 0.0],
                                                   "run.cycles": 6}), encoding="utf-8")
    code, out, err = run_cli("run", case, "--out", tmp_path / "o", "--quiet")
    assert code == 0, err
    assert err == ""


# -- lists of values that were flattened whatever their nesting --------------------------

@pytest.mark.parametrize("example, command, changes, key", [
    # a nested list reached a Numba kernel: internal typing error (exit 4)
    ("halfspace_rough_map", ["map"], {"map.fig7_Q1_hat": [[[1.0]]]}, "map.fig7_Q1_hat"),
    # read row after row as one axis, silently
    ("halfspace_rough_map", ["map"], {"map.Q1_hat": [[0.2, 0.4], [0.6, 0.8]]}, "map.Q1_hat"),
    ("halfspace_rough_map", ["map"], {"map.phase": [[[1.0]]]}, "map.phase"),
    ("halfspace_sphere", ["run"], {"run.snapshots": [[0.1, 0.2]]}, "run.snapshots"),
])
def test_nested_lists_where_a_list_of_values_goes_are_refused(run_cli, tmp_path, example,
                                                               command, changes, key):
    line = _refused(run_cli, tmp_path, command, _mutated(example, changes), key)
    assert "flat list" in line


# -- coefficients of friction far beyond any real one ------------------------------------

@pytest.mark.parametrize("example, changes, key", [
    # the Iwan fit of the rods overflowed: internal ValueError (exit 4)
    ("rods_spec", {"rods.friction": 1e100}, "rods.friction"),
    ("rods_spec", {"rods.friction": 1e300}, "rods.friction"),
    # Ŵ = W/(λ_c γσ f² P0): f² overflowed, internal OverflowError (exit 4)
    ("halfspace_rough", {"halfspace.friction": 1e300}, "halfspace.friction"),
])
def test_friction_coefficients_that_overflow_the_models_are_refused(run_cli, tmp_path,
                                                                    example, changes, key):
    line = _refused(run_cli, tmp_path, ["run"], _mutated(example, changes), key)
    assert "<= 1e+12" in line


@pytest.mark.parametrize("example, key", [("rods_spec", "rods.friction"),
                                          ("halfspace_rough", "halfspace.friction")])
def test_a_friction_coefficient_of_1e12_still_runs(run_cli, tmp_path, example, key):
    case = tmp_path / "case.toml"
    case.write_text(_mutated(example, {key: 1e12}), encoding="utf-8")
    code, out, err = run_cli("run", case, "--out", tmp_path / "o", "--quiet")
    assert code == 0, err
