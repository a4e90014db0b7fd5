"""Malformed input never ends in a traceback: one line naming the key or file, exit 2, and
nothing left behind.

The corpus has two parts. Generated cases mutate every key of the shipped examples of each
model (a typo of the key, a value of the wrong type, a non-finite value); hand-written
cases cover files, paths, command-line options and sizes that cannot be allocated, for
every command. Each case runs the real command line (``slipcycle.cli.main.main``) in a
fresh directory and checks

- exit code 2,
- stderr is exactly one line ``error: ...`` that names the expected key, option or file,
- no traceback anywhere,
- the directory holds exactly the input files afterwards (no output, no staging folder).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from slipcycle.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"


@dataclass(frozen=True)
class Bad:
    """One malformed invocation: ``argv`` run in a directory holding ``files``; stderr must
    name ``names`` (a substring)."""

    id: str
    argv: tuple[str, ...]
    names: str
    files: dict = field(default_factory=dict)


def _example(name: str) -> str:
    return (EXAMPLES / name).read_text(encoding="utf-8")


_ASSIGN = re.compile(r"^(?P<key>[A-Za-z_][A-Za-z0-9_]*)\s*=\s*(?P<value>.*?)\s*(#.*)?$")


def _assignments(text: str):
    """(table, key, value, line index) of every top-level ``key = value`` in a table."""
    table = ""
    for i, line in enumerate(text.splitlines()):
        head = re.match(r"^\[([A-Za-z0-9_.]+)\]", line)
        if head:
            table = head.group(1)
            continue
        m = _ASSIGN.match(line)
        if m and table and not line.startswith("["):
            yield table, m.group("key"), m.group("value"), i


def _typo(key: str) -> str:
    """A misspelling of ``key`` that a reader would recognise."""
    if len(key) <= 2:
        return key.swapcase() if key.swapcase() != key else key + key
    mid = len(key) // 2
    return key[:mid] + key[mid + 1:]


def _replace_line(text: str, index: int, line: str) -> str:
    lines = text.splitlines()
    lines[index] = line
    return "\n".join(lines) + "\n"


def _mutations(example: str, command: str, extra: tuple[str, ...] = ()) -> list[Bad]:
    """Typo, wrong type and non-finite value of every key of ``example``."""
    text = _example(example)
    stem = Path(example).stem
    cases = []
    for table, key, value, i in _assignments(text):
        dotted = f"{table}.{key}"
        typo = _typo(key)
        cases.append(Bad(f"{command}-{stem}-{dotted}-typo", (command, "case.toml", *extra),
                         f"{table}.{typo}",
                         {"case.toml": _replace_line(text, i, f"{typo} = {value}")}))
        is_text = value.startswith('"')
        wrong = "3" if is_text else '"oops"'
        cases.append(Bad(f"{command}-{stem}-{dotted}-type", (command, "case.toml", *extra),
                         dotted, {"case.toml": _replace_line(text, i, f"{key} = {wrong}")}))
        if not is_text and value not in ("true", "false") and not value.startswith("{"):
            cases.append(Bad(f"{command}-{stem}-{dotted}-nan", (command, "case.toml", *extra),
                             dotted, {"case.toml": _replace_line(text, i, f"{key} = nan")}))
    return cases


def _generated() -> list[Bad]:
    out = "--out=out"
    return (_mutations("halfspace_sphere.toml", "run", (out,))
            + _mutations("discrete_two_node.toml", "run", (out,))
            + _mutations("rods_spec.toml", "run", (out,))
            + _mutations("halfspace_rough_map.toml", "map", (out,))
            + _mutations("rods_limits_equal.toml", "limits", (out,))
            + _mutations("fe_cylinder.toml", "reduce", ("--out=out.npz",)))


SPHERE = _example("halfspace_sphere.toml")
TWO_NODE = _example("discrete_two_node.toml")
RODS = _example("rods_spec.toml")
ROUGH_MAP = _example("halfspace_rough_map.toml")
LIMITS = _example("rods_limits_equal.toml")
FE = _example("fe_cylinder.toml")
NOT_UTF8 = b"model = \"halfspace\"\n# \xff\xfe caf\xe9\n"
BINARY = b"\x7fELF\x02\x01\x01\x00\x00\x00" + bytes(range(256))


def _with(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def _from_file(text: str, name: str) -> str:
    """``text`` with its inline A, B, C replaced by ``stiffness_file = name``."""
    lines = [ln for ln in text.splitlines() if not re.match(r"^[ABC] = ", ln)]
    i = lines.index("[discrete]")
    lines.insert(i + 1, f'stiffness_file = "{name}"')
    return "\n".join(lines) + "\n"


def _file_cases() -> list[Bad]:
    """Every command meets unusable case files the same way."""
    cases = []
    commands = {"run": ("--out=out",), "map": ("--out=out",), "limits": ("--out=out",),
                "shakedown": ("--out=out",), "basins": ("--out=out", "--grid=5"),
                "sweep": ("--out=out", "--set=loading.lam=1.0"),
                "reduce": ("--out=out.npz",)}
    for cmd, extra in commands.items():
        cases += [
            Bad(f"{cmd}-missing-file", (cmd, "nowhere.toml", *extra), "nowhere.toml"),
            Bad(f"{cmd}-directory", (cmd, "adir", *extra), "adir", {"adir/keep.txt": "x"}),
            Bad(f"{cmd}-binary", (cmd, "case.toml", *extra), "case.toml",
                {"case.toml": BINARY}),
            Bad(f"{cmd}-not-utf8", (cmd, "case.toml", *extra), "case.toml",
                {"case.toml": NOT_UTF8}),
            Bad(f"{cmd}-not-toml", (cmd, "case.toml", *extra), "case.toml",
                {"case.toml": "model = halfspace\n[run\n"}),
            Bad(f"{cmd}-empty", (cmd, "case.toml", *extra), "model", {"case.toml": ""}),
            Bad(f"{cmd}-model-not-string", (cmd, "case.toml", *extra), "model",
                {"case.toml": "model = 3\n"}),
            Bad(f"{cmd}-model-misspelt", (cmd, "case.toml", *extra), "model",
                {"case.toml": 'model = "halfspce"\n'}),
        ]
    # a known model given to a command that does not serve it says which command does
    # (every model is run and swept: fe cases are reduced and solved, tests/test_fe_mesh_*)
    wrong = [("map", TWO_NODE), ("limits", SPHERE), ("shakedown", RODS), ("basins", SPHERE),
             ("reduce", SPHERE)]
    for cmd, text in wrong:
        cases.append(Bad(f"{cmd}-wrong-model", (cmd, "case.toml", *commands[cmd]), "model",
                         {"case.toml": text}))
    return cases


def _output_cases() -> list[Bad]:
    """--out naming a file, or a place under a file, for every command."""
    cases = []
    inputs = {"run": SPHERE, "map": ROUGH_MAP, "limits": LIMITS, "shakedown": TWO_NODE,
              "basins": TWO_NODE, "sweep": SPHERE, "demo": None}
    for cmd, text in inputs.items():
        files = {"afile": "not a directory"}
        head = (cmd,) if text is None else (cmd, "case.toml")
        if text is not None:
            files["case.toml"] = text
        tail = ("--grid=5",) if cmd == "basins" else ()
        tail += ("--set=loading.lam=1.0",) if cmd == "sweep" else ()
        cases.append(Bad(f"{cmd}-out-is-file", (*head, "--out=afile", *tail), "afile", files))
        cases.append(Bad(f"{cmd}-out-under-file", (*head, "--out=afile/sub", *tail), "afile",
                         files))
    fe = {"case.toml": FE, "afile": "x"}
    cases += [
        Bad("reduce-out-is-directory", ("reduce", "case.toml", "--out=adir"), "adir",
            {**fe, "adir/keep.txt": "x"}),
        Bad("reduce-out-not-npz", ("reduce", "case.toml", "--out=out.txt"), "--out", fe),
        Bad("reduce-out-under-file", ("reduce", "case.toml", "--out=afile/r.npz"), "afile", fe),
        Bad("reduce-case-under-file", ("reduce", "case.toml", "--out=r.npz",
                                       "--case=afile/c.toml"), "afile", fe),
    ]
    return cases


def _value_cases() -> list[Bad]:
    """Values, shapes and sizes that the generated mutations do not reach."""
    out = "--out=out"
    run = ("run", "case.toml", out)
    return [
        # half-space
        Bad("hs-tensile-P0", run, "loading.P0", {"case.toml": _with(SPHERE, "P0 = 100.0",
                                                                      "P0 = -100.0")}),
        Bad("hs-negative-friction", run, "halfspace.friction",
            {"case.toml": _with(SPHERE, "friction = 0.5", "friction = -0.5")}),
        Bad("hs-E-one-value", run, "halfspace.E",
            {"case.toml": _with(SPHERE, "E = [200e9, 200e9]", "E = [200e9]")}),
        Bad("hs-nu-above-half", run, "halfspace.nu",
            {"case.toml": _with(SPHERE, "nu = [0.3, 0.3]", "nu = [0.7, 0.3]")}),
        Bad("hs-unknown-profile", run, "halfspace.profile",
            {"case.toml": _with(SPHERE, 'profile = "sphere"', 'profile = "spehre"')}),
        Bad("hs-zero-cycles", run, "run.cycles",
            {"case.toml": _with(SPHERE, "cycles = 3", "cycles = 0")}),
        Bad("hs-steps-1e9", run, "run.steps_per_cycle",
            {"case.toml": _with(SPHERE, "steps_per_cycle = 400",
                                "steps_per_cycle = 1000000000")}),
        Bad("hs-sliders-1e7", run, "sliders",
            {"case.toml": _with(SPHERE, "steps_per_cycle = 400",
                                "steps_per_cycle = 400\nsliders = 10000000")}),
        Bad("hs-unknown-table", run, "loadings",
            {"case.toml": SPHERE.replace("[loading]", "[loadings]")}),
        Bad("hs-unknown-top-level", run, "modle",
            {"case.toml": SPHERE + '\nmodle = "x"\n'}),
        Bad("hs-missing-loading", run, "loading",
            {"case.toml": SPHERE.split("[loading]")[0]}),
        # discrete
        Bad("disc-tensile-p0", run, "loading.p0",
            {"case.toml": _with(TWO_NODE, "p0 = [1.0, 1.0]", "p0 = [-1.0, 1.0]")}),
        Bad("disc-A-not-square", run, "discrete.A",
            {"case.toml": _with(TWO_NODE, "A = [[1.0, -0.3], [-0.3, 0.8]]",
                                "A = [[1.0, -0.3, 0.0], [-0.3, 0.8, 0.0]]")}),
        Bad("disc-A-ragged", run, "discrete.A",
            {"case.toml": _with(TWO_NODE, "A = [[1.0, -0.3], [-0.3, 0.8]]",
                                "A = [[1.0, -0.3], [-0.3]]")}),
        Bad("disc-p0-three-nodes", run, "loading.p0",
            {"case.toml": _with(TWO_NODE, "p0 = [1.0, 1.0]", "p0 = [1.0, 1.0, 1.0]")}),
        Bad("disc-initial-slip-shape", run, "discrete.initial_slip",
            {"case.toml": _with(TWO_NODE, "initial_slip = [0.0, 0.0]",
                                "initial_slip = [0.0, 0.0, 0.0]")}),
        Bad("disc-steps-1e9", run, "run.steps_per_cycle",
            {"case.toml": _with(TWO_NODE, "steps_per_cycle = 400",
                                "steps_per_cycle = 1000000000")}),
        Bad("disc-stiffness-file-missing", run, "stiffness_file",
            {"case.toml": _from_file(TWO_NODE, "missing.npz")}),
        Bad("disc-stiffness-file-corrupt", run, "stiffness_file",
            {"case.toml": _from_file(TWO_NODE, "bad.npz"),
             "bad.npz": b"PK\x03\x04 this is not a zip archive"}),
        # rods
        Bad("rods-unknown-interface", run, "rods.interface",
            {"case.toml": _with(RODS, 'interface = "distributed"', 'interface = "glue"')}),
        Bad("rods-negative-length", run, "rods.L",
            {"case.toml": _with(RODS, "L = [0.5, 0.5]", "L = [-0.5, 0.5]")}),
        Bad("rods-zero-modes", run, "rods.modes",
            {"case.toml": _with(RODS, "modes = 50", "modes = 0")}),
        Bad("rods-negative-damping", run, "rods.damping_ratio",
            {"case.toml": _with(RODS, "damping_ratio = 0.01", "damping_ratio = -0.01")}),
        # command-line options and their sizes
        Bad("shakedown-lam-points-0", ("shakedown", "case.toml", out, "--lam-points=0"),
            "--lam-points", {"case.toml": TWO_NODE}),
        Bad("shakedown-lam-points-1e9", ("shakedown", "case.toml", out,
                                         "--lam-points=1000000000"),
            "--lam-points", {"case.toml": TWO_NODE}),
        Bad("shakedown-lam-points-text", ("shakedown", "case.toml", out, "--lam-points=1e9"),
            "--lam-points", {"case.toml": TWO_NODE}),
        Bad("shakedown-starts-negative", ("shakedown", "case.toml", out, "--starts=-1"),
            "--starts", {"case.toml": TWO_NODE}),
        Bad("shakedown-tol-negative", ("shakedown", "case.toml", out, "--tol=-1"),
            "--tol", {"case.toml": TWO_NODE}),
        Bad("basins-grid-0", ("basins", "case.toml", out, "--grid=0"), "--grid",
            {"case.toml": TWO_NODE}),
        Bad("basins-grid-huge", ("basins", "case.toml", out, "--grid=1000000"), "--grid",
            {"case.toml": TWO_NODE}),
        Bad("basins-random-0", ("basins", "case.toml", out, "--random=0"), "--random",
            {"case.toml": TWO_NODE}),
        Bad("basins-v1-garbage", ("basins", "case.toml", out, "--grid=5", "--v1=abc"),
            "--v1", {"case.toml": TWO_NODE}),
        Bad("limits-tolerance-negative", ("limits", "case.toml", out, "--tolerance=-1"),
            "--tolerance", {"case.toml": LIMITS}),
        Bad("limits-unknown-key", ("limits", "case.toml", out), "limits.frequncy_ratio",
            {"case.toml": LIMITS.replace("frequency_ratio = {start",
                                         "frequncy_ratio = {start")}),
        Bad("limits-huge-grid", ("limits", "case.toml", out), "limits",
            {"case.toml": LIMITS.replace("num = 40}", "num = 100000}").replace(
                "num = 20}", "num = 100000}")}),
        Bad("map-huge-grid", ("map", "case.toml", out), "map",
            {"case.toml": ROUGH_MAP.replace("num = 37}", "num = 100000}").replace(
                "num = 19}", "num = 100000}")}),
        Bad("sweep-no-equals", ("sweep", "case.toml", out, "--set=loading.lam"), "--set",
            {"case.toml": SPHERE}),
        Bad("sweep-unknown-key", ("sweep", "case.toml", out, "--set=loading.Q11=1:2:3"),
            "loading.Q11", {"case.toml": SPHERE}),
        Bad("sweep-bad-range", ("sweep", "case.toml", out, "--set=loading.Q1=a:b:c"),
            "loading.Q1", {"case.toml": SPHERE}),
        Bad("sweep-invalid-cell", ("sweep", "case.toml", out, "--set=loading.P0=-1,100"),
            "loading.P0", {"case.toml": SPHERE}),
        Bad("sweep-workers-0", ("sweep", "case.toml", out, "--set=loading.Q1=10,20",
                                "--workers=0"), "--workers", {"case.toml": SPHERE}),
        Bad("sweep-resume-without-store", ("sweep", "case.toml", out,
                                           "--set=loading.Q1=10,20", "--resume"),
            "--resume", {"case.toml": SPHERE}),
        Bad("sweep-1e9-cells", ("sweep", "case.toml", out,
                                "--set=loading.Q1=1:30:1000000000"), "cells",
            {"case.toml": SPHERE}),
        Bad("sweep-scheduler-unreachable", ("sweep", "case.toml", out,
                                            "--set=loading.Q1=10,20",
                                            "--scheduler=tcp://127.0.0.1:9"),
            "--scheduler", {"case.toml": SPHERE}),
        Bad("unknown-command", ("runn", "case.toml"), "runn", {"case.toml": SPHERE}),
        Bad("run-missing-out", ("run", "case.toml"), "--out", {"case.toml": SPHERE}),
    ]


CORPUS = _generated() + _file_cases() + _output_cases() + _value_cases()


def _listing(root: Path) -> dict[str, bytes]:
    """Every path under ``root`` with its bytes: a new file or a changed input shows."""
    return {str(p.relative_to(root)): (p.read_bytes() if p.is_file() else b"")
            for p in root.rglob("*")}


def refused_in_one_line(argv, tmp_path, monkeypatch, capsys) -> str:
    """Run the CLI in ``tmp_path``: exit 2, one ``error:`` line, no traceback, nothing
    written and no input changed. Returns the line."""
    before = _listing(tmp_path)
    monkeypatch.chdir(tmp_path)
    try:
        code = main(list(argv))
    except SystemExit as exc:  # argparse
        code = exc.code
    captured = capsys.readouterr()
    err_lines = [line for line in captured.err.splitlines() if line.strip()]
    assert "Traceback" not in captured.err + captured.out
    assert code == 2, captured.err
    assert len(err_lines) == 1, captured.err
    assert err_lines[0].startswith("error: "), err_lines[0]
    assert _listing(tmp_path) == before, "output left behind or an input changed"
    return err_lines[0]


def test_corpus_has_at_least_150_cases_with_unique_ids():
    ids = [c.id for c in CORPUS]
    assert len(ids) >= 150
    assert len(set(ids)) == len(ids)


@pytest.mark.parametrize("bad", CORPUS, ids=[c.id for c in CORPUS])
def test_malformed_input_is_one_line_exit_2_and_leaves_nothing(bad, tmp_path, monkeypatch,
                                                               capsys):
    for name, content in bad.files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")
    line = refused_in_one_line(bad.argv, tmp_path, monkeypatch, capsys)
    assert bad.names in line, line
