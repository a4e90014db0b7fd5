"""A validated half-space contact problem and its load path."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from slipcycle.halfspace.bed import SliderBed, lumped_slider_slipped, lumping_load, make_bed
from slipcycle.halfspace.elastic import ContactElasticity
from slipcycle.halfspace.history import HistoryResult, run_history
from slipcycle.loading import cycle_angles, piecewise_linear_path

__all__ = ["HalfspaceModel", "solve"]


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

    @classmethod
    def harmonic(cls, profile, friction: float, compliance_ratio: float, *, P0: float,
                 P1=0.0, Q0: float = 0.0, Q1=0.0, phase=0.0, P1_phase=0.0, lam: float = 1.0,
                 **settings) -> HalfspaceModel:
        """A model under P = P0 + λP1 cos(θ − P1_phase), Q = Q0 + λQ1 cos(θ − phase).

        Exactly the meaning of the case-file keys of the same names (see
        :func:`~slipcycle.halfspace.contact_loads`); ``settings`` are the other fields.
        """
        from slipcycle.halfspace.loads import contact_loads

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
        tractions resolve the whole contact). The rough law lumps the sliders below
        :meth:`lumping_load`, which never slip; with ``lump=False`` (or no bound) it lumps
        only below ``UNLUMPED_FRACTION`` of the largest load.
        """
        hi = self.normal_load_range()[1]
        if self.normal_control == "approach":   # the largest load, from the exact law
            hi = _load_from_approach(self.profile, hi)
        P_lo = None
        if not self.has_first_touch():
            P_lo = self.lumping_load() if lump else 0.0
        return make_bed(self.profile, friction=self.friction,
                        compliance_ratio=self.compliance_ratio, P_max=hi * (1 + 1e-9),
                        n_sliders=self.n_sliders, P_lo=P_lo)


def _load_from_approach(profile, U: float) -> float:
    from scipy.optimize import brentq

    hi = 1.0
    while profile.approach(np.array([hi]))[0] < U:
        hi *= 2.0
    return float(brentq(lambda P: profile.approach(np.array([P]))[0] - U, 0.0, hi, xtol=1e-14))


def solve(model: HalfspaceModel, *, record_last_cycle: bool = True
          ) -> tuple[SliderBed, HistoryResult]:
    """Build the slider bed and run the assembly and cycles to a steady state."""
    bed = model.bed()
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
