"""A validated half-space contact problem and its load path."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from slipcycle.errors import InputError
from slipcycle.halfspace.bed import SliderBed, lumped_slider_slipped, lumping_load, make_bed
from slipcycle.halfspace.elastic import ContactElasticity
from slipcycle.halfspace.history import HistoryResult, run_history
from slipcycle.halfspace.loads import contact_loads
from slipcycle.halfspace.profiles import (
    Cylinder2D,
    RoughExponential,
    Tabulated,
    slope_warning,
)
from slipcycle.loading import cycle_angles, piecewise_linear_path

log = logging.getLogger("slipcycle")

__all__ = ["HalfspaceModel", "LoadPathError", "solve"]


class LoadPathError(InputError):
    """A load path the contact cannot carry (:meth:`HalfspaceModel.check_loads`).

    ``key`` names the field (``normal``, ``protocol[i]``, ``profile``,
    ``profile.reference_depth``); ``reason`` names the check that failed, one of
    ``"not_finite"``, ``"never_compressive"``, ``"tensile"``, ``"rough_unloaded"``,
    ``"reference_depth"``, ``"table_end"`` (a case-file reader blames the mean of a
    harmonic load for ``"never_compressive"``, its amplitude for ``"tensile"``).
    """

    def __init__(self, key: str, problem: str, reason: str):
        super().__init__(key, problem)
        self.reason = reason


@dataclass(frozen=True)
class HalfspaceModel:
    """Everything needed to run one half-space contact history.

    Attributes
    ----------
    profile : Profile
    elasticity : ContactElasticity or None
        None for profiles defined without elastic constants (rough, tabulated).
    friction : float
    compliance_ratio : float
        λ_c.
    normal, tangential : PeriodicLoad
        One-component periodic loads: P (N) or U (m); Q (N) or V (m). Build harmonic ones
        with :func:`~slipcycle.halfspace.contact_loads` (or :meth:`harmonic`), which gives
        ``phase`` the meaning it has in case files (a lag of Q behind P).
    normal_control : {"force", "approach"}
    tangential_control : {"force", "displacement"}
    protocol : (S, 2) array
        Assembly states after the unloaded state (normal, tangential); the path continues
        linearly to the state at θ = 0. Empty: a straight line from the unloaded state in
        force control, normal approach first and then the tangential load in approach
        control.
    steps_per_cycle, max_cycles, n_sliders, assembly_steps : int
    snapshots : (m,) array
        Cycle angles (rad) at which tractions are reported.
    steady_tol : float
        Relative change of the cycle below which the history is steady, in (0, 1).
    profile_name : str
        Name of the profile in results (informative).
    surface : dict
        Description of a measured surface whose BEM law is ``profile`` (informative, for
        the summary: :meth:`~slipcycle.halfspace.topography.TopographySource.describe`);
        empty for analytic profiles.

    Raises
    ------
    slipcycle.errors.InputError
        Keyed by the field name, at construction: a profile without a normal law, f ≤ 0,
        λ_c ≤ 0, non-finite numbers, an unknown control, a protocol that is not (S, 2),
        settings out of range (steps_per_cycle ≥ 8, max_cycles ≥ 1, n_sliders ≥ 10,
        assembly_steps ≥ 1, snapshots in [0, 2π], 0 < steady_tol < 1). The load path
        (a tensile or never compressive normal load, a rough contact unloaded, a table
        or cylinder reference depth too short for the loads) is checked by
        :meth:`check_loads`, which :func:`solve` calls first.
    """

    profile: object
    elasticity: ContactElasticity | None
    friction: float
    compliance_ratio: float
    normal: object
    tangential: object
    normal_control: str = "force"
    tangential_control: str = "force"
    protocol: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    steps_per_cycle: int = 400
    max_cycles: int = 5
    n_sliders: int = 2000
    assembly_steps: int = 100
    snapshots: np.ndarray = field(default_factory=lambda: np.array([0.0, np.pi / 2, np.pi]))
    steady_tol: float = 1e-9
    profile_name: str = ""
    surface: dict = field(default_factory=dict)

    def __post_init__(self):
        if not callable(getattr(self.profile, "approach", None)):
            raise InputError("profile", "must be a normal law P(U) (a slipcycle.halfspace "
                                        f"Profile), got {type(self.profile).__name__}")
        if self.elasticity is not None and not isinstance(self.elasticity, ContactElasticity):
            raise InputError("elasticity", "must be a ContactElasticity or None")
        _positive("friction", self.friction)
        _positive("compliance_ratio", self.compliance_ratio)
        for name in ("normal", "tangential"):
            if not callable(getattr(self, name)):
                raise InputError(name, "must be a periodic load (HarmonicLoad or "
                                       "TabulatedLoad; see contact_loads)")
        if self.normal_control not in ("force", "approach"):
            raise InputError("normal_control", "must be 'force' or 'approach', got "
                                               f"{self.normal_control!r}")
        if self.tangential_control not in ("force", "displacement"):
            raise InputError("tangential_control", "must be 'force' or 'displacement', "
                                                   f"got {self.tangential_control!r}")
        protocol = _finite_array("protocol", self.protocol)
        if protocol.size == 0:
            protocol = protocol.reshape(0, 2)
        if protocol.ndim != 2 or protocol.shape[1] != 2:
            raise InputError("protocol", "must be an (S, 2) array of (normal, tangential) "
                                         f"states, got shape {protocol.shape}")
        snaps = np.atleast_1d(_finite_array("snapshots", self.snapshots))
        if snaps.ndim != 1:
            raise InputError("snapshots", "must be cycle angles in [0, 2π] rad")
        _bound("snapshots", snaps, ">=", 0.0)
        _bound("snapshots", snaps, "<=", 2 * np.pi)
        for name, low in (("steps_per_cycle", 8), ("max_cycles", 1), ("n_sliders", 10),
                          ("assembly_steps", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise InputError(name, f"must be an integer >= {low}, got {value!r}")
            _bound(name, value, ">=", low)
        tol = self.steady_tol
        if isinstance(tol, bool) or not isinstance(tol, (int, float, np.integer, np.floating)) \
                or not np.isfinite(tol):
            raise InputError("steady_tol", f"must be in (0, 1), got {tol!r}")
        _bound("steady_tol", tol, ">", 0.0)
        _bound("steady_tol", tol, "<", 1.0)
        object.__setattr__(self, "protocol", protocol)
        object.__setattr__(self, "snapshots", snaps)

    def check_loads(self) -> None:
        """Refuse a load path the contact cannot carry.

        In force control the normal load must compress the contact somewhere and never
        become tensile (adhesion is not modelled); a rough (exponential) contact needs
        P > 0 throughout; a 2-D cylinder's reference depth and a tabulated law must cover
        the largest load.

        Returns
        -------
        None

        Raises
        ------
        LoadPathError
            An :class:`~slipcycle.errors.InputError` keyed ``normal`` (cycle),
            ``protocol[i]`` (assembly state i), ``profile.reference_depth`` (cylinder) or
            ``profile`` (table), with the ``reason`` of the failed check.
        """
        if self.normal_control != "force":
            return
        _, cycle_n, _ = self.cycle_samples()
        lo, hi = self.normal_load_range()
        if not np.isfinite(lo) or not np.isfinite(hi):
            raise LoadPathError("normal", "the normal load must be finite", "not_finite")
        if hi <= 0:
            raise LoadPathError("normal", "the normal load never compresses the contact",
                                "never_compressive")
        rough = isinstance(self.profile, RoughExponential)
        states = [("normal", float(cycle_n.min()))]
        states += [(f"protocol[{i}]", float(v)) for i, v in enumerate(self.protocol[:, 0])]
        for key, v in states:
            if rough and v <= 0:
                raise LoadPathError(key, "a rough contact needs P > 0 throughout the load "
                                         f"path (minimum {v:g} N)", "rough_unloaded")
            if v < 0:
                raise LoadPathError(key, f"normal load becomes tensile (minimum {v:g} N); "
                                         "adhesion is not modelled", "tensile")
        if isinstance(self.profile, Cylinder2D) and hi >= self.profile.max_load():
            raise LoadPathError("profile.reference_depth", "too shallow for the largest "
                                "load: the plane approach needs a < 2d/e", "reference_depth")
        if isinstance(self.profile, Tabulated) and hi > self.profile.P[-1] * (1 + 1e-12):
            raise LoadPathError("profile", f"table ends at {self.profile.P[-1]:g} N but the "
                                           f"loads reach {hi:g} N", "table_end")
        self._check_computable(hi)

    def _check_computable(self, P_max: float) -> None:
        """Refuse (key ``profile.size``) a profile whose contact under the largest load
        ``P_max`` double precision cannot compute: a radius of 1e-300 m overflowed the
        sphere's coefficient 1/(2R) and ended in an internal error."""
        P = np.array([P_max])
        with np.errstate(all="ignore"):
            values = [self.profile.approach(P), self.profile.compliance(P)]
            size = self.profile.contact_size(P)
        if size is not None:
            values.append(np.asarray(size, float))
        if all(np.all(np.isfinite(v) & (np.asarray(v) > 0)) for v in values):
            return
        raise LoadPathError("profile.size", "the contact under the largest load "
                            f"({P_max:.3g} N) is beyond what double precision computes "
                            "(approach, compliance and contact size must be finite and "
                            "> 0): check the size and units of the profile",
                            "not_computable")

    @classmethod
    def harmonic(cls, profile, friction: float, compliance_ratio: float, *, P0: float,
                 P1=0.0, Q0: float = 0.0, Q1=0.0, phase=0.0, P1_phase=0.0, lam: float = 1.0,
                 **settings) -> HalfspaceModel:
        """A model under P = P0 + λP1 cos(θ − P1_phase), Q = Q0 + λQ1 cos(θ − phase).

        Exactly the meaning of the case-file keys of the same names (see
        :func:`~slipcycle.halfspace.contact_loads`); ``settings`` are the other fields.
        """
        normal, tangential = contact_loads(P0, P1, Q0, Q1, phase, P1_phase, lam)
        settings.setdefault("elasticity", None)
        return cls(profile=profile, friction=friction, compliance_ratio=compliance_ratio,
                   normal=normal, tangential=tangential, **settings)

    def cycle_samples(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """θ_k = 2πk/S (k = 1..S) and the normal and tangential loads there."""
        theta = cycle_angles(self.steps_per_cycle)[1:]
        return theta, self.normal(theta)[:, 0], self.tangential(theta)[:, 0]

    def assembly_path(self, unloaded_normal: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Load states from the unloaded state through the protocol to θ = 0.

        ``unloaded_normal`` is the normal coordinate of the unloaded state: 0 in force
        control, the approach of first touch in approach control.
        """
        start = np.array([[self.normal(np.zeros(1))[0, 0], self.tangential(np.zeros(1))[0, 0]]])
        zero = np.array([[unloaded_normal, 0.0]])
        protocol = self.protocol
        if self.normal_control == "approach" and protocol.size == 0:
            # A straight line in (U, Q) would shear a barely loaded contact (P ∝ U^{3/2} for
            # a sphere) into gross slip: by default approach first, then shear.
            protocol = np.array([[start[0, 0], 0.0]])
        states = np.vstack([zero, protocol, start])
        path = piecewise_linear_path(states, self.assembly_steps)[1:]
        return path[:, 0], path[:, 1]

    def normal_load_range(self) -> tuple[float, float]:
        """(min, max) of the normal load over the cycle and the protocol (N)."""
        _, n, _ = self.cycle_samples()
        vals = np.concatenate([n, self.protocol[:, 0], self.normal(np.zeros(1))[:, 0]])
        return float(vals.min()), float(vals.max())

    def lumping_load(self) -> float:
        """Load below which no slider slips in this history (0: no bound; see bed.py).

        Derived from the loads the whole history reaches: the assembly states and the cycle
        (the path is linear between them, so its extremes are among them). The first leg
        from the unloaded state is proportional, Q/P constant, and slips nowhere while
        |Q| < fP (Ciavarella 1998; Jäger 1998), so its small loads do not count; the
        unloaded Q = 0 does. Under displacement control Q is not known beforehand, so
        there is no bound.
        """
        if self.tangential_control != "force":
            return 0.0
        an = np.concatenate([self.protocol[:, 0], self.normal(np.zeros(1))[:, 0]])
        at = np.concatenate([self.protocol[:, 1], self.tangential(np.zeros(1))[:, 0]])
        _, cn, ct = self.cycle_samples()
        n_all = np.concatenate([an, cn])
        if self.normal_control == "approach":
            P_lo = _load_from_approach(self.profile, float(n_all.min()))
            P_hi = _load_from_approach(self.profile, float(n_all.max()))
        else:
            P_lo, P_hi = float(n_all.min()), float(n_all.max())
        q_all = np.concatenate([at, ct, [0.0]])
        return float(lumping_load(P_lo, P_hi, float(q_all.min()), float(q_all.max()),
                                  self.friction))

    def has_first_touch(self) -> bool:
        """False for laws with contact at every approach (rough): their beds must lump."""
        return bool(np.isfinite(self.profile.approach(np.array([0.0]))[0]))

    def bed(self, lump: bool = True) -> SliderBed:
        """The slider bed covering every load level this history reaches.

        Profiles with a first touch get the default bed (exact from first touch, so that
        tractions resolve the whole contact), with cells of its own for a slip zone that
        would be thinner than a few cells (``P_slip`` of :func:`make_bed`). The rough law
        lumps the sliders below :meth:`lumping_load`, which never slip; with
        ``lump=False`` (or no bound) it lumps only below ``UNLUMPED_FRACTION`` of the
        largest load.
        """
        hi = self.normal_load_range()[1]
        if self.normal_control == "approach":   # the largest load, from the exact law
            hi = _load_from_approach(self.profile, hi)
        P_lo = P_slip = None
        if not self.has_first_touch():
            P_lo = self.lumping_load() if lump else 0.0
        else:   # a slip zone thinner than a few cells gets cells of its own
            P_slip = self.lumping_load() or None
        return make_bed(self.profile, friction=self.friction,
                        compliance_ratio=self.compliance_ratio, P_max=hi * (1 + 1e-9),
                        n_sliders=self.n_sliders, P_lo=P_lo, P_slip=P_slip)


def _positive(name: str, value) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not np.isfinite(value):
        raise InputError(name, f"must be a finite number > 0, got {value!r}")
    _bound(name, value, ">", 0.0)


_HOLDS = {">": np.greater, ">=": np.greater_equal, "<": np.less, "<=": np.less_equal}


def _bound(name: str, value, sym: str, bound: float) -> None:
    """Refuse the first entry of ``value`` not ``sym bound`` ("must be > 0, got -1")."""
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    bad = ~_HOLDS[sym](arr, bound)
    if np.any(bad):
        raise InputError(name, f"must be {sym} {bound:g}, got {arr[bad][0]:g}")


def _finite_array(name: str, value) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, "must be an array of numbers") from None
    if not np.all(np.isfinite(arr)):
        raise InputError(name, "must contain only finite numbers")
    return arr


def _load_from_approach(profile, U: float) -> float:
    from scipy.optimize import brentq

    hi = 1.0
    while profile.approach(np.array([hi]))[0] < U:
        hi *= 2.0
    return float(brentq(lambda P: profile.approach(np.array([P]))[0] - U, 0.0, hi, xtol=1e-14))


def solve(model: HalfspaceModel, *, record_last_cycle: bool = True
          ) -> tuple[SliderBed, HistoryResult]:
    """Build the slider bed and run the assembly and cycles to a steady state.

    The contact is a bed of independent Coulomb sliders (the Ciavarella–Jäger
    superposition of Cattaneo–Mindlin solutions: C. Cattaneo 1938, R. D. Mindlin 1949,
    M. Ciavarella, Int. J. Solids Struct. 35 (1998) 2349–2362, J. Jäger, Wear 220 (1998)
    1–8), driven exactly along the piecewise-linear load path.

    Parameters
    ----------
    model : HalfspaceModel
        The validated contact and its loads; its load path is checked first
        (:meth:`HalfspaceModel.check_loads`).
    record_last_cycle : bool, optional
        Keep every slider's force and slip over the last cycle (needed for tractions).

    Returns
    -------
    bed : SliderBed
        The sliders (levels, stiffnesses, capacities) the history ran on.
    result : HistoryResult
        Load path, U, V, P, Q per step (m, m, N, N), dissipation per cycle (J),
        steady-state flag and gross-slip detection.

    Raises
    ------
    slipcycle.errors.InputError
        A load path the contact cannot carry.
    """
    model.check_loads()
    bed = model.bed()
    slope = slope_warning(model.profile, float(bed.edge_load[-1]))
    if slope:
        log.warning("halfspace: %s", slope)
    result = _run(model, bed, record_last_cycle)
    if not model.has_first_touch() and bed.size > 1 and bed.level[0] < bed.level[1] \
            and lumped_slider_slipped(result.first_slip) and model.lumping_load() > 0:
        # slip reached the lumped loads (the bound was not enough): lump (almost) nothing
        bed = model.bed(lump=False)
        result = _run(model, bed, record_last_cycle)
    return bed, result


def _run(model: HalfspaceModel, bed: SliderBed, record_last_cycle: bool) -> HistoryResult:
    an, at = model.assembly_path(bed.level[0] if model.normal_control == "approach" else 0.0)
    _, cn, ct = model.cycle_samples()
    return run_history(bed, an, at, cn, ct, normal_control=model.normal_control,
                       tangential_control=model.tangential_control,
                       max_cycles=model.max_cycles, steady_tol=model.steady_tol,
                       record_last_cycle=record_last_cycle, unloaded_approach=bed.level[0])
