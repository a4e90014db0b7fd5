"""Reading and validating TOML case files.

A case file names its model at the top level (``model = "halfspace"``); the table of that
name holds the model, ``[loading]`` the loads and ``[run]`` the numerical settings.

Validation happens before any computation. Every problem is reported as a
:class:`CaseError` whose message names the offending key with its full dotted path, e.g.
``halfspace.radius: must be > 0, got -0.01``. A :class:`Section` reader records which keys
were read, so that unknown keys (typos) are refused as well.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from slipcycle.errors import CaseError
from slipcycle.io.files import check_input_file
from slipcycle.io.sniff import describe
from slipcycle.registry import MODEL_COMMANDS

__all__ = ["Case", "CaseError", "Section", "read_case", "parse_case_text", "MODEL_COMMANDS"]

#: a case file larger than this is not a case file (read before parsing)
MAX_CASE_BYTES = 64 * 1024 * 1024

_MISSING = object()


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


class Section:
    """Validating reader over one TOML table.

    Each accessor converts and checks one key and remembers that it was read;
    :meth:`finish` then refuses any key that no accessor asked for.

    Parameters
    ----------
    data : dict
        The TOML table.
    prefix : str
        Dotted path of the table, used in error messages.
    base_dir : Path
        Directory against which relative file names in the table are resolved.
    """

    def __init__(self, data: dict, prefix: str, base_dir: Path | None = None):
        if not isinstance(data, dict):
            raise CaseError(prefix, "must be a table")
        self.data = data
        self.prefix = prefix
        self.base_dir = base_dir or Path.cwd()
        self._used: set[str] = set()

    # -- bookkeeping -------------------------------------------------------------------
    def key(self, key: str) -> str:
        """Full dotted name of ``key``, for error messages."""
        return _join(self.prefix, key)

    def error(self, key: str, problem: str) -> CaseError:
        """The error for ``key``; a problem with an absent key that has an unread
        look-alike in the table is reported as that typo instead."""
        if key not in self.data:
            typo = _typo_of(key, [k for k in self.data if k not in self._used and k != key])
            if typo is not None:
                return CaseError(self.key(typo), f"unknown key (did you mean {key!r}?)")
        return CaseError(self.key(key), problem)

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = _MISSING) -> Any:
        """The TOML value of ``key`` unconverted (marked read); ``default`` where absent
        (required without one). For values the caller validates itself."""
        return self._get(key, default)

    def accept(self, keys) -> None:
        """Mark ``keys`` read (validated by the caller, e.g. through a sub-section)."""
        self._used.update(keys)

    def _get(self, key: str, default: Any) -> Any:
        self._used.add(key)
        if key in self.data:
            return self.data[key]
        if default is _MISSING:
            # error() names an unread look-alike as the typo it is
            raise self.error(key, "required key is missing")
        return default

    def finish(self) -> None:
        """Refuse keys that were never read (typos, keys of another model)."""
        unknown = sorted(set(self.data) - self._used)
        if unknown:
            raise self.error(unknown[0], "unknown key" + _did_you_mean(unknown[0], self._used))

    # -- scalars -------------------------------------------------------------------------
    def float(
        self,
        key: str,
        default: Any = _MISSING,
        *,
        gt: float | None = None,
        ge: float | None = None,
        lt: float | None = None,
        le: float | None = None,
    ) -> float:
        """A finite real number, optionally bounded."""
        raw = self._get(key, default)
        if raw is None:
            return None  # type: ignore[return-value]
        if isinstance(raw, bool) or not isinstance(raw, int | float):
            raise self.error(key, f"must be a number, got {raw!r}")
        value = float(raw)
        if not math.isfinite(value):
            raise self.error(key, f"must be finite, got {value}")
        _check_bounds(self, key, np.array([value]), gt, ge, lt, le)
        return value

    def int(self, key: str, default: Any = _MISSING, *, ge: int | None = None,
            le: int | None = None) -> int:
        """An integer, optionally bounded."""
        raw = self._get(key, default)
        # 1e7 is how people write ten million; accept integral floats, refuse 2.5
        if isinstance(raw, float) and math.isfinite(raw) and raw.is_integer():
            raw = int(raw)
        if isinstance(raw, bool) or not isinstance(raw, int):
            raise self.error(key, f"must be an integer, got {raw!r}")
        _check_bounds(self, key, np.array([raw]), None, ge, None, le)
        return int(raw)

    def bool(self, key: str, default: Any = _MISSING) -> bool:
        raw = self._get(key, default)
        if not isinstance(raw, bool):
            raise self.error(key, f"must be true or false, got {raw!r}")
        return raw

    def string(self, key: str, default: Any = _MISSING, *,
               choices: Sequence[str] | None = None) -> str:
        """A string, optionally one of ``choices``."""
        raw = self._get(key, default)
        if not isinstance(raw, str):
            raise self.error(key, f"must be a string, got {raw!r}")
        if choices is not None and raw not in choices:
            raise self.error(key, f"must be one of {', '.join(map(repr, choices))}; got {raw!r}"
                             + _did_you_mean(raw, choices))
        return raw

    def path(self, key: str, default: Any = _MISSING, *, must_exist: bool = True) -> Path:
        """A file name, resolved relative to the case file's directory."""
        raw = self.string(key, default)
        p = Path(raw)
        if not p.is_absolute():
            p = self.base_dir / p
        if must_exist and not p.exists():
            raise self.error(key, f"file not found: {p}")
        if must_exist:
            # kind and size before any reader opens it (a device or FIFO is read forever)
            check_input_file(p, self.key(key))
        return p

    # -- arrays --------------------------------------------------------------------------
    def array(
        self,
        key: str,
        default: Any = _MISSING,
        *,
        shape: tuple[int | None, ...] | None = None,
        gt: float | None = None,
        ge: float | None = None,
        lt: float | None = None,
        le: float | None = None,
        scalar_ok: bool = False,
    ) -> np.ndarray:
        """A finite float array.

        ``shape`` gives the expected shape; ``None`` entries accept any length. With
        ``scalar_ok`` a bare number is broadcast to ``shape`` (which must then be fully known).
        """
        raw = self._get(key, default)
        return self.coerce_array(key, raw, shape=shape, gt=gt, ge=ge, lt=lt, le=le,
                                 scalar_ok=scalar_ok)

    def coerce_array(self, key, raw, *, shape=None, gt=None, ge=None, lt=None, le=None,
                     scalar_ok=False) -> np.ndarray:
        """Convert an already-read value to a checked float array (see :meth:`array`)."""
        if raw is None:
            return None  # type: ignore[return-value]
        if _holds(raw, bool | np.bool_):
            # NumPy reads true as 1.0: a switch where a number goes is a mistake, not a 1
            raise self.error(key, f"must contain numbers, not true or false, got {raw!r}")
        if _holds(raw, str | bytes):
            # NumPy reads "30" as 30.0: a quoted number is text, as it is for one number
            raise self.error(key, f"must contain numbers, not text, got {raw!r}")
        try:
            arr = np.asarray(raw, dtype=float)
        except (TypeError, ValueError):
            raise self.error(key, "must be a number or a (nested) list of numbers "
                             "with equal-length rows") from None
        if scalar_ok and arr.ndim == 0 and shape is not None and None not in shape:
            arr = np.full(shape, float(arr))
        if shape is not None:
            mismatch = any(want is not None and got != want
                           for got, want in zip(arr.shape, shape, strict=False))
            if arr.ndim != len(shape) or mismatch:
                want = "×".join("n" if s is None else str(s) for s in shape) or "scalar"
                got = "×".join(map(str, arr.shape)) or "scalar"
                raise self.error(key, f"wrong shape: expected {want}, got {got}")
        if not np.all(np.isfinite(arr)):
            raise self.error(key, "must contain only finite numbers (found nan or inf)")
        _check_bounds(self, key, arr, gt, ge, lt, le)
        return arr

    def values(self, key: str, default: Any = _MISSING, *, gt: float | None = None,
               ge: float | None = None, lt: float | None = None,
               le: float | None = None) -> np.ndarray:
        """A number or a flat list of numbers, as a 1-D float array (bounds on each).

        A nested list is refused: its rows would otherwise be read one after another as
        if they were one list (``[[0.2, 0.4]]`` is not a list of values).
        """
        raw = self._get(key, default)
        arr = self.coerce_array(key, raw, gt=gt, ge=ge, lt=lt, le=le)
        if arr is None:
            return None  # type: ignore[return-value]
        if arr.ndim > 1:
            raise self.error(key, "must be a number or a flat list of numbers, got a nested "
                                  f"list (shape {'×'.join(map(str, arr.shape))})")
        return np.atleast_1d(arr)

    def grid(self, key: str, default: dict, *, gt: float | None = None,
             ge: float | None = None, le: float | None = None, geometric: bool = False,
             max_num: int = 100_000) -> np.ndarray:
        """A 1-D grid: a list of values, or a table ``{start, stop, num}`` (``default``).

        The table form gives ``num`` values from ``start`` to ``stop`` inclusive, equally
        spaced (or geometrically, with ``geometric``); bounds apply to every value; an
        empty or nested list is refused.
        """
        raw = self.data.get(key, default)
        if isinstance(raw, dict):
            sub = self.table(key) if self.has(key) else Section(raw, self.key(key),
                                                                  self.base_dir)
            self._used.add(key)
            a = sub.float("start", gt=gt, ge=ge, le=le)
            b = sub.float("stop", gt=gt, ge=ge, le=le)
            n = sub.int("num", ge=1, le=max_num)
            sub.finish()
            return np.geomspace(a, b, n) if geometric else np.linspace(a, b, n)
        values = self.values(key, gt=gt, ge=ge, le=le)
        if values.size == 0:   # a grid of no points: a study with nothing to compute
            raise self.error(key, "must hold at least one value, got an empty list")
        return values

    def ignore(self) -> None:
        """Accept every key of this table unread (a table another command uses)."""
        self._used.update(self.data)

    # -- nested tables -------------------------------------------------------------------
    def table(self, key: str, default: Any = _MISSING) -> Section | None:
        raw = self._get(key, default)
        if raw is None:
            return None
        if not isinstance(raw, dict):
            raise self.error(key, "must be a table")
        return Section(raw, self.key(key), self.base_dir)

    def tables(self, key: str, default: Any = _MISSING) -> list[Section]:
        """An array of tables (``[[key]]`` in TOML)."""
        raw = self._get(key, default)
        if raw is None:
            return []
        if not isinstance(raw, list) or not all(isinstance(t, dict) for t in raw):
            raise self.error(key, "must be an array of tables ([[...]] in TOML)")
        return [Section(t, f"{self.key(key)}[{i}]", self.base_dir) for i, t in enumerate(raw)]


def _holds(raw: Any, kind) -> bool:
    """Whether ``raw`` is of ``kind`` or a (nested) list or tuple holding one."""
    if isinstance(raw, kind):
        return True
    if isinstance(raw, list | tuple):
        return any(_holds(item, kind) for item in raw)
    return False


def _check_bounds(section: Section, key: str, arr: np.ndarray, gt, ge, lt, le) -> None:
    checks = (
        (gt, lambda a, b: a > b, ">"),
        (ge, lambda a, b: a >= b, ">="),
        (lt, lambda a, b: a < b, "<"),
        (le, lambda a, b: a <= b, "<="),
    )
    for bound, ok, sym in checks:
        if bound is None:
            continue
        bad = ~ok(arr, bound)
        if np.any(bad):
            worst = arr[bad].flat[0]
            raise section.error(key, f"must be {sym} {bound:g}, got {worst:g}")


def _typo_of(key: str, present) -> str | None:
    """The key in ``present`` that looks like a misspelling of ``key``, if any."""
    import difflib

    close = difflib.get_close_matches(key, list(present), n=1, cutoff=0.65)
    if close:
        return close[0]
    lowered = {k.lower(): k for k in present if isinstance(k, str)}
    return lowered.get(key.lower())


def _did_you_mean(word: str, candidates) -> str:
    import difflib

    close = difflib.get_close_matches(word, list(candidates), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


@dataclass(frozen=True)
class Case:
    """A parsed case file.

    Attributes
    ----------
    model : str
        The model named at the top level.
    data : dict
        The whole TOML document.
    text : str
        The case file as written; embedded in every result as metadata.
    path : Path or None
        Where the case was read from (None for embedded cases).
    """

    model: str
    data: dict
    text: str
    path: Path | None = None
    _sections: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def base_dir(self) -> Path:
        return self.path.parent if self.path is not None else Path.cwd()

    def section(self, name: str, *, required: bool = True) -> Section | None:
        """The validating reader of a top-level table (the same object on each call)."""
        if name not in self._sections:
            if name not in self.data:
                typo = _typo_of(name, [k for k in self.data
                                       if k not in self._sections and k != "model"])
                if typo is not None:
                    raise CaseError(typo, f"unknown top-level key or table (did you mean "
                                    f"[{name}]?)")
                if required:
                    raise CaseError(name, f"required table [{name}] is missing")
                self._sections[name] = Section({}, name, self.base_dir)
            else:
                self._sections[name] = Section(self.data[name], name, self.base_dir)
        return self._sections[name]

    def finish(self) -> None:
        """Refuse unknown top-level keys and unknown keys in every table that was read."""
        allowed = {"model", "title", "description"} | set(self._sections)
        for key in self.data:
            if key not in allowed:
                raise CaseError(key, "unknown top-level key or table"
                                + _did_you_mean(key, allowed))
        for sec in self._sections.values():
            sec.finish()


def parse_case_text(text: str, path: Path | None = None, models: Sequence[str] | None = None
                    ) -> Case:
    """Parse TOML text into a :class:`Case` (checks only the ``model`` key).

    ``models`` lists the models the calling command serves; a known model outside that list
    is refused with the commands that do serve it.
    """
    where = str(path) if path is not None else "case"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        kind = describe(where, text[:4096].encode("latin-1", "replace"))
        if kind is not None:  # a matrix export given where the case file goes
            raise CaseError(where, f"is {kind}, not a TOML case file; name it in a case "
                            "file: [discrete] stiffness_file = \"...\"") from None
        raise CaseError(where, f"not a valid TOML case file: {exc}") from None
    model = data.get("model", _MISSING)
    if model is _MISSING:
        raise CaseError("model", "required key is missing (e.g. model = \"halfspace\")")
    if not isinstance(model, str):
        raise CaseError("model", f"must be a string, got {model!r}")
    if models is not None and model not in models:
        if model in MODEL_COMMANDS:
            serving = ", ".join(f"slipcycle {c}" for c in MODEL_COMMANDS[model])
            raise CaseError("model", f"{model!r} cases are not served by this command "
                            f"(it takes {', '.join(map(repr, models))}); use {serving}")
        raise CaseError("model", f"unknown model {model!r}; known: {', '.join(models)}"
                        + _did_you_mean(model, models))
    return Case(model=model, data=data, text=text, path=path)


def read_text_file(path: str | Path, what: str = "case file") -> str:
    """The UTF-8 text of ``path``; :class:`CaseError` naming the file for anything else.

    Refuses directories, missing or unreadable files, binary files (NUL bytes), text that is
    not UTF-8 and files too large to be a case file, each with one line.
    """
    path = Path(path)
    check_input_file(path, str(path), MAX_CASE_BYTES, what=what, empty_ok=True)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise CaseError(str(path), f"cannot read {what}: {exc.strerror or exc}") from None
    if b"\x00" in raw:
        kind = describe(path, raw[:4096])
        raise CaseError(str(path), f"is {kind}, not a {what} (TOML text); name it in a case "
                        "file: [discrete] stiffness_file = \"...\"" if kind else
                        f"is a binary file, not a {what} (TOML text)")
    try:
        # "utf-8-sig": a byte-order mark (Windows editors) is not part of the TOML text
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise CaseError(str(path), f"is not UTF-8 text (byte 0x{raw[exc.start]:02x} at "
                        f"offset {exc.start}); save the {what} as UTF-8") from None


def read_case(path: str | Path, models: Sequence[str] | None = None) -> Case:
    """Read a TOML case file. Raises :class:`CaseError` for unreadable or invalid files."""
    path = Path(path)
    text = read_text_file(path)
    return parse_case_text(text, path.resolve(), models)


def case_error_of(exc, keys) -> CaseError:
    """A model object's :class:`slipcycle.errors.ModelError` under the case-file key of its
    field (``keys``: field → key).

    A remedy that names another field (``accept_ill_posed=True``) is said with its key
    and TOML value (``discrete.accept_ill_posed = true``).
    """
    problem = exc.problem
    if exc.remedy is not None:
        field, value, purpose = exc.remedy
        toml_value = str(value).lower() if isinstance(value, bool) else repr(value)
        problem = f"{exc.detail}. Set {keys.get(field, field)} = {toml_value} to {purpose}"
    return CaseError(keys.get(exc.name, exc.name), problem)


#: largest accepted coefficient of friction: real ones are of order 1, and far above this
#: (1e100 in the rods' Iwan fit, 1.3e154 squared in Ŵ = W/(λ_c γσ f² P0)) the models'
#: arithmetic overflows; a value this large is a typing or unit mistake
MAX_FRICTION = 1e12
#: smallest positive coefficient of friction accepted (0, frictionless, is accepted): a
#: cone narrower than 1e-12 of the normal force is below what the solvers' force
#: tolerances resolve (f = 1e-300 hung the 3-D engine and gave 700 events on one load
#: segment in 2-D)
MIN_FRICTION = 1e-12


def read_friction(sec: Section, key: str = "friction", **bounds) -> float:
    """A coefficient of friction (one number): finite, within ``bounds`` and at most
    :data:`MAX_FRICTION`, which is refused naming the key."""
    f = sec.float(key, **bounds)
    if f is not None:
        problem = friction_range_problem(np.asarray([f]))
        if problem:
            raise sec.error(key, problem)
    return f


def friction_range_problem(f: np.ndarray) -> str | None:
    """Why coefficients of friction ``f`` (finite, ≥ 0) lie outside what the models
    compute with — above :data:`MAX_FRICTION` or positive below :data:`MIN_FRICTION` —
    or None."""
    big = f[f > MAX_FRICTION]
    if big.size:
        return (f"must be <= {MAX_FRICTION:g}, got {big[0]:g}: a coefficient of friction is "
                "of order 1; one this large is a typing or unit mistake, and the models' "
                "friction forces would overflow")
    tiny = f[(f > 0) & (f < MIN_FRICTION)]
    if tiny.size:
        return (f"must be 0 (frictionless) or >= {MIN_FRICTION:g}, got {tiny[0]:g}: a "
                "friction cone this narrow is below the solvers' force tolerance")
    return None


def read_steady_tol(sec: Section, default: float) -> float:
    """``steady_tol`` of a ``[run]`` table (the relative steady-state test, in (0, 1)).

    ``tolerance`` is its older name in the discrete models' cases (read, same meaning);
    both at once are refused.
    """
    if sec.has("tolerance") and sec.has("steady_tol"):
        raise sec.error("tolerance", "give steady_tol (or its older name tolerance), not both")
    return sec.float("tolerance" if sec.has("tolerance") else "steady_tol", default,
                     gt=0.0, lt=1.0)
