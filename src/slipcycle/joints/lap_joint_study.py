"""Does the assembly decide the damping? Assembly-protocol studies of a bolted joint.

In a coupled frictional system (normal–tangential coupling B ≠ 0) the steady state reached
under a periodic load can depend on the initial state, so the dissipation per cycle of a
bolted joint may depend on how it was assembled, e.g. on the order in which the bolts were
tightened (Barber, Davies & Hills, Int. J. Solids Struct. 48 (2011) 2041–2047; Ahn,
Bertocchi & Barber, J. Mech. Phys. Solids 56 (2008) 3433–3440). Where B = 0 the normal
reactions do not depend on slip and the frictional analogue of Melan's theorem makes the
steady dissipation unique: every protocol that ends with the same loads then gives the
same dissipation (Klarbring, Ciavarella & Barber, Int. J. Solids Struct. 44 (2007)
8355–8365).

A protocol (:mod:`slipcycle.joints.lap_joint_protocol`) is followed from the unloaded,
stress-free state (every node in contact, no slip); then the service cycle

    r^w(θ) = r^w_0 + F sin θ r_service

(r^w_0 the load the assembly leaves at zero service load) is run with the one 3-D engine
(:func:`slipcycle.discrete3d.solve_model`) to its steady state. Per protocol the study
reports (:mod:`slipcycle.joints.lap_joint_result`) the steady-state class, the
dissipation per cycle (total and per bolt region), the permanently stuck area, the slip
map and the bolt forces, and, when the joint was reduced on more than one mesh, the mesh
convergence of each protocol's dissipation
(:func:`slipcycle.joints.convergence.mesh_convergence`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import as_completed
from dataclasses import dataclass, replace

import numpy as np

from slipcycle.discrete3d import FrictionalSystem3D, Load3D, LoadCase3D, solve_model
from slipcycle.discrete3d.case import DiscreteResult3D
from slipcycle.errors import InputError
from slipcycle.joints.lap_joint_protocol import (
    STANDARD_PROTOCOLS,
    JointContact,
    Protocol,
    Step,
    StudySettings,
    assemble,
    locked_system,
    protocol_states,
    standard_protocol,
)
from slipcycle.joints.lap_joint_result import (
    NODE_CLASSES,
    BoltForces,
    LapJointResult,
    MeshRuns,
)
from slipcycle.kernels.threads import single_threaded_blas
from slipcycle.loading import HarmonicLoad
from slipcycle.sweep.core import TaskRunner

__all__ = ["JointContact", "Protocol", "Step", "StudySettings", "STANDARD_PROTOCOLS",
           "standard_protocol", "joint_load", "protocol_states", "joint_system",
           "run_protocol", "ProtocolRun", "protocol_runs", "lap_joint_study",
           "LapJointResult", "MeshRuns", "NODE_CLASSES"]


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


def joint_system(contact: JointContact, settings: StudySettings) -> FrictionalSystem3D:
    """The validated 3-D frictional system of the joint with constant-force bolts
    (checked well posed once: the sampled critical friction coefficient, unless
    ``settings.accept_ill_posed``).

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


@dataclass(frozen=True)
class ProtocolRun:
    """One protocol run: the engine's result and the bolt forces."""

    result: DiscreteResult3D
    bolts: BoltForces


def run_protocol(contact: JointContact, protocol: Protocol, settings: StudySettings,
                 fields: tuple = (), system: FrictionalSystem3D | None = None
                 ) -> ProtocolRun:
    """Assemble the joint by ``protocol`` and cycle the service load to the steady state.

    Parameters
    ----------
    contact : JointContact
    protocol : Protocol
    settings : StudySettings
    fields : tuple of str
        Field formats of the run (written by the study's ``to_outputs``).
    system : FrictionalSystem3D, optional
        :func:`joint_system` (constant-force bolts) or
        :func:`~slipcycle.joints.lap_joint_protocol.locked_system` (elastic bolts) of
        ``contact``, already checked well posed: the check is not repeated (elastic
        bolts: where the protocol ends with every bolt locked, the same stiffness).

    Returns
    -------
    ProtocolRun
        The 3-D engine's result, its histories trimmed to the last cycle (the only one
        the study reports), and the bolt forces after the assembly and over that cycle.
    """
    run = settings.run
    asm = assemble(contact, protocol, settings.preload, settings.friction,
                   step_tol=float(run["step_tol"]))
    if contact.elastic:
        # every bolt locked at the end: the stiffness of locked_system (the same
        # computation), checked once per mesh; otherwise this protocol's own check
        if system is None or not asm.bolts.locked.all():
            system = asm.system(contact, settings.friction, settings.accept_ill_posed)
    elif system is None:
        system = joint_system(contact, settings)
    res = solve_model(system, asm.load(settings.service_amplitude), run,
                      protocol=asm.protocol, initial_slip=asm.initial_slip, fields=fields)
    sol = res.solution
    if sol.x.shape[0] > 1:   # keep the last cycle only: the study reports nothing else
        sol = replace(sol, x=sol.x[-1:], r=sol.r[-1:], modes=sol.modes[-1:])
        res = replace(res, solution=sol)
    service = settings.service_amplitude * np.sin(sol.theta)
    cycle = asm.cycle_forces(sol.x[-1], service) if sol.x.shape[0] else \
        asm.bolt_force[None, :]
    return ProtocolRun(res, BoltForces(asm.bolt_force, cycle))


def lap_joint_study(contacts: JointContact | Sequence[JointContact],
                    protocols: Sequence[Protocol], settings: StudySettings, *,
                    fields: tuple = ("xdmf",), progress=None,
                    workers: int | None = None) -> LapJointResult:
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
    workers : int, optional
        Processes running the protocol runs side by side (:func:`protocol_runs`;
        default 1, this process). The results do not depend on it.

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
            p.check(c.bolt_count, settings.preload)
    # the systems are checked well posed once per mesh, before any run starts
    systems = [locked_system(c, settings.friction, settings.accept_ill_posed)
               if c.elastic else joint_system(c, settings) for c in contacts]
    last = len(contacts) - 1
    tasks = [(contact, protocol, settings, fields if m == last else (), systems[m])
             for m, contact in enumerate(contacts) for protocol in protocols]
    runs = protocol_runs(tasks, workers, progress)
    k = len(protocols)
    diss = np.array([r.result.solution.dissipation_per_cycle for r in runs]).reshape(-1, k)
    states = np.array([r.result.solution.steady_state for r in runs], dtype=object)
    finest = runs[last * k:]
    mesh = MeshRuns(tuple(spacing), diss, states.reshape(-1, k).astype(str))
    return LapJointResult.from_runs(contacts[-1], tuple(protocols),
                                    tuple(r.result for r in finest), mesh, settings,
                                    time.perf_counter() - t0,
                                    tuple(r.bolts for r in finest))


def _protocol_task(contact, protocol, settings, fields, system) -> ProtocolRun:
    """:func:`run_protocol` with one BLAS thread (small dense solves: threads only
    spin, :mod:`slipcycle.kernels.threads`)."""
    with single_threaded_blas():
        return run_protocol(contact, protocol, settings, fields, system)


def protocol_runs(tasks: Sequence[tuple], workers: int | None = None, progress=None
                  ) -> list[ProtocolRun]:
    """The protocol runs ``tasks`` (argument tuples of :func:`run_protocol`), in order.

    Each run is independent of the others, so with ``workers`` > 1 they run side by side
    in local worker processes (:class:`~slipcycle.sweep.core.TaskRunner`; at most one
    per run), the last tasks (the finest mesh: the longest runs) started first. A run
    gives the same numbers in a worker as in this process. If a run fails, the runs not
    started are cancelled and its error is raised. As with any process pool, a script
    that asks for workers must guard its entry point (``if __name__ == "__main__":``):
    the workers import the script's main module.

    Parameters
    ----------
    tasks : sequence of tuple
        ``(contact, protocol, settings, fields, system)`` per run.
    workers : int, optional
        Worker processes (default 1: every run in this process).
    progress : callable, optional
        ``progress(done, total)`` after each run.

    Returns
    -------
    list of ProtocolRun
        In the order of ``tasks``.
    """
    total = len(tasks)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise InputError("workers", f"must be a whole number >= 1, got {workers!r}")
    workers = min(total, workers or 1)
    runs: list = [None] * total
    if workers <= 1:
        for i, task in enumerate(tasks):
            runs[i] = _protocol_task(*task)
            if progress is not None:
                progress(i + 1, total)
        return runs
    with TaskRunner(workers) as runner:
        pool = runner.pool(_protocol_task)
        order = list(range(total))           # popped from the end: the last tasks first
        # at most one run waiting per worker: each task carries its mesh's stiffness
        pending = {}
        for done in range(1, total + 1):
            while order and len(pending) < 2 * workers:
                i = order.pop()
                pending[pool.submit(_protocol_task, *tasks[i])] = i
            fut = next(as_completed(pending))
            runs[pending.pop(fut)] = fut.result()
            if progress is not None:
                progress(done, total)
    return runs
