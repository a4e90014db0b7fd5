"""Writing results: ``summary.json``, ``result.nc`` and ``figures/*.png``.

Outputs are staged in a temporary directory beside the target and moved into place only
when every file has been written, so a run that fails leaves nothing that looks like a
result. Every output carries the case text, units and the provenance of
:func:`slipcycle.io.metadata.provenance` (versions, platform, command line); ``result.nc``
is completed to the CF-1.10 conventions in one place, :func:`write_netcdf`. Figures are
drawn with the non-interactive Agg backend and written by :func:`save_figure`, here one
after another (:func:`draw_figures`) or by a caller's drawer running beside the netCDF
write (the command line's worker processes, :mod:`slipcycle.cli.figure_worker`). xarray is
imported only when a Dataset is written, and kept from importing dask where none is used
(:func:`dask_not_imported`).
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import os
import shutil
import sys
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from slipcycle.errors import CaseError
from slipcycle.io.metadata import provenance

if TYPE_CHECKING:  # pragma: no cover
    import xarray as xr

log = logging.getLogger("slipcycle")

__all__ = ["RunOutputs", "write_outputs", "provenance", "to_jsonable", "check_output_dir",
           "check_output_file", "remove_stale_partials", "write_together", "write_netcdf",
           "defer_dask_detection", "dask_not_imported", "FIGURE_DPI", "save_figure",
           "draw_figures", "FigureDrawing"]

RESULT_FILES = ("summary.json", "result.nc", "figures")

#: resolution of every figure file [dots per inch]
FIGURE_DPI = 120


class _DeferredDask:
    """xarray's record of the ``dask`` duck-array module, resolved only once
    ``dask.array`` has been imported by someone.

    xarray asks, on the first Dataset it builds, whether each variable is a dask array, and
    answers by importing dask (about 1-2 s when the sweep extra is installed). No object can
    be a dask array before ``dask.array`` is imported, so until then the answer "no dask
    array types" is exact; afterwards the real record is built and used.
    """

    def __init__(self, real_factory):
        self._factory = real_factory
        self._real = None

    def _resolved(self):
        if self._real is None and "dask.array" in sys.modules:
            self._real = self._factory("dask")
        return self._real

    @property
    def type(self):
        real = self._resolved()
        return real.type if real is not None else ()

    @property
    def module(self):
        real = self._resolved()
        return real.module if real is not None else None

    @property
    def available(self):
        real = self._resolved()
        return real.available if real is not None else False

    @property
    def version(self):
        real = self._resolved()
        if real is not None:
            return real.version
        from packaging.version import Version

        return Version("0.0.0")


def defer_dask_detection() -> bool:
    """Keep xarray from importing dask until dask arrays can exist (see
    :class:`_DeferredDask`). Returns True if the deferral is in place."""
    try:
        from xarray.namedarray import pycompat
    except ImportError:  # another xarray layout: leave it alone
        return False
    cache = getattr(pycompat, "_cached_duck_array_modules", None)
    factory = getattr(pycompat, "DuckArrayModule", None)
    if not isinstance(cache, dict) or factory is None:
        return False
    if "dask" not in cache and "dask.array" not in sys.modules:
        cache["dask"] = _DeferredDask(factory)
    return isinstance(cache.get("dask"), _DeferredDask)


@contextlib.contextmanager
def dask_not_imported():
    """Within the block, xarray sees dask as absent unless dask is loaded already.

    xarray asks, for every Dataset it builds and every netCDF file it writes, whether a
    value is a dask collection and which dask scheduler is active, importing dask to learn
    it (1-2 s where the sweep extra is installed). Before dask is imported no dask
    collection and no dask computation can exist, so "no dask" is the exact answer: the
    block makes ``import dask`` fail (``sys.modules["dask"] = None``) and keeps xarray from
    caching the failure (:func:`defer_dask_detection`). Nothing changes if dask is already
    loaded. For code that uses no dask (the command line around a command that does not
    use a Dask scheduler, :func:`write_outputs`); not thread-safe against a thread that
    imports dask meanwhile.
    """
    if "dask" in sys.modules:
        yield
        return
    sys.modules["dask"] = None  # type: ignore[assignment]  # import dask -> ImportError
    try:
        defer_dask_detection()
        _forget_module_checks()
        yield
    finally:
        if sys.modules.get("dask", 0) is None:
            del sys.modules["dask"]
        _forget_module_checks()


def _forget_module_checks() -> None:
    """Clear xarray's cache of which optional modules are installed (it holds the answer
    for dask from before or inside :func:`dask_not_imported`)."""
    utils = sys.modules.get("xarray.namedarray.utils")
    check = getattr(utils, "module_available", None)
    if hasattr(check, "cache_clear"):
        check.cache_clear()


@dataclass
class RunOutputs:
    """Everything one analysis writes.

    Attributes
    ----------
    summary : dict
        The numbers a user quotes (JSON-serialisable after :func:`to_jsonable`).
    dataset : xarray.Dataset or None
        Full histories; every variable should carry a ``units`` attribute.
    figures : dict of str to callable
        Figure name -> function returning a matplotlib Figure. Called at write time so
        figures are drawn only once the numbers exist.
    extra_files : dict of str to callable
        Relative path -> function ``f(path)`` writing an additional file (e.g. a report).
    flags : dict of str to tuple of str
        The model's own description of its categorical summary entries: summary key ->
        every word that entry can take (e.g. ``"steady_state": ("shakedown",
        "cyclic_slip", ...)``). Stores that keep such an entry as an integer (sweeps) use
        the position in this tuple as the code, with CF ``flag_values``/``flag_meanings``.
        Units of numeric entries are in ``summary["units"]`` (``"1"`` when dimensionless).
    cf_completed : bool
        The Dataset is already completed to the CF conventions (a result's
        ``to_outputs``): the writer does not complete it again.
    """

    summary: dict
    dataset: xr.Dataset | None = None
    figures: dict[str, Callable[[], Any]] = field(default_factory=dict)
    extra_files: dict[str, Callable[[Path], None]] = field(default_factory=dict)
    flags: dict[str, tuple[str, ...]] = field(default_factory=dict)
    cf_completed: bool = False


def to_jsonable(obj: Any) -> Any:
    """Convert NumPy scalars/arrays (recursively) to JSON types; non-finite floats to None."""
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, Path):
        return str(obj)
    return obj


class FigureDrawing(Protocol):
    """Figures being drawn into a directory (what a ``draw`` of :func:`write_outputs`
    returns)."""

    def result(self) -> None:
        """Wait until every figure file is written; raise what drawing raised."""

    def cancel(self) -> None:
        """Stop drawing; once this returns, nothing more is written."""


class _Drawn:
    """Figures already written (the drawing of :func:`draw_figures`)."""

    def result(self) -> None:
        pass

    def cancel(self) -> None:
        pass


def write_outputs(out_dir: str | Path, outputs: RunOutputs, case_text: str | None = None,
                  case_path: Path | None = None, *,
                  draw: Callable[[Mapping[str, Callable[[], Any]], Path], FigureDrawing]
                  | None = None) -> Path:
    """Write ``outputs`` to ``out_dir`` atomically.

    Files are written into a staging directory next to ``out_dir`` and then renamed into
    place. If anything fails, the staging directory is removed and ``out_dir`` keeps
    whatever it held before (previous result files are only replaced on success).

    Parameters
    ----------
    out_dir : str or Path
        The result directory (created if missing).
    outputs : RunOutputs
    case_text : str, optional
        The case file's text, kept in the provenance.
    case_path : Path, optional
        Where the case was read from.
    draw : callable, optional
        ``draw(figures, directory)`` starts writing each figure of ``figures`` (name ->
        function returning a Figure) to ``directory/<name>.png`` with
        :func:`save_figure` and returns its :class:`FigureDrawing`; the files are
        committed only after its ``result()`` returned. It is started before the summary
        and ``result.nc`` are written, so that it may run beside them. Default
        :func:`draw_figures` (here, one after another).

    Returns
    -------
    Path
        ``out_dir``.
    """
    out_dir = Path(out_dir)
    check_output_dir(out_dir)
    try:
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_partials(out_dir)
        stage = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.partial-{os.getpid()}-",
                                      dir=out_dir.parent))
    except OSError as exc:
        raise _output_error(out_dir, exc) from None
    drawing: FigureDrawing | None = None
    try:
        meta = provenance(case_text, case_path)   # inside: an interrupt here removes stage
        if outputs.figures:
            (stage / "figures").mkdir()
            drawing = (draw or draw_figures)(outputs.figures, stage / "figures")
        summary = dict(outputs.summary)
        summary.setdefault("units", {})
        summary["metadata"] = {k: v for k, v in meta.items() if k != "case"}
        (stage / "summary.json").write_text(
            json.dumps(to_jsonable(summary), indent=2, allow_nan=False) + "\n", encoding="utf-8"
        )
        if outputs.dataset is not None:
            write_netcdf(stage / "result.nc", outputs.dataset, meta,
                         summary.get("units"), outputs.flags,
                         complete=not outputs.cf_completed)
        for rel, writer in outputs.extra_files.items():
            target = stage / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            writer(target)
        if drawing is not None:
            drawing.result()
            drawing = None
        _commit(stage, out_dir)
    except OSError as exc:
        raise _output_error(out_dir, exc) from None
    finally:
        if drawing is not None:  # failed or interrupted: no figure may land after cleanup
            drawing.cancel()
        shutil.rmtree(stage, ignore_errors=True)
    return out_dir


def save_figure(fig, path: Path) -> None:
    """Write the matplotlib Figure ``fig`` to ``path`` as PNG at :data:`FIGURE_DPI`
    (and close it if pyplot manages it).

    zlib level 1 rather than PIL's default 6: PNG is lossless at every level, so the image
    is the same; it is written faster and the file is about 9 % larger.
    """
    fig.savefig(path, dpi=FIGURE_DPI, pil_kwargs={"compress_level": 1})
    plt = sys.modules.get("matplotlib.pyplot")
    if plt is not None:
        plt.close(fig)


def draw_figures(figures: Mapping[str, Callable[[], Any]], directory: Path) -> FigureDrawing:
    """Draw each figure of ``figures`` (name -> function returning a Figure) and write it
    to ``directory/<name>.png`` (:func:`save_figure`), one after another, in this process.

    Returns
    -------
    FigureDrawing
        Done already.
    """
    with _figure_backend():
        for name, make in figures.items():
            save_figure(make(), Path(directory) / f"{name}.png")
    return _Drawn()


def write_netcdf(path: Path, dataset: xr.Dataset, meta: Mapping | None = None,
                 units: Mapping[str, str] | None = None,
                 flags: Mapping[str, tuple[str, ...]] | None = None, *,
                 complete: bool = True) -> None:
    """Write ``dataset`` to ``path`` as CF-1.10 netCDF with the provenance ``meta``.

    The Dataset is completed by :func:`slipcycle.io.metadata.cf_complete` (coordinate
    variables, ``long_name``/``units`` from the variables or the summary ``units``, flag
    attributes, ``Conventions``) unless ``complete`` is False (a result's Dataset, completed
    once by its ``to_outputs``); what is still missing is logged (INFO). The global
    attributes are :func:`slipcycle.io.metadata.netcdf_attributes` of ``meta``.
    """
    from slipcycle.io.metadata import cf_complete, cf_problems, netcdf_attributes

    ds = cf_complete(dataset, units, flags) if complete else dataset.copy()
    ds.attrs.update(netcdf_attributes(meta or provenance(None)))
    for problem in cf_problems(ds):
        log.info("result.nc: CF: %s", problem)
    with dask_not_imported(), _interrupt_deferred():
        ds.to_netcdf(path)


@contextlib.contextmanager
def _interrupt_deferred():
    """Hold an interrupt (SIGINT, Ctrl-C) back until the block ends.

    An interrupt inside xarray's netCDF writer, between the acquisition of its HDF5 lock
    and its cleanup, leaves the lock held and the cleanup waiting on it for ever; held
    back, it is raised once the file is complete (and the staged write removes it). Only
    in the main thread (where Python handlers run); elsewhere the block runs as it is.
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    # a Python-level handler, not a signal mask: the signal may be delivered to any thread
    # (BLAS, Numba and test-runner threads do not block it), but Python handlers always
    # run in the main thread, between bytecodes
    caught = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler if previous is None
                      else previous)
    if caught:
        raise KeyboardInterrupt


@contextlib.contextmanager
def _figure_backend():
    """matplotlib on the non-interactive Agg backend (no display is needed, and no GUI
    toolkit is loaded). pyplot is not imported for it: figures made as
    ``matplotlib.figure.Figure`` do not need it (0.1 s saved), and a plot function that
    uses pyplot starts it on Agg."""
    import matplotlib

    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")  # records the backend; nothing is loaded
    elif matplotlib.get_backend().lower() != "agg":
        matplotlib.use("Agg")
    yield


def write_together(outputs: list[tuple[Path, Callable[[Path], None]]]) -> None:
    """Write several files so that either all of them appear or none does.

    Each ``(path, write)`` is first written by ``write(tmp)`` to a temporary file beside
    ``path``; only when every one is complete are they renamed into place. If a rename
    fails, the targets already replaced get their previous content back. Directories
    created for the outputs are removed again on failure. Any file-system problem is one
    :class:`~slipcycle.io.CaseError` naming the path.
    """
    created: list[Path] = []
    staged: list[tuple[Path, Path]] = []
    backups: list[tuple[Path, Path | None]] = []
    try:
        for path, write in outputs:
            missing = [d for d in [path.parent, *path.parent.parents] if not d.exists()]
            try:
                for d in reversed(missing):
                    d.mkdir()
                    created.append(d)
                remove_stale_partials(path)
                fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.partial-{os.getpid()}-",
                                           dir=path.parent)
                os.close(fd)
                staged.append((Path(tmp), path))
                write(Path(tmp))
                os.chmod(tmp, 0o644)
            except OSError as exc:
                raise _output_error(path, exc) from None
        for tmp, path in staged:
            try:
                old = None
                if path.exists():
                    fd, name = tempfile.mkstemp(prefix=f".{path.name}.old-{os.getpid()}-",
                                                dir=path.parent)
                    os.close(fd)
                    old = Path(name)
                    os.replace(path, old)
                backups.append((path, old))
                os.replace(tmp, path)
            except OSError as exc:
                raise _output_error(path, exc) from None
    except BaseException:
        for path, old in reversed(backups):        # undo the renames already made
            try:
                if old is not None:
                    os.replace(old, path)
                elif path.exists():
                    path.unlink()
            except OSError:
                pass
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
        for d in reversed(created):
            try:
                d.rmdir()
            except OSError:
                pass
        raise
    for _, old in backups:
        if old is not None:
            old.unlink(missing_ok=True)


def _output_error(path: Path, exc: OSError):
    # name what the user asked for, not a staging name they never saw
    return CaseError(str(path), f"cannot write: {exc.strerror or exc}")


def _first_existing(path: Path) -> Path:
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _check_parent_writable(path: Path) -> None:
    anchor = _first_existing(Path(path).parent if not Path(path).exists() else path)
    if not anchor.is_dir():
        raise CaseError(str(path), f"cannot be created: {anchor} is a file, not a directory")
    if not os.access(anchor, os.W_OK | os.X_OK):
        raise CaseError(str(path), f"cannot be created: no permission to write in {anchor}")


def _check_not_in_package(path: Path) -> None:
    """Refuse an output inside the installed slipcycle package (its example cases and
    code): results written there would change, or be lost with, the installation."""
    from slipcycle.io.files import resolved

    package = resolved(Path(__file__).resolve().parents[1])
    target = resolved(path)
    if target == package or package in target.parents:
        raise CaseError(str(path), f"is inside the installed slipcycle package ({package}); "
                        "write results to a folder of your own (slipcycle examples --copy "
                        "DIR copies the example cases out)")


def _is_slipcycle_summary(path: Path) -> bool:
    """Whether ``path`` is a ``summary.json`` written by slipcycle (its provenance names
    the slipcycle version)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    meta = data.get("metadata") if isinstance(data, dict) else None
    return isinstance(meta, dict) and "slipcycle_version" in meta


#: entries of a result directory that a write replaces: files by name, folders whole
_REPLACED_FILES, _REPLACED_DIRS = ("summary.json", "result.nc"), ("figures", "fields")


def _check_replaceable(path: Path) -> None:
    """Refuse a result directory whose entries of the result names belong to the user.

    A write replaces ``summary.json`` and ``result.nc`` and the folders ``figures/`` and
    ``fields/`` whole (:func:`_commit`); that is only safe where they are an earlier
    slipcycle result, i.e. where ``summary.json`` was written by slipcycle. Otherwise such
    an entry (a user's own ``figures/`` folder of drawings, a ``summary.json`` of another
    tool, a folder named ``result.nc``) would be deleted without a word.
    """
    summary = path / "summary.json"
    if summary.is_file() and not summary.is_symlink() and _is_slipcycle_summary(summary):
        return
    for name in (*_REPLACED_FILES, *_REPLACED_DIRS):
        entry = path / name
        if not (entry.exists() or entry.is_symlink()):
            continue
        if name in _REPLACED_DIRS and entry.is_dir() and not entry.is_symlink():
            try:
                if not any(entry.iterdir()):
                    continue                      # an empty folder holds nothing to lose
            except OSError:
                pass
        what = (f"a {name} that slipcycle did not write" if name == "summary.json" else
                f"{'the folder ' if entry.is_dir() else ''}{name} but no summary.json "
                "written by slipcycle (so no earlier result)")
        raise CaseError(str(path), f"holds {what}; the results would replace it: move it "
                        "or choose another --out")


def check_output_dir(path: str | Path) -> None:
    """Refuse, before any work, an output directory that cannot be written.

    Raises :class:`~slipcycle.io.CaseError` naming the path when it is an existing file,
    when neither it nor its nearest existing parent can be written, when it lies inside
    the installed slipcycle package, or when it holds entries of the result names
    (``summary.json``, ``result.nc``, ``figures/``, ``fields/``) that are not an earlier
    slipcycle result (:func:`_check_replaceable`).
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise CaseError(str(path), "exists and is not a directory; choose another --out")
    _check_not_in_package(path)
    if path.is_dir():
        if not os.access(path, os.W_OK | os.X_OK):
            raise CaseError(str(path), "no permission to write in this directory")
        _check_replaceable(path)
        return
    _check_parent_writable(path)


def check_output_file(path: str | Path) -> None:
    """Refuse, before any work, an output file that cannot be written (see
    :func:`check_output_dir`)."""
    path = Path(path)
    _check_not_in_package(path)
    if path.is_dir():
        raise CaseError(str(path), "is a directory; give a file name")
    if path.exists():
        if not os.access(path, os.W_OK) or not os.access(path.parent, os.W_OK | os.X_OK):
            raise CaseError(str(path), "no permission to replace this file")
        return
    _check_parent_writable(path)


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_partials(out_dir: str | Path) -> list[Path]:
    """Remove staging folders and files left by a killed write of ``out_dir`` (a result
    directory or a single output file).

    Staging entries are named ``.<name>.partial-<pid>-*`` (and replaced results
    ``.<entry>.old-<pid>``); those whose process no longer runs are deleted. Entries of a
    live process (a concurrent write) are left alone.

    Returns
    -------
    list of Path
        What was removed.
    """
    out_dir = Path(out_dir)
    candidates = []
    if out_dir.parent.is_dir():
        candidates += out_dir.parent.glob(f".{out_dir.name}.partial-*")
        candidates += out_dir.parent.glob(f".{out_dir.name}.old-*")
    if out_dir.is_dir():
        candidates += out_dir.glob(".*.old-*")
    removed = []
    for path in candidates:
        tail = path.name.rsplit(".partial-", 1)[-1] if ".partial-" in path.name \
            else path.name.rsplit(".old-", 1)[-1]
        pid_text = tail.split("-", 1)[0]
        if pid_text.isdigit() and _pid_alive(int(pid_text)):
            continue
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)
        removed.append(path)
    return removed


def _commit(stage: Path, out_dir: Path) -> None:
    """Move staged entries into ``out_dir``, replacing older result entries of the same name."""
    out_dir.mkdir(parents=True, exist_ok=True)
    for entry in sorted(stage.iterdir()):
        target = out_dir / entry.name
        if target.is_dir() and not target.is_symlink():
            old = target.with_name(f".{target.name}.old-{os.getpid()}")
            target.rename(old)
            entry.rename(target)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(entry, target)
