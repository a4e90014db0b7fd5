"""Regularisation study: dissipation per cycle versus amplitude, per model.

The quasi-static loop of each interface model (distributed, jenkins, coulomb, fitted iwan) is
computed over drive amplitudes Θ_a from well inside stick to far into gross slip. Two
log–log slopes are reported per model:

``slope_microslip``
    d log D / d log T* over the points with D > 0 and T* < 0.95 T_g (T* the torque
    amplitude, T_g the gross-slip torque): the partial-slip law. Segalman's Iwan element
    gives ≈ 3 + χ at small amplitude; the rings, whose first slip threshold is finite
    (the rim at T_s = 3/4 T_g), give D ∝ (T* − T_s)² — a local slope that starts infinite
    and has no power law; Jenkins and Coulomb dissipate nothing below gross slip (None).
``slope_macroslip``
    d log D / d log Θ_a over the largest amplitudes (gross slip): → 1 for every model,
    since D ≈ 4 T_g Θ_a once the interface slides.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from slipcycle.figure_task import figure_task
from slipcycle.result import StudyResult
from slipcycle.rods.interfaces import Bed, Iwan, SegalmanIwan, gross_slip_torque, interface_law
from slipcycle.rods.model import Excitation, TwoRods
from slipcycle.rods.quasistatic import quasi_static_loop

__all__ = ["regularisation_study", "RegularisationResult", "REG_MODELS", "REG_UNITS"]

REG_MODELS = ("distributed", "jenkins", "coulomb", "iwan")

#: unit of every numeric entry of :meth:`RegularisationResult.summary` (nested dotted)
REG_UNITS = {
    "gross_slip_torque": "N m", "theta_gross": "rad", "points": "1", "wall_time_s": "s",
    **{f"{m}.{k}": "1" for m in REG_MODELS for k in ("slope_microslip", "slope_macroslip")},
    **{f"first_slip_torque.{m}": "N m" for m in REG_MODELS},
    "iwan_fit.F_S": "N m", "iwan_fit.K_T": "N m/rad", "iwan_fit.chi": "1",
    "iwan_fit.beta": "1",
}

_KEYS = ("amplitude", "gross_slip_torque", "iwan_params", *REG_MODELS, "theta_gross",
         "first_slip_torque", "_beds")


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class RegularisationResult(StudyResult, Mapping):
    """Dissipation per cycle versus amplitude of the four interface models.

    Returned by :func:`regularisation_study`. Besides the analysis contract
    (:meth:`summary`, :meth:`to_dataset`, :meth:`figures`, one-line ``repr``, HTML table)
    it is a read-only mapping with the keys ``amplitude``, ``gross_slip_torque``,
    ``iwan_params``, ``distributed``, ``jenkins``, ``coulomb``, ``iwan``, ``theta_gross``,
    ``first_slip_torque`` and ``_beds`` (see :func:`regularisation_study`).

    Attributes
    ----------
    wall_time_s : float
        Wall time of the study [s].
    amplitude : numpy.ndarray, shape (n,)
        Drive amplitudes Θ_a [rad], ascending.
    gross_slip_torque : float
        T_g = (2/3) f F0 a [N m].
    theta_gross : float
        Θ_g, the amplitude at which the stuck interface carries T_g [rad].
    iwan_params : dict
        ``F_S`` [N m], ``K_T`` [N m/rad], ``chi`` [1], ``beta`` [1] of the Iwan model used.
    models : dict
        Per model of :data:`REG_MODELS`: ``T_amp`` (n,) [N m], ``dissipation`` (n,) [J],
        ``slope_microslip``, ``slope_macroslip`` [1] (float or None).
    first_slip_torque : dict
        Per model, the torque at which its first element slips at F0 [N m].
    beds : dict
        Per model, the :class:`~slipcycle.rods.interfaces.Bed` used.
    """

    model: ClassVar[str] = "rods"
    analysis: ClassVar[str] = "regularisation"
    FLAGS: ClassVar[dict[str, tuple[str, ...]]] = {"model": ("rods",),
                                                   "analysis": ("regularisation",)}

    amplitude: np.ndarray
    gross_slip_torque: float
    theta_gross: float
    iwan_params: dict
    models: dict
    first_slip_torque: dict = field(default_factory=dict)
    beds: dict = field(default_factory=dict)

    # -- mapping interface (the dictionary this study used to return) ----------------------
    def __getitem__(self, key: str) -> Any:
        if key in REG_MODELS:
            return self.models[key]
        if key == "_beds":
            return self.beds
        if key in _KEYS:
            return getattr(self, key)
        raise KeyError(key)

    def __iter__(self) -> Iterator[str]:
        return iter(_KEYS)

    def __len__(self) -> int:
        return len(_KEYS)

    # -- contract -----------------------------------------------------------------------
    def slopes(self) -> dict:
        """Per model, ``slope_microslip`` and ``slope_macroslip`` [1] (float or None)."""
        return {m: {"slope_microslip": self.models[m]["slope_microslip"],
                    "slope_macroslip": self.models[m]["slope_macroslip"]}
                for m in REG_MODELS}

    def headline(self) -> list[tuple[str, Any, str]]:
        """T_g, Θ_g, the microslip slopes of the rings and the Iwan model, the wall time."""
        return [("gross_slip_torque", self.gross_slip_torque, "N m"),
                ("theta_gross", self.theta_gross, "rad"),
                ("points", int(np.asarray(self.amplitude).size), "1"),
                ("slope_microslip_distributed",
                 self.models["distributed"]["slope_microslip"], "1"),
                ("slope_microslip_iwan", self.models["iwan"]["slope_microslip"], "1"),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """The study's numbers with ``units`` (:data:`REG_UNITS`).

        Returns
        -------
        dict
            ``model``, ``analysis``, ``gross_slip_torque`` [N m], ``theta_gross`` [rad],
            ``points``, the slopes per model [1] (as in the ``regularisation`` entry of
            the rods ``slipcycle run`` summary), ``iwan_fit``, ``first_slip_torque``
            [N m], ``wall_time_s`` [s], ``units``.
        """
        out: dict = {"model": "rods", "analysis": "regularisation",
                     "gross_slip_torque": float(self.gross_slip_torque),
                     "theta_gross": float(self.theta_gross),
                     "points": int(np.asarray(self.amplitude).size)}
        out.update(self.slopes())
        out["iwan_fit"] = dict(self.iwan_params)
        out["first_slip_torque"] = {k: (float(v) if math.isfinite(v) else None)
                                    for k, v in self.first_slip_torque.items()}
        out["wall_time_s"] = float(self.wall_time_s)
        out["units"] = {k: u for k, u in REG_UNITS.items() if k.split(".")[0] in out}
        return out

    def _build_dataset(self):
        """The amplitude sweep (dimension ``amplitude`` [rad]): ``reg_T_<model>`` [N m] and
        ``reg_D_<model>`` [J] per model, the variables of the rods run Dataset."""
        import xarray as xr

        ds = xr.Dataset(coords={"amplitude": ("amplitude", np.asarray(self.amplitude),
                                              {"units": "rad"})})
        for m in REG_MODELS:
            ds[f"reg_T_{m}"] = ("amplitude", self.models[m]["T_amp"], {"units": "N m"})
            ds[f"reg_D_{m}"] = ("amplitude", self.models[m]["dissipation"], {"units": "J"})
        ds.attrs.update(gross_slip_torque=float(self.gross_slip_torque),
                        theta_gross=float(self.theta_gross))
        return ds

    def figures(self, dataset=None) -> dict:
        """``regularisation``: dissipation versus T*/T_g and Θ_a/Θ_g, log–log."""
        return {"regularisation": figure_task("slipcycle.plot.rods:regularisation", self)}


def _slope(x, y):
    if x.size < 2:
        return None
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def regularisation_study(rods: TwoRods, exc: Excitation, rings: int = 100,
                         iwan: SegalmanIwan | None = None, points: int = 25,
                         steps_per_cycle: int = 400) -> RegularisationResult:
    """Quasi-static dissipation per cycle versus amplitude for the four interface models.

    Amplitudes are Θ_a = s Θ_g with s ∈ [0.03, 30] (geometric, plus 8 points in the
    rings' microslip range 0.77–0.99) and Θ_g = T_g (C_r + 1/k_t J_a)
    the amplitude at which a stuck interface would carry the gross-slip torque T_g.
    Each point is a :func:`~slipcycle.rods.quasistatic.quasi_static_loop` at constant
    normal force F0 (the axial amplitude is set to 0). The slopes are least-squares
    log–log fits (module docstring): ``slope_microslip`` of D against T* over the points
    with D > 1e-9 max D and T* < 0.95 T_g, ``slope_macroslip`` of D against Θ_a over the
    five largest amplitudes.

    Parameters
    ----------
    rods : TwoRods
        Friction f, contact radius a (m), rods' compliance C_r (rad/(N m)) and a finite
        tangential interface stiffness k_t (N/m³; :func:`slipcycle.rods.case.parse_case`
        switches the study off without one); all four models are built from them,
        whatever ``rods.interface`` is.
    exc : Excitation
        Its mean axial force F0 (N) is the normal force; Θ_a is swept and F_a set to 0; Ω
        (rad/s) only sets the time axis.
    rings : int
        Rings of the ``distributed`` model (≥ 1).
    iwan : SegalmanIwan, optional
        The ``iwan`` model; None: fitted to the rings at F0 (:func:`slipcycle.rods.
        interfaces.fit_iwan`).
    points : int
        Geometric amplitudes s ∈ [0.03, 30]; with the 8 microslip points the study has
        n ≤ ``points`` + 8 distinct amplitudes.
    steps_per_cycle : int
        K, steps per period of each quasi-static loop.

    Returns
    -------
    RegularisationResult
        The analysis result; also a read-only mapping with the keys:

        ``amplitude`` : (n,) ndarray
            Drive amplitudes Θ_a (rad), ascending.
        ``gross_slip_torque`` : float
            T_g = (2/3) f F0 a (N m).
        ``theta_gross`` : float
            Θ_g (rad).
        ``iwan_params`` : dict
            ``F_S`` (N m), ``K_T`` (N m/rad), ``chi``, ``beta`` of the Iwan model used.
        ``distributed``, ``jenkins``, ``coulomb``, ``iwan`` : dict
            Per model: ``T_amp`` (n,) torque amplitudes max|T| (N m), ``dissipation`` (n,)
            per cycle (J, ≥ 0), ``slope_microslip`` and ``slope_macroslip`` (float, or None
            where fewer than two points qualify or some macroslip point does not dissipate).
        ``first_slip_torque`` : dict
            Per model, the torque at which its first element slips at F0 (N m).
        ``_beds`` : dict
            Per model, the :class:`~slipcycle.rods.interfaces.Bed` used (internal).

    References
    ----------
    Segalman, D. J. (2005). A four-parameter Iwan model for lap-type joints. J. Appl. Mech.
    72, 752–760 (D ∝ T*^(3+χ)). Iwan, W. D. (1966). J. Appl. Mech. 33, 893–900. Johnson,
    K. L. (1985). Contact Mechanics, §7.3 (the rings; slip inception at the rim).
    """
    t0 = time.perf_counter()
    N0 = exc.axial_force
    Tg = gross_slip_torque(rods.friction, N0, rods.contact_radius)
    k0 = rods.interface_stiffness * rods.contact_J
    theta_g = Tg * (rods.rods_compliance + 1.0 / k0)
    amps = theta_g * np.unique(np.concatenate([np.geomspace(0.03, 30.0, points),
                                               np.linspace(0.77, 0.99, 8)]))
    points = amps.size
    laws = {name: interface_law(name, rings=rings, iwan=iwan) for name in REG_MODELS}
    laws[Iwan.name] = iwan_law = laws[Iwan.name].fitted(rods, N0)  # fit once, report it
    beds: dict[str, Bed] = {name: law.bed(rods, N0) for name, law in laws.items()}
    iw = iwan_law.params
    iwan_params = {"F_S": iw.F_S, "K_T": iw.K_T, "chi": iw.chi, "beta": iw.beta}
    models: dict = {}
    for name in REG_MODELS:
        T = np.empty(points)
        D = np.empty(points)
        for i, a in enumerate(amps):
            res = quasi_static_loop(rods, exc.with_(rotation_amplitude=float(a),
                                                    axial_amplitude=0.0), beds[name],
                                    steps_per_cycle)
            T[i], D[i] = res.T_max, max(res.dissipation, 0.0)
        floor = 1e-9 * max(float(D.max()), 1e-300)
        micro = (D > floor) & (T < 0.95 * Tg)
        macro = np.arange(points) >= points - 5
        models[name] = {"T_amp": T, "dissipation": D,
                     "slope_microslip": _slope(T[micro], D[micro]) if micro.sum() >= 2
                     else None,
                     "slope_macroslip": _slope(amps[macro], D[macro])
                     if np.all(D[macro] > 0) else None}
    if not math.isfinite(theta_g):  # pragma: no cover - guarded by validation
        raise ValueError("interface_stiffness: must be finite for the regularisation study")
    return RegularisationResult(
        wall_time_s=time.perf_counter() - t0, amplitude=amps, gross_slip_torque=Tg,
        theta_gross=theta_g, iwan_params=iwan_params, models=models,
        first_slip_torque={k: b.first_slip_torque(N0) for k, b in beds.items()}, beds=beds)
