"""Typed run settings and solver statistics of the coupled discrete models.

:class:`RunSettings` is the ``[run]`` table of a ``discrete`` or ``discrete3d`` case, one
name per setting from the case file to the steady-state driver (the case-file spellings
``steady_tol``/``tolerance`` and ``step_tolerance`` are read as ``tol`` and ``step_tol``
once, where the settings are made). :class:`SolverStats` counts what a run did.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

from slipcycle.errors import InputError

__all__ = ["RunSettings", "SolverStats", "SETTING_ALIASES"]

#: case-file and keyword spellings read as the setting's one name
SETTING_ALIASES = {"steady_tol": "tol", "tolerance": "tol", "step_tolerance": "step_tol"}


def _finite(value) -> bool:
    """A real number (not a bool), finite."""
    return (isinstance(value, numbers.Real) and not isinstance(value, bool)
            and math.isfinite(value))


@dataclass(frozen=True)
class RunSettings(Mapping):
    """Run settings of a steady-state run (both discrete models).

    A read-only mapping of the settings that apply to the model (those not None), so that
    ``simulate(system, load, **settings)`` passes them on unchanged.

    Attributes
    ----------
    cycles : int
        Most load cycles run (default 40).
    steps_per_cycle : int
        Load samples per cycle (default 100).
    tol : float
        Relative tolerance of the steady-state test [1] (default 1e-8).
    min_cycles : int
        Fewest cycles run (default 1).
    step_tol : float or None
        Relative tolerance of the 3-D step control [1] (``discrete3d``: default 1e-7;
        None for the exact 2-D engine, which has no step control).
    replay : bool or None
        3-D: freeze and replay the step control's subdivision (default False; None in 2-D).
    accelerate : bool or None
        The accelerated steady state with its certificate (``True``), plain cycling
        (``False``), or (None, the default) the model's rule: in 2-D the accelerators
        where they pay (:func:`slipcycle.discrete.simulate`), in 3-D plain cycling (the
        Anderson mixing is opt-in: :func:`slipcycle.discrete3d.simulate3d`).

    Raises
    ------
    TypeError
        ``accelerate`` that is neither a bool nor None (named ``run.accelerate``).
    InputError
        A count that is not a whole number >= 1, ``tol`` < 0 or ``step_tol`` <= 0 (or
        not finite), or ``replay`` that is neither a bool nor None (named
        ``run.<setting>``): the settings made in Python (the case readers check tighter
        bounds).
    """

    cycles: int = 40
    steps_per_cycle: int = 100
    tol: float = 1e-8
    min_cycles: int = 1
    step_tol: float | None = None
    replay: bool | None = None
    accelerate: bool | None = None

    def __post_init__(self):
        if self.accelerate is not None and not isinstance(self.accelerate, bool):
            raise TypeError(f"run.accelerate: must be true or false, got {self.accelerate!r}")
        for key in ("cycles", "steps_per_cycle", "min_cycles"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
                raise InputError(f"run.{key}", f"must be a whole number >= 1, got {value!r}")
        tol, step_tol = self.tol, self.step_tol
        if not _finite(tol) or tol < 0.0:
            # 0: no cycle is accepted as steady (every cycle run); the case files ask (0, 1)
            raise InputError("run.tol", f"must be a finite number >= 0, got {tol!r}")
        if step_tol is not None and (not _finite(step_tol) or step_tol <= 0.0):
            raise InputError("run.step_tol", f"must be a finite number > 0, got "
                                             f"{step_tol!r}")
        if self.replay is not None and not isinstance(self.replay, bool):
            raise InputError("run.replay", f"must be true or false, got {self.replay!r}")

    @classmethod
    def of(cls, run: Mapping | None, defaults: RunSettings) -> RunSettings:
        """``defaults`` with the entries of ``run`` (aliases: :data:`SETTING_ALIASES`).

        Raises
        ------
        TypeError
            For a setting the model does not have (its default is None; ``accelerate``,
            None by default, both models have).
        """
        known = list(defaults) + [k for k in _BOTH if k not in defaults]
        given = {}
        for key, value in dict(run or {}).items():
            key = SETTING_ALIASES.get(key, key)
            if key not in known:
                raise TypeError(f"unknown run setting {key!r} (known: {', '.join(known)})")
            given[key] = value
        return replace(defaults, **given)

    def __getitem__(self, key: str) -> Any:
        value = getattr(self, key, None) if key in _NAMES else None
        if value is None:
            raise KeyError(key)
        return value

    def __iter__(self) -> Iterator[str]:
        return (k for k in _NAMES if getattr(self, k) is not None)

    def __len__(self) -> int:
        return sum(1 for _ in self)


_NAMES = tuple(f.name for f in fields(RunSettings))
#: settings of both models whose default is None (the driver's rule)
_BOTH = ("accelerate",)


@dataclass(frozen=True)
class SolverStats(Mapping):
    """What a steady-state run did: the accelerators' counts and the step solver's own.

    A read-only mapping: the accelerators' counts by name, then the step solver's counters
    (2-D: ``factorizations``, ``lemke``, ...; 3-D: ``solves``, ``newton_iterations``, ...).

    Attributes
    ----------
    periodic_attempts, periodic_steps, periodic_steps_rejected : int
        2-D periodic follower: cycles that recorded what a step needs, steps taken (the
        slow-mode steps included), steps refused by their checking cycle.
    cycles_discarded : int
        Checking cycles thrown away with their refused step.
    slow_mode_steps, slow_mode_steps_rejected : int
        2-D slow-mode steps taken and refused.
    jumps, jumps_undone : int
        3-D Anderson-mixing jumps taken and undone.
    replayed_cycles, replay_freezes, replay_mismatches : int
        3-D cycles run on a frozen subdivision, subdivisions frozen, replayed sub-steps that
        did not fit.
    solver : dict
        The step solver's own counters.
    """

    periodic_attempts: int = 0
    periodic_steps: int = 0
    periodic_steps_rejected: int = 0
    cycles_discarded: int = 0
    slow_mode_steps: int = 0
    slow_mode_steps_rejected: int = 0
    jumps: int = 0
    jumps_undone: int = 0
    replayed_cycles: int = 0
    replay_freezes: int = 0
    replay_mismatches: int = 0
    solver: dict = field(default_factory=dict)

    def __getitem__(self, key: str) -> Any:
        if key in _COUNTS:
            return getattr(self, key)
        return self.solver[key]

    def __iter__(self) -> Iterator[str]:
        yield from self.solver
        yield from (k for k in _COUNTS if k not in self.solver)

    def __len__(self) -> int:
        return len(set(self.solver) | set(_COUNTS))


_COUNTS = tuple(f.name for f in fields(SolverStats) if f.name != "solver")
