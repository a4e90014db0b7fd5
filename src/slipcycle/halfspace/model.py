"""A validated half-space contact problem and its load path."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from slipcycle.halfspace.bed import SliderBed, make_bed
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
        One-component periodic loads: P (N) or U (m); Q (N) or V (m).
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

    def bed(self) -> SliderBed:
        """The slider bed covering this history's loads."""
        lo, hi = self.normal_load_range()
        if self.normal_control == "approach":
            # convert approach range to loads with the exact profile law
            lo, hi = _load_from_approach(self.profile, lo), _load_from_approach(self.profile, hi)
        P_lo = None
        if not np.isfinite(self.profile.approach(np.array([0.0]))[0]):
            P_lo = 0.5 * lo  # profiles with no first touch (rough): lump below half the minimum
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
    an, at = model.assembly_path(bed.level[0] if model.normal_control == "approach" else 0.0)
    _, cn, ct = model.cycle_samples()
    result = run_history(bed, an, at, cn, ct, normal_control=model.normal_control,
                         tangential_control=model.tangential_control,
                         max_cycles=model.max_cycles, steady_tol=model.steady_tol,
                         record_last_cycle=record_last_cycle)
    return bed, result
