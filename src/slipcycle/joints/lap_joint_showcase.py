"""The assembly showcase of a lap joint in one run: protocols, their B = 0 check and the
shakedown window, on every mesh.

A ``lap_joint`` case with ``melan_check = true`` and/or a ``[lap_joint.window]`` table
runs, besides the protocol study (:func:`~slipcycle.joints.lap_joint_study.
lap_joint_study`: tightening orders with elastic bolts, fit-up and overload steps, every
mesh), the same protocols on the joint with B = 0 (normal and tangential problems
decoupled: by the frictional Melan converse every protocol that ends with the same loads
then has one steady dissipation, Klarbring, Ciavarella & Barber 2007) and the shakedown
window of the protocols on every mesh (:func:`~slipcycle.discrete3d.shakedown_window.
shakedown_window`: λ2 with separation, each protocol's shakedown limit in service
amplitude, the λ1 bracket and the class window in which one protocol shakes down and
another slips; Barber 2012, §3). The result is a :class:`LapJointShowcase`, the protocol
study's result with these added to its summary, dataset, figures and report.

References
----------
Barber, J. R. (2012). Frictional systems subjected to oscillating loads. Ann. Solid Struct.
Mech. 2, 45–55.
Klarbring, A., Ciavarella, M. & Barber, J. R. (2007). Shakedown in elastic contact
problems with Coulomb friction. Int. J. Solids Struct. 44, 8355–8365.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np
import xarray as xr

from slipcycle.discrete3d.shakedown_window import Subject, shakedown_window
from slipcycle.joints.lap_joint_protocol import JointContact, StudySettings, assemble
from slipcycle.joints.lap_joint_result import LapJointResult, _spread
from slipcycle.joints.lap_joint_study import lap_joint_study

__all__ = ["WindowOptions", "LapJointShowcase", "protocol_subjects", "lap_joint_showcase"]


@dataclass(frozen=True)
class WindowOptions:
    """The shakedown window's grid (``[lap_joint.window]``).

    Attributes
    ----------
    lam_points : int
        Service amplitudes on the grid (0, ``lam_max``].
    lam_max : float or None
        Top of the grid [N] (None: 1.1 × the largest λ2).
    lam_tol : float
        Width of each protocol's limit bracket relative to ``lam_max``.
    meshes : tuple of int or None
        The meshes (0 the coarsest) the window is computed on; None: every mesh. (λ2
        of a 751-node joint takes about 20 CPU s; each protocol's limit is bracketed by
        runs of the engine, which dominate.)
    """

    lam_points: int = 5
    lam_max: float | None = None
    lam_tol: float = 0.05
    meshes: tuple | None = None


def protocol_subjects(contact: JointContact, protocols: Sequence, settings: StudySettings
                      ) -> list[Subject]:
    """One shakedown-window :class:`Subject` per protocol: the system and start its
    assembly leaves, the service load per newton of amplitude."""
    subjects = []
    for proto in protocols:
        asm = assemble(contact, proto, settings.preload, settings.friction,
                       float(settings.run["step_tol"]))
        start = ({"initial_slip": asm.initial_slip.reshape(-1, 2)}
                 if asm.initial_slip is not None else
                 {"protocol": asm.protocol} if asm.protocol is not None else {})
        subjects.append(Subject(proto.name, asm.system(contact, settings.friction,
                                                       settings.accept_ill_posed),
                                asm.load(1.0), start))
    return subjects


def _window(contact: JointContact, protocols, settings: StudySettings, opts: WindowOptions):
    run = dict(settings.run)
    steps = run.pop("steps_per_cycle")
    return shakedown_window(protocol_subjects(contact, protocols, settings),
                            lam_max=opts.lam_max, lam_points=opts.lam_points,
                            rtol=opts.lam_tol, steps_per_cycle=steps, **run)


def lap_joint_showcase(contacts: JointContact | Sequence[JointContact], protocols: Sequence,
                       settings: StudySettings, *, melan_check: bool = True,
                       window: WindowOptions | None = None, fields: tuple = ("xdmf",),
                       progress=None, workers: int | None = None) -> LapJointShowcase:
    """The protocol study, its B = 0 twin and the shakedown window on every mesh.

    Parameters
    ----------
    contacts : JointContact or sequence of JointContact
        The joint on one or more meshes, coarse → fine.
    protocols : sequence of Protocol
    settings : StudySettings
    melan_check : bool
        Also run every protocol with B = 0 on every mesh.
    window : WindowOptions, optional
        The shakedown window of the protocols on every mesh (None: none).
    fields : tuple of str
        Field formats of the coupled study.
    progress : callable, optional
        ``progress(done, total)`` of the coupled study.
    workers : int, optional
        Processes running the protocol runs of each study side by side
        (:func:`~slipcycle.joints.lap_joint_study.protocol_runs`).

    Returns
    -------
    LapJointShowcase
    """
    contacts = [contacts] if isinstance(contacts, JointContact) else list(contacts)
    coupled = lap_joint_study(contacts, protocols, settings, fields=fields,
                              progress=progress, workers=workers)
    decoupled = (lap_joint_study([c.decoupled() for c in contacts], protocols, settings,
                                 fields=(), workers=workers) if melan_check else None)
    chosen = [] if window is None else (
        list(range(len(contacts))) if window.meshes is None else list(window.meshes))
    windows = tuple(_window(contacts[i], protocols, settings, window) for i in chosen)
    wall = coupled.wall_time_s + (decoupled.wall_time_s if decoupled else 0.0) + sum(
        w.wall_time_s for w in windows)
    base = {f.name: getattr(coupled, f.name) for f in fields_of(coupled)}
    base["wall_time_s"] = wall
    return LapJointShowcase(**base, decoupled=decoupled, windows=windows,
                            window_spacing=tuple(contacts[i].spacing for i in chosen))


def fields_of(obj) -> tuple:
    """The dataclass fields of ``obj`` that ``__init__`` takes."""
    return tuple(f for f in fields(obj) if f.init)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class LapJointShowcase(LapJointResult):
    """:class:`~slipcycle.joints.lap_joint_result.LapJointResult` with the B = 0 twin
    and the shakedown window of every mesh (module docstring).

    Attributes
    ----------
    decoupled : LapJointResult or None
        The same protocols and meshes with B = 0.
    windows : tuple of ShakedownWindow3D
        One per mesh of the window, coarse → fine; its first subjects are the protocols,
        in order.
    window_spacing : tuple of float
        Node spacing of each window's mesh [m].
    """

    model: ClassVar[str] = "lap_joint"

    decoupled: Any = None
    windows: tuple = ()
    window_spacing: tuple = ()

    @property
    def decoupled_spread(self) -> float | None:
        """(max − min)/max of the B = 0 dissipation over the protocols, finest mesh."""
        return None if self.decoupled is None else self.decoupled.dissipation_spread

    def mesh_spreads(self) -> tuple[list, list]:
        """(max − min)/max of the dissipation over the protocols on each mesh, coupled
        and with B = 0 (coarse → fine)."""
        d0 = self.decoupled
        return ([_spread(x) for x in self.mesh.dissipation],
                [] if d0 is None else [_spread(x) for x in d0.mesh.dissipation])

    def window_limits(self) -> np.ndarray:
        """(meshes, protocols, 2): each protocol's shakedown-limit bracket [N]."""
        k = len(self.protocols)
        return np.array([w.limits[:k] for w in self.windows]).reshape(-1, k, 2)

    def protocol_class_window(self) -> list:
        """Per window mesh, [a, b] [N]: from a (the lowest amplitude at which some
        protocol slips) to b (the highest at which another still shakes down), the
        amplitudes where the protocol decides the class; None where there is none."""
        out = []
        for m in self.window_limits():
            hi = m[:, 1][~np.isnan(m[:, 1])]
            a, b = (float(hi.min()) if hi.size else np.inf), float(m[:, 0].max())
            out.append([a, b] if a <= b else None)
        return out

    def summary(self) -> dict:
        """The protocol study's summary plus ``decoupled_*`` (B = 0) and ``window_*``
        (per mesh of the window, coarse → fine) entries."""
        out = super().summary()
        d = self.decoupled
        if d is not None:
            out.update(decoupled_protocol_dissipation_per_cycle=d.dissipation,
                       decoupled_mesh_dissipation=d.mesh.dissipation,
                       decoupled_dissipation_spread=d.dissipation_spread,
                       decoupled_protocol_bolt_force=d.bolt_force)
        if self.windows:
            k = len(self.protocols)
            lim = self.window_limits()
            out.update(
                window_mesh_spacing=list(self.window_spacing),
                window_lambda2=[w.lambda2[:k].tolist() for w in self.windows],
                window_shakedown_limits=[[[float(a), None if np.isnan(b) else float(b)]
                                          for a, b in m] for m in lim],
                window_lambda1_bracket=[list(w.lambda1_bracket) for w in self.windows],
                window_class_window=[None if w.class_window is None else
                                     list(w.class_window) for w in self.windows],
                window_protocol_class_window=self.protocol_class_window())
        out["units"] = dict(out["units"], **SHOWCASE_UNITS)
        return out

    def _build_dataset(self) -> xr.Dataset:
        ds = super()._build_dataset()
        if self.decoupled is not None:
            ds["decoupled_dissipation_per_cycle"] = (
                ("protocol",), self.decoupled.dissipation,
                {"units": "J", "long_name": "steady dissipation per cycle with B = 0"})
        if self.windows:
            lim = self.window_limits()
            k = len(self.protocols)
            ds = ds.assign_coords(window_mesh=("window_mesh", np.array(self.window_spacing),
                                               {"units": "m"}))
            ds["window_lambda2"] = (("window_mesh", "protocol"),
                                    np.array([w.lambda2[:k] for w in self.windows]),
                                    {"units": "N", "long_name": "lambda2 with separation"})
            ds["window_limit_lo"] = (("window_mesh", "protocol"), lim[..., 0],
                                     {"units": "N", "long_name": "shakes down at"})
            ds["window_limit_hi"] = (("window_mesh", "protocol"), lim[..., 1],
                                     {"units": "N", "long_name": "slips at (NaN: never)"})
        return ds

    def figures(self, dataset: xr.Dataset | None = None) -> dict[str, Any]:
        """The protocol study's figures and ``shakedown_map_mesh<i>`` per window mesh."""
        out = super().figures(dataset)
        for i, w in enumerate(self.windows):
            out[f"shakedown_map_mesh{i}"] = w.figures()["shakedown_map"]
        return out

    def report(self) -> str:
        from slipcycle.joints.lap_joint_report import showcase_markdown

        return super().report() + showcase_markdown(self)


#: units of the showcase's summary entries
SHOWCASE_UNITS = {"decoupled_protocol_dissipation_per_cycle": "J",
                  "decoupled_mesh_dissipation": "J", "decoupled_dissipation_spread": "1",
                  "decoupled_protocol_bolt_force": "N", "window_mesh_spacing": "m",
                  "window_lambda2": "N", "window_shakedown_limits": "N",
                  "window_lambda1_bracket": "N", "window_class_window": "N",
                  "window_protocol_class_window": "N"}

