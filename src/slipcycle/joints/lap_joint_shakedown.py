"""``slipcycle shakedown`` / ``slipcycle basins`` of a ``lap_joint`` case: the service
amplitudes at which each assembly protocol shakes down.

Every protocol of ``[lap_joint.protocols]`` is assembled on the case's joint (its finest
mesh) by :func:`~slipcycle.joints.lap_joint_protocol.assemble`; its service cycle is
``start + λ sin θ · service`` with λ the service amplitude in newtons. For each protocol:
λ2 with separation (the nodes outside the bolts' pressure cones are open), the class
over a grid of amplitudes, and the bracket of the largest amplitude at which it shakes
down (:func:`~slipcycle.discrete3d.shakedown_window.shakedown_window`). The class window
is the range of amplitudes in which one protocol shakes down and another slips (Barber
2012, §3: the assembly decides).
"""

from __future__ import annotations

from typing import ClassVar

from slipcycle.discrete3d.shakedown_window import (
    ShakedownWindow3D,
    Subject,
    check_window_options,
    shakedown_window,
)
from slipcycle.io import Case
from slipcycle.joints.lap_joint_case import case_keys, joint_contact, read_lap_joint_case
from slipcycle.joints.lap_joint_showcase import protocol_subjects
from slipcycle.sweep.dataset import StudyStatus

__all__ = ["LapJointShakedown", "lap_joint_subjects", "lap_joint_shakedown",
           "lap_joint_shakedown_study"]


class LapJointShakedown(ShakedownWindow3D):
    """:class:`~slipcycle.discrete3d.shakedown_window.ShakedownWindow3D` of a lap joint:
    one subject per assembly protocol, λ the service amplitude [N]."""

    model: ClassVar[str] = "lap_joint"
    lam_unit: ClassVar[str] = "N"


def lap_joint_subjects(case: Case) -> tuple[list[Subject], dict]:
    """One :class:`Subject` per protocol of a ``lap_joint`` case (its finest mesh), and
    the engine settings of the case's ``[run]``."""
    lc = read_lap_joint_case(case)
    with case_keys():
        subjects = protocol_subjects(joint_contact(lc.joint), lc.protocols, lc.settings)
    run = dict(lc.settings.run)
    return subjects, run


def lap_joint_shakedown(case: Case, *, lam_max: float | None = None, lam_points: int = 9,
                        lam_tol: float = 1e-2) -> LapJointShakedown:
    """The shakedown window of the protocols of a ``lap_joint`` case.

    Parameters
    ----------
    case : Case
    lam_max : float, optional
        Largest service amplitude [N] (default 1.1 × the largest λ2).
    lam_points : int
        Amplitudes on the grid.
    lam_tol : float
        Width of each protocol's limit bracket relative to ``lam_max``.

    Returns
    -------
    LapJointShakedown
    """
    check_window_options(lam_max, lam_points, lam_tol)
    subjects, run = lap_joint_subjects(case)
    steps = run.pop("steps_per_cycle")
    return shakedown_window(subjects, lam_max=lam_max, lam_points=lam_points, rtol=lam_tol,
                            steps_per_cycle=steps, result_type=LapJointShakedown, **run)


def lap_joint_shakedown_study(case: Case, out=None, *, lam_max: float | None = None,
                              lam_points: int = 9, lam_tol: float = 1e-2) -> StudyStatus:
    """:func:`lap_joint_shakedown` as a finished study (``slipcycle shakedown`` and
    ``slipcycle basins`` of a ``lap_joint`` case; the command line writes ``out``)."""
    result = lap_joint_shakedown(case, lam_max=lam_max, lam_points=lam_points,
                                 lam_tol=lam_tol)
    n = len(result.labels)
    return StudyStatus(result.to_outputs(), n, n, result)
