"""What the studies of the discrete models share: the case of a sweep task and the files of
assembly protocols.

- :func:`model_case` — the :class:`~slipcycle.io.Case` of a case text restricted to the
  tables its model reads (a study's own table, e.g. ``[basins]``, left out), which a sweep
  task validates in its worker process;
- :func:`read_protocols` — assembly protocols (load states visited before cycling, Ahn,
  Bertocchi & Barber 2008) of an N-node system, 2-D or 3-D, from a file of ``[[protocol]]``
  tables read with the case files' :class:`~slipcycle.io.Section` rules;
- :class:`BasinsStudyResult` — what the 2-D and 3-D basins results share: the starts'
  records, their class codes (:data:`~slipcycle.result.STEADY_STATES`), class counts, the
  starts that converged and the Dataset of a sweep store.
"""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import xarray as xr

from slipcycle.io import Case, CaseError
from slipcycle.io.case import Section, parse_case_text
from slipcycle.result import STEADY_STATES, SteadyState, StudyResult
from slipcycle.sweep.dataset import store_dataset

__all__ = ["model_case", "read_protocols", "BasinsStudyResult", "CONVERGED_ATTRS"]

#: attributes of the ``converged`` variable of a basins Dataset
CONVERGED_ATTRS = {"units": "1", "long_name": "the start reached a steady state (shakedown, "
                   "cyclic slip or ratcheting) within run.cycles; false for not_converged, "
                   "inadmissible and failed starts"}


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


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class BasinsStudyResult(StudyResult):
    """Steady states of a discrete case over many starts: what the 2-D and 3-D basins
    studies share.

    Attributes
    ----------
    wall_time_s : float
        Wall time of the runs in this call [s].
    mode : str
        How the starts were made (``grid``, ``random``, ``protocols``).
    lam : float
        Load factor λ of the runs [1].
    n_nodes : int
        Nodes N of the system.
    data : dict of str to ndarray
        The stored outputs over the starts: ``steady_state`` (codes of
        :data:`~slipcycle.result.STEADY_STATES`), ``dissipation_per_cycle`` [J],
        ``dissipation_per_node`` [J] (last axis: node), ``cycles_run``, ``n_slipping``,
        ``memory_erased`` and the model's own records.
    store : SweepStore or None
        The store the runs were kept in (the Dataset of :meth:`store_dataset` is read from
        it, with the task's own attributes).
    axes : tuple of Axis
        The sweep axes of ``store``.
    """

    analysis: ClassVar[str] = "basins"

    mode: str
    lam: float
    n_nodes: int
    data: dict
    store: object = None
    axes: tuple = ()

    @property
    def steady_state(self) -> np.ndarray:
        """Class codes over the starts (:data:`~slipcycle.result.STEADY_STATES`)."""
        return np.asarray(self.data["steady_state"])

    @property
    def class_counts(self) -> dict[str, int]:
        """Number of starts per steady-state class."""
        cls = self.steady_state
        return {STEADY_STATES[c]: int((cls == c).sum()) for c in np.unique(cls)}

    @property
    def converged(self) -> np.ndarray:
        """Starts that reached a steady state (shakedown, cyclic slip or ratcheting)."""
        return np.isin(self.steady_state, [s.code for s in SteadyState if s.converged])

    @staticmethod
    def record_attrs(**units: str) -> dict[str, dict]:
        """Attributes of the records of a start: class codes (CF flags), dissipation [J],
        cycles run, slipping nodes, memory erased, and the records given in ``units``
        (name -> unit)."""
        attrs = {"steady_state": {"units": "1", "flag_values": list(range(len(STEADY_STATES))),
                                  "flag_meanings": " ".join(STEADY_STATES)},
                 "dissipation_per_cycle": {"units": "J"}, "dissipation_per_node": {"units": "J"},
                 "cycles_run": {"units": "1"}, "n_slipping": {"units": "1"},
                 "memory_erased": {"units": "1"}}
        attrs.update({name: {"units": u} for name, u in units.items()})
        return attrs

    def store_dataset(self, **units: str) -> xr.Dataset:
        """The Dataset of the store: the records of :meth:`record_attrs` and ``converged``
        over the sweep axes."""
        ds = store_dataset(self.store, self.axes, attrs=self.record_attrs(**units))
        ds["converged"] = (tuple(ds["steady_state"].dims), self.converged, CONVERGED_ATTRS)
        return ds
