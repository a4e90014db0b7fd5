"""Files a command reads and writes: checked before any work.

- :func:`check_input_file`: a file named by the user is a regular file of a sane size before
  it is opened (a device such as ``/dev/zero`` or a FIFO would be read forever, a 10 GB
  file would exhaust the memory budget).
- :func:`check_no_overwrite`: no output of a command is, or holds, one of its inputs
  (paths compared after resolving symbolic links).

Both raise :class:`slipcycle.io.CaseError` (one line naming the key or option and the
file; exit code 2 on the command line). Only the standard library is imported.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable
from pathlib import Path

from slipcycle.errors import CaseError

__all__ = ["check_input_file", "check_no_overwrite", "resolved"]

_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"))


def _error(key: str, problem: str):
    return CaseError(key, problem)


def check_input_file(path: str | os.PathLike, key: str, max_bytes: float | None = None, *,
                     what: str = "file", empty_ok: bool = False) -> Path:
    """Refuse, without opening it, a path that cannot be an input file.

    Parameters
    ----------
    path : str or path-like
        The file named by the user.
    key : str
        The key or option that named it (``discrete.stiffness_file``, ``case``).
    max_bytes : float, optional
        Largest accepted size [bytes]; default the memory budget of one analysis
        (:func:`slipcycle.io.sizes.memory_limit`, 4 GB unless ``SLIPCYCLE_MEMORY_LIMIT``).
    what : str, optional
        What the file is, in words ("case file", "stiffness file"), for the messages.
    empty_ok : bool, optional
        Accept an empty file (a case file: its reader names the missing keys).

    Returns
    -------
    Path
        ``path`` as a :class:`~pathlib.Path` (not resolved).

    Raises
    ------
    slipcycle.io.CaseError
        ``key: <path>: <problem>`` for an empty path, a missing file, a directory, a
        device, FIFO or socket, an empty file, a file larger than ``max_bytes`` (with its
        size and the limit) or one that cannot be read.
    """
    if str(path) == "":
        raise _error(key, f"the {what} name is empty")
    p = Path(path)
    at = "" if key == str(p) else f"{p}: "     # the key may be the path itself
    try:
        st = p.stat()                       # stat never blocks, even on a FIFO
    except FileNotFoundError:
        raise _error(key, f"{at}{what} not found") from None
    except OSError as exc:
        raise _error(key, f"{at}cannot read {what}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise _error(key, f"{at}is a directory, not a {what}")
    for test, kind in _KINDS:
        if test(st.st_mode):
            raise _error(key, f"{at}is {kind}, not a regular {what}")
    if max_bytes is None:
        from slipcycle.io.sizes import memory_limit

        max_bytes = memory_limit()
    if st.st_size > max_bytes:
        from slipcycle.io.sizes import format_bytes

        raise _error(key, f"{at}is {format_bytes(st.st_size)}, larger than the "
                     f"{format_bytes(max_bytes)} accepted for a {what}")
    if st.st_size == 0 and not empty_ok:
        raise _error(key, f"{at}is an empty {what}")
    if not os.access(p, os.R_OK):
        raise _error(key, f"{at}cannot read {what}: permission denied")
    return p


def resolved(path: str | os.PathLike) -> Path:
    """``path`` made absolute with every symbolic link resolved (missing parts kept)."""
    return Path(os.path.realpath(os.path.abspath(os.fspath(path))))


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def check_no_overwrite(inputs: Iterable[tuple[str, str | os.PathLike]],
                       outputs: Iterable[tuple[str, str | os.PathLike, str]]) -> None:
    """Refuse outputs that would write over an input.

    Parameters
    ----------
    inputs : iterable of (str, path)
        ``(key, path)`` of every file the command reads (the case file, the files it
        names, option arguments).
    outputs : iterable of (str, path, str)
        ``(option, path, kind)`` of every output; ``kind`` is ``"file"`` (written or
        replaced) or ``"dir"`` (a result directory whose entries are replaced).

    Raises
    ------
    slipcycle.io.CaseError
        ``<option>: <path> ...`` when an output file is an input (also through a symbolic
        or hard link), when an output directory holds an input, or when an output path is
        empty.
    """
    ins = []
    for key, path in inputs:
        r = resolved(path)
        try:
            ident = (r.stat().st_dev, r.stat().st_ino)
        except OSError:
            ident = None
        ins.append((key, Path(path), r, ident))
    for option, path, kind in outputs:
        if str(path) == "":
            raise _error(option, "is empty; name an output " + ("file" if kind == "file"
                                                                 else "directory"))
        out = resolved(path)
        try:
            out_ident = (out.stat().st_dev, out.stat().st_ino)
        except OSError:
            out_ident = None
        for key, given, r, ident in ins:
            which = f"{given}" if key == str(given) else f"{given} ({key})"
            same = r == out or (ident is not None and ident == out_ident)
            if same:
                raise _error(option, f"{path} is the input {which}; writing there "
                             "would destroy it: choose another output")
            if kind == "dir" and _inside(r, out):
                raise _error(option, f"{path} holds the input {which}; results "
                             "replace entries of the output directory: choose another "
                             "directory")
