"""``slipcycle shakedown`` for ``model = "discrete3d"`` cases: λ2 with separation, the class
of every start over λ and the window in which the start decides shakedown
(:mod:`slipcycle.discrete3d.shakedown_window`).

The starts are the case's own (its ``initial_slip`` or ``protocol``, else zero slip) and
the assembly protocols of ``--protocols FILE`` (:func:`~slipcycle.studies.common.
read_protocols`). The runs are those of :func:`~slipcycle.discrete3d.steady.simulate3d`
with the case's ``[run]`` settings.
"""

from __future__ import annotations

from pathlib import Path

from slipcycle.discrete3d.shakedown_window import (
    Subject,
    check_window_options,
    shakedown_window,
)
from slipcycle.io import Case
from slipcycle.studies.basins3d import load_discrete3d_case
from slipcycle.studies.common import read_protocols
from slipcycle.sweep.dataset import StudyStatus

__all__ = ["shakedown3d_study"]


def shakedown3d_study(case: Case, out=None, *, lam_max: float | None = None,
                      lam_points: int = 9, lam_tol: float = 1e-2,
                      protocols: Path | None = None) -> StudyStatus:
    """Shakedown window of a ``discrete3d`` case.

    Parameters
    ----------
    case : Case
        A ``model = "discrete3d"`` case.
    out : path, optional
        Not written here (the command line writes the outputs).
    lam_max : float, optional
        Top of the λ grid (default 1.1 × the largest λ2).
    lam_points : int
        Grid values of λ.
    lam_tol : float
        Width of each start's shakedown-limit bracket relative to ``lam_max``.
    protocols : Path, optional
        TOML file of assembly protocols, each one more start.

    Returns
    -------
    StudyStatus
        ``result``: :class:`~slipcycle.discrete3d.shakedown_window.ShakedownWindow3D`.
    """
    check_window_options(lam_max, lam_points, lam_tol)
    dc = load_discrete3d_case(case.text, str(case.path) if case.path else None)
    run = dict(dc.run)
    steps = run.pop("steps_per_cycle")
    own = ({"initial_slip": dc.initial_slip} if dc.initial_slip is not None else
           {"protocol": dc.protocol} if dc.protocol is not None else {})
    subjects = [Subject("case", dc.system, dc.load, own)]
    if protocols is not None:
        protos = read_protocols(protocols, dc.system.n_nodes, pairs=True)
        subjects += [Subject(f"protocol {i}", dc.system, dc.load, {"protocol": p})
                     for i, p in enumerate(protos)]
    result = shakedown_window(subjects, lam_max=lam_max, lam_points=lam_points,
                              rtol=lam_tol, steps_per_cycle=steps, **run)
    return StudyStatus(result.to_outputs(), len(subjects), len(subjects), result)
