"""The command line answers at once: ``--help``, ``--version``, ``examples`` and argument
errors import no numerical stack, ``run`` imports only the case's model, and xarray does
not import dask for a run that uses none. (Start-up times are benchmarks, in
``benchmarks/bench_cli.py``; here only what is imported is checked.)"""

from __future__ import annotations

import gc
import json
import os
import subprocess
import sys
import textwrap

import pytest

from slipcycle.examples import example_text

HEAVY = ("numpy", "scipy", "numba", "xarray", "pandas", "matplotlib", "netCDF4", "dask",
         "PIL", "llvmlite")

_PROBE = textwrap.dedent("""
    import json, sys
    from slipcycle.cli.main import main
    try:
        code = main(sys.argv[1:])
    except SystemExit as exc:
        code = exc.code
    print("@@" + json.dumps({"code": code, "modules": sorted(sys.modules)}))
""")


def _probe(args, cwd=None) -> dict:
    proc = subprocess.run([sys.executable, "-c", _PROBE, *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("@@")][-1]
    return {**json.loads(line[2:]), "stdout": proc.stdout, "stderr": proc.stderr}


@pytest.mark.parametrize("args", [
    ["--help"],
    ["--version"],
    ["run", "--help"],
    ["sweep", "--help"],
    ["nonsense-command"],
    ["run"],                                    # missing arguments
    ["run", "case.toml", "--out"],              # option without its value
    ["shakedown", "case.toml", "--out", "o", "--workers", "0"],
    ["examples"],
])
def test_help_and_argument_errors_import_no_numerical_stack(args):
    res = _probe(args)
    loaded = [m for m in HEAVY if m in res["modules"]]
    assert loaded == [], f"{args} imported {loaded}"
    assert res["code"] in (0, 2)
    if res["code"] == 2:
        # one line, no traceback
        assert res["stderr"].count("\n") == 1 and "Traceback" not in res["stderr"]


def test_version_is_printed_without_importing_the_library():
    res = _probe(["--version"])
    assert res["stdout"].startswith("slipcycle ")
    assert not any(m.startswith("slipcycle.") and m.split(".")[1] in
                   ("halfspace", "discrete", "rods", "fe", "sweep", "api", "io")
                   for m in res["modules"])


def test_run_imports_only_the_model_of_its_case_and_no_dask(tmp_path):
    case = tmp_path / "sphere.toml"
    case.write_text(example_text("halfspace_sphere").replace("steps_per_cycle = 400",
                                                             "steps_per_cycle = 40"))
    res = _probe(["run", str(case), "--out", str(tmp_path / "out"), "-q"])
    assert res["code"] == 0, res["stderr"]
    mods = set(res["modules"])
    assert "slipcycle.halfspace" in mods
    for other in ("slipcycle.discrete", "slipcycle.rods", "slipcycle.fe", "slipcycle.sweep",
                  "slipcycle.demo", "dask", "distributed", "zarr"):
        assert other not in mods, f"run of a half-space case imported {other}"
    # figures with the non-interactive backend: no GUI toolkit was loaded
    assert not any(m.split(".")[0] in ("tkinter", "PyQt5", "PyQt6", "PySide6", "gi")
                   for m in mods)
    assert (tmp_path / "out" / "figures").is_dir()


def _figure_workers_used() -> bool:
    """Whether ``slipcycle run`` draws its figures in worker processes here."""
    return sys.platform.startswith("linux") and len(os.sched_getaffinity(0)) > 1 \
        and not os.environ.get("SLIPCYCLE_DEBUG")


def test_run_of_a_sphere_defers_scipy_and_draws_figures_outside_the_solving_process(tmp_path):
    """SciPy's interpolation and special functions serve other profiles and the measured
    topography only; with figure workers (Linux, more than one CPU) the process that
    solves imports no matplotlib and no image library at all."""
    case = tmp_path / "sphere.toml"
    case.write_text(example_text("halfspace_sphere").replace("steps_per_cycle = 400",
                                                             "steps_per_cycle = 40"))
    res = _probe(["run", str(case), "--out", str(tmp_path / "out"), "-q"])
    assert res["code"] == 0, res["stderr"]
    mods = set(res["modules"])
    for deferred in ("scipy.interpolate", "scipy.special", "scipy.optimize",
                     "matplotlib.pyplot"):
        assert deferred not in mods, f"run of a sphere imported {deferred}"
    if _figure_workers_used():
        assert not {"matplotlib", "PIL"} & {m.split(".")[0] for m in mods}
    names = sorted(p.name for p in (tmp_path / "out" / "figures").iterdir())
    assert names == ["dissipation_density.png", "hysteresis.png", "load_path.png",
                     "stick_zone.png", "tractions.png"]
    assert not list(tmp_path.glob(".out.partial-*"))


def test_help_of_every_command_imports_no_numerical_stack():
    from slipcycle.cli.main import COMMANDS

    for command in COMMANDS:
        res = _probe([command, "--help"])
        loaded = [m for m in HEAVY if m in res["modules"]]
        assert res["code"] == 0 and loaded == [], f"{command} --help imported {loaded}"


def test_main_called_with_arguments_leaves_the_garbage_collector_as_it_was(tmp_path):
    """In-process callers (tests, notebooks) keep their collector settings; only the
    ``slipcycle`` process itself runs with larger thresholds and freezes at its end."""
    from slipcycle.cli.main import main

    before = gc.get_threshold()
    frozen = gc.get_freeze_count()
    assert main(["examples"]) == 0
    assert gc.get_threshold() == before
    assert gc.get_freeze_count() == frozen


def test_dask_guard_keeps_real_dask_arrays_working():
    """The guard that keeps xarray from importing dask is exact: once dask is imported,
    dask arrays are recognised again."""
    code = textwrap.dedent("""
        import sys
        import numpy as np
        import xarray as xr
        from slipcycle.io.results import dask_not_imported
        with dask_not_imported():
            xr.Dataset({"a": ("x", np.arange(3.0))})
            assert "dask" not in sys.modules or sys.modules["dask"] is None
        assert "dask" not in sys.modules
        import dask.array as da
        ds = xr.Dataset({"a": ("x", da.arange(4.0, chunks=2))})
        assert ds.chunks == {"x": (2, 2)}
        print("ok")
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert proc.stdout.strip() == "ok", proc.stderr
