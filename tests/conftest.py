"""Shared test helpers."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

SHARED = Path(__file__).resolve().parents[1].parent / "shared"

#: the longest tests (CI, 2 workers: about 500, 60, 55 and 50 s), run first. ``make test``
#: (xdist work stealing) hands each worker a contiguous half of the collection and an idle
#: worker steals from the END of the other's queue: the long tests at the head start at
#: once instead of wherever their file falls, and the rest balances around them.
LONGEST_FIRST = (
    "tests/test_lap_joint_study.py::"
    "test_docs_table_of_the_shipped_example_is_what_slipcycle_run_gives",
    "tests/test_fe3d_sphere.py::test_mindlin_deresiewicz_loss_converges_to_the_closed_form",
    "tests/test_lap_joint_study.py::test_nested_meshes_show_unresolved_slip_rings_as_not_converged",
    "tests/test_map_speed_reference.py::test_fast_map_equals_the_reference_algorithm_on_a_grid",
)


def pytest_collection_modifyitems(config, items):
    """Move :data:`LONGEST_FIRST` to the head of the run, in that order (stable sort: every
    other test keeps its place)."""
    rank = {nodeid: k for k, nodeid in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid, len(rank)))


@pytest.fixture
def run_cli(capsys):
    """Run the ``slipcycle`` CLI in-process; returns (exit_code, stdout, stderr)."""
    from slipcycle.cli.main import main

    def _run(*argv: str):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:  # argparse errors
            code = exc.code
        out, err = capsys.readouterr()
        return code, out, err

    return _run


@pytest.fixture
def write_case(tmp_path):
    """Write TOML text to a case file in tmp_path and return its path."""

    def _write(text: str, name: str = "case.toml") -> Path:
        path = tmp_path / name
        path.write_text(text)
        return path

    return _write


EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


def _toml_value(value) -> str:
    """TOML text of a Python value (bool, int, float, str, list)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"no TOML text for {value!r}")


def _strip_comment(line: str) -> str:
    """``line`` without its ``# ...`` comment (a ``#`` inside a quoted string is kept)."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            return line[:i].rstrip()
    return line.rstrip()


def case_text(name: str, **tables) -> str:
    """The text of ``examples/<name>.toml`` without comments, with per-table overrides.

    Each keyword names a table (``loading={"Q1": 80.0}``): a key already there has its
    value replaced in place, a key given as ``None`` is removed, a new key is added right
    after the key named before it in the overrides (when that key is in the table) or else
    at the end of the table; a table not in the example is added at the end, in keyword
    order, and a table given as ``None`` is removed whole. Values are Python values
    (bool, int, float, str, list) written as TOML.
    """
    text = (EXAMPLES / f"{name}.toml").read_text(encoding="utf-8")
    sections: list[tuple[str, list[str]]] = [("", [])]  # (table name, its lines)
    for line in filter(None, map(_strip_comment, text.splitlines())):
        if line.startswith("["):
            sections.append((line.strip("[] "), [line]))
        else:
            sections[-1][1].append(line)
    known = {table for table, _ in sections}
    sections += [(table, [f"[{table}]"]) for table, edits in tables.items()
                 if table not in known and edits is not None]
    out: list[str] = []
    for table, body in sections:
        if table in tables and tables[table] is None:
            continue
        keyed = [(line.split("=", 1)[0].strip() if "=" in line else None, line)
                 for line in body]
        previous = None
        for key, value in tables.get(table, {}).items():
            at = [k for k, _ in keyed].index
            line = None if value is None else f"{key} = {_toml_value(value)}"
            if key in (k for k, _ in keyed):
                i = at(key)
                if line is None:
                    del keyed[i]
                else:
                    keyed[i] = (key, line)
            elif line is not None:
                present = previous in (k for k, _ in keyed)
                keyed.insert(at(previous) + 1 if present else len(keyed), (key, line))
            previous = key
        out += [line for _, line in keyed]
    return "\n".join(out) + "\n"


def slid_block(elements: int):
    """The steel block of fe_block_nu03.toml reduced with ``elements`` quadratic elements
    across the contact (2·elements + 1 nodes), assembled slide-first (pressed 0.2 µm,
    pushed 3 µm along +t, pressed to 2 µm): (system, load, protocol)."""
    import numpy as np

    from slipcycle.discrete import DiscreteLoad, FrictionalSystem
    from slipcycle.fe.builders import block_on_rigid
    from slipcycle.fe.loads import combined_loads
    from slipcycle.fe.reduction import reduce_problem

    r = reduce_problem(block_on_rigid(width=0.04, height=0.02, E=210e9, nu=0.3,
                                      elements=elements, thickness=0.01))
    load = DiscreteLoad(*combined_loads(r, {"normal": 2e-6},
                                        {"normal": 0.5e-6, "tangential": 1.5e-6},
                                        {"tangential": np.pi / 2}))
    system = FrictionalSystem(r.A, r.B, r.C, 0.5, accept_ill_posed=True)
    protocol = np.array([np.concatenate(r.combine(normal=a, tangential=t))
                         for a, t in ((0.2e-6, 0.0), (0.2e-6, 3e-6), (2e-6, 3e-6))])
    return system, load, protocol


def assert_reproduced_by_one_more_cycle(run, system, load, steps: int, state_tol: float):
    """One more exact cycle from a run's final state reproduces that state (to
    ``state_tol`` of its scale) and its dissipation per node (to 1e-6 of D): a periodic
    state, not a stop on the way."""
    import numpy as np

    from slipcycle.discrete.evolution import Evolution

    x0 = run.cycle_start_states[-1]
    theta, vals = load.cycle_samples(steps)
    evo = Evolution(system, x0, vals[0], run.force_scale)
    totals = evo.follow(theta, vals)
    scale = max(run.disp_scale, float(np.abs(x0).max()))
    assert np.abs(evo.x - x0).max() <= state_tol * scale
    np.testing.assert_allclose(totals.dissipation, run.dissipation_per_node, rtol=0,
                               atol=1e-6 * run.dissipation_per_cycle)


def assert_same_steady_state(fast, plain, rel: float = 1e-6):
    """The accelerated run ends where plain cycling does: the same class and permanently
    stuck nodes, and D and D per node within ``rel`` of max(|D|, force × displacement
    scale) of plain cycling's."""
    import numpy as np

    assert fast.steady_state == plain.steady_state
    scale = max(abs(plain.dissipation_per_cycle), plain.force_scale * plain.disp_scale)
    assert abs(fast.dissipation_per_cycle - plain.dissipation_per_cycle) <= rel * scale
    np.testing.assert_allclose(fast.dissipation_per_node, plain.dissipation_per_node,
                               rtol=0, atol=rel * scale)
    assert fast.permanently_stuck_nodes == plain.permanently_stuck_nodes


#: one contact node of a 3-D body under a rotating tangential load (format ``f``: its
#: friction coefficient): the smallest discrete3d case, at the origin
ONE_NODE_3D = """
model = "discrete3d"
[discrete3d]
A = [[2.0, 0.0], [0.0, 2.0]]
B = [[0.0, 0.0]]
C = [[2.0]]
friction = {f}
coordinates = [[0.0, 0.0, 0.0]]
[loading]
p0 = [1.0]
q1 = [[0.6, 0.6]]
q1_phase = [[0.0, -1.5707963]]
[run]
cycles = 10
steps_per_cycle = 40
"""
