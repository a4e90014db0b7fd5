"""One memory budget for every analysis, checked before any work.

Sizes that validation accepts (slider counts, load steps, grid points, λ values, sweep
cells, node counts) but that cannot be allocated are refused up front with one line naming
the key or option and the estimated memory. Each model estimates its own dominant arrays
(upper bounds within a small factor, not measurements) and calls :func:`check_memory`.

The budget is 4 GB unless the environment variable ``SLIPCYCLE_MEMORY_LIMIT`` says otherwise
(``"32GB"``, ``"500MB"`` or a number of bytes): a fixed default keeps the same case accepted
or refused on every machine.
"""

from __future__ import annotations

import os
import re

from slipcycle.errors import CaseError, InputError

__all__ = ["MEMORY_LIMIT", "memory_limit", "format_bytes", "check_memory"]

#: default budget of one analysis [bytes]
MEMORY_LIMIT = 4.0e9

_UNITS = {"": 1.0, "b": 1.0, "kb": 1e3, "mb": 1e6, "gb": 1e9, "tb": 1e12,
          "kib": 2.0**10, "mib": 2.0**20, "gib": 2.0**30, "tib": 2.0**40}


def memory_limit() -> float:
    """The budget in bytes: ``SLIPCYCLE_MEMORY_LIMIT`` if set, else :data:`MEMORY_LIMIT`."""
    text = os.environ.get("SLIPCYCLE_MEMORY_LIMIT", "").strip()
    if not text:
        return MEMORY_LIMIT
    m = re.fullmatch(r"([0-9.eE+]+)\s*([KMGT]i?B|B)?", text, flags=re.IGNORECASE)
    try:
        value = float(m.group(1)) * _UNITS[(m.group(2) or "").lower()] if m else -1.0
    except ValueError:
        value = -1.0
    if not value > 0:
        raise InputError("SLIPCYCLE_MEMORY_LIMIT", f"must be a size such as 32GB or 5e9, got "
                         f"{text!r}")
    return value


def format_bytes(nbytes: float) -> str:
    """``nbytes`` as a short decimal size ("80 GB", "512 MB", "6.08 TB")."""
    for unit, size in (("EB", 1e18), ("PB", 1e15), ("TB", 1e12), ("GB", 1e9), ("MB", 1e6),
                       ("kB", 1e3)):
        if nbytes >= size:
            return f"{nbytes / size:.3g} {unit}"
    return f"{nbytes:.0f} B"


def check_memory(key: str, nbytes: float, what: str, limit: float | None = None,
                 advice: str = "") -> None:
    """Refuse a size whose estimated memory exceeds the budget.

    Parameters
    ----------
    key : str
        The key or option to blame (``run.steps_per_cycle``, ``--grid``).
    nbytes : float
        Estimated peak memory [bytes].
    what : str
        The size in words, plural verb agreement ("1e9 steps per cycle").
    limit : float, optional
        Budget [bytes]; :func:`memory_limit` by default.
    advice : str, optional
        Appended after a semicolon ("reduce sliders").

    Raises
    ------
    slipcycle.io.CaseError
        ``key: <what> need about <size> of memory (limit 4 GB); <advice> (...)``.
    """
    limit = memory_limit() if limit is None else limit
    if nbytes > limit:
        tail = f"; {advice}" if advice else ""
        raise CaseError(key, f"{what} need about {format_bytes(nbytes)} of memory (limit "
                        f"{format_bytes(limit)}){tail} (SLIPCYCLE_MEMORY_LIMIT sets the "
                        "limit)")
