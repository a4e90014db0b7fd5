"""Assembly protocols as steps: the one step vocabulary of every assembly.

A protocol is a sequence of :class:`Step`; each step moves some load amplitudes linearly
(the path the engine follows quasi-statically) and leaves them there:

=============== =====================================================================
step            what it does
=============== =====================================================================
``tighten``     brings the listed bolts (lap joint) or nodes (``discrete3d``) to their
                target normal forces (N; default the preload, or the node's normal
                load at θ = 0)
``loosen``      the same with the default target 0
``turn``        shortens the free length of locked elastic bolts (lap joint only) [m]
``service``     moves the service load to, and holds it at, a level: a fit-up offset
                (lap joint: grip force [N], or ``offset`` [m]; ``discrete3d``: a
                multiple of the tangential load at θ = 0 [1])
``overload``    takes the service load to a level and back to the one held before
``release``     takes the service load back to zero
=============== =====================================================================

After the last step the load goes on, linearly, to the load at θ = 0 of the cycle.
:func:`read_step` reads a step from a case file (the same keys and one-line errors for
every model); :func:`step_states` turns the steps of a discrete case into the load states
its engine passes through (the ``[[protocol]]`` form).

References
----------
Barber, J. R. (2012). Frictional systems subjected to oscillating loads. Ann. Solid Struct.
Mech. 2, 45–55 (the assembly decides the steady state of a coupled system).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from slipcycle.errors import CaseError, InputError

__all__ = ["STEP_ACTIONS", "Step", "read_step", "step_states"]

#: the largest force (or service level) a step may set [N]: 1e12 N is beyond any joint
#: (an M100 bolt carries about 4e6 N)
MAX_FORCE = 1e12

#: the step actions (module docstring)
STEP_ACTIONS = ("tighten", "loosen", "turn", "service", "overload", "release")


@dataclass(frozen=True)
class Step:
    """One assembly step (module docstring).

    Parameters
    ----------
    action : str
        One of :data:`STEP_ACTIONS`.
    bolts : tuple of int
        The bolts (lap joint) or nodes (discrete models) of ``tighten``, ``loosen``,
        ``turn``.
    force : float or tuple of float, optional
        ``tighten``/``loosen``: target force of each listed bolt or node [N] (one value
        for all; default the preload or the normal load at θ = 0 / 0).
        ``service``/``overload``: the service load [N] (lap joint) or its level relative to
        the tangential load at θ = 0 [1] (discrete models).
    by : float
        ``turn``: shortening of the free length of each listed bolt [m].
    offset : float, optional
        ``service``: the grip offset [m] instead of ``force`` (converted with the grip
        stiffness of the stuck joint).
    """

    action: str
    bolts: tuple = ()
    force: float | tuple | None = None
    by: float = 0.0
    offset: float | None = None

    def __post_init__(self):
        if self.action not in STEP_ACTIONS:
            raise InputError("action", f"must be one of {', '.join(STEP_ACTIONS)}, got "
                             f"{self.action!r}")
        try:
            bolts = tuple(int(b) for b in np.atleast_1d(self.bolts))
        except (TypeError, ValueError):
            raise InputError("bolts", "must be bolt numbers") from None
        object.__setattr__(self, "bolts", bolts)
        if self.action in ("tighten", "loosen", "turn"):
            if not bolts or len(set(bolts)) != len(bolts):
                raise InputError("bolts", f"{self.action} needs distinct bolt numbers, got "
                                 f"{list(bolts)}")
        elif bolts:
            raise InputError("bolts", f"{self.action} takes no bolts")
        if self.force is not None:
            if self.action not in ("tighten", "loosen", "service", "overload"):
                raise InputError("force", f"{self.action} takes no force")
            f = np.atleast_1d(np.asarray(self.force, float))
            if self.action in ("service", "overload") and f.size != 1:
                raise InputError("force", "must be one number [N]")
            if f.size not in (1, len(bolts)) and self.action in ("tighten", "loosen"):
                raise InputError("force", f"must be one force or one per bolt "
                                 f"({len(bolts)}), got {f.size}")
            if not np.all(np.isfinite(f)) or (self.action != "service" and np.any(f < 0)):
                sign = "" if self.action == "service" else " and ≥ 0"
                raise InputError("force", f"must be finite{sign}, got {f.tolist()}")
            if np.any(np.abs(f) > MAX_FORCE):
                raise InputError("force", f"must be at most {MAX_FORCE:g} in size (beyond "
                                 "any joint, and the round-off of such a load would exceed "
                                 f"the preload), got {f.tolist()}")
            if self.action == "overload" and f[0] == 0:
                raise InputError("force", "an overload needs a nonzero service load")
            object.__setattr__(self, "force", float(f[0]) if f.size == 1 else tuple(f.tolist()))
        if self.action == "turn" and not (np.isfinite(self.by) and self.by != 0):
            raise InputError("by", f"a turn needs a nonzero finite shortening [m], got "
                             f"{self.by!r}")
        if self.action != "turn" and self.by != 0:
            raise InputError("by", f"{self.action} takes no turn")
        if self.offset is not None:
            if self.action != "service" or self.force is not None:
                raise InputError("offset", "only a service step takes an offset (instead "
                                 "of its force)")
            if not np.isfinite(self.offset):
                raise InputError("offset", f"must be finite [m], got {self.offset!r}")
        if self.action in ("service", "overload") and self.force is None \
                and self.offset is None:
            raise InputError("force", f"{self.action} needs its load [N]")

    def targets(self, preload: float) -> np.ndarray:
        """Target force of each listed bolt [N] (``tighten``/``loosen``)."""
        default = preload if self.action == "tighten" else 0.0
        f = default if self.force is None else self.force
        return np.broadcast_to(np.asarray(f, float), (len(self.bolts),)).copy()

    @property
    def label(self) -> str:
        """Short text: ``0+1``, ``loosen 0``, ``service 900 N`` …"""
        if self.action == "tighten" and self.force is None:
            return "+".join(map(str, self.bolts))
        what = " ".join([self.action, "+".join(map(str, self.bolts))]).strip()
        if self.action == "turn":
            return f"{what} {self.by:g} m"
        if self.offset is not None:
            return f"{what} {self.offset:g} m"
        if self.force is not None:
            f = self.force if isinstance(self.force, float) else "/".join(
                f"{x:g}" for x in self.force)
            return f"{what} {f if isinstance(f, str) else format(f, 'g')} N"
        return what



#: the keys of a step table besides its action
_STEP_OPTIONS = ("force", "by")


def read_step(key: str, raw, what: str = "bolt") -> Step:
    """One step of an assembly protocol in a case file: a table with one action key.

    The one reader of ``[lap_joint.protocols.steps]`` and of ``[discrete3d] steps``.

    Parameters
    ----------
    key : str
        Full dotted key of the step (``lap_joint.protocols.steps.fit_up[0]``), named by
        every error.
    raw : dict
        The parsed TOML table, e.g. ``{"tighten": [0, 1], "force": 5e3}``.
    what : str
        What ``tighten``/``loosen``/``turn`` list: ``"bolt"`` or ``"node"``.

    Returns
    -------
    Step

    Raises
    ------
    CaseError
        One line naming the step's key and the problem.
    """
    if not isinstance(raw, dict):
        raise CaseError(key, f"a step is a table with one action ({', '.join(STEP_ACTIONS)}"
                             f", offset), e.g. {{tighten = [0, 1]}}; got {raw!r}")
    actions = [a for a in (*STEP_ACTIONS, "offset") if a in raw]
    if len(actions) != 1:
        raise CaseError(key, f"needs exactly one action of {', '.join(STEP_ACTIONS)}, "
                             f"offset; got {sorted(raw) or 'none'}")
    action = actions[0]
    extra = sorted(set(raw) - {action, *_STEP_OPTIONS})
    if extra:
        raise CaseError(f"{key}.{extra[0]}", "unknown key")
    value = raw[action]
    kw = {k: raw[k] for k in _STEP_OPTIONS if k in raw}
    allowed = {"tighten": ("force",), "loosen": ("force",), "turn": ("by",)}.get(action, ())
    for k in kw:
        if k not in allowed:
            raise CaseError(f"{key}.{k}", f"a {action} step takes no {k}")
    for k, v in kw.items():
        items = v if isinstance(v, list) else [v]
        if not items or any(isinstance(x, bool) or not isinstance(x, int | float)
                            for x in items):
            raise CaseError(f"{key}.{k}", f"must be a number (or a list of numbers), got "
                                          f"{v!r}")
    if action in ("tighten", "loosen", "turn"):
        bolts = value if isinstance(value, list) else [value]
        if not bolts or any(isinstance(b, bool) or not isinstance(b, int) for b in bolts):
            raise CaseError(f"{key}.{action}", f"must be {what} numbers, got {value!r}")
        kw["bolts"] = tuple(bolts)
    elif action == "release":
        if value is not True:
            raise CaseError(f"{key}.release", f"must be true, got {value!r}")
    elif isinstance(value, bool) or not isinstance(value, int | float):
        raise CaseError(f"{key}.{action}", f"must be a number, got {value!r}")
    elif action == "offset":
        action, kw["offset"] = "service", float(value)
    else:
        kw["force"] = float(value)
    try:
        return Step(action, **kw)
    except InputError as exc:
        sub = exc.key if exc.key in raw else actions[0]
        raise CaseError(f"{key}.{sub}", exc.problem) from None



def step_states(steps: Sequence[Step], q0: np.ndarray, p0: np.ndarray) -> np.ndarray:
    """The load states a discrete model passes through along an assembly of ``steps``.

    Nodes play the bolts: ``tighten``/``loosen`` set the normal loads of the listed nodes
    (default targets: their normal load at θ = 0, and 0); ``service`` holds the
    tangential load at ``force`` × its value at θ = 0, ``overload`` goes to that level
    and back, ``release`` to zero. From the unloaded state the engine follows the states
    linearly, then goes on to the load at θ = 0.

    Parameters
    ----------
    steps : sequence of Step
    q0 : (N, c) or (N,) array
        Tangential load at θ = 0 [N] (c = 2 in 3-D, node-major).
    p0 : (N,) array
        Normal load at θ = 0 [N].

    Returns
    -------
    (S, (c + 1) N) array
        Rows [q^w, p^w] [N], one per step (two per overload).

    Raises
    ------
    InputError
        Key ``steps[j].<action>``: a node out of range, a ``turn`` or ``offset`` (no
        bolts, no grip), or a service level with no tangential load at θ = 0.
    """
    q0 = np.asarray(q0, float)
    p0 = np.asarray(p0, float)
    n = p0.size
    p, level, out = np.zeros(n), 0.0, []

    def state(lev):
        return np.concatenate([lev * q0.ravel(), p])

    for j, s in enumerate(steps):
        if not isinstance(s, Step):
            raise InputError(f"steps[{j}]", f"must be a Step, got {s!r}")
        key = f"steps[{j}].{s.action}"
        if s.action == "turn" or s.offset is not None:
            raise InputError(f"steps[{j}].{'turn' if s.action == 'turn' else 'offset'}",
                             "needs the elastic bolts or the grip of a lap_joint case")
        if any(b < 0 or b >= n for b in s.bolts):
            raise InputError(key, f"node numbers must lie in 0 … {n - 1}, got "
                                  f"{list(s.bolts)}")
        if s.action in ("tighten", "loosen"):
            nodes = list(s.bolts)
            default = p0[nodes] if s.action == "tighten" else 0.0
            p[nodes] = default if s.force is None else s.force
        elif s.action == "release":
            level = 0.0
        else:
            if not np.any(q0) and s.force != 0:
                raise InputError(key, "the tangential load at θ = 0 is zero: a service "
                                      "level scales it")
            if s.action == "overload":
                out.append(state(s.force))
            else:
                level = s.force
        out.append(state(level))
    if not out:
        raise InputError("steps", "needs at least one step")
    return np.array(out)
