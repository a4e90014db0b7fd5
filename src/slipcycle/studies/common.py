"""What the studies of the discrete models share: the case of a sweep task and the files of
assembly protocols.

- :func:`model_case` — the :class:`~slipcycle.io.Case` of a case text restricted to the
  tables its model reads (a study's own table, e.g. ``[basins]``, left out), which a sweep
  task validates in its worker process;
- :func:`read_protocols` — assembly protocols (load states visited before cycling, Ahn,
  Bertocchi & Barber 2008) of an N-node system, 2-D or 3-D, from a file of ``[[protocol]]``
  tables read with the case files' :class:`~slipcycle.io.Section` rules.
"""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from slipcycle.io import Case, CaseError
from slipcycle.io.case import Section, parse_case_text

__all__ = ["model_case", "read_protocols"]


def model_case(case_text: str, case_path: str | None, tables: Sequence[str]) -> Case:
    """The case of ``case_text`` with only the top-level keys ``tables``.

    Parameters
    ----------
    case_text : str
        TOML text of the case.
    case_path : str or None
        Its file (relative file names in the case are taken from its folder).
    tables : sequence of str
        Top-level keys kept (``model``, ``title``, the model's tables, ``loading``,
        ``run``...).

    Returns
    -------
    Case
    """
    base = parse_case_text(case_text, Path(case_path) if case_path else None)
    data = {k: v for k, v in base.data.items() if k in tables}
    return Case(base.model, data, case_text, base.path)


def read_protocols(path: Path, n: int, pairs: bool = False) -> list[np.ndarray]:
    """Assembly protocols of an N-node system from a TOML file.

    Parameters
    ----------
    path : Path
        TOML file of ``[[protocol]]`` tables, each with ``p_w`` ((S, N) nested list [N])
        and optional ``q_w`` ((S, N) [N]; with ``pairs`` (S, N, 2), the (t1, t2) pair of
        every node), the load states visited before cycling.
    n : int
        Number of nodes N.
    pairs : bool
        A 3-D system: two tangential components per node.

    Returns
    -------
    list of (S, 2N) arrays, or (S, 3N) with ``pairs``
        Each protocol as rows [q^w (node-major pairs), p^w] [N].

    Raises
    ------
    CaseError
        Naming ``--protocols`` (unreadable file, not TOML) or the offending key.
    """
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise CaseError("--protocols", f"cannot read {path}: {exc.strerror}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError("--protocols", f"not valid TOML: {exc}") from None
    root = Section(data, "", Path(path).parent)
    tangential = (n, 2) if pairs else (n,)
    out = []
    for ps in root.tables("protocol"):
        p = ps.array("p_w", shape=(None, n))
        q = ps.array("q_w", np.zeros((p.shape[0],) + tangential),
                     shape=(p.shape[0],) + tangential)
        ps.finish()
        out.append(np.hstack([q.reshape(p.shape[0], -1), p]))
    root.finish()
    if not out:
        raise CaseError("protocol", "the protocols file holds no [[protocol]] tables")
    return out
