"""What every result file says about itself: provenance and the CF conventions.

:func:`provenance` is the metadata of every ``summary.json`` and ``result.nc``: the
slipcycle version, the versions of its main dependencies, the platform, the command line,
the case text and file, the time. :func:`cf_complete` brings a Dataset to the CF-1.10
conventions (Eaton et al., *NetCDF Climate and Forecast (CF) Metadata Conventions*,
version 1.10, 2022) before it is written, in one place for every command:

- the global ``Conventions = "CF-1.10"`` attribute;
- a coordinate variable for every dimension (an integer index ``0 .. n-1`` where the
  Dataset has none), without ``_FillValue`` (CF §5);
- ``long_name`` and ``units`` on every variable and coordinate, taken from the variable,
  else from the result's ``summary["units"]``, else ``"1"`` for integer, boolean and text
  variables (counts, codes and labels) — a floating-point variable with no unit anywhere
  is a gap the model must fill and is reported by :func:`cf_problems`;
- ``flag_values``/``flag_meanings`` consistent for categorical codes (CF §3.5);
- text as fixed-length char arrays (a ``<name>_strlen`` dimension), never the
  variable-length strings netCDF-4 writes by default (CF §2.2).

:func:`cf_problems` checks these rules and returns what is missing (empty when the
Dataset conforms); the writer logs its findings, and the tests hold every command to an
empty list.

Only the standard library is imported at load time.
"""

from __future__ import annotations

import logging
import platform
import re
import shlex
import sys
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from slipcycle._version import __version__

if TYPE_CHECKING:  # pragma: no cover
    import xarray as xr

__all__ = ["CONVENTIONS", "DEPENDENCIES", "set_command_line", "command_line", "versions",
           "platform_info", "provenance", "cf_complete", "cf_problems"]

CONVENTIONS = "CF-1.10"

#: the packages whose versions every result records
DEPENDENCIES = ("numpy", "scipy", "numba", "xarray", "netCDF4", "matplotlib")

log = logging.getLogger("slipcycle")

_COMMAND: list[str] | None = None
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def set_command_line(argv: Sequence[str] | None) -> None:
    """Record the command line of this process (the ``slipcycle`` command sets it; None
    forgets it, so :func:`command_line` falls back to ``sys.argv``)."""
    global _COMMAND
    _COMMAND = None if argv is None else [str(a) for a in argv]


def command_line() -> str:
    """The command line that produced the results: the one recorded by
    :func:`set_command_line`, else this process's ``sys.argv``."""
    argv = _COMMAND if _COMMAND is not None else list(sys.argv)
    return shlex.join(argv)


@lru_cache(maxsize=1)
def versions() -> dict[str, str]:
    """Versions of slipcycle, Python and :data:`DEPENDENCIES` (read from the installed
    package metadata, so nothing is imported).

    Returns
    -------
    dict
        Package name -> version (``"not installed"`` where absent).
    """
    from importlib.metadata import PackageNotFoundError, version

    out = {"slipcycle": __version__, "python": platform.python_version()}
    for name in DEPENDENCIES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "not installed"
    return out


@lru_cache(maxsize=1)
def platform_info() -> str:
    """The operating system, machine and Python implementation, one line."""
    return (f"{platform.system()} {platform.release()} {platform.machine()}; "
            f"{platform.python_implementation()} {platform.python_version()}")


def provenance(case_text: str | None, case_path: Path | str | None = None) -> dict:
    """Metadata attached to every result.

    Parameters
    ----------
    case_text : str or None
        The case as given (TOML text).
    case_path : path, optional
        The case file.

    Returns
    -------
    dict
        ``slipcycle_version``, ``versions`` (package -> version), ``platform``,
        ``command_line``, ``case_file``, ``case``, ``case_sha256`` (SHA-256 of the case
        text as UTF-8, ``""`` without one), ``created`` (ISO 8601, UTC) and
        ``units_system``.

    Notes
    -----
    ``summary.json`` keeps every entry but the case text itself, so ``case_sha256`` is
    what ties a summary to its case when no file was named (a case run from Python, the
    demo) or the file has changed since.
    """
    import hashlib

    return {
        "slipcycle_version": __version__,
        "versions": dict(versions()),
        "platform": platform_info(),
        "command_line": command_line(),
        "case_file": str(case_path) if case_path else "",
        "case": case_text or "",
        "case_sha256": hashlib.sha256(case_text.encode("utf-8", "surrogatepass")).hexdigest()
        if case_text else "",
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "units_system": "SI (N, m, Pa, J, rad, s)",
    }


def netcdf_attributes(meta: Mapping[str, Any]) -> dict[str, str]:
    """:func:`provenance` as global netCDF attributes (strings; versions flattened to
    ``version_<package>``), with ``Conventions``, ``title``, ``source`` and ``history``."""
    attrs: dict[str, str] = {"Conventions": CONVENTIONS}
    for key, value in meta.items():
        if key == "versions":
            attrs.update({f"version_{k}": str(v) for k, v in value.items()})
        else:
            attrs[key] = str(value)
    attrs["source"] = f"slipcycle {meta.get('slipcycle_version', __version__)}"
    attrs["history"] = f"{meta.get('created', '')}: {meta.get('command_line', '')}".strip()
    return attrs


# -- CF conventions ---------------------------------------------------------------------

def _is_float(var) -> bool:
    return var.dtype.kind in "fc"


def _default_long_name(name: str) -> str:
    return str(name).replace("_", " ")


def cf_complete(ds: xr.Dataset, units: Mapping[str, str] | None = None,
                flags: Mapping[str, Sequence[str]] | None = None) -> xr.Dataset:
    """A copy of ``ds`` completed to the CF conventions (see the module text).

    Parameters
    ----------
    ds : xarray.Dataset
        The result's Dataset (not modified).
    units : mapping, optional
        Variable name -> unit, from the result's ``summary["units"]``; used where a
        variable has no ``units`` attribute.
    flags : mapping, optional
        Variable name -> the words of its integer codes (``RunOutputs.flags``); used where
        an integer variable has no ``flag_values``.

    Returns
    -------
    xarray.Dataset
    """
    import numpy as np

    units = dict(units or {})
    flags = dict(flags or {})
    ds = ds.copy()
    for dim in list(ds.dims):
        if dim in ds.coords and _is_text(ds[dim].variable):
            # a coordinate variable must be numeric (CF §5): index the dimension and keep
            # its labels as an auxiliary coordinate "<dim>_name"
            labels = ds[dim].values.astype(str)
            attrs = dict(ds[dim].attrs)
            ds = ds.assign_coords({
                f"{dim}_name": (dim, labels, {**attrs, "long_name": attrs.get(
                    "long_name", f"{_default_long_name(dim)} name"), "units": "1"}),
                dim: (dim, np.arange(labels.size, dtype=np.int64),
                      {"long_name": f"{_default_long_name(dim)} index", "units": "1"})})
    for dim, size in ds.sizes.items():
        if dim not in ds.coords and dim not in ds.data_vars:
            ds = ds.assign_coords({dim: (dim, np.arange(size, dtype=np.int64),
                                         {"long_name": f"{_default_long_name(dim)} index",
                                          "units": "1"})})
    for name in list(ds.variables):
        var = ds[name].variable
        attrs = var.attrs
        if "long_name" not in attrs and "standard_name" not in attrs:
            attrs["long_name"] = str(attrs.get("description", _default_long_name(name)))
        words = flags.get(str(name))
        if words and var.dtype.kind in "iu" and "flag_values" not in attrs:
            attrs["flag_values"] = np.arange(len(words), dtype=var.dtype)
            attrs["flag_meanings"] = " ".join(str(w).replace(" ", "_") for w in words)
        if "units" not in attrs and "units" not in var.encoding:
            if str(name) in units and units[str(name)]:
                attrs["units"] = str(units[str(name)])
            elif not _is_float(var) or "flag_values" in attrs:
                attrs["units"] = "1"    # counts, codes, booleans and text
        if name in ds.dims:
            var.encoding["_FillValue"] = None      # coordinate variables have no fill
        if _is_text(var):
            # netCDF-4 would store text as variable-length strings, which CF checkers and
            # netCDF-3 readers refuse (CF §2.2): store fixed-length char arrays instead
            var.encoding["dtype"] = "S1"
            var.encoding["char_dim_name"] = f"{name}_strlen"
            var.encoding.pop("_FillValue", None)
    ds.attrs["Conventions"] = CONVENTIONS
    return ds


def _is_text(var) -> bool:
    """Whether an xarray Variable holds text (str/bytes, or objects that are all str)."""
    kind = var.dtype.kind
    if kind in "US":
        return True
    if kind == "O":
        return all(isinstance(v, str | bytes) for v in var.values.ravel())
    return False


def cf_problems(ds: xr.Dataset) -> list[str]:
    """What keeps ``ds`` from the CF rules of :func:`cf_complete` (empty if none).

    Checks: ``Conventions``; names that start with a letter and hold only letters,
    digits and underscores (CF §2.3); a coordinate variable for every dimension, with no
    ``_FillValue`` (CF §5); ``long_name`` (or ``standard_name``) and ``units`` on every
    variable; ``flag_values`` of the variable's type and as many as the words of
    ``flag_meanings`` (CF §3.5); text as fixed-length char arrays, not variable-length
    strings (CF §2.2).

    Parameters
    ----------
    ds : xarray.Dataset
        A Dataset as written, or as read back from a file.

    Returns
    -------
    list of str
        One line per problem, naming the variable.
    """
    import numpy as np

    problems = []
    if ds.attrs.get("Conventions") != CONVENTIONS:
        problems.append(f"global: Conventions is {ds.attrs.get('Conventions')!r}, "
                        f"not {CONVENTIONS!r}")
    for dim in ds.dims:
        if dim not in ds.variables:
            problems.append(f"{dim}: dimension without a coordinate variable")
        elif "_FillValue" in ds[dim].attrs or ds[dim].encoding.get("_FillValue") is not None:
            # read back from a file, a fill value is in the encoding
            problems.append(f"{dim}: coordinate variable with a _FillValue")
    for name in ds.variables:
        attrs = ds[name].attrs
        if not _NAME.match(str(name)):
            problems.append(f"{name}: not a CF variable name")
        if "long_name" not in attrs and "standard_name" not in attrs:
            problems.append(f"{name}: no long_name")
        if "units" not in attrs:
            problems.append(f"{name}: no units")
        if "flag_values" in attrs or "flag_meanings" in attrs:
            values = np.atleast_1d(attrs.get("flag_values", []))
            meanings = str(attrs.get("flag_meanings", "")).split()
            if len(values) != len(meanings):
                problems.append(f"{name}: {len(values)} flag_values but {len(meanings)} "
                                "flag_meanings")
            if values.size and values.dtype.kind != ds[name].dtype.kind:
                problems.append(f"{name}: flag_values of type {values.dtype}, variable of "
                                f"type {ds[name].dtype}")
        var = ds[name].variable
        if _is_text(var) and np.dtype(var.encoding.get("dtype", object)) != np.dtype("S1"):
            problems.append(f"{name}: text stored as variable-length strings, not as a "
                            "char array (CF §2.2)")
    return problems
