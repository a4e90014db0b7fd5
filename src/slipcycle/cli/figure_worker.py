"""Figures drawn in worker processes beside the solve and the netCDF write.

A command that writes figures spends most of its time in matplotlib: importing it and
drawing. :meth:`FigureWorker.start`, called before the solve, forks a process that imports
matplotlib and loads its fonts while the parent reads the case and solves; its
:meth:`~FigureWorker.draw` is the ``draw`` of :func:`slipcycle.io.results.write_outputs`:
it hands the figures over (pickled: each is a function of the result Dataset, such as a
:func:`functools.partial` of a :mod:`slipcycle.plot` function) and returns at once, so the
parent writes ``summary.json`` and ``result.nc`` meanwhile. The worker forks once more, so
that two processes draw the figures, taking them one by one from a shared pipe. Each figure
is drawn and written by :func:`slipcycle.io.results.save_figure`, the same code as without
workers, into the staging directory of :func:`~slipcycle.io.results.write_outputs`, which
commits the files only once every one of them is written.

Used only where it is safe and helps: on Linux (``fork`` of a process that has loaded NumPy
and xarray but no GUI toolkit), with more than one CPU, from a process with no other
Python thread, and not under ``SLIPCYCLE_DEBUG`` (where a figure's traceback should be
local). Otherwise :meth:`FigureWorker.start` returns None and figures are drawn in the
process, one after another. Figures that cannot be pickled (a model whose ``figures()``
returns closures) are drawn in the process as well.

The workers form their own process group: an interrupt (Ctrl-C) reaches only the parent,
which stops them (:meth:`~FigureWorker.cancel` kills the group), so no figure lands in the
staging directory after it is removed. Warnings a figure raises are shown by the parent; an
exception is raised again in the parent, with the worker's traceback as its cause.

This module imports only the standard library; matplotlib is imported in the worker.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import struct
import sys
import tempfile
import threading
import traceback
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

__all__ = ["FigureWorker"]

_LENGTH = struct.Struct("<Q")
_TOKEN = struct.Struct("<I")
_PIPE_BUFFER = 4096  # bytes a pipe takes without a reader on every Linux (PIPE_BUF)


class _RemoteTraceback(Exception):
    """The traceback of an exception raised in a figure worker (shown as the cause)."""

    def __init__(self, text: str):
        super().__init__(text)
        self.text = text

    def __str__(self) -> str:
        return f"\n\"\"\"\n{self.text}\"\"\""


def _safe_to_fork() -> bool:
    """Whether forking this process for figure workers is safe and useful."""
    if not sys.platform.startswith("linux") or not hasattr(os, "fork"):
        return False
    if os.environ.get("SLIPCYCLE_DEBUG"):
        return False
    if threading.active_count() > 1:  # a lock held by another thread would stay held
        return False
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    return cpus > 1


class FigureWorker:
    """A forked process that draws figures (see the module docstring).

    Use :meth:`start` (None where workers are not used), pass :meth:`draw` as the ``draw``
    of :func:`~slipcycle.io.results.write_outputs`, and :meth:`close` at the end (or use
    the worker as a context manager)."""

    def __init__(self, pid: int, jobs_w: int, reply_r: int, payload):
        self._pid = pid
        self._jobs_w, self._reply_r = jobs_w, reply_r
        self._payload = payload
        self._sent = False
        self._reaped = False

    # -- parent side -------------------------------------------------------------------
    @classmethod
    def start(cls, drawers: int = 2) -> FigureWorker | None:
        """Fork the worker (it loads matplotlib at once); None where workers are not used.

        Parameters
        ----------
        drawers : int
            Processes that draw (the worker and ``drawers - 1`` forked from it when the
            figures arrive).
        """
        if not _safe_to_fork():
            return None
        try:
            payload = tempfile.TemporaryFile(prefix="slipcycle-figures-")
            jobs_r, jobs_w = os.pipe()
            reply_r, reply_w = os.pipe()
        except OSError:
            return None
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        try:
            pid = os.fork()
        except OSError:
            payload.close()
            for fd in (jobs_r, jobs_w, reply_r, reply_w):
                os.close(fd)
            return None
        if pid == 0:  # the worker: never returns
            code = 1
            try:
                os.close(jobs_w)
                os.close(reply_r)
                code = _serve(jobs_r, reply_w, payload.fileno(), max(1, int(drawers)))
            finally:
                os._exit(code)
        os.close(jobs_r)
        os.close(reply_w)
        with contextlib.suppress(OSError):  # also done by the worker: whichever runs first
            os.setpgid(pid, pid)
        return cls(pid, jobs_w, reply_r, payload)

    def draw(self, figures: Mapping[str, Callable[[], Any]], directory: Path):
        """Start drawing ``figures`` into ``directory`` (the ``draw`` of
        :func:`~slipcycle.io.results.write_outputs`); returns the drawing (this worker),
        or draws them here and returns a finished drawing if they cannot be pickled."""
        from slipcycle.io.results import draw_figures

        if self._sent or self._reaped:
            return draw_figures(figures, directory)
        jobs = [(str(Path(directory) / f"{name}.png"), make) for name, make in figures.items()]
        try:
            data = pickle.dumps(jobs, protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, TypeError, AttributeError):
            self.cancel()
            return draw_figures(figures, directory)
        try:
            fd = self._payload.fileno()
            view, offset = memoryview(data), 0
            while offset < len(data):
                offset += os.pwrite(fd, view[offset:], offset)
            os.write(self._jobs_w, _LENGTH.pack(len(data)))
        except OSError:  # no room for the hand-over, or the worker is gone: draw here
            self.cancel()
            return draw_figures(figures, directory)
        self._sent = True
        return self

    def result(self) -> None:
        """Wait until the figures are written; raise what drawing raised."""
        chunks = []
        while chunk := os.read(self._reply_r, 1 << 16):
            chunks.append(chunk)
        status = self._reap()
        self._close_fds()
        if not chunks:
            raise RuntimeError(f"the figure worker ended without an answer ({status})")
        reply = pickle.loads(b"".join(chunks))
        for message, category, filename, lineno in reply["warnings"]:
            warnings.warn_explicit(message, category, filename, lineno)
        if reply["error"] is not None:
            exc, text = reply["error"]
            raise exc from _RemoteTraceback(text)

    def cancel(self) -> None:
        """Stop the worker and everything it forked; nothing is written after this."""
        if not self._reaped:
            with contextlib.suppress(OSError):
                os.killpg(self._pid, signal.SIGKILL)
            with contextlib.suppress(OSError):
                os.kill(self._pid, signal.SIGKILL)
            self._reap()
        self._close_fds()

    close = cancel

    def __enter__(self) -> FigureWorker:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _reap(self) -> str:
        if self._reaped:
            return "ended"
        self._reaped = True
        while True:
            try:
                _, status = os.waitpid(self._pid, 0)
            except ChildProcessError:
                return "ended"
            except InterruptedError:  # pragma: no cover - retried by Python itself
                continue
            if os.WIFSIGNALED(status):
                return f"killed by signal {os.WTERMSIG(status)}"
            return f"exit status {os.WEXITSTATUS(status)}"

    def _close_fds(self) -> None:
        for name in ("_jobs_w", "_reply_r"):
            fd = getattr(self, name)
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
                setattr(self, name, None)
        self._payload.close()


# -- worker side ---------------------------------------------------------------------------
def _serve(jobs_r: int, reply_w: int, payload_fd: int, drawers: int) -> int:
    """The worker: load matplotlib, wait for the figures, draw them with ``drawers``
    processes, answer ``{"error": ..., "warnings": [...]}``. Returns the exit code."""
    with contextlib.suppress(OSError):
        os.setpgid(0, 0)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops the workers
    _preload()
    header = _read_exactly(jobs_r, _LENGTH.size)
    if len(header) < _LENGTH.size:  # no figures for this run
        return 0
    (size,) = _LENGTH.unpack(header)
    data = _pread_exactly(payload_fd, size)
    try:
        jobs = pickle.loads(data)
    except BaseException as exc:  # noqa: BLE001 - reported to the parent
        _answer(reply_w, _error(exc), [])
        return 1
    # the index of each figure, written at once: every drawer reads the next one (a read
    # of one token from a pipe that holds them all is atomic), the slow figures balance
    tokens = b"".join(_TOKEN.pack(i) for i in range(len(jobs)))
    tokens_r = None  # more figures than fit: this process draws them all
    if len(tokens) <= _PIPE_BUFFER:
        tokens_r, tokens_w = os.pipe()
        os.write(tokens_w, tokens)
        os.close(tokens_w)
    else:
        drawers = 1
    helpers = []
    for _ in range(min(drawers, len(jobs)) - 1):
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:
            code = 1
            try:
                os.close(r)
                os.close(reply_w)
                os.close(jobs_r)
                error, caught = _draw_share(jobs, tokens_r)
                _answer(w, error, caught)
                code = 0
            finally:
                os._exit(code)
        os.close(w)
        helpers.append((pid, r))
    error, caught = _draw_share(jobs, tokens_r)
    for pid, r in helpers:
        chunks = []
        while chunk := os.read(r, 1 << 16):
            chunks.append(chunk)
        os.close(r)
        os.waitpid(pid, 0)
        if not chunks:
            error = error or _error(RuntimeError("a figure-drawing process ended "
                                                 "without an answer"))
            continue
        reply = pickle.loads(b"".join(chunks))
        error = error or reply["error"]
        caught += reply["warnings"]
    _answer(reply_w, error, caught)
    return 0


def _preload() -> None:
    """Import matplotlib and load its fonts while the parent solves."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with contextlib.suppress(Exception):
            import io

            from matplotlib.figure import Figure

            from slipcycle.io.results import _figure_backend, save_figure

            with _figure_backend():
                # a small figure through the whole path: fonts, glyphs, layout, PNG writer
                fig = Figure(figsize=(2, 2))
                ax = fig.add_subplot()
                ax.plot([0, 1], [0, 1], label="x")
                ax.fill_between([0, 1], [0, 1], [0, -1], alpha=0.1)
                ax.set_title("Q [N], V [µm], θ [rad], Ŵ = W / (λ γσ f² P0)")
                ax.grid(alpha=0.3)
                ax.legend(fontsize=8)
                fig.tight_layout()
                save_figure(fig, io.BytesIO())


def _draw_share(jobs: list, tokens_r: int | None) -> tuple:
    """Draw the figures whose index this process takes from ``tokens_r``; returns
    (first error or None, warnings caught)."""
    from slipcycle.io.results import _figure_backend, save_figure

    caught = []
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("default")
        try:
            with _figure_backend():
                for index in _take(tokens_r, len(jobs)):
                    path, make = jobs[index]
                    save_figure(make(), Path(path))
            error = None
        except BaseException as exc:  # noqa: BLE001 - reported to the parent
            error = _error(exc)
        for w in record:
            caught.append((str(w.message), w.category, w.filename, w.lineno))
    return error, caught


def _take(tokens_r: int | None, n: int):
    """The indices of the figures this process draws (all ``n`` without tokens)."""
    if tokens_r is None:
        yield from range(n)
        return
    while token := os.read(tokens_r, _TOKEN.size):
        yield _TOKEN.unpack(token)[0]


def _error(exc: BaseException) -> tuple:
    text = "".join(traceback.format_exception(exc))
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:  # noqa: BLE001 - an exception that does not pickle
        exc = RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc, text


def _answer(fd: int, error, caught: list) -> None:
    try:
        data = pickle.dumps({"error": error, "warnings": caught})
    except Exception:  # noqa: BLE001 - a warning category that does not pickle
        data = pickle.dumps({"error": error, "warnings": []})
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]
    os.close(fd)


def _read_exactly(fd: int, n: int) -> bytes:
    data = b""
    while len(data) < n and (chunk := os.read(fd, n - len(data))):
        data += chunk
    return data


def _pread_exactly(fd: int, n: int) -> bytes:
    parts, offset = [], 0
    while offset < n and (chunk := os.pread(fd, n - offset, offset)):
        parts.append(chunk)
        offset += len(chunk)
    return b"".join(parts)
