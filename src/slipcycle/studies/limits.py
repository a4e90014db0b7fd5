"""``slipcycle limits``: the limit frequency of the quasi-static analysis of two rods and
its regime maps, as a study (the ``[limits]`` table, summary, Dataset and figures).

The analysis itself — every point computed exactly as ``slipcycle run`` computes its one
point, the first crossing of the tolerance located by bisection in log Ω, poles of the
undamped welded system flagged — is :mod:`slipcycle.rods.limits`
(:func:`~slipcycle.rods.limits.limit_frequency`, :func:`~slipcycle.rods.limits.regime_map`,
:func:`~slipcycle.rods.limits.position_map`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from slipcycle.figure_task import figure_task
from slipcycle.io import CaseError
from slipcycle.io.results import RunOutputs
from slipcycle.io.sizes import check_memory
from slipcycle.result import StudyResult
from slipcycle.rods.case import parse_case
from slipcycle.rods.limits import limit_frequency, make_study, position_map, regime_map

__all__ = ["LimitsCase", "parse_limits", "run_limits", "limits_study", "LimitsResult",
           "LIMITS_UNITS", "LIMITS_FLAGS"]

#: bytes per map point kept until the figures are written (arrays, Dataset, figure mesh)
_MAP_POINT_BYTES = 400.0


@dataclass
class LimitsCase:
    """A validated limits case: the rods case and the axes of the sweeps."""

    rc: object  # slipcycle.rods.case.RodsCase
    tolerance: float
    ratios: np.ndarray
    amplitude_ratios: np.ndarray
    positions: np.ndarray
    position_frequencies: int


def _axis(sec, key, default, **bounds):
    """A grid axis, sorted increasing whatever the order given (a list, or a table whose
    ``start`` exceeds its ``stop``), so that the first crossing of the tolerance is always
    searched from the low end of the range.

    Raises
    ------
    CaseError
        Naming the key, for an empty list (:meth:`~slipcycle.io.case.Section.grid`) or
        a value given twice (a repeated point would be computed twice and makes the
        bisection between neighbours void).
    """
    vals = np.sort(sec.grid(key, default, max_num=10000, **bounds))
    same = np.flatnonzero(np.diff(vals) <= 0.0)
    if same.size:
        raise sec.error(key, f"holds the value {vals[same[0]]:g} more than once; "
                        "give distinct values")
    return vals


def parse_limits(case, tolerance: float, maps: bool = True) -> LimitsCase:
    """Validate a limits case completely: ``[limits]`` with the same :class:`Section` rules
    as every table (unknown keys with a suggestion, types, bounds, sizes refused with their
    estimated memory), then the rods case (:func:`slipcycle.rods.case.parse_case`).

    ``[limits]`` keys: ``frequency_ratio`` (Ω/ω1 axis, list or ``{start, stop, num}``
    geometric; default 0.01…3 × 40), ``amplitude_ratio`` (Θa/Θg, geometric; 0.3…3 × 20),
    ``position`` (L1/(L1 + L2), linear; 0.1…0.9 × 9), ``position_frequencies`` (20).
    """
    if not (0.0 < tolerance < 1.0):
        raise CaseError("--tolerance", f"must be in (0, 1), got {tolerance:g}")
    load = case.data.get("loading")
    if isinstance(load, dict) and "frequency_ratio" not in load and "frequency" not in load:
        load["frequency_ratio"] = 1.0  # the sweep sets the frequency
    sec = case.section("limits", required=False)
    ratios = _axis(sec, "frequency_ratio", {"start": 0.01, "stop": 3.0, "num": 40},
                   gt=0.0, le=1e3, geometric=True)
    amps = _axis(sec, "amplitude_ratio", {"start": 0.3, "stop": 3.0, "num": 20},
                 gt=0.0, le=1e4, geometric=True)
    pos = _axis(sec, "position", {"start": 0.1, "stop": 0.9, "num": 9}, gt=0.0, le=0.999)
    npf = sec.int("position_frequencies", 20, ge=2, le=10000)
    if maps:
        for key, size in (("amplitude_ratio", ratios.size * amps.size),
                          ("position", pos.size * npf)):
            check_memory(sec.key(key), size * _MAP_POINT_BYTES, f"a map of {size:.3g} points")
    rc = parse_case(case, limits=True)
    return LimitsCase(rc, tolerance, ratios, amps, pos, npf)


#: unit of every numeric entry of the limits summary
LIMITS_UNITS = {
    "tolerance": "1", "omega1": "rad/s", "rotation_amplitude": "rad",
    "qs_limit_frequency_ratio": "1", "qs_limit_frequency": "rad/s",
    "qs_limit_frequency_ratio_dissipation": "1", "poles_frequency_ratio": "1",
    "sweep_points_not_converged": "1", "sweep_points_at_pole": "1",
    "wall_time_sweep_s": "s", "map_shape": "1", "map_points_not_converged": "1",
    "position_map_points_not_converged": "1", "wall_time_map_s": "s",
    "wall_time_position_map_s": "s", "theta_gross": "rad",
    "resonances_frequency_ratio": "1", "position_omega1": "rad/s",
    "iwan.F_S": "N m", "iwan.K_T": "N m/rad", "iwan.chi": "1", "iwan.beta": "1",
    "iwan.elements": "1",
}

#: every word of the categorical entries of the limits summary
LIMITS_FLAGS = {
    "model": ("rods",),
    "analysis": ("limits",),
    "interface": ("welded", "distributed", "coulomb", "jenkins", "iwan"),
    "qs_limit_frequency_ratio_status": ("found", "below_range", "above_range",
                                        "not_converged"),
    "qs_limit_frequency_ratio_dissipation_status": ("found", "below_range", "above_range",
                                                    "not_converged", "no_dissipation"),
}


def run_limits(lc: LimitsCase, maps: bool = True, progress: bool = False) -> RunOutputs:
    """What ``slipcycle limits`` writes: ``limits_study(lc, maps, progress).to_outputs()``.

    Parameters
    ----------
    lc, maps, progress
        See :func:`limits_study`.

    Returns
    -------
    RunOutputs
    """
    return limits_study(lc, maps=maps, progress=progress).to_outputs()


def limits_study(lc: LimitsCase, maps: bool = True, progress: bool = False) -> LimitsResult:
    """Limit frequency of the quasi-static analysis (and the regime maps) of a limits case.

    Parameters
    ----------
    lc : LimitsCase
        A validated limits case (:func:`parse_limits`).
    maps : bool
        Also compute the regime map (Ω/ω1 × Θa/Θg) and the position map
        (L1/(L1 + L2) × Ω/ω1).
    progress : bool
        Show progress bars.

    Returns
    -------
    LimitsResult
        Its ``to_outputs()`` is what ``slipcycle limits`` writes.
    """
    import time

    study, iw = make_study(lc.rc)
    t0 = time.perf_counter()
    lim = limit_frequency(study, lc.tolerance, lc.ratios, progress=progress)
    t1 = time.perf_counter()
    m = pm = None
    t2 = t3 = t1
    if maps:
        m = regime_map(study, lc.ratios, lc.amplitude_ratios, progress=progress)
        t2 = time.perf_counter()
        pr = np.geomspace(lc.ratios.min(), lc.ratios.max(), lc.position_frequencies)
        pm = position_map(study, lc.positions, pr, progress=progress)
        t3 = time.perf_counter()
    return LimitsResult(
        wall_time_s=t3 - t0, tolerance=lc.tolerance, interface=lc.rc.rods.interface,
        omega1=study.omega1, rotation_amplitude=lc.rc.exc.rotation_amplitude, sweep=lim,
        iwan=None if iw is None else {"F_S": iw.F_S, "K_T": iw.K_T, "chi": iw.chi,
                                      "beta": iw.beta, "elements": study.bed.size},
        wall_time_sweep_s=t1 - t0, regime=m, positions=pm, wall_time_map_s=t2 - t1,
        wall_time_position_map_s=t3 - t2)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class LimitsResult(StudyResult):
    """Limit frequency of the quasi-static analysis and regime maps (``slipcycle limits``).

    Attributes
    ----------
    wall_time_s : float
        Wall time of the sweep and the maps [s].
    tolerance : float
        Relative tolerance ε on T_dyn/T_qs and D_dyn/D_qs [1].
    interface : str
        Interface law of the case.
    omega1 : float
        First natural frequency ω1 of the stuck system [rad/s].
    rotation_amplitude : float
        Drive amplitude Θa of the case [rad].
    sweep : dict
        :func:`limit_frequency` at the case amplitude (arrays over Ω/ω1, the limits and
        their status).
    iwan : dict or None
        Iwan parameters used (F_S [N m], K_T [N m/rad], chi, beta, elements).
    wall_time_sweep_s : float
        Wall time of the frequency sweep [s].
    regime, positions : dict or None
        :func:`regime_map` and :func:`position_map` (None without maps).
    wall_time_map_s, wall_time_position_map_s : float
        Wall times of the two maps [s] (0 without maps).
    """

    model: ClassVar[str] = "rods"
    analysis: ClassVar[str] = "limits"
    FLAGS: ClassVar[dict] = LIMITS_FLAGS

    tolerance: float
    interface: str
    omega1: float
    rotation_amplitude: float
    sweep: dict
    iwan: dict | None
    wall_time_sweep_s: float
    regime: dict | None = None
    positions: dict | None = None
    wall_time_map_s: float = 0.0
    wall_time_position_map_s: float = 0.0

    @property
    def qs_limit_frequency_ratio(self) -> float:
        """Ω/ω1 below which |T_dyn/T_qs − 1| ≤ ε (see its ``_status``) [1]."""
        return self.sweep["qs_limit_frequency_ratio"]

    def headline(self) -> list[tuple]:
        """ω1, the two limit frequency ratios with their status, and the wall time."""
        lim = self.sweep
        return [("omega1", self.omega1, "rad/s"),
                ("qs_limit_frequency_ratio", lim["qs_limit_frequency_ratio"], "1"),
                ("status", lim["qs_limit_frequency_ratio_status"], ""),
                ("qs_limit_frequency_ratio_dissipation",
                 lim["qs_limit_frequency_ratio_dissipation"], "1"),
                ("status_dissipation", lim["qs_limit_frequency_ratio_dissipation_status"], ""),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """``summary.json`` of ``slipcycle limits`` (units: :data:`LIMITS_UNITS`).

        Returns
        -------
        dict
            ``omega1`` [rad/s], ``qs_limit_frequency_ratio`` and its status,
            ``qs_limit_frequency`` [rad/s], the same for the dissipation, poles, points
            not converged, wall times [s], ``iwan``, with maps their shapes, points not
            converged, ``theta_gross`` [rad], resonances and ``position_omega1`` [rad/s];
            ``units``.
        """
        lim = self.sweep
        summary = {
            "model": "rods",
            "analysis": "limits",
            "tolerance": self.tolerance,
            "interface": self.interface,
            "omega1": self.omega1,
            "rotation_amplitude": self.rotation_amplitude,
            "qs_limit_frequency_ratio": lim["qs_limit_frequency_ratio"],
            "qs_limit_frequency_ratio_status": lim["qs_limit_frequency_ratio_status"],
            "qs_limit_frequency": lim["qs_limit_frequency_ratio"] * self.omega1,
            "qs_limit_frequency_ratio_dissipation":
                lim["qs_limit_frequency_ratio_dissipation"],
            "qs_limit_frequency_ratio_dissipation_status":
                lim["qs_limit_frequency_ratio_dissipation_status"],
            "poles_frequency_ratio": lim["poles"],
            "dissipation_per_cycle": None,
            "sweep_points_not_converged": int(np.sum(~lim["converged"] & ~lim["pole"])),
            "sweep_points_at_pole": int(np.sum(lim["pole"])),
            "wall_time_sweep_s": self.wall_time_sweep_s,
        }
        if self.iwan is not None:
            summary["iwan"] = dict(self.iwan)
        m, pm = self.regime, self.positions
        if m is not None:
            summary.update({
                "map_shape": list(m["torque_ratio"].shape),
                "map_points_not_converged": int(np.sum(~m["converged"])),
                "position_map_points_not_converged": int(np.sum(~pm["converged"])),
                "wall_time_map_s": self.wall_time_map_s,
                "wall_time_position_map_s": self.wall_time_position_map_s,
                "theta_gross": m["theta_gross"],
                "resonances_frequency_ratio": m["resonances"],
                "position_omega1": pm["omega1"],
            })
        summary["units"] = {k: v for k, v in LIMITS_UNITS.items()
                            if k.split(".")[0] in summary}
        return summary

    def _build_dataset(self):
        """Ratios, maximum torques [N m], dissipation [J], ``converged`` and ``pole`` over
        Ω/ω1; with maps, the ratios and ``converged`` over (map_frequency_ratio,
        amplitude_ratio) and (position, position_frequency_ratio).

        The only place the Dataset of a limits study is built.

        Returns
        -------
        xarray.Dataset
        """
        import xarray as xr

        lim, one, fdim = self.sweep, {"units": "1"}, "frequency_ratio"
        ds = xr.Dataset(
            {"torque_ratio": (fdim, lim["torque_ratio"], one),
             "dissipation_ratio": (fdim, lim["dissipation_ratio"], one),
             "T_dyn_max": (fdim, lim["T_dyn"], {"units": "N m"}),
             "T_qs_max": (fdim, lim["T_qs"], {"units": "N m"}),
             "dissipation_per_cycle": (fdim, lim["D_dyn"], {"units": "J"}),
             "dissipation_per_cycle_qs": (fdim, lim["D_qs"], {"units": "J"}),
             "converged": (fdim, lim["converged"], one),
             "pole": (fdim, lim["pole"], one)},
            coords={fdim: (fdim, lim["ratios"], one)})
        m, pm = self.regime, self.positions
        if m is None:
            return ds
        ds = ds.assign_coords(
            map_frequency_ratio=("map_frequency_ratio", m["ratios"], one),
            amplitude_ratio=("amplitude_ratio", m["amplitude_factors"], one),
            position=("position", pm["fractions"], one),
            position_frequency_ratio=("position_frequency_ratio", pm["ratios"], one))
        dims = ("map_frequency_ratio", "amplitude_ratio")
        ds["map_torque_ratio"] = (dims, m["torque_ratio"], one)
        ds["map_dissipation_ratio"] = (dims, m["dissipation_ratio"], one)
        ds["map_converged"] = (dims, m["converged"], one)
        pd = ("position", "position_frequency_ratio")
        ds["position_torque_ratio"] = (pd, pm["torque_ratio"], one)
        ds["position_dissipation_ratio"] = (pd, pm["dissipation_ratio"], one)
        ds["position_converged"] = (pd, pm["converged"], one)
        return ds

    def figures(self, dataset=None) -> dict:
        """``limit_frequency`` and, with maps, ``regime_map`` and ``position_map``.

        Returns
        -------
        dict of str to callable
        """
        tol = self.tolerance
        figures = {"limit_frequency": figure_task("slipcycle.plot.rods:limit_curve",
                                                  self.sweep, tol)}
        if self.regime is not None:
            figures["regime_map"] = figure_task("slipcycle.plot.rods:regime_map",
                                                self.regime, tol)
            figures["position_map"] = figure_task("slipcycle.plot.rods:position_map",
                                                  self.positions, tol)
        return figures
