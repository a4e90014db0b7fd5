"""The studies package names its entry points lazily: importing it loads no study (each
study loads its model, xarray and the sweep engine), and every name it lists is the
object of the module that defines it."""

from __future__ import annotations

import importlib
import subprocess
import sys

import slipcycle.studies as studies


def test_every_listed_name_is_the_defining_modules_object():
    for name in studies.__all__:
        module = importlib.import_module(f"slipcycle.studies.{studies._LAZY[name]}")
        assert getattr(studies, name) is getattr(module, name), name


def test_importing_the_package_loads_no_study():
    code = ("import sys, slipcycle.studies; "
            "print(sorted(m for m in sys.modules if m.startswith('slipcycle.studies.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
