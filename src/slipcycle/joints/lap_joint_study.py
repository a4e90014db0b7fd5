"""Does the tightening order decide the damping? Assembly protocols of a bolted joint.

In a coupled frictional system (normal–tangential coupling B ≠ 0) the steady state reached
under a periodic load can depend on the initial state, so the dissipation per cycle of a
bolted joint may depend on how it was assembled, e.g. on the order in which the bolts were
tightened (Barber, Davies & Hills, Int. J. Solids Struct. 48 (2011) 2041–2047; Ahn,
Bertocchi & Barber, J. Mech. Phys. Solids 56 (2008) 3433–3440). Where B = 0 the normal
reactions do not depend on slip and the frictional analogue of Melan's theorem makes the
steady dissipation unique: every protocol then gives the same dissipation (Klarbring,
Ciavarella & Barber, Int. J. Solids Struct. 44 (2007) 8355–8365).

A protocol is a sequence of assembly steps; each step brings one or more bolts to their
preload P with the service load zero. The load states visited are

    r_s = P Σ_{k tightened after step s} r_k,      r_k = [q_k, p_k] per 1 N of bolt k,

followed linearly from the unloaded, stress-free state (every node in contact, no slip)
and then the service cycle

    r^w(θ) = P Σ_k r_k + F sin θ r_service,

run with the one 3-D engine (:func:`slipcycle.discrete3d.solve_model`) to its steady state.
Per protocol the study reports the steady-state class, the dissipation per cycle (total
and per bolt region), the permanently stuck area and the slip map, and, when the joint was
reduced on more than one mesh, the mesh convergence of each protocol's dissipation
(:func:`slipcycle.joints.convergence.mesh_convergence`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import xarray as xr

from slipcycle.discrete3d import FrictionalSystem3D, Load3D, LoadCase3D, solve_model
from slipcycle.discrete3d.case import RUN_DEFAULTS, DiscreteResult3D
from slipcycle.errors import InputError
from slipcycle.io.matrices import ReducedStiffness
from slipcycle.kernels.threads import single_threaded_blas
from slipcycle.loading import HarmonicLoad
from slipcycle.result import STEADY_STATES, RunResult, SteadyState

__all__ = ["JointContact", "Protocol", "StudySettings", "STANDARD_PROTOCOLS",
           "standard_protocol", "joint_load", "protocol_states", "joint_system",
           "run_protocol",
           "lap_joint_study", "LapJointResult", "MeshRuns", "NODE_CLASSES"]

#: the standard tightening patterns of a row of K bolts (:func:`standard_protocol`)
STANDARD_PROTOCOLS = ("sequential", "star", "reversed", "simultaneous")

#: classes of a node over the steady cycle (``node_class`` of the Dataset): stuck over the
#: whole cycle, slipping while in contact, or opening at some time (it may slip too)
NODE_CLASSES = ("stuck", "slipping", "separating")

#: severity of the steady-state classes, for the class of the whole study
_SEVERITY = ("shakedown", "cyclic_slip", "ratcheting", "not_converged")


@dataclass(frozen=True)
class JointContact:
    """The reduced contact of a bolted joint: what the tightening-order study needs.

    Parameters
    ----------
    reduced : ReducedStiffness
        Reduced stiffness of the N contact nodes with two tangential directions (A 2N×2N
        node-major, B N×2N, C N×N, N/m), their ``coordinates`` (N, 3) [m] and the load
        cases ``"bolt_0"`` … ``"bolt_{K-1}"`` (reactions per 1 N of preload of that bolt)
        and ``"service"`` (per 1 N of service force), N.
    node_area : (N,) array
        Tributary area of each contact node [m²].
    bolt_region : (N,) int array
        The bolt each node belongs to (nearest bolt), 0 … K−1.
    spacing : float
        Node spacing h of the mesh at the interface [m] (for mesh convergence).
    description : dict, optional
        Geometry and mesh, for reports (name -> value).
    """

    reduced: ReducedStiffness
    node_area: np.ndarray
    bolt_region: np.ndarray
    spacing: float
    description: dict = field(default_factory=dict)

    def __post_init__(self):
        red = self.reduced
        if not isinstance(red, ReducedStiffness) or red.tangential_dims != 2:
            raise InputError("reduced", "must be a ReducedStiffness with two tangential "
                             "directions (a 3-D contact)")
        n = red.C.shape[0]
        if red.coordinates is None:
            raise InputError("reduced", "needs the coordinates of its contact nodes")
        area = np.asarray(self.node_area, float)
        if area.shape != (n,) or not np.all(area > 0):
            raise InputError("node_area", f"must be {n} positive areas, got shape "
                             f"{area.shape}")
        region = np.asarray(self.bolt_region)
        if region.shape != (n,) or not np.issubdtype(region.dtype, np.integer):
            raise InputError("bolt_region", f"must be {n} integers, got shape {region.shape}")
        k = 0
        while f"bolt_{k}" in red.loads:
            k += 1
        if k == 0 or "service" not in red.loads:
            raise InputError("reduced", "needs the load cases bolt_0 … bolt_{K-1} and "
                             f"service (has: {', '.join(red.loads) or 'none'})")
        if region.min() < 0 or region.max() >= k:
            raise InputError("bolt_region", f"must lie in 0 … {k - 1}")
        if not (np.isfinite(self.spacing) and self.spacing > 0):
            raise InputError("spacing", f"must be a positive length, got {self.spacing!r}")
        object.__setattr__(self, "node_area", area)
        object.__setattr__(self, "bolt_region", region.astype(int))

    @property
    def n_nodes(self) -> int:
        """N, the number of contact nodes."""
        return self.reduced.C.shape[0]

    @property
    def bolt_count(self) -> int:
        """K, the number of bolts (load cases ``bolt_0`` … ``bolt_{K-1}``)."""
        k = 0
        while f"bolt_{k}" in self.reduced.loads:
            k += 1
        return k

    def case_vector(self, name: str) -> np.ndarray:
        """[q, p] of load case ``name`` per unit of the case, (3N,) [N]."""
        case = self.reduced.loads[name]
        return np.concatenate([np.asarray(case["q"], float), np.asarray(case["p"], float)])

    def decoupled(self) -> JointContact:
        """The same joint with B = 0: normal and tangential problems decoupled.

        A and C are kept (K stays positive definite), so the normal reactions no longer
        depend on slip; the frictional Melan theorem then makes the steady dissipation the
        same for every assembly protocol (Klarbring, Ciavarella & Barber 2007).
        """
        red = replace(self.reduced, B=np.zeros_like(self.reduced.B),
                      source=f"{self.reduced.source} (B = 0)")
        return replace(self, reduced=red)


@dataclass(frozen=True)
class Protocol:
    """An assembly protocol: bolts tightened step by step to their preload.

    Parameters
    ----------
    name : str
    steps : tuple of tuple of int
        The bolts brought to their preload in each step (a step of several bolts tightens
        them together, proportionally). Every bolt is tightened exactly once.
    """

    name: str
    steps: tuple[tuple[int, ...], ...]

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise InputError("protocols", "a protocol needs a non-empty name")
        try:
            steps = tuple(tuple(int(b) for b in np.atleast_1d(s)) for s in self.steps)
        except (TypeError, ValueError):
            raise InputError("protocols", f"{self.name}: steps must be bolt numbers or "
                             "lists of bolt numbers") from None
        if not steps or any(not s for s in steps):
            raise InputError("protocols", f"{self.name}: every step must tighten a bolt")
        object.__setattr__(self, "steps", steps)

    def check(self, bolt_count: int) -> None:
        """Raise InputError unless every bolt 0 … K−1 is tightened exactly once."""
        flat = [b for s in self.steps for b in s]
        if sorted(flat) != list(range(bolt_count)):
            raise InputError("protocols", f"{self.name}: must tighten each of the "
                             f"{bolt_count} bolts 0 … {bolt_count - 1} exactly once, got "
                             f"{[list(s) for s in self.steps]}")

    @property
    def label(self) -> str:
        """The order as text: ``0 → 2 → 1`` (``0+1`` for bolts tightened together)."""
        return " → ".join("+".join(map(str, s)) for s in self.steps)


def standard_protocol(name: str, bolt_count: int) -> Protocol:
    """A standard tightening pattern of a row of K bolts numbered along the row.

    ``sequential``: 0, 1, …, K−1; ``reversed``: K−1, …, 0; ``star``: every other bolt,
    then the ones between (0, 2, 4, …, 1, 3, …; the crossing pattern of a row; for K = 2
    the same as ``sequential``); ``simultaneous``: all bolts together.

    Returns
    -------
    Protocol
    """
    k = int(bolt_count)
    orders = {"sequential": list(range(k)), "reversed": list(range(k))[::-1],
              "star": list(range(0, k, 2)) + list(range(1, k, 2))}
    if name == "simultaneous":
        return Protocol(name, (tuple(range(k)),))
    if name not in orders:
        raise InputError("protocols", f"no standard protocol {name!r} (known: "
                         f"{', '.join(STANDARD_PROTOCOLS)}; give its order instead)")
    return Protocol(name, tuple((b,) for b in orders[name]))


@dataclass(frozen=True)
class StudySettings:
    """Loads and run settings of the study.

    Parameters
    ----------
    preload : float
        Preload P of every bolt [N].
    service_amplitude : float
        Amplitude F of the service force F sin θ [N].
    friction : float
        Coulomb coefficient f of the interface.
    run : dict
        ``cycles``, ``steps_per_cycle``, ``tol``, ``min_cycles``, ``step_tol`` of the
        3-D engine (:data:`slipcycle.discrete3d.case.RUN_DEFAULTS` for the others).
    difference_tol : float
        Relative spread of the protocols' dissipation above which the orders are said to
        differ.
    mesh_rtol : float
        Relative error below which the dissipation is mesh-converged.
    accept_ill_posed : bool
        Run even if f reaches the sampled critical friction coefficient of the reduced
        joint (:class:`~slipcycle.discrete3d.FrictionalSystem3D`); by default such a
        joint is refused.
    """

    preload: float
    service_amplitude: float
    friction: float
    run: dict = field(default_factory=dict)
    difference_tol: float = 1e-3
    mesh_rtol: float = 0.05
    accept_ill_posed: bool = False

    def __post_init__(self):
        for name, low in (("preload", 0.0), ("friction", 0.0), ("difference_tol", 0.0),
                          ("mesh_rtol", 0.0)):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and np.isfinite(value) and value > low):
                raise InputError(name, f"must be a positive number, got {value!r}")
        F = self.service_amplitude
        if not (isinstance(F, int | float) and np.isfinite(F) and F >= 0):
            raise InputError("service_amplitude", f"must be ≥ 0 N, got {F!r}")
        unknown = set(self.run) - set(RUN_DEFAULTS)
        if unknown:
            raise InputError("run", f"unknown run setting {sorted(unknown)[0]!r} (known: "
                             f"{', '.join(RUN_DEFAULTS)})")
        object.__setattr__(self, "run", {**RUN_DEFAULTS, **self.run})


def joint_load(contact: JointContact, preload: float, service_amplitude: float) -> Load3D:
    """r^w(θ) = P Σ_k r_k + F sin θ r_service (module docstring), as a :class:`Load3D`.

    Returns
    -------
    Load3D
        With one load case per bolt (constant P) and the service case (F sin θ =
        F cos(θ − π/2)).
    """
    n = contact.n_nodes
    red = contact.reduced
    zero = HarmonicLoad(np.zeros(n), np.zeros((1, n)), 0.0)
    zero_q = HarmonicLoad(np.zeros(2 * n), np.zeros((1, 2 * n)), 0.0)
    cases = [LoadCase3D(p=np.asarray(red.loads[f"bolt_{k}"]["p"], float),
                        q=np.asarray(red.loads[f"bolt_{k}"]["q"], float),
                        time=HarmonicLoad([float(preload)], [[0.0]], 0.0))
             for k in range(contact.bolt_count)]
    cases.append(LoadCase3D(p=np.asarray(red.loads["service"]["p"], float),
                            q=np.asarray(red.loads["service"]["q"], float),
                            time=HarmonicLoad([0.0], [[float(service_amplitude)]],
                                              -np.pi / 2)))
    if "gap" in red.loads:          # an initial gap (rounded plate ends): once, constant
        cases.append(LoadCase3D(p=np.asarray(red.loads["gap"]["p"], float),
                                q=np.asarray(red.loads["gap"]["q"], float),
                                time=HarmonicLoad([1.0], [[0.0]], 0.0)))
    return Load3D(p=zero, q=zero_q, cases=tuple(cases))


def protocol_states(contact: JointContact, protocol: Protocol, preload: float
                    ) -> np.ndarray | None:
    """Load states [q^w, p^w] after each assembly step but the last, (S − 1, 3N) [N].

    The last step reaches the load at θ = 0 (every bolt at P, service zero), which the
    engine visits anyway; a protocol of one step (all bolts together) is plain loading
    from the unloaded state (None). A joint with an initial gap (load case ``gap``, the
    rounded plate ends of :class:`~slipcycle.fe.lap_joint.LapJoint`) first opens it: the
    gap's reactions are the first state, and every later state includes them.
    """
    protocol.check(contact.bolt_count)
    vec = [contact.case_vector(f"bolt_{k}") for k in range(contact.bolt_count)]
    states, total = [], np.zeros(3 * contact.n_nodes)
    if "gap" in contact.reduced.loads:
        # the initial gap first: its reactions open the gap g with every force zero
        total = contact.case_vector("gap")
        states.append(total.copy())
    for step in protocol.steps[:-1]:
        total = total + preload * sum(vec[b] for b in step)
        states.append(total.copy())
    return np.array(states) if states else None


def joint_system(contact: JointContact, settings: StudySettings) -> FrictionalSystem3D:
    """The validated 3-D frictional system of the joint (checked well posed once: the
    sampled critical friction coefficient, unless ``settings.accept_ill_posed``).

    Raises
    ------
    ModelError
        f reaches the critical friction coefficient of the reduced joint.
    """
    red = contact.reduced
    return FrictionalSystem3D(red.A, red.B, red.C, settings.friction,
                              coordinates=red.coordinates, normals=red.normals,
                              tangents=red.tangents, area=contact.node_area,
                              accept_ill_posed=settings.accept_ill_posed)


def run_protocol(contact: JointContact, protocol: Protocol, settings: StudySettings,
                 fields: tuple = (), system: FrictionalSystem3D | None = None
                 ) -> DiscreteResult3D:
    """Tighten the bolts by ``protocol`` and cycle the service load to the steady state.

    Parameters
    ----------
    contact : JointContact
    protocol : Protocol
    settings : StudySettings
    fields : tuple of str
        Field formats of the run (written by the study's ``to_outputs``).
    system : FrictionalSystem3D, optional
        :func:`joint_system` of ``contact``, when already built (its well-posedness check
        is then not repeated).

    Returns
    -------
    DiscreteResult3D
        The 3-D engine's result, its histories trimmed to the last cycle (the only one
        the study reports).
    """
    system = joint_system(contact, settings) if system is None else system
    load = joint_load(contact, settings.preload, settings.service_amplitude)
    res = solve_model(system, load, settings.run,
                      protocol=protocol_states(contact, protocol, settings.preload),
                      fields=fields)
    sol = res.solution
    if sol.x.shape[0] > 1:   # keep the last cycle only: the study reports nothing else
        sol = replace(sol, x=sol.x[-1:], r=sol.r[-1:], modes=sol.modes[-1:])
        res = replace(res, solution=sol)
    return res


@dataclass(frozen=True)
class MeshRuns:
    """The dissipation of every protocol on each mesh (coarse → fine).

    Attributes
    ----------
    spacing : tuple of float
        Node spacing h of each mesh [m].
    dissipation : (M, P) array
        Steady dissipation per cycle [J] of protocol p on mesh m.
    steady_state : (M, P) array of str
    """

    spacing: tuple
    dissipation: np.ndarray
    steady_state: np.ndarray


def lap_joint_study(contacts: JointContact | Sequence[JointContact],
                    protocols: Sequence[Protocol], settings: StudySettings, *,
                    fields: tuple = ("xdmf",), progress=None) -> LapJointResult:
    """Run every protocol on the joint (and on coarser meshes for the mesh convergence).

    Parameters
    ----------
    contacts : JointContact or sequence of JointContact
        The joint reduced on one mesh, or on several meshes ordered coarse → fine; the
        finest is reported in detail, the others give the mesh convergence of each
        protocol's dissipation.
    protocols : sequence of Protocol
        Distinct names; the first is the reference whose dissipation is the result's
        ``dissipation_per_cycle``.
    settings : StudySettings
    fields : tuple of str
        Field formats (``"xdmf"``, ``"pvd"``) written per protocol by ``to_outputs``.
    progress : callable, optional
        ``progress(done, total)`` after each run.

    Returns
    -------
    LapJointResult
    """
    t0 = time.perf_counter()
    contacts = [contacts] if isinstance(contacts, JointContact) else list(contacts)
    if not contacts:
        raise InputError("contacts", "needs the joint reduced on at least one mesh")
    names = [p.name for p in protocols]
    if not protocols or len(set(names)) != len(names):
        raise InputError("protocols", f"needs one or more protocols with distinct names, "
                         f"got {names}")
    spacing = [c.spacing for c in contacts]
    if any(b >= a for a, b in zip(spacing, spacing[1:], strict=False)):
        raise InputError("contacts", f"meshes must be ordered coarse → fine, got spacings "
                         f"{spacing}")
    for c in contacts:
        for p in protocols:
            p.check(c.bolt_count)
    total = len(contacts) * len(protocols)
    diss = np.full((len(contacts), len(protocols)), np.nan)
    states = np.full((len(contacts), len(protocols)), "not_converged", dtype=object)
    finest: list[DiscreteResult3D] = []
    done = 0
    with single_threaded_blas():   # small dense solves: threads only spin (kernels.threads)
        for m, contact in enumerate(contacts):
            last = m == len(contacts) - 1
            system = joint_system(contact, settings)
            for j, protocol in enumerate(protocols):
                res = run_protocol(contact, protocol, settings, fields if last else (),
                                   system)
                diss[m, j] = res.solution.dissipation_per_cycle
                states[m, j] = res.solution.steady_state
                if last:
                    finest.append(res)
                done += 1
                if progress is not None:
                    progress(done, total)
    mesh = MeshRuns(tuple(spacing), diss, states.astype(str))
    return LapJointResult.from_runs(contacts[-1], tuple(protocols), tuple(finest), mesh,
                                    settings, time.perf_counter() - t0)


def _worst(words: Sequence[str]) -> str:
    return max(words, key=_SEVERITY.index)


#: unit of every numeric summary entry
SUMMARY_UNITS = {
    "n_nodes": "1", "bolt_count": "1", "converged": "1", "residual": "1",
    "cycles_run": "1", "dissipation_per_cycle": "J", "preload": "N",
    "service_amplitude": "N", "friction": "1", "contact_area": "m^2",
    "protocol_dissipation_per_cycle": "J", "protocol_dissipation_per_region": "J",
    "protocol_stuck_area": "m^2", "protocol_stuck_fraction": "1",
    "protocol_slipping_nodes": "1", "protocol_separating_nodes": "1",
    "protocol_cycles_run": "1", "protocol_residual": "1", "protocol_converged": "1",
    "protocol_energy_balance_error": "1",
    "dissipation_spread": "1", "dissipation_min": "J", "dissipation_max": "J",
    "orders_differ": "1", "difference_tol": "1", "mesh_spacing": "m",
    "mesh_dissipation": "J", "protocol_dissipation_extrapolated": "J",
    "protocol_dissipation_observed_order": "1", "protocol_dissipation_relative_error": "1",
    "protocol_dissipation_mesh_converged": "1", "dissipation_mesh_converged": "1",
    "mesh_rtol": "1", "wall_time_s": "s", "f_crit": "1",
}

#: every word of the categorical summary entries
SUMMARY_FLAGS = {"steady_state": _SEVERITY, "steady_state_class": STEADY_STATES,
                 "protocol_steady_state": _SEVERITY}


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class LapJointResult(RunResult):
    """Result of the tightening-order study of a bolted joint (``model = "lap_joint"``).

    The shared fields describe the study as a whole: ``steady_state`` is the most severe
    class over the protocols, ``dissipation_per_cycle`` the reference (first) protocol's
    [J], ``cycles_run`` and ``residual`` the largest, ``converged`` true when every
    protocol reached its steady state.

    Attributes
    ----------
    contact : JointContact
        The joint on the finest mesh.
    protocols : tuple of Protocol
    runs : tuple of DiscreteResult3D
        One per protocol, on the finest mesh (histories of the last cycle).
    mesh : MeshRuns
        Every protocol's dissipation on each mesh.
    convergence : tuple
        One :class:`~slipcycle.joints.convergence.MeshConvergence` per protocol (None with
        one mesh).
    settings : StudySettings
    wall_time : float
        Seconds the study took.
    """

    model: ClassVar[str] = "lap_joint"

    contact: JointContact
    protocols: tuple
    runs: tuple
    mesh: MeshRuns
    convergence: tuple
    settings: StudySettings
    wall_time: float

    @classmethod
    def from_runs(cls, contact, protocols, runs, mesh, settings, wall) -> LapJointResult:
        """Fill the shared fields from the per-protocol runs (class docstring)."""
        convergence = _mesh_convergence(mesh, settings.mesh_rtol)
        words = [r.solution.steady_state for r in runs]
        state = _worst(words)
        diss = np.array([r.solution.dissipation_per_cycle for r in runs])
        spread = _spread(diss)
        differ = spread > settings.difference_tol
        lines = [f"{len(protocols)} tightening protocols: {state}"
                 + ("" if len(set(words)) == 1 else f" (classes {', '.join(words)})"),
                 f"dissipation {diss.min():.4g}–{diss.max():.4g} J per cycle, spread "
                 f"{spread:.3g} ({'the orders differ' if differ else 'the orders agree'} "
                 f"at tolerance {settings.difference_tol:g})"]
        unconverged = [p.name for p, c in zip(protocols, convergence, strict=True)
                       if c is not None and not c.converged]
        if unconverged:
            lines.append("WARNING: dissipation not mesh-converged for "
                         + ", ".join(unconverged))
        elif all(c is None for c in convergence):
            lines.append("WARNING: dissipation not checked for mesh convergence (one mesh; "
                         "[lap_joint.convergence] coarsening adds coarser ones)")
        return cls(steady_state=SteadyState(state), steady_state_detail=state,
                   dissipation_per_cycle=float(diss[0]),
                   cycles_run=max(int(r.cycles_run) for r in runs),
                   residual=max(float(r.residual) for r in runs),
                   converged=all(r.converged for r in runs), message="; ".join(lines),
                   contact=contact, protocols=protocols, runs=runs, mesh=mesh,
                   convergence=convergence, settings=settings, wall_time=wall)

    # -- per-protocol numbers ----------------------------------------------------------
    @property
    def dissipation(self) -> np.ndarray:
        """Steady dissipation per cycle of each protocol, (P,) [J]."""
        return np.array([r.solution.dissipation_per_cycle for r in self.runs])

    @property
    def dissipation_per_region(self) -> np.ndarray:
        """Dissipation per cycle of each protocol in each bolt region, (P, K) [J]."""
        k = self.contact.bolt_count
        return np.array([np.bincount(self.contact.bolt_region,
                                     weights=r.solution.dissipation_per_node, minlength=k)
                         for r in self.runs])

    @property
    def node_class(self) -> np.ndarray:
        """Class of each node over the steady cycle of each protocol, (P, N) int8
        (0 stuck, 1 slipping, 2 separating: :data:`NODE_CLASSES`)."""
        out = np.zeros((len(self.runs), self.contact.n_nodes), np.int8)
        for j, r in enumerate(self.runs):
            out[j, r.solution.slipping_nodes] = 1
            out[j, r.solution.separating_nodes] = 2
        return out

    @property
    def stuck_area(self) -> np.ndarray:
        """Permanently stuck area of each protocol (nodes stuck over the whole steady
        cycle), (P,) [m²]."""
        return np.array([float(self.contact.node_area[r.solution.permanently_stuck_nodes]
                               .sum()) for r in self.runs])

    @property
    def dissipation_spread(self) -> float:
        """(max − min)/max of the protocols' dissipation [1]."""
        return _spread(self.dissipation)

    @property
    def orders_differ(self) -> bool:
        """Whether the spread exceeds ``settings.difference_tol``."""
        return bool(self.dissipation_spread > self.settings.difference_tol)

    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word of the categorical summary entries."""
        return dict(SUMMARY_FLAGS)

    def summary(self) -> dict:
        """The summary dictionary (keys in docs/lap_joint.md), with ``units``.

        Per-protocol entries are lists in the order of ``protocols``.
        """
        c = self.contact
        conv = self.convergence
        have_conv = any(x is not None for x in conv)

        def per(attr):
            return [None if x is None else getattr(x, attr) for x in conv]

        out = {
            "model": "lap_joint",
            "steady_state": self.steady_state_detail,
            "steady_state_class": self.steady_state.value,
            "converged": self.converged,
            "residual": self.residual,
            "cycles_run": self.cycles_run,
            "dissipation_per_cycle": self.dissipation_per_cycle,
            "n_nodes": c.n_nodes,
            "bolt_count": c.bolt_count,
            "contact_area": float(c.node_area.sum()),
            "preload": self.settings.preload,
            "service_amplitude": self.settings.service_amplitude,
            "friction": self.settings.friction,
            "f_crit": _finite(self.runs[0].case.system.critical_friction.f_crit),
            "protocols": [p.name for p in self.protocols],
            "protocol_orders": [p.label for p in self.protocols],
            "protocol_steady_state": [r.solution.steady_state for r in self.runs],
            "protocol_dissipation_per_cycle": self.dissipation,
            "protocol_dissipation_per_region": self.dissipation_per_region,
            "protocol_stuck_area": self.stuck_area,
            "protocol_stuck_fraction": self.stuck_area / c.node_area.sum(),
            "protocol_slipping_nodes": [len(r.solution.slipping_nodes) for r in self.runs],
            "protocol_separating_nodes": [len(r.solution.separating_nodes)
                                          for r in self.runs],
            "protocol_cycles_run": [int(r.cycles_run) for r in self.runs],
            "protocol_residual": [float(r.residual) for r in self.runs],
            "protocol_converged": [bool(r.converged) for r in self.runs],
            "protocol_energy_balance_error": [r.solution.energy_balance_error
                                              for r in self.runs],
            "dissipation_min": float(self.dissipation.min()),
            "dissipation_max": float(self.dissipation.max()),
            "dissipation_spread": self.dissipation_spread,
            "orders_differ": self.orders_differ,
            "difference_tol": self.settings.difference_tol,
            "mesh_spacing": list(self.mesh.spacing),
            "mesh_dissipation": self.mesh.dissipation,
            "protocol_dissipation_extrapolated": per("extrapolated") if have_conv else None,
            "protocol_dissipation_observed_order": (per("observed_order") if have_conv
                                                    else None),
            "protocol_dissipation_relative_error": (per("relative_error") if have_conv
                                                    else None),
            "protocol_dissipation_mesh_converged": per("converged") if have_conv else None,
            "dissipation_mesh_converged": (all(x.converged for x in conv) if have_conv
                                           else None),
            "mesh_convergence_messages": per("message") if have_conv else None,
            "mesh_rtol": self.settings.mesh_rtol,
            "message": self.message,
            "wall_time_s": self.wall_time,
            "units": dict(SUMMARY_UNITS),
        }
        return out

    def to_dataset(self) -> xr.Dataset:
        """Per protocol: class, dissipation (total, per bolt region, per node), node
        classes and slip of the steady cycle; per mesh: the dissipation of each protocol."""
        c = self.contact
        n, k = c.n_nodes, c.bolt_count
        P = len(self.protocols)
        hist_len = max(len(r.solution.dissipation_history) for r in self.runs)
        hist = np.full((P, hist_len), np.nan)
        for j, r in enumerate(self.runs):
            h = r.solution.dissipation_history
            hist[j, :len(h)] = h
        start = np.array([r.solution.cycle_start_states[-1] for r in self.runs])
        p0 = np.array([r.solution.r[-1, 0, 2 * n:] for r in self.runs])
        conv = self.convergence
        extrap = np.array([np.nan if x is None or x.extrapolated is None else x.extrapolated
                           for x in conv])
        rel = np.array([np.nan if x is None or x.relative_error is None
                        else x.relative_error for x in conv])
        codes = np.array([_SEVERITY.index(r.solution.steady_state) for r in self.runs],
                         np.int8)

        def var(dims, data, units, long_name, **extra):
            return (dims, data, {"units": units, "long_name": long_name, **extra})

        coords = c.reduced.coordinates
        ds = xr.Dataset(
            {
                "steady_state": var(("protocol",), codes, "1", "steady-state class",
                                    flag_values=np.arange(len(_SEVERITY), dtype=np.int8),
                                    flag_meanings=" ".join(_SEVERITY)),
                "dissipation": var(("protocol",), self.dissipation, "J",
                                   "steady dissipation per cycle"),
                "dissipation_error": var(("protocol",), np.abs(rel * self.dissipation), "J",
                                         "estimated mesh error of the dissipation"),
                "dissipation_extrapolated": var(("protocol",), extrap, "J",
                                                "dissipation extrapolated to h -> 0"),
                "dissipation_per_region": var(("protocol", "bolt"),
                                              self.dissipation_per_region, "J",
                                              "dissipation per cycle in each bolt region"),
                "stuck_area": var(("protocol",), self.stuck_area, "m2",
                                  "permanently stuck area"),
                "cycles_run": var(("protocol",), [r.cycles_run for r in self.runs], "1",
                                  "load cycles run after the assembly"),
                "dissipation_history": var(("protocol", "cycle"), hist, "J",
                                           "total dissipation of each cycle"),
                "dissipation_per_node": var(("protocol", "node"),
                                            np.array([r.solution.dissipation_per_node
                                                      for r in self.runs]), "J",
                                            "dissipation of each node over the steady cycle"),
                "dissipation_per_area": var(("protocol", "node"),
                                            np.array([r.solution.dissipation_per_node
                                                      for r in self.runs]) / c.node_area,
                                            "J m-2", "dissipation per cycle per unit area"),
                "node_class": var(("protocol", "node"), self.node_class, "1",
                                  "node class over the steady cycle",
                                  flag_values=np.arange(3, dtype=np.int8),
                                  flag_meanings=" ".join(NODE_CLASSES)),
                "slip_length": var(("protocol", "node"),
                                   np.array([r.solution.slip_length for r in self.runs]),
                                   "m", "slip length over the steady cycle"),
                "slip_at_start": var(("protocol", "node", "component"),
                                     start[:, :2 * n].reshape(P, n, 2), "m",
                                     "slip at the start of the steady cycle (theta = 0)"),
                "pressure_at_start": var(("protocol", "node"), p0 / c.node_area, "Pa",
                                         "contact pressure at the start of the steady cycle"),
                "node_area": var(("node",), c.node_area, "m2", "tributary area of the node"),
                "bolt_region": var(("node",), c.bolt_region.astype(np.int32), "1",
                                   "bolt region of the node (nearest bolt)"),
                "mesh_dissipation": var(("mesh", "protocol"), self.mesh.dissipation, "J",
                                        "steady dissipation per cycle on each mesh"),
            },
            coords={
                "protocol": ("protocol", [p.name for p in self.protocols],
                             {"units": "1", "long_name": "assembly protocol"}),
                "order": ("protocol", [p.label for p in self.protocols],
                          {"units": "1", "long_name": "tightening order"}),
                "bolt": ("bolt", np.arange(k), {"units": "1", "long_name": "bolt (from 0)"}),
                "node": ("node", np.arange(n), {"units": "1", "long_name": "node (from 0)"}),
                "component": ("component", ["t1", "t2"],
                              {"units": "1", "long_name": "tangent direction"}),
                "cycle": ("cycle", np.arange(1, hist_len + 1),
                          {"units": "1", "long_name": "cycle"}),
                "mesh": ("mesh", np.arange(len(self.mesh.spacing)),
                         {"units": "1", "long_name": "mesh (coarse to fine)"}),
                "mesh_spacing": ("mesh", np.array(self.mesh.spacing),
                                 {"units": "m", "long_name": "node spacing h"}),
                "x": ("node", coords[:, 0], {"units": "m", "long_name": "node coordinate x"}),
                "y": ("node", coords[:, 1], {"units": "m", "long_name": "node coordinate y"}),
                "z": ("node", coords[:, 2], {"units": "m", "long_name": "node coordinate z"}),
            },
        )
        ds.attrs["preload_N"] = float(self.settings.preload)
        ds.attrs["service_amplitude_N"] = float(self.settings.service_amplitude)
        ds.attrs["friction"] = float(self.settings.friction)
        return ds

    def figures(self, dataset: xr.Dataset | None = None) -> dict[str, Any]:
        """``dissipation_by_protocol`` (with mesh error bars), ``slip_maps``,
        ``dissipation_maps``, ``dissipation_by_bolt``, ``dissipation_history``."""
        from slipcycle.plot import joints as plots  # matplotlib only for figures

        ds = self.to_dataset() if dataset is None else dataset
        # partials of module-level functions: picklable, so drawn by the CLI's workers
        return {
            "dissipation_by_protocol": partial(plots.dissipation_by_protocol, ds),
            "slip_maps": partial(plots.slip_maps, ds),
            "dissipation_maps": partial(plots.dissipation_maps, ds),
            "dissipation_by_bolt": partial(plots.dissipation_by_bolt, ds),
            "dissipation_history": partial(plots.dissipation_history, ds),
        }

    def write_fields(self, directory: str | Path) -> list[Path]:
        """The steady cycle's contact fields of every protocol for ParaView
        (``directory/<protocol>/interface.xdmf`` …, :func:`~slipcycle.discrete3d.fields.
        write_fields`).

        Returns
        -------
        list of Path
        """
        files = []
        for p, r in zip(self.protocols, self.runs, strict=True):
            if r.case.fields:
                target = Path(directory) / p.name
                target.mkdir(parents=True, exist_ok=True)
                files += r.write_fields(target)
        return files

    def report(self) -> str:
        """A Markdown report comparing the protocols (``report.md``)."""
        from slipcycle.joints.lap_joint_report import report_markdown

        return report_markdown(self)

    def to_outputs(self):
        """Summary, Dataset, figures, ``report.md`` and the field files under
        ``fields/<protocol>/``."""
        out = super().to_outputs()
        out.extra_files["report.md"] = lambda path: path.write_text(self.report(),
                                                                    encoding="utf-8")
        if any(r.case.fields for r in self.runs):
            out.extra_files["fields/README.txt"] = self._write_all_fields
        return out

    def _write_all_fields(self, path: Path) -> None:
        files = self.write_fields(path.parent)
        path.write_text("Contact fields of the steady cycle of each protocol (open in "
                        "ParaView):\n" + "".join(f"{f.relative_to(path.parent)}\n"
                                                 for f in files), encoding="utf-8")


def _finite(x) -> float | None:
    return None if x is None or not np.isfinite(x) else float(x)


def _spread(values: np.ndarray) -> float:
    vmax = float(np.max(values))
    return float((vmax - np.min(values)) / vmax) if vmax > 0 else 0.0


def _mesh_convergence(mesh: MeshRuns, rtol: float) -> tuple:
    """One MeshConvergence per protocol (None per protocol with one mesh)."""
    if len(mesh.spacing) < 2:
        return tuple(None for _ in range(mesh.dissipation.shape[1]))
    from slipcycle.joints.convergence import mesh_convergence

    return tuple(mesh_convergence(mesh.spacing, tuple(float(v) for v in mesh.dissipation[:, j]),
                                  rtol=rtol, unit="J")
                 for j in range(mesh.dissipation.shape[1]))
