"""The malformed-input corpus extended to the surfaces added after it (issue 34 item 4).

Same contract as ``test_malformed_inputs.py``, on the 3-D discrete model (every key of the
shipped example: a typo, a wrong type, a non-finite value; protocols of the wrong shape;
tolerances that would hang; loads that leave every node open), topographies (every key,
units, undefined points, flat maps, filters that keep nothing, random bytes and truncated
files), the lap joint's keys and protocols, and the file paths of every command (devices,
FIFOs, outputs over inputs). Each case runs the real command line in-process in a fresh
directory and checks: exit code 2, one line ``error: ...`` naming the key or file, no
traceback, nothing written, no input changed. The FE-export readers' own corpus (truncated,
missing, complex, triangle-only exports) is in ``test_fe_exports*.py`` (CalculiX and the
other formats, owned with those readers).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from test_malformed_inputs import Bad, _assignments, _replace_line, _typo, refused_in_one_line

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
OUT = "--out=out"


def _example(name: str) -> str:
    return (EXAMPLES / name).read_text(encoding="utf-8")


def _single_line(value: str) -> bool:
    """A value complete on its line (a multi-line array cannot be replaced line-wise)."""
    return value.count("[") == value.count("]") and value.count("{") == value.count("}")


def _mutations(example: str, command: str, extra=(OUT,), files=None, tables=None
               ) -> list[Bad]:
    """Typo, wrong type and non-finite value of every one-line key of ``example``."""
    text = _example(example)
    stem = Path(example).stem
    base = dict(files or {})
    cases = []
    for table, key, value, i in _assignments(text):
        dotted = f"{table}.{key}"
        if not _single_line(value) or (tables is not None and table not in tables):
            continue
        argv = (command, "case.toml", *extra)
        typo = _typo(key)
        cases.append(Bad(f"{stem}-{dotted}-typo", argv, f"{table}.{typo}",
                         {**base, "case.toml": _replace_line(text, i, f"{typo} = {value}")}))
        wrong = "3" if value.startswith('"') else '"oops"'
        cases.append(Bad(f"{stem}-{dotted}-type", argv, dotted,
                         {**base, "case.toml": _replace_line(text, i, f"{key} = {wrong}")}))
        if not value.startswith(('"', "{")) and value not in ("true", "false"):
            cases.append(Bad(f"{stem}-{dotted}-nan", argv, dotted,
                             {**base, "case.toml": _replace_line(text, i, f"{key} = nan")}))
            cases.append(Bad(f"{stem}-{dotted}-inf", argv, dotted,
                             {**base, "case.toml": _replace_line(text, i, f"{key} = inf")}))
    return cases


def _with(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


# -- discrete3d ---------------------------------------------------------------------------

D3 = _example("discrete3d_three_node.toml")
P = "\n[[discrete3d.protocol]]\n"


def _discrete3d_cases() -> list[Bad]:
    bad = {
        "protocol-qw-flat": (P + "p_w = [1.0, 1.0, 1.0]\nq_w = [0.0, 0.0, 0.0]\n",
                             "discrete3d.protocol[0].q_w"),
        "protocol-qw-rows": (P + "p_w = [1.0, 1.0, 1.0]\nq_w = [[0.0, 0.0], [0.0, 0.0]]\n",
                             "discrete3d.protocol[0].q_w"),
        "protocol-qw-3": (P + "p_w = 1.0\nq_w = [[0.0, 0.0, 0.0]]\n",
                          "discrete3d.protocol[0].q_w"),
        "protocol-pw-length": (P + "p_w = [1.0, 1.0]\n", "discrete3d.protocol[0].p_w"),
        "protocol-pw-missing": (P + "q_w = 0.0\n", "discrete3d.protocol[0]"),
        "protocol-pw-nan": (P + "p_w = [1.0, nan, 1.0]\n", "discrete3d.protocol[0].p_w"),
        "protocol-typo": (P + "p_w = 1.0\nqw = 0.0\n", "discrete3d.protocol[0].qw"),
    }
    cases = [Bad(f"discrete3d-{k}", ("run", "case.toml", OUT), names,
                 {"case.toml": _with(D3, "\n[loading]", extra + "\n[loading]")})
             for k, (extra, names) in bad.items()]
    values = {
        "step-tolerance-1e-300": ("step_tolerance = 1e-7", "step_tolerance = 1e-300",
                                  "run.step_tolerance"),
        "step-tolerance-1e-11": ("step_tolerance = 1e-7", "step_tolerance = 1e-11",
                                 "run.step_tolerance"),
        "step-tolerance-0": ("step_tolerance = 1e-7", "step_tolerance = 0.0",
                             "run.step_tolerance"),
        "step-tolerance-1": ("step_tolerance = 1e-7", "step_tolerance = 1.0",
                             "run.step_tolerance"),
        "steady-tol-0": ("steady_tol = 1e-8", "steady_tol = 0.0", "run.steady_tol"),
        "all-open": ("p0 = [1.0, 1.2, 1.0]", "p0 = [-1.0, -1.0, -1.0]", "loading.p0"),
        "all-open-scalar": ("p0 = [1.0, 1.2, 1.0]", "p0 = -2.0", "loading.p0"),
        "p0-length": ("p0 = [1.0, 1.2, 1.0]", "p0 = [1.0, 1.2]", "loading.p0"),
        "q1-flat": ("q1 = [[0.6, 0.6], [0.3, 0.0], [0.6, 0.6]]", "q1 = [0.6, 0.3, 0.6]",
                    "loading.q1"),
        "q0-three": ("q0 = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]", "q0 = [[0.0, 0.0, 0.0]]",
                     "loading.q0"),
        "friction-negative": ("friction = 0.4", "friction = -0.4", "discrete3d.friction"),
        "friction-length": ("friction = 0.4", "friction = [0.4, 0.4]", "discrete3d.friction"),
        "area-zero": ("area = 1.0", "area = 0.0", "discrete3d.area"),
        "coordinates-2d": ("coordinates = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]",
                           "coordinates = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]",
                           "discrete3d.coordinates"),
        "C-asymmetric": ("C = [[2.0, -0.3, 0.0]", "C = [[2.0, -0.2, 0.0]", "discrete3d.C"),
        "C-shape": ("C = [[2.0, -0.3, 0.0], [-0.3, 2.0, -0.3], [0.0, -0.3, 2.0]]",
                    "C = [[2.0, -0.3], [-0.3, 2.0]]", "discrete3d"),
        "fields-unknown": ('fields = ["xdmf", "pvd"]', 'fields = ["vtk"]', "output.fields"),
        "cycles-zero": ("cycles = 40", "cycles = 0", "run.cycles"),
        "steps-zero": ("steps_per_cycle = 100", "steps_per_cycle = 0", "run.steps_per_cycle"),
        "stiffness-device": ("friction = 0.4", 'friction = 0.4\nstiffness_file = "/dev/zero"',
                             "discrete3d"),
    }
    cases += [Bad(f"discrete3d-{k}", ("run", "case.toml", OUT), names,
                  {"case.toml": _with(D3, old, new)})
              for k, (old, new, names) in values.items()]
    return cases + _mutations("discrete3d_three_node.toml", "run")


# -- topographies -------------------------------------------------------------------------

TOPO = _example("halfspace_topography.toml")
SURFACE = (EXAMPLES / "rough_surface.nc").read_bytes()


def _topography_cases() -> list[Bad]:
    files = {"rough_surface.nc": SURFACE}
    cut = 'bem_grid = 128\nshort_cutoff = 3e-4\nlong_cutoff = 1e-4'
    values = {
        "cutoffs-crossed": ("bem_grid = 128", cut, "halfspace.short_cutoff", files),
        "cutoffs-equal": ("bem_grid = 128",
                          "bem_grid = 128\nshort_cutoff = 1e-4\nlong_cutoff = 1e-4",
                          "halfspace.short_cutoff", files),
        "cutoff-keeps-nothing": ("bem_grid = 128", "bem_grid = 128\nshort_cutoff = 10.0",
                                 "halfspace.short_cutoff", files),
        "file-missing": ('"rough_surface.nc"', '"nosuch.nc"', "halfspace.topography_file", {}),
        "file-random-bytes": ('"rough_surface.nc"', '"junk.nc"', "halfspace.topography_file",
                              {"junk.nc": bytes(range(256)) * 40}),
        "file-truncated": ('"rough_surface.nc"', '"cut.nc"', "halfspace.topography_file",
                           {"cut.nc": SURFACE[:len(SURFACE) // 3]}),
        "file-empty": ('"rough_surface.nc"', '"empty.nc"', "halfspace.topography_file",
                       {"empty.nc": b""}),
        "file-device": ('"rough_surface.nc"', '"/dev/zero"', "halfspace.topography_file", {}),
        "file-directory": ('"rough_surface.nc"', '"."', "halfspace.topography_file", {}),
        "fill-undefined-type": ("bem_grid = 128", 'bem_grid = 128\nfill_undefined = "yes"',
                                "halfspace.fill_undefined", files),
        "bem-grid-small": ("bem_grid = 128", "bem_grid = 4", "halfspace.bem_grid", files),
        "bem-loads-huge": ("bem_grid = 128", "bem_grid = 128\nbem_loads = 100000",
                           "halfspace.bem_loads", files),
        "nominal-area-negative": ("nominal_area = 1.0e-4", "nominal_area = -1.0e-4",
                                  "halfspace.nominal_area", files),
        "fit-unknown": ('fit = "table"', 'fit = "spline"', "halfspace.fit", files),
    }
    cases = [Bad(f"topography-{k}", ("run", "case.toml", OUT), names,
                 {**extra, "case.toml": _with(TOPO, old, new)})
             for k, (old, new, names, extra) in values.items()]
    # [roughness] is read by 'slipcycle roughness' only (its own corpus: test_roughness_cli)
    return cases + _mutations("halfspace_topography.toml", "run", files=files,
                              tables=("halfspace", "loading", "run"))


def _topography_file_cases(tmp_path: Path) -> dict[str, tuple[bytes, str]]:
    """Height maps written by SurfaceTopography: (file bytes, words of the message)."""
    np = pytest.importorskip("numpy")
    st = pytest.importorskip("SurfaceTopography")
    tmp_path.mkdir(parents=True, exist_ok=True)
    src = tmp_path / "rough_surface.nc"
    src.write_bytes(SURFACE)
    topo = st.read_topography(str(src))
    h, size = np.array(topo.heights()), topo.physical_sizes
    maps = {"furlong": (h, "furlong", "height unit 'furlong'"),
            "nan": (np.where(np.arange(h.size).reshape(h.shape) == 77, np.nan, h), "m",
                    "1 of 16384 height points are undefined"),
            "inf": (np.where(np.arange(h.size).reshape(h.shape) == 5, np.inf, h), "m",
                    "1 of 16384 height points are undefined"),
            "flat": (np.zeros_like(h), "m", "perfectly flat")}
    out = {}
    for name, (heights, unit, words) in maps.items():
        path = tmp_path / f"{name}.nc"
        st.Topography(heights, size, periodic=True, unit=unit).to_netcdf(str(path))
        out[name] = (path.read_bytes(), words)
    return out


# -- lap joint ----------------------------------------------------------------------------

LAP = _example("bolted_lap_joint.toml")


def _lap_joint_cases() -> list[Bad]:
    values = {
        "protocol-unknown": ('names = ["sequential", "reversed", "simultaneous"]',
                             'names = ["sideways"]', "lap_joint.protocols.names"),
        "protocol-empty": ('names = ["sequential", "reversed", "simultaneous"]',
                           "names = []", "lap_joint.protocols.names"),
        "orders-bolt-out-of-range": ('names = ["sequential", "reversed", "simultaneous"]',
                                     'names = ["mine"]\norders = [[0, 7]]',
                                     "lap_joint.protocols.orders"),
        "preload-negative": ("preload = 5e3", "preload = -5e3", "lap_joint.loading.preload"),
        "bolt-count-zero": ("bolt_count = 2", "bolt_count = 0", "lap_joint.bolt_count"),
        "element-unknown": ('element = "H8I"', 'element = "Q4"', "lap_joint.element"),
        "mesh-size-zero": ("mesh_size = 0.005", "mesh_size = 0.0", "lap_joint.mesh_size"),
        # refused before meshing with the node count and memory (it ran for minutes)
        "bolt-wider-than-plate": ("bolt_diameter = 0.0066", "bolt_diameter = 0.04",
                                  "lap_joint.bolt_diameter"),
        "mesh-size-1e-5": ("mesh_size = 0.005", "mesh_size = 1e-5", "lap_joint.mesh_size"),
        "friction-negative": ("friction = 0.3", "friction = -0.3", "lap_joint.friction"),
        "rtol-one": ("rtol = 0.05", "rtol = 1.5", "lap_joint.convergence.rtol"),
        "cycles-zero": ("cycles = 30", "cycles = 0", "run.cycles"),
        # below round-off the step control would subdivide without end (it hung)
        "step-tolerance-1e-300": ("step_tolerance = 1e-4", "step_tolerance = 1e-300",
                                  "run.step_tolerance"),
    }
    return [Bad(f"lap-joint-{k}", ("run", "case.toml", OUT), names,
                {"case.toml": _with(LAP, old, new)}) for k, (old, new, names) in values.items()
            ]


# -- paths of every command ---------------------------------------------------------------

SPHERE = _example("halfspace_sphere.toml")
FE = _example("fe_cylinder.toml")


def _path_cases() -> list[Bad]:
    cases = []
    for command in ("run", "map", "limits", "shakedown", "basins", "sweep", "roughness"):
        cases += [
            Bad(f"{command}-out-is-the-case", (command, "case.toml", "--out", "case.toml"),
                "case.toml", {"case.toml": SPHERE}),
            Bad(f"{command}-out-holds-the-case", (command, "case.toml", "--out", "."),
                "--out", {"case.toml": SPHERE}),
            Bad(f"{command}-out-empty", (command, "case.toml", "--out", ""), "--out",
                {"case.toml": SPHERE}),
            Bad(f"{command}-case-device", (command, "/dev/zero", OUT), "/dev/zero", {}),
        ]
    cases += [
        Bad("reduce-case-over-model", ("reduce", "model.toml", "--out", "r.npz", "--case",
                                       "model.toml"), "--case", {"model.toml": FE}),
        Bad("reduce-case-over-model-dotted", ("reduce", "model.toml", "--out", "r.npz",
                                              "--case", "./sub/../model.toml"), "--case",
            {"model.toml": FE, "sub/keep.txt": "x"}),
        Bad("reduce-out-over-model", ("reduce", "model.toml", "--out", "model.toml"),
            "--out", {"model.toml": FE}),
        Bad("reduce-out-empty", ("reduce", "model.toml", "--out", ""), "--out",
            {"model.toml": FE}),
        Bad("reduce-model-device", ("reduce", "/dev/zero", "--out", "r.npz"), "/dev/zero",
            {}),
        Bad("basins-protocols-device", ("basins", "case.toml", OUT, "--protocols",
                                        "/dev/zero"), "--protocols",
            {"case.toml": _example("discrete_two_node.toml")}),
        Bad("run-case-bom-then-garbage", ("run", "case.toml", OUT), "case.toml",
            {"case.toml": b"\xef\xbb\xbfmodel = \n"}),
    ]
    return cases


CORPUS = (_discrete3d_cases() + _topography_cases() + _lap_joint_cases() + _path_cases())


_run = refused_in_one_line


def _write(files: dict, root: Path) -> None:
    for name, content in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")


def test_new_corpus_has_at_least_150_cases_with_unique_ids():
    ids = [c.id for c in CORPUS]
    assert len(ids) >= 150 and len(set(ids)) == len(ids)


@pytest.mark.parametrize("bad", CORPUS, ids=[c.id for c in CORPUS])
def test_new_surface_malformed_input_is_one_line_exit_2_and_leaves_nothing(
        bad, tmp_path, monkeypatch, capsys):
    _write(bad.files, tmp_path)
    line = _run(bad.argv, tmp_path, monkeypatch, capsys)
    assert bad.names in line, line


@pytest.mark.parametrize("name", ["furlong", "nan", "inf", "flat"])
def test_topography_height_map_problems_are_named_before_the_bem(name, tmp_path,
                                                                   monkeypatch, capsys):
    data, words = _topography_file_cases(tmp_path / "src")[name]
    _write({"map.nc": data, "case.toml": _with(TOPO, '"rough_surface.nc"', '"map.nc"')}, tmp_path)
    import shutil

    shutil.rmtree(tmp_path / "src")
    line = _run(("run", "case.toml", OUT), tmp_path, monkeypatch, capsys)
    assert "halfspace.topography_file" in line and words in line, line


def test_undefined_topography_points_are_filled_only_on_request(tmp_path, monkeypatch,
                                                                capsys):
    from slipcycle.halfspace.topography import read_surface

    data, _ = _topography_file_cases(tmp_path / "src")["nan"]
    (tmp_path / "nan.nc").write_bytes(data)
    surface = read_surface(tmp_path / "nan.nc", fill_undefined=True)
    import numpy as np

    assert np.all(np.isfinite(surface.heights)) and surface.rms_height > 0


def test_a_fifo_named_in_a_case_is_refused_without_blocking(tmp_path, monkeypatch, capsys):
    os.mkfifo(tmp_path / "pipe.nc")
    _write({"case.toml": _with(TOPO, '"rough_surface.nc"', '"pipe.nc"')}, tmp_path)
    line = _run(("run", "case.toml", OUT), tmp_path, monkeypatch, capsys)
    assert "halfspace.topography_file" in line and "FIFO" in line


def test_the_names_of_the_corpus_are_keys_files_or_options():
    for bad in CORPUS:
        assert re.fullmatch(r"[\w.\[\]/-]+", bad.names), bad
