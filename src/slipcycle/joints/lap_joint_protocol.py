"""Assembly protocols of a bolted joint, with constant-force or elastic bolts.

What an assembly-protocol study needs besides the engine: the reduced joint
(:class:`JointContact`), the protocols (:class:`Step`, :class:`Protocol`, the standard
patterns), the loads and run settings (:class:`StudySettings`) and the assembly itself
(:func:`assemble`: the system and load of the service cycle and the bolt forces).

A protocol is a sequence of steps; each step moves some load amplitudes linearly (the
path the 3-D engine follows quasi-statically) and leaves them there:

=============== =====================================================================
step            what it does
=============== =====================================================================
``tighten``     brings the listed bolts to their target forces (N; default the
                preload), force-controlled, then locks an elastic bolt at that length
``loosen``      the same with the default target 0 (a bolt at 0 N is loose: absent)
``turn``        shortens the free length of locked elastic bolts by ``by`` (m), the
                nut's turn: displacement-controlled
``service``     moves the upper grip to, and holds it at, a service load (N; or an
                ``offset`` in m of grip motion): a fit-up offset
``overload``    takes the service load to a level and back to the one held before
``release``     takes the service load back to zero
=============== =====================================================================

After the last step the service load returns to zero (the start θ = 0 of the service
cycle). The standard tightening patterns (``sequential``, ``star``, ``reversed``,
``simultaneous``) and plain orders (lists of bolts) are shorthands for ``tighten`` steps
at the preload.

Elastic bolts (the pretension section of FE codes). Bolt k is a shank of stiffness k_b
between its washer faces. While it is tightened its force T_k is prescribed; at the end
of its step its length is locked: its force is then T_k = k_b (e_k − s_k), s_k the grip
shortening (:mod:`slipcycle.fe.lap_joint`, "Elastic bolts"), e_k fixed, so that later
steps change it (tightening a neighbour compresses the joint and unloads it: the elastic
interaction of bolted joints, Bickford 2008, ch. 7). With the locked set L, grip
shortenings s = Φ α − Rᵀ x (Φ the bonded shortenings per unit of the load amplitudes α,
R the reactions [q_k; p_k] of the bolt cases, x = [v, w] the interface state),
eliminating the locked forces gives

    T_L = D_L (e_L − Φ_L α' + R_Lᵀ x),       D_L = (k_b⁻¹ I + Φ_LL)⁻¹,
    r   = (K + R_L D_L R_Lᵀ) x + R_L D_L (e_L − Φ_L α') + R α',

α' the amplitudes with the locked bolts' entries zero: a rank-|L| stiffening of the
reduced stiffness K and a load, exactly the reduction of the FE model with the shanks as
springs (tested). The system changes when a bolt locks or unlocks, so the engine follows
each segment of constant L with its own system, the state carried over (the contact
forces r are continuous there: the locked force equals the prescribed one). k_b → 0
recovers constant-force bolts (D_L → k_b), k_b → ∞ rigid ones (D_L → Φ_LL⁻¹).

References
----------
Bickford, J. H. (2008). *Introduction to the Design and Behavior of Bolted Joints*, 4th
ed. CRC Press (elastic interaction, ch. 7).
Barber, J. R. (2012). Frictional systems subjected to oscillating loads. Ann. Solid Struct.
Mech. 2, 45–55 (the assembly decides the steady state of a coupled system).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

import numpy as np

from slipcycle.coupled.settings import RunSettings
from slipcycle.discrete3d import FrictionalSystem3D, Load3D, LoadCase3D
from slipcycle.discrete3d.case import RUN_DEFAULTS
from slipcycle.discrete3d.evolution import Evolution3D
from slipcycle.errors import InputError
from slipcycle.io.matrices import ReducedStiffness
from slipcycle.loading import HarmonicLoad
from slipcycle.loading.nodal import force_scale
from slipcycle.loading.protocol import MAX_FORCE, STEP_ACTIONS, Step

__all__ = ["JointContact", "Step", "Protocol", "StudySettings", "STANDARD_PROTOCOLS",
           "STEP_ACTIONS",
           "standard_protocol", "protocol_states", "Assembly", "assemble", "locked_system"]

#: a protocol's name (a file name of its field output)
PROTOCOL_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+-]*")


def protocol_name_problem(name) -> str | None:
    """What is wrong with ``name`` as a protocol's name, or None: it becomes a file name
    of the field output, so no separators, no "..", nothing a shell or a file system
    reads specially."""
    if isinstance(name, str) and PROTOCOL_NAME.fullmatch(name):
        return None
    return ("a protocol name is letters, digits and _ . + - (starting with a letter or "
            f"digit; it names files), got {name!r}")

#: the standard tightening patterns of a row of K bolts (:func:`standard_protocol`)
STANDARD_PROTOCOLS = ("sequential", "star", "reversed", "simultaneous")

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
    bolt_stiffness : float, optional
        k_b of each bolt shank [N/m]; 0 (default): constant-force bolts.
    bolt_shortening : dict, optional
        Load case → (K,) grip shortening of each bolt per unit of the case with the
        interface bonded [m per unit] (:func:`slipcycle.fe.lap_joint.bonded_shortening`);
        needed for elastic bolts (the bolt cases and ``service``; ``gap`` if present).
    """

    reduced: ReducedStiffness
    node_area: np.ndarray
    bolt_region: np.ndarray
    spacing: float
    description: dict = field(default_factory=dict)
    bolt_stiffness: float = 0.0
    bolt_shortening: dict = field(default_factory=dict)

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
        k = self.bolt_count
        if k == 0 or "service" not in red.loads:
            raise InputError("reduced", "needs the load cases bolt_0 … bolt_{K-1} and "
                             f"service (has: {', '.join(red.loads) or 'none'})")
        if region.min() < 0 or region.max() >= k:
            raise InputError("bolt_region", f"must lie in 0 … {k - 1}")
        if not (np.isfinite(self.spacing) and self.spacing > 0):
            raise InputError("spacing", f"must be a positive length, got {self.spacing!r}")
        kb = self.bolt_stiffness
        if not (isinstance(kb, int | float) and np.isfinite(kb) and kb >= 0):
            raise InputError("bolt_stiffness", f"must be ≥ 0 N/m, got {kb!r}")
        if kb > 0:
            missing = [c for c in self.case_names if c not in self.bolt_shortening]
            if missing:
                raise InputError("bolt_shortening", "elastic bolts need the bonded grip "
                                 f"shortening of every case, missing {missing[0]!r}")
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

    @property
    def elastic(self) -> bool:
        """Whether the bolts are elastic (k_b > 0)."""
        return self.bolt_stiffness > 0

    @property
    def case_names(self) -> tuple[str, ...]:
        """The load amplitudes α of an assembly: the bolts, ``service`` and ``gap``."""
        gap = ("gap",) if "gap" in self.reduced.loads else ()
        return (*(f"bolt_{k}" for k in range(self.bolt_count)), "service", *gap)

    def case_vector(self, name: str) -> np.ndarray:
        """[q, p] of load case ``name`` per unit of the case, (3N,) [N]."""
        case = self.reduced.loads[name]
        return np.concatenate([np.asarray(case["q"], float), np.asarray(case["p"], float)])

    def decoupled(self) -> JointContact:
        """The same joint with B = 0: normal and tangential problems decoupled.

        A and C are kept (K stays positive definite), so the normal reactions no longer
        depend on slip; the frictional Melan theorem then makes the steady dissipation the
        same for every assembly protocol that ends with the same loads (Klarbring,
        Ciavarella & Barber 2007).
        """
        red = replace(self.reduced, B=np.zeros_like(self.reduced.B),
                      source=f"{self.reduced.source} (B = 0)")
        return replace(self, reduced=red)


def _as_step(item) -> Step:
    if isinstance(item, Step):
        return item
    return Step("tighten", tuple(int(b) for b in np.atleast_1d(item)))


@dataclass(frozen=True)
class Protocol:
    """An assembly protocol: a sequence of :class:`Step` (module docstring).

    Parameters
    ----------
    name : str
    steps : tuple
        Steps; a plain bolt number or tuple of numbers is a ``tighten`` step at the
        preload (a step of several bolts tightens them together, proportionally).
    """

    name: str
    steps: tuple

    def __post_init__(self):
        problem = protocol_name_problem(self.name)
        if problem is not None:
            raise InputError("protocols", problem)
        try:
            steps = tuple(_as_step(s) for s in self.steps)
        except InputError as exc:
            raise InputError("protocols", f"{self.name}: {exc.key}: {exc.problem}") from None
        except (TypeError, ValueError):
            raise InputError("protocols", f"{self.name}: steps must be bolt numbers or "
                             "lists of bolt numbers") from None
        if not steps:
            raise InputError("protocols", f"{self.name}: needs at least one step")
        if self.plain(steps):       # the order shorthand: tuples of bolts, as before
            object.__setattr__(self, "steps", tuple(s.bolts for s in steps))
        else:
            object.__setattr__(self, "steps", steps)

    @staticmethod
    def plain(steps) -> bool:
        """Whether every step tightens bolts to the preload (a tightening order)."""
        return all(s.action == "tighten" and s.force is None for s in steps)

    @property
    def step_list(self) -> tuple[Step, ...]:
        """The steps as :class:`Step` objects."""
        return tuple(_as_step(s) for s in self.steps)

    def check(self, bolt_count: int, preload: float | None = None) -> None:
        """Raise InputError unless the steps fit K bolts: every step names bolts
        0 … K−1 only; an order tightens every bolt exactly once; a general protocol
        tightens every bolt at least once, loosens only bolts tightened before it, and,
        given the ``preload`` [N] (the default target), never loosens a bolt to more
        than its force; a tighten targets more than 0 N. A step's error has key
        ``protocols`` and its ``step`` = (j, field)."""
        steps = self.step_list
        for j, s in enumerate(steps):
            bad = [b for b in s.bolts if not 0 <= b < bolt_count]
            if bad:
                raise _step_error(self.name, j, s.action, f"no bolt {bad[0]} (bolts 0 … "
                                  f"{bolt_count - 1})")
            if s.action == "tighten" and s.force is not None and \
                    np.any(np.asarray(s.force) == 0):
                raise _step_error(self.name, j, "force", "a tighten targets more than 0 N (a "
                                  "loosen step takes a bolt to 0)")
        if self.plain(steps):
            flat = [b for s in steps for b in s.bolts]
            if sorted(flat) != list(range(bolt_count)):
                raise InputError("protocols", f"{self.name}: must tighten each of the "
                                 f"{bolt_count} bolts 0 … {bolt_count - 1} exactly once, "
                                 f"got {[list(s.bolts) for s in steps]}")
            return
        self._check_loosening(steps, preload)
        tightened = {b for s in steps if s.action == "tighten" for b in s.bolts}
        missing = sorted(set(range(bolt_count)) - tightened)
        if missing:
            raise InputError("protocols", f"{self.name}: bolt {missing[0]} is never "
                             "tightened")

    def _check_loosening(self, steps, preload: float | None) -> None:
        """A loosen step acts on bolts tightened before it and lowers their force."""
        force: dict[int, float | None] = {}
        for j, s in enumerate(steps):
            if s.action not in ("tighten", "loosen"):
                continue
            targets = s.targets(np.nan if preload is None else preload)
            for b, t in zip(s.bolts, targets, strict=True):
                if s.action == "loosen" and b not in force:
                    raise _step_error(self.name, j, "loosen", f"bolt {b} is loosened before "
                                      "it is tightened")
                if s.action == "loosen" and t > force[b]:
                    raise _step_error(self.name, j, "force", f"loosening bolt {b} to {t:g} N "
                                      f"would raise its force ({force[b]:g} N): tighten it "
                                      "instead")
                force[b] = t

    @property
    def label(self) -> str:
        """The steps as text: ``0 → 2 → 1`` (``0+1`` for bolts tightened together)."""
        return " → ".join(s.label for s in self.step_list)


def _step_error(name: str, j: int, field: str, problem: str) -> InputError:
    """The error of step ``j`` of protocol ``name`` (key ``protocols``), carrying
    ``step`` = (j, field) so that a case reader can name the step's key."""
    err = InputError("protocols", f"{name}: step {j} ({field}): {problem}")
    err.step = (j, field)
    return err


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
        ``cycles``, ``steps_per_cycle``, ``tol``, ``min_cycles``, ``step_tol``,
        ``replay``, ``accelerate`` of the 3-D engine
        (:data:`slipcycle.discrete3d.case.RUN_DEFAULTS` for the others; ``accelerate``
        False: plain cycling).
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
        for name in ("preload", "service_amplitude"):
            if getattr(self, name) > MAX_FORCE:
                raise InputError(name, f"must be at most {MAX_FORCE:g} N (beyond any "
                                 f"joint), got {getattr(self, name)!r}")
        known = [*RUN_DEFAULTS, "accelerate"]
        unknown = set(self.run) - set(known)
        if unknown:
            raise InputError("run", f"unknown run setting {sorted(unknown)[0]!r} (known: "
                             f"{', '.join(known)})")
        run = {**RUN_DEFAULTS, **self.run}
        RunSettings(**run)      # the values checked before any run (one line per key)
        object.__setattr__(self, "run", run)



# -- the assembly path -----------------------------------------------------------------

@dataclass
class _Bolts:
    """Bookkeeping of an assembly: amplitudes α (bolt forces of unlocked bolts, service,
    gap), the locked set and the locked lengths e [m]."""

    alpha: np.ndarray
    locked: np.ndarray
    e: np.ndarray

    def copy(self) -> _Bolts:
        return _Bolts(self.alpha.copy(), self.locked.copy(), self.e.copy())


@dataclass(frozen=True)
class _Algebra:
    """R (3N, m) reactions and Φ (K, m) bonded shortenings of the amplitudes, k_b."""

    R: np.ndarray
    Phi: np.ndarray
    kb: float
    K: np.ndarray

    @classmethod
    def of(cls, contact: JointContact) -> _Algebra:
        names = contact.case_names
        R = np.stack([contact.case_vector(c) for c in names], axis=1)
        k = contact.bolt_count
        if contact.elastic:
            Phi = np.stack([np.asarray(contact.bolt_shortening[c], float) for c in names], 1)
        else:
            Phi = np.zeros((k, len(names)))
        red = contact.reduced
        K = np.block([[red.A, red.B.T], [red.B, red.C]])
        return cls(R, Phi, float(contact.bolt_stiffness), K)

    def coupling(self, locked: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """R_L (3N, |L|) and D_L (|L|, |L|) of the locked set."""
        L = np.flatnonzero(locked)
        D = np.linalg.inv(np.eye(L.size) / self.kb + self.Phi[np.ix_(L, L)])
        return self.R[:, L], 0.5 * (D + D.T)

    def load(self, b: _Bolts) -> np.ndarray:
        """r^w (3N,) of the bookkeeping ``b`` (module docstring)."""
        a = np.where(np.r_[b.locked, np.zeros(self.R.shape[1] - b.locked.size, bool)],
                     0.0, b.alpha)
        r = self.R @ a
        if b.locked.any():
            RL, D = self.coupling(b.locked)
            r += RL @ (D @ (b.e[b.locked] - self.Phi[b.locked] @ a))
        return r

    def stiffness(self, locked: np.ndarray) -> np.ndarray:
        """K + R_L D_L R_Lᵀ (3N, 3N) [N/m]."""
        if not locked.any():
            return self.K
        RL, D = self.coupling(locked)
        return self.K + RL @ D @ RL.T

    def forces(self, b: _Bolts, x: np.ndarray) -> np.ndarray:
        """Bolt forces T (K,) [N] at the interface state x (..., 3N)."""
        k = b.locked.size
        x = np.asarray(x, float)
        T = np.broadcast_to(b.alpha[:k], (*x.shape[:-1], k)).copy()
        if b.locked.any():
            a = np.where(np.r_[b.locked, np.zeros(self.R.shape[1] - k, bool)], 0.0,
                         b.alpha)
            RL, D = self.coupling(b.locked)
            T[..., b.locked] = (D @ (b.e[b.locked] - self.Phi[b.locked] @ a)
                                + x @ RL @ D)
        return T

    def lock(self, b: _Bolts, bolts, x: np.ndarray) -> None:
        """Lock ``bolts`` (force-controlled now) at their current length."""
        T = self.forces(b, x)
        s = self.Phi @ np.r_[T, b.alpha[T.size:]] - self.R[:, :T.size].T @ x
        for j in bolts:
            b.e[j] = T[j] / self.kb + s[j]
            b.locked[j] = True
            b.alpha[j] = 0.0

    def unlock(self, b: _Bolts, bolts, x: np.ndarray) -> None:
        """Make ``bolts`` force-controlled at their current force."""
        T = self.forces(b, x)
        for j in bolts:
            if b.locked[j]:
                b.alpha[j] = T[j]
                b.locked[j] = False


def _plan(contact: JointContact, protocol: Protocol, preload: float) -> list[tuple]:
    """The assembly as operations on the bookkeeping: ``("set", indices, values)`` moves
    amplitudes linearly to new values, ``("turn", bolts, by)`` shortens locked lengths,
    ``("lock", bolts)`` / ``("unlock", bolts)`` switch bolts between locked length and
    prescribed force (elastic bolts). Ends with the service load at zero."""
    k = contact.bolt_count
    m = len(contact.case_names)
    grip = contact.description.get("service_grip_stiffness_N_per_m")
    ops: list[tuple] = []
    if "gap" in contact.reduced.loads:
        ops.append(("set", [m - 1], [1.0]))     # the initial gap first: its reactions
    locked = np.zeros(k, bool)
    held = level = 0.0
    for j, step in enumerate(protocol.step_list):
        where = f"{protocol.name}: step {j} ({step.action})"
        if step.action in ("tighten", "loosen"):
            bolts = list(step.bolts)
            targets = step.targets(preload)
            ops += [("unlock", bolts), ("set", bolts, targets)]
            locked[bolts] = False
            if contact.elastic:
                tight = [b for b, t in zip(bolts, targets, strict=True) if t > 0]
                ops.append(("lock", tight))
                locked[tight] = True
        elif step.action == "turn":
            if not contact.elastic or not locked[list(step.bolts)].all():
                raise InputError("protocols", f"{where}: bolts {list(step.bolts)} must be "
                                 "elastic (bolt_modulus > 0) and tightened before a turn")
            ops.append(("turn", list(step.bolts), step.by))
        else:
            if step.offset is not None:
                if not grip:
                    raise InputError("protocols", f"{where}: a grip offset needs the grip "
                                     "stiffness of the joint (its description)")
                level = step.offset * grip
                if abs(level) > MAX_FORCE:
                    raise InputError("protocols", f"{where}: the offset {step.offset:g} m "
                                     f"is a grip force of {level:g} N, beyond "
                                     f"{MAX_FORCE:g} N")
            else:
                level = 0.0 if step.action == "release" else float(step.force)
            ops.append(("set", [k], [level]))
            if step.action == "overload":
                ops.append(("set", [k], [held]))
                level = held
            held = level
    if level != 0.0:                 # the service cycle starts from zero service load
        ops.append(("set", [k], [0.0]))
    return ops


def _apply(b: _Bolts, op: tuple) -> _Bolts:
    """The bookkeeping after a ``set`` or ``turn`` operation."""
    out = b.copy()
    if op[0] == "set":
        out.alpha[op[1]] = op[2]
    else:
        out.e[op[1]] += op[2]
    return out


def protocol_states(contact: JointContact, protocol: Protocol, preload: float
                    ) -> np.ndarray | None:
    """Load states [q^w, p^w] after each assembly step but the last, (S − 1, 3N) [N],
    with the bolts as constant forces.

    The last step reaches the load at θ = 0, which the engine visits anyway; a protocol
    of one step (all bolts together) is plain loading from the unloaded state (None). A
    joint with an initial gap (load case ``gap``, the rounded plate ends of
    :class:`~slipcycle.fe.lap_joint.LapJoint`) first opens it: the gap's reactions are the
    first state, and every later state includes them.
    """
    protocol.check(contact.bolt_count, preload)
    rigid = replace(contact, bolt_stiffness=0.0)
    alg = _Algebra.of(rigid)
    k, m = contact.bolt_count, len(contact.case_names)
    b = _Bolts(np.zeros(m), np.zeros(k, bool), np.zeros(k))
    states = []
    for op in _plan(rigid, protocol, preload):
        if op[0] == "set":
            b = _apply(b, op)
            states.append(alg.load(b))
    states = states[:-1]
    return np.array(states) if states else None


@dataclass(frozen=True)
class Assembly:
    """The assembled joint: the system and load of its service cycle, how to start it,
    and its bolt forces.

    Attributes
    ----------
    stiffness : (3N, 3N) array
        K + R_L D_L R_Lᵀ of the bolts locked at the end [N/m] (K for constant-force bolts).
    start : (3N,) array
        Load r^w at θ = 0, service zero [N].
    service : (3N,) array
        Reactions per newton of service load with the bolts as they end [N/N].
    initial_slip : (2N,) array or None
        Slip at the end of the assembly [m] (elastic bolts); None: the assembly path is
        ``protocol`` (constant-force bolts, one system throughout).
    protocol : (S, 3N) array or None
        Load states of the assembly before θ = 0 (constant-force bolts).
    bolt_force : (K,) array
        Bolt forces at the end of the assembly (θ = 0) [N].
    bolts : _Bolts
        Bookkeeping of the end of the assembly (bolt forces over the cycle:
        :meth:`cycle_forces`).
    """

    stiffness: np.ndarray
    start: np.ndarray
    service: np.ndarray
    initial_slip: np.ndarray | None
    protocol: np.ndarray | None
    bolt_force: np.ndarray
    bolts: _Bolts
    algebra: _Algebra

    def system(self, contact: JointContact, friction: float,
               accept_ill_posed: bool) -> FrictionalSystem3D:
        """The frictional system of the service cycle."""
        return _system(contact, self.stiffness, friction, accept_ill_posed)

    def load(self, service_amplitude: float) -> Load3D:
        """r^w(θ) = start + F sin θ · service, as a :class:`Load3D`."""
        n = self.start.size // 3
        zero = HarmonicLoad(np.zeros(n), np.zeros((1, n)), 0.0)
        zero_q = HarmonicLoad(np.zeros(2 * n), np.zeros((1, 2 * n)), 0.0)
        cases = (LoadCase3D(p=self.start[2 * n:], q=self.start[:2 * n],
                            time=HarmonicLoad([1.0], [[0.0]], 0.0)),
                 LoadCase3D(p=self.service[2 * n:], q=self.service[:2 * n],
                            time=HarmonicLoad([0.0], [[float(service_amplitude)]],
                                              -np.pi / 2)))
        return Load3D(p=zero, q=zero_q, cases=cases)

    def cycle_forces(self, x: np.ndarray, service: np.ndarray) -> np.ndarray:
        """Bolt forces (S, K) [N] at the states x (S, 3N) of the service cycle with the
        service loads ``service`` (S,) [N]."""
        k = self.bolt_force.size
        out = np.empty((x.shape[0], k))
        for i, (xi, s) in enumerate(zip(x, service, strict=True)):
            b = self.bolts.copy()
            b.alpha[k] = s
            out[i] = self.algebra.forces(b, xi)
        return out


def _system(contact: JointContact, K: np.ndarray, friction: float,
            accept_ill_posed: bool) -> FrictionalSystem3D:
    n2 = 2 * contact.n_nodes
    red = contact.reduced
    return FrictionalSystem3D(K[:n2, :n2], K[n2:, :n2], K[n2:, n2:], friction,
                              coordinates=red.coordinates, normals=red.normals,
                              tangents=red.tangents, area=contact.node_area,
                              accept_ill_posed=accept_ill_posed)


def locked_system(contact: JointContact, friction: float,
                  accept_ill_posed: bool = False) -> FrictionalSystem3D:
    """The frictional system with every bolt locked (elastic bolts; K itself for
    constant-force bolts): the service system of every protocol that ends with all bolts
    tightened, checked well posed once (the sampled critical friction coefficient, unless
    ``accept_ill_posed``).

    Raises
    ------
    ModelError
        f reaches the critical friction coefficient of the joint with its bolts.
    """
    alg = _Algebra.of(contact)
    locked = np.full(contact.bolt_count, contact.elastic)
    return _system(contact, alg.stiffness(locked), friction, accept_ill_posed)


def assemble(contact: JointContact, protocol: Protocol, preload: float, friction: float,
             step_tol: float = 1e-6) -> Assembly:
    """Follow the assembly ``protocol`` of the joint (module docstring).

    Constant-force bolts: one system throughout; the load states are returned for the
    engine to follow from the unloaded state (:func:`protocol_states`). Elastic bolts:
    every segment with one locked set is followed by
    :class:`~slipcycle.discrete3d.evolution.Evolution3D` with its own system, from the
    unloaded state to θ = 0 (service zero); the state is carried across the switches.

    Parameters
    ----------
    contact : JointContact
    protocol : Protocol
    preload : float
        Default target of ``tighten`` [N].
    friction : float
    step_tol : float
        Relative tolerance of the step control of the assembly path (elastic bolts).

    Returns
    -------
    Assembly
    """
    protocol.check(contact.bolt_count, preload)
    alg = _Algebra.of(contact)
    k, m = contact.bolt_count, len(contact.case_names)
    ops = _plan(contact, protocol, preload)
    b = _Bolts(np.zeros(m), np.zeros(k, bool), np.zeros(k))
    x = np.zeros(3 * contact.n_nodes)
    if not contact.elastic:
        for op in ops:
            if op[0] == "set":
                b = _apply(b, op)
        return Assembly(alg.K, alg.load(b), alg.R[:, k], None,
                        protocol_states(contact, protocol, preload), b.alpha[:k].copy(), b,
                        alg)
    # the scale of the loads: the constant-force path's
    rigid, bc = _Algebra.of(replace(contact, bolt_stiffness=0.0)), b.copy()
    moves = [rigid.load(bc := _apply(bc, op)) for op in ops if op[0] == "set"]
    scale = force_scale(np.array(moves))
    evo = None
    for op in ops:
        if op[0] in ("lock", "unlock"):
            if op[1]:
                (alg.lock if op[0] == "lock" else alg.unlock)(b, op[1], x)
                evo = None              # a new system from here on, the state carried
            continue
        if evo is None:
            sys = _system(contact, alg.stiffness(b.locked), friction, True)
            evo = Evolution3D(sys, x, alg.load(b), scale, step_tol=step_tol)
        nxt = _apply(b, op)
        evo.follow(np.array([0.0, 1.0]), np.array([alg.load(b), alg.load(nxt)]))
        evo.resync()
        x, b = evo.x.copy(), nxt
    n2 = 2 * contact.n_nodes
    unit = b.copy()
    unit.alpha[k] += 1.0
    return Assembly(alg.stiffness(b.locked), alg.load(b), alg.load(unit) - alg.load(b),
                    x[:n2].copy(), None, alg.forces(b, x), b, alg)
