"""The public Python API of every model is documented (numpydoc sections, checked here)."""

from __future__ import annotations

import importlib
import inspect

import pytest

PACKAGES = ("slipcycle.halfspace", "slipcycle.discrete", "slipcycle.rods", "slipcycle.fe",
            "slipcycle.discrete3d")


def _public(pkg):
    mod = importlib.import_module(pkg)
    assert hasattr(mod, "__all__") and mod.__all__, f"{pkg} has no __all__"
    return [(pkg, name) for name in mod.__all__]


#: exported but not yet documented with numpydoc sections (strict xfail: remove a name when
#: its docstring gains Parameters/Returns). Empty: every public name is documented.
UNDOCUMENTED: set[str] = set()

NAMES = [item for pkg in PACKAGES for item in _public(pkg)]


def _takes_parameters(obj) -> bool:
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return False
    return any(p.name not in ("self", "cls") for p in sig.parameters.values())


def _doc_of(obj) -> str:
    doc = inspect.getdoc(obj) or ""
    if inspect.isclass(obj) and obj.__init__ is not object.__init__:
        doc += "\n" + (inspect.getdoc(obj.__init__) or "")
    return doc


@pytest.mark.parametrize(("pkg", "name"), [
    pytest.param(p, n, id=f"{p}.{n}", marks=pytest.mark.xfail(
        f"{p}.{n}" in UNDOCUMENTED, reason="numpydoc sections still missing", strict=True))
    for p, n in NAMES])
def test_every_public_name_is_documented(pkg, name):
    obj = getattr(importlib.import_module(pkg), name)
    if not (inspect.isclass(obj) or inspect.isfunction(obj)):
        return  # constants (INTERFACES): documented in the module docstring
    doc = _doc_of(obj)
    assert doc.strip(), f"{pkg}.{name} has no docstring"
    if _takes_parameters(obj):
        assert ("Parameters\n----------" in doc or "Attributes\n----------" in doc), \
            f"{pkg}.{name}: no numpydoc Parameters section"
    if inspect.isfunction(obj):
        assert "Returns\n-------" in doc or "Yields\n------" in doc, \
            f"{pkg}.{name}: no numpydoc Returns section"


@pytest.mark.parametrize("pkg", PACKAGES)
def test_all_lists_resolve(pkg):
    mod = importlib.import_module(pkg)
    assert len(set(mod.__all__)) == len(mod.__all__)
    for name in mod.__all__:
        assert getattr(mod, name) is not None
