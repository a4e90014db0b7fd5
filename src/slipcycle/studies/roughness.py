"""Rough interfaces from topography: which wavelengths matter (``slipcycle roughness``).

Barber (2012, §4.6) argues that every engineering contact is incomplete because of
roughness, that the incremental normal stiffness of a rough interface is roughly
proportional to the load (dP/dU = P/(γσ)), that the dissipation per unit area can be
estimated by applying the rough-surface result locally to the nominal traction cycle of the
smooth problem, and that "only the long wavelength terms in the surface profile spectrum"
matter. This study puts those claims to a quantitative test for one surface and one load
cycle:

1. the BEM normal law P(U) of the surface (:mod:`~slipcycle.halfspace.topography`), the
   fitted γσ and the load window where the exponential law holds;
2. the dissipation per cycle W (∮Q dV of the Ciavarella–Jäger slider bed, Ciavarella 1998;
   Jäger 1998) of the rough joint, per unit nominal area, and its phase dependence;
   convergence in the BEM grid and in the slider count;
3. W and the incremental stiffness dP/dU at the mean load after removing wavelengths
   below λ_s (and, separately, above λ_l): the largest λ_s (smallest λ_l) that changes
   them by less than the tolerance (5 %);
4. the local fretting map of a nominally flat joint: a rigid flat circular punch of the
   nominal area, whose smooth (Boussinesq–Mindlin) solution sticks completely, with the
   rough law applied to every ring's own traction cycle (:func:`local_dissipation`).

The case is a ``model = "halfspace"`` case with ``profile = "topography"`` and a
``[roughness]`` table: ``short_cutoffs``, ``long_cutoffs`` (lists of wavelengths, m),
``phases`` (list or ``{start, stop, num}``, rad), ``grids`` (BEM grid sizes), ``sliders``
(slider counts), ``rings`` (rings of the fretting map) and ``tolerance`` (default 0.05).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np
import xarray as xr

from slipcycle.errors import InputError
from slipcycle.halfspace.case import parse_case
from slipcycle.halfspace.model import HalfspaceModel, solve
from slipcycle.halfspace.profiles import FlatPunch, RoughExponential
from slipcycle.halfspace.topography import (
    BEMLaw,
    ExponentialFit,
    SurfaceMap,
    TopographySource,
    cached_bem_normal_law,
    check_bem_memory,
    filter_surface,
    fit_exponential,
    largest_normal_load,
    read_source,
    resample,
    smooth_table,
)
from slipcycle.io import CaseError, Section
from slipcycle.loading import HarmonicLoad
from slipcycle.plot.roughness import (
    cutoff_study,
    dissipation_vs_phase,
    fretting_map,
    normal_law,
)
from slipcycle.result import StudyResult

log = logging.getLogger("slipcycle")

__all__ = ["RoughnessSettings", "RoughnessResult", "cutoff_within", "local_dissipation",
           "parse_roughness_case", "punch_rings", "roughness_study"]


@dataclass(frozen=True)
class RoughnessSettings:
    """Settings of the study (``[roughness]`` table).

    Attributes
    ----------
    short_cutoffs, long_cutoffs : (Ns,), (Nl,) arrays
        λ_s and λ_l in m.
    phases : (Nφ,) array
        Lags φ of Q behind P (rad) for the phase dependence.
    grids : tuple of int
        BEM grid sizes of the convergence check.
    sliders : tuple of int
        Slider (table point) counts of the convergence check.
    rings : int
        Rings of the fretting map.
    tolerance : float
        Relative change that defines the cut-off wavelengths (0.05).
    """

    short_cutoffs: np.ndarray | None
    long_cutoffs: np.ndarray | None
    phases: np.ndarray
    grids: tuple[int, ...]
    sliders: tuple[int, ...]
    rings: int = 24
    tolerance: float = 0.05

    def __post_init__(self):
        for name in ("short_cutoffs", "long_cutoffs", "phases"):
            if getattr(self, name) is None:
                continue
            arr = np.atleast_1d(np.asarray(getattr(self, name), float))
            if arr.ndim != 1 or not np.all(np.isfinite(arr)):
                raise InputError(name, "must be a list of finite numbers")
            if name != "phases" and (arr.size == 0 or np.any(arr <= 0)):
                raise InputError(name, "must be a non-empty list of wavelengths > 0 (m)")
            object.__setattr__(self, name, np.sort(arr) if name != "phases" else arr)
        if not self.grids or any(g < 8 or g > 4096 for g in self.grids):
            raise InputError("grids", f"BEM grids must lie in [8, 4096], got {self.grids}")
        if not self.sliders or any(m < 10 for m in self.sliders):
            raise InputError("sliders", f"slider counts must be >= 10, got {self.sliders}")
        if not 2 <= self.rings <= 1000:
            raise InputError("rings", f"must be in [2, 1000], got {self.rings}")
        if not 0 < self.tolerance < 1:
            raise InputError("tolerance", f"must be in (0, 1), got {self.tolerance}")


def parse_roughness_case(case):
    """The base model, its topography source and the study settings of a case.

    Parameters
    ----------
    case : Case
        ``model = "halfspace"``, ``profile = "topography"``, harmonic force-controlled
        loads, and an optional ``[roughness]`` table (module docstring).

    Returns
    -------
    model : HalfspaceModel
        The case as ``slipcycle run`` solves it (BEM law computed or read from the cache).
    source : TopographySource
    settings : RoughnessSettings

    Raises
    ------
    CaseError
        Naming the key; the BEM of the base law runs only once every key is valid.
    """
    halfspace = case.data.get("halfspace")
    if not isinstance(halfspace, dict) or halfspace.get("profile") != "topography":
        raise CaseError("halfspace.profile", "the roughness study needs profile = "
                        "\"topography\" (a topography_file pressed by the BEM)")
    sec = case.section("roughness", required=False)
    grid = halfspace.get("bem_grid")
    grid = grid if isinstance(grid, int) and grid >= 16 else 64
    sliders = case.data.get("run", {}).get("sliders", 2000)
    sliders = sliders if isinstance(sliders, int) and sliders >= 40 else 2000

    def wavelengths(key):
        return _nonempty(sec, key, sec.array(key, shape=(None,), gt=0.0)) if sec.has(key) \
            else None

    try:
        settings = RoughnessSettings(
            short_cutoffs=wavelengths("short_cutoffs"), long_cutoffs=wavelengths("long_cutoffs"),
            phases=sec.grid("phases", {"start": -np.pi, "stop": np.pi, "num": 13}),
            grids=_counts(sec, "grids", [grid // 2, grid, 2 * grid], 8),
            sliders=_counts(sec, "sliders", [sliders // 4, sliders // 2, sliders], 10),
            rings=sec.int("rings", 24), tolerance=sec.float("tolerance", 0.05))
    except InputError as exc:
        if isinstance(exc, CaseError):
            raise
        raise sec.error(exc.key, exc.problem) from None
    sec.finish()   # typos in [roughness], before parse_case accepts the table unread
    model = parse_case(case)
    if model.tangential_control != "force":
        raise CaseError("loading", "the roughness study needs force control (P0, P1, Q0, Q1)")
    if not isinstance(model.normal, HarmonicLoad) or not isinstance(model.tangential,
                                                                     HarmonicLoad) \
            or model.tangential.amplitudes.shape[0] != 1:
        raise CaseError("loading", "the roughness study needs one-harmonic loads (P0, P1, "
                        "Q0, Q1, phase), not a table")
    source = read_source(Section(halfspace, "halfspace", case.base_dir),
                         model.elasticity.contact_modulus)
    _check_study_surfaces(model, source, settings)
    return model, source, settings


def _check_study_surfaces(model: HalfspaceModel, source: TopographySource,
                          settings: RoughnessSettings) -> None:
    """Refuse, before any BEM, the study's filters that keep no wavelength of the map
    (``roughness.short_cutoffs``, ``roughness.long_cutoffs``) and a fretting map whose rim
    pressure is beyond complete contact (``roughness.rings``).

    Raises
    ------
    CaseError
    """
    surface = source.surface()
    try:
        check_bem_memory("grids", max(settings.grids))
    except InputError as exc:
        raise CaseError("roughness.grids", exc.problem) from None
    span = f"the map on its BEM grid spans {2 * surface.pixel:.3g} m to " \
           f"{max(surface.size):.3g} m"
    for key, short in (("short_cutoffs", True), ("long_cutoffs", False)):
        for cut in [] if getattr(settings, key) is None else getattr(settings, key):
            kept = filter_surface(surface, **{"short_cutoff" if short else "long_cutoff": cut})
            if kept.flat:
                raise CaseError(f"roughness.{key}", f"{cut:g} m keeps no wavelength ("
                                f"{span}): the filtered surface is flat")
    A = source.nominal_area
    P_max = largest_normal_load(model.normal, model.protocol, model.steps_per_cycle)
    rim = float(punch_rings(np.sqrt(A / np.pi), settings.rings)[2].max() * A)
    try:
        source.check_pressure(P_max / A * max(1.0, rim), surface)
    except InputError as exc:
        raise CaseError("roughness.rings", f"the rim ring of the fretting map carries "
                        f"{rim:.3g} times the mean pressure: {exc.problem}") from None


def _nonempty(sec: Section, key: str, values: np.ndarray) -> np.ndarray:
    """``values`` of ``[roughness] key``, refused when the list is empty (the study would
    have nothing to compute or plot on that axis)."""
    if np.asarray(values).size == 0:
        raise sec.error(key, "must hold at least one value, got an empty list")
    return values


def _counts(sec: Section, key: str, default: list[int], least: int) -> tuple[int, ...]:
    """A non-empty list of counts (BEM grids, sliders) of ``[roughness]``, each an integer
    >= ``least``: 32.7 is refused rather than truncated to 32 (a count written as a float,
    ``1e3``, is accepted)."""
    values = _nonempty(sec, key, sec.array(key, default, shape=(None,), ge=least))
    bad = [v for v in values.tolist() if not float(v).is_integer()]
    if bad:
        raise sec.error(key, f"counts must be whole numbers, got {bad[0]!r}")
    return tuple(int(v) for v in values)


def cutoff_within(cutoffs: np.ndarray, ratio: np.ndarray, tolerance: float,
                  short: bool) -> float:
    """The cut-off wavelength at which |ratio − 1| first reaches ``tolerance``.

    For a short cut-off (``short``) the wavelengths are scanned upwards from the smallest,
    for a long cut-off downwards from the largest; the crossing is interpolated linearly in
    log λ between the last point within the tolerance and the first outside it.

    Parameters
    ----------
    cutoffs : (N,) array
        Wavelengths (m), increasing.
    ratio : (N,) array
        Quantity relative to the unfiltered surface.
    tolerance : float
    short : bool

    Returns
    -------
    float
        λ (m); the last scanned wavelength if the tolerance is never reached; nan if the
        first one already exceeds it.
    """
    lam = np.asarray(cutoffs, float)
    dev = np.abs(np.asarray(ratio, float) - 1.0)
    order = np.arange(lam.size) if short else np.arange(lam.size)[::-1]
    prev = None
    for k in order:
        if dev[k] > tolerance:
            if prev is None:
                return float("nan")
            # linear in log λ between prev (inside) and k (outside)
            t = (tolerance - dev[prev]) / (dev[k] - dev[prev])
            return float(np.exp(np.log(lam[prev]) + t * (np.log(lam[k]) - np.log(lam[prev]))))
        prev = k
    return float(lam[order[-1]])


def _scaled(load: HarmonicLoad, factor: float) -> HarmonicLoad:
    return replace(load, mean=load.mean * factor, amplitudes=load.amplitudes * factor)


def local_dissipation(profile, normal: HarmonicLoad, tangential: HarmonicLoad,
                      factors: np.ndarray, *, friction: float, compliance_ratio: float,
                      **settings) -> tuple[np.ndarray, np.ndarray]:
    """Dissipation per unit area of points whose traction cycles are scaled load cycles.

    Point i carries the nominal tractions p_i(θ) = c_i P(θ), q_i(θ) = c_i Q(θ) (the stuck
    flat punch, or any smooth solution with proportional tractions); each point is a small
    rough contact of unit nominal area under its own cycle (Barber 2012, §4.6), solved by
    the slider bed of its normal law.

    Parameters
    ----------
    profile : Profile
        Normal law per unit nominal area, p(U) (Pa against m).
    normal, tangential : HarmonicLoad
        P(θ), Q(θ) (N).
    factors : (M,) array
        c_i (1/m²).
    friction, compliance_ratio : float
    **settings
        Other :class:`HalfspaceModel` fields (steps_per_cycle, max_cycles, n_sliders, ...).

    Returns
    -------
    W : (M,) array
        Dissipation per cycle per unit nominal area (J/m²); nan at gross slip.
    steady : (M,) bool array
    """
    W = np.full(factors.size, np.nan)
    steady = np.zeros(factors.size, bool)
    for i, c in enumerate(np.asarray(factors, float)):
        m = HalfspaceModel(profile=profile, elasticity=None, friction=friction,
                           compliance_ratio=compliance_ratio, normal=_scaled(normal, c),
                           tangential=_scaled(tangential, c), **settings)
        _, res = solve(m, record_last_cycle=False)
        if res.gross_slip is None:
            W[i] = res.dissipation_per_cycle
            steady[i] = res.steady
    return W, steady


def punch_rings(radius: float, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rings of a flat circular punch and their share of the load.

    The stuck rigid flat punch carries p = P/(2πa√(a² − r²)) and, by the same Boussinesq
    kernel in the uncoupled approximation, q = Q/(2πa√(a² − r²)) (Johnson 1985, §3.8,
    §7.2): every point sees P and Q scaled by the same factor, integrated exactly over each
    ring: c_i = (√(a² − r_i²) − √(a² − r_{i+1}²)) / (π a (r_{i+1}² − r_i²)).

    Parameters
    ----------
    radius : float
        a in m.
    n : int
        Rings of equal width.

    Returns
    -------
    r_mid : (n,) array
        Ring mid-radii (m).
    area : (n,) array
        Ring areas (m²).
    factor : (n,) array
        c_i (1/m²), with Σ c_i area_i = 1.
    """
    r = np.linspace(0.0, radius, n + 1)
    area = np.pi * np.diff(r**2)
    s = np.sqrt(np.maximum(radius**2 - r**2, 0.0))
    # ∫ 2πr dr / (2πa√(a²−r²)) = (s_i − s_{i+1})/a over the ring
    factor = -np.diff(s) / radius / area
    return 0.5 * (r[1:] + r[:-1]), area, factor


@dataclass(frozen=True)
class _Point:
    """One law's numbers: dissipation, stiffness at P0, γσ of the fit."""

    W: float
    stiffness: float
    gamma_sigma: float


def _dissipation(model: HalfspaceModel, profile) -> float:
    m = replace(model, profile=profile, profile_name="")
    _, res = solve(m, record_last_cycle=False)
    return float(res.dissipation_per_cycle) if res.gross_slip is None else float("nan")


def _exponential_dissipation(model: HalfspaceModel, fit: ExponentialFit) -> float:
    """W (J) with the fitted exponential law; NaN, said once, when no window was found."""
    if np.isfinite(fit.gamma_sigma):
        return _dissipation(model, RoughExponential(fit.gamma_sigma))
    log.warning("roughness: no load window where dP/dU = P/(gamma sigma) holds within "
                "%.0f%% (fit_tolerance): gamma_sigma and the exponential law's dissipation "
                "are NaN; the tabulated law is used", 100 * fit.tolerance)
    return float("nan")


def _phase_dependence(model: HalfspaceModel, profile, phases: np.ndarray) -> np.ndarray:
    """W (J) of ``model`` with ``profile`` for each lag φ (rad) of the single-harmonic Q."""
    W = np.empty(phases.size)
    for k, ph in enumerate(phases):
        tang = replace(model.tangential, phases=np.full_like(model.tangential.phases, -ph))
        W[k] = _dissipation(replace(model, tangential=tang), profile)
    return W


def _cutoffs(surface: SurfaceMap, settings: RoughnessSettings
             ) -> tuple[np.ndarray, np.ndarray]:
    """λ_s and λ_l of the study (m): the settings', or by default 7 from 4 pixels to half
    the size and 6 from 8 pixels to two thirds of it."""
    L = min(surface.size)
    short, long_ = settings.short_cutoffs, settings.long_cutoffs
    if short is None:
        short = np.geomspace(4 * surface.pixel, L / 2, 7)
    if long_ is None:
        long_ = np.geomspace(8 * surface.pixel, L / 1.5, 6)
    return short, long_


def _fretting_map(model: HalfspaceModel, source: TopographySource, law: BEMLaw,
                  factor: np.ndarray) -> tuple[np.ndarray, float]:
    """Local dissipation of the punch rings and the smooth punch's own dissipation.

    Parameters
    ----------
    law : BEMLaw
        The rough law pressed up to the rim ring's pressure (per unit area).
    factor : (R,) array
        Traction factors of the rings (1/m², :func:`punch_rings`).

    Returns
    -------
    W_ring : (R,) array
        Dissipation per cycle per unit area (J/m²).
    W_smooth : float
        Dissipation per cycle of the smooth flat punch (J).
    """
    per_area = smooth_table(law, 1.0, model.n_sliders)
    run = dict(steps_per_cycle=model.steps_per_cycle, max_cycles=model.max_cycles,
               n_sliders=model.n_sliders, assembly_steps=model.assembly_steps)
    W_ring, _ = local_dissipation(per_area, model.normal, model.tangential, factor,
                                  friction=model.friction,
                                  compliance_ratio=model.compliance_ratio, **run)
    punch = FlatPunch(float(np.sqrt(source.nominal_area / np.pi)), source.contact_modulus)
    return W_ring, _dissipation(model, punch)


def roughness_study(model: HalfspaceModel, source: TopographySource,
                    settings: RoughnessSettings) -> RoughnessResult:
    """Run the study (module docstring) for a validated case.

    Parameters
    ----------
    model : HalfspaceModel
        Base model with harmonic force-controlled loads (:func:`parse_roughness_case`).
    source : TopographySource
        Surface, nominal area, E*, BEM grid and loads.
    settings : RoughnessSettings

    Returns
    -------
    RoughnessResult
    """
    t0 = time.perf_counter()
    A = source.nominal_area
    n_sl = model.n_sliders
    P0 = float(model.normal.mean[0])
    p0 = P0 / A
    rings = punch_rings(np.sqrt(A / np.pi), settings.rings)
    # the joint's law is the one `slipcycle run` solves (same largest load, same BEM
    # pressures, same cache file): pressing to the punch rim instead moved the PCHIP points
    # and gave another W (142.7 against 143.3 µJ for the example); only the fretting map
    # needs the law up to the largest local pressure (punch rim)
    P_max = largest_normal_load(model.normal, model.protocol, model.steps_per_cycle)
    pressures = source.pressures(P_max / A)
    rim_pressures = source.pressures(P_max / A * max(1.0, float(rings[2].max() * A)))
    native, base_surface = source.native(), source.surface()
    cache: list[str] = []

    def law_of(surface: SurfaceMap, p: np.ndarray = pressures) -> BEMLaw:
        law, path, _ = cached_bem_normal_law(surface, source.contact_modulus, p)
        if path is not None:
            cache.append(str(path))
        return law

    def point(law: BEMLaw, n: int = n_sl) -> _Point:
        table = smooth_table(law, A, n)
        fit = fit_exponential(law.pressure, law.approach, source.fit_tolerance)
        return _Point(_dissipation(model, table), float(A * law.stiffness(p0)),
                      fit.gamma_sigma)

    base = law_of(base_surface)
    fit = fit_exponential(base.pressure, base.approach, source.fit_tolerance)
    ref = point(base)
    table = smooth_table(base, A, n_sl)
    W_exp = _exponential_dissipation(model, fit)
    W_phase = _phase_dependence(model, table, settings.phases)

    # convergence in the BEM grid and in the slider count
    conv_grid = [point(law_of(resample(native, g))) for g in settings.grids]
    W_sliders = np.array([_dissipation(model, smooth_table(base, A, m))
                          for m in settings.sliders])

    L = min(base_surface.size)
    short, long_ = _cutoffs(base_surface, settings)
    pts_short = [point(law_of(filter_surface(base_surface, short_cutoff=s))) for s in short]
    pts_long = [point(law_of(filter_surface(base_surface, long_cutoff=s))) for s in long_]

    # local fretting map of the flat punch (rough law per unit area) and its smooth twin
    r_mid, r_area, factor = rings
    W_ring, W_smooth = _fretting_map(model, source, law_of(base_surface, rim_pressures),
                                     factor)

    return RoughnessResult(
        wall_time_s=time.perf_counter() - t0, nominal_area=A, P0=P0,
        friction=model.friction, compliance_ratio=model.compliance_ratio,
        size=float(L), grid=int(base_surface.grid[0]), rms_height=base.rms_height, law=base,
        fit=fit, dissipation=ref.W, dissipation_exponential=W_exp, stiffness=ref.stiffness,
        phases=settings.phases, dissipation_phase=W_phase,
        grids=np.array(settings.grids), **_columns("grid", conv_grid),
        sliders=np.array(settings.sliders), dissipation_sliders=W_sliders,
        short_cutoffs=short, **_columns("short", pts_short, gamma_sigma=False),
        long_cutoffs=long_, **_columns("long", pts_long, gamma_sigma=False),
        tolerance=settings.tolerance, ring_radius=r_mid, ring_area=r_area, ring_factor=factor,
        ring_dissipation=W_ring, smooth_dissipation=W_smooth,
        cache_files=tuple(dict.fromkeys(cache)))


def _columns(suffix: str, points: list[_Point], gamma_sigma: bool = True) -> dict:
    """``dissipation_<suffix>`` (J), ``stiffness_<suffix>`` (N/m) and, with
    ``gamma_sigma``, ``gamma_sigma_<suffix>`` (m) of a list of law points."""
    names = ("W", "stiffness", "gamma_sigma") if gamma_sigma else ("W", "stiffness")
    field_of = {"W": "dissipation", "stiffness": "stiffness", "gamma_sigma": "gamma_sigma"}
    return {f"{field_of[n]}_{suffix}": np.array([getattr(p, n) for p in points])
            for n in names}


_UNITS = {"pressure": "Pa", "approach": "m", "contact_fraction": "1", "gamma_sigma": "m"}


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class RoughnessResult(StudyResult):
    """Rough interface from topography: normal law, dissipation and the wavelengths that
    matter (``slipcycle roughness``; Barber 2012, §4.6).

    Attributes
    ----------
    nominal_area : float
        A (m²).
    P0 : float
        Mean normal load (N).
    friction, compliance_ratio : float
    size : float
        Side of the surface (m).
    grid : int
        BEM grid of the reference law.
    rms_height : float
        σ (m) on the BEM grid.
    law : BEMLaw
        Reference BEM law (per unit area).
    fit : ExponentialFit
        Exponential fit of ``law`` (pressures in Pa).
    dissipation : float
        W of the joint (J per cycle), tabulated law.
    dissipation_exponential : float
        W with the fitted exponential law (J).
    stiffness : float
        dP/dU at P0 (N/m).
    phases, dissipation_phase : (Nφ,) arrays
        φ (rad) and W(φ) (J).
    grids, dissipation_grid, stiffness_grid, gamma_sigma_grid : (Ng,) arrays
        BEM grid convergence: W (J), dP/dU at P0 (N/m), γσ (m).
    sliders, dissipation_sliders : (Nm,) arrays
        Slider-count convergence: W (J).
    short_cutoffs, dissipation_short, stiffness_short : (Ns,) arrays
        λ_s (m), W (J), dP/dU (N/m) with wavelengths below λ_s removed.
    long_cutoffs, dissipation_long, stiffness_long : (Nl,) arrays
        The same with wavelengths above λ_l removed.
    tolerance : float
        Relative change defining the cut-offs.
    ring_radius, ring_area, ring_factor, ring_dissipation : (R,) arrays
        Fretting map of the flat punch: mid-radius (m), area (m²), traction factor (1/m²),
        local dissipation per cycle per unit area (J/m²).
    smooth_dissipation : float
        W of the smooth flat punch under the same loads (J).
    cache_files : tuple of str
        BEM cache files used.
    """

    model: ClassVar[str] = "halfspace"
    analysis: ClassVar[str] = "roughness"
    FLAGS: ClassVar[dict] = {"model": ("halfspace",), "analysis": ("roughness",),
                             "exponential_fit": ("found", "none")}

    nominal_area: float
    P0: float
    friction: float
    compliance_ratio: float
    size: float
    grid: int
    rms_height: float
    law: BEMLaw
    fit: ExponentialFit
    dissipation: float
    dissipation_exponential: float
    stiffness: float
    phases: np.ndarray
    dissipation_phase: np.ndarray
    grids: np.ndarray
    dissipation_grid: np.ndarray
    stiffness_grid: np.ndarray
    gamma_sigma_grid: np.ndarray
    sliders: np.ndarray
    dissipation_sliders: np.ndarray
    short_cutoffs: np.ndarray
    dissipation_short: np.ndarray
    stiffness_short: np.ndarray
    long_cutoffs: np.ndarray
    dissipation_long: np.ndarray
    stiffness_long: np.ndarray
    tolerance: float
    ring_radius: np.ndarray
    ring_area: np.ndarray
    ring_factor: np.ndarray
    ring_dissipation: np.ndarray
    smooth_dissipation: float
    cache_files: tuple = ()

    # -- derived numbers ----------------------------------------------------------------
    @property
    def short_cutoff_dissipation(self) -> float:
        """Largest λ_s (m) changing W by less than the tolerance."""
        return cutoff_within(self.short_cutoffs, self.dissipation_short / self.dissipation,
                             self.tolerance, True)

    @property
    def short_cutoff_stiffness(self) -> float:
        """Largest λ_s (m) changing dP/dU at P0 by less than the tolerance."""
        return cutoff_within(self.short_cutoffs, self.stiffness_short / self.stiffness,
                             self.tolerance, True)

    @property
    def long_cutoff_dissipation(self) -> float:
        """Smallest λ_l (m) changing W by less than the tolerance."""
        return cutoff_within(self.long_cutoffs, self.dissipation_long / self.dissipation,
                             self.tolerance, False)

    @property
    def long_cutoff_stiffness(self) -> float:
        """Smallest λ_l (m) changing dP/dU at P0 by less than the tolerance."""
        return cutoff_within(self.long_cutoffs, self.stiffness_long / self.stiffness,
                             self.tolerance, False)

    @property
    def exponential_fit(self) -> str:
        """``"found"``, or ``"none"`` when no window of 3 BEM loads has dP/dU = P/(γσ)
        within the fit tolerance (γσ, γ and Ŵ are then NaN in ``result.nc``, null in
        ``summary.json``)."""
        return "found" if np.isfinite(self.fit.gamma_sigma) else "none"

    @property
    def fretting_map_total(self) -> float:
        """Σ W_i area_i of the punch map (J per cycle)."""
        return float(np.nansum(self.ring_dissipation * self.ring_area))

    def _convergence(self, values: np.ndarray) -> float:
        """Relative difference of the last two entries (the finest two)."""
        v = np.asarray(values, float)
        return float(abs(v[-1] - v[-2]) / abs(v[-1])) if v.size >= 2 else float("nan")

    def headline(self) -> list[tuple]:
        return [("gamma_sigma", self.fit.gamma_sigma, "m"),
                ("dissipation_per_cycle", self.dissipation, "J"),
                ("short_cutoff_dissipation", self.short_cutoff_dissipation, "m"),
                ("long_cutoff_dissipation", self.long_cutoff_dissipation, "m"),
                ("wall_time_s", self.wall_time_s, "s")]

    def summary(self) -> dict:
        """``summary.json`` of ``slipcycle roughness`` (every number with its unit).

        Returns
        -------
        dict
            ``gamma_sigma`` [m], ``gamma`` (γσ/σ), ``rms_height`` [m],
            ``exponential_fit_pressure_range`` [Pa] and ``exponential_fit_load_range`` [N]
            (where the local γσ stays within ``fit_tolerance``), ``fit_max_deviation``,
            ``mean_load_in_fit_range``, ``dissipation_per_cycle`` [J] (tabulated BEM law),
            ``dissipation_per_area`` [J/m²], ``dissipation_per_cycle_exponential`` [J],
            ``W_hat`` (W/(λ_c γσ f² P0)), ``stiffness`` [N/m] at P0, the four cut-off
            wavelengths [m] and the same relative to the surface size, the phase of the
            largest dissipation [rad], grid and slider convergence [1], the fretting-map
            total [J] against the smooth punch [J], ``wall_time_s``, ``units``.
        """
        f, L = self.fit, self.size
        lo, hi = f.load_range
        in_range = bool(np.isfinite(lo) and lo <= self.P0 / self.nominal_area <= hi)
        gs = f.gamma_sigma
        W_hat = (self.dissipation / (self.compliance_ratio * gs * self.friction**2 * self.P0)
                 if np.isfinite(gs) and np.isfinite(self.dissipation) else None)
        cut = {"short_cutoff_dissipation": self.short_cutoff_dissipation,
               "short_cutoff_stiffness": self.short_cutoff_stiffness,
               "long_cutoff_dissipation": self.long_cutoff_dissipation,
               "long_cutoff_stiffness": self.long_cutoff_stiffness}
        i_max = int(np.nanargmax(self.dissipation_phase)) if np.any(
            np.isfinite(self.dissipation_phase)) else 0
        s = {
            "model": "halfspace", "analysis": "roughness",
            "gamma_sigma": _num(gs), "gamma": _num(gs / self.rms_height),
            "exponential_fit": self.exponential_fit,
            "rms_height": self.rms_height, "surface_size": L, "bem_grid": self.grid,
            "fit_tolerance": f.tolerance, "fit_max_deviation": _num(f.max_deviation),
            "exponential_fit_pressure_range": [_num(lo), _num(hi)],
            "exponential_fit_load_range": [_num(lo * self.nominal_area),
                                           _num(hi * self.nominal_area)],
            "exponential_fit_decades": f.decades,
            "mean_load_in_fit_range": in_range,
            "dissipation_per_cycle": _num(self.dissipation),
            "dissipation_per_area": _num(self.dissipation / self.nominal_area),
            "dissipation_per_cycle_exponential": _num(self.dissipation_exponential),
            "W_hat": _num(W_hat) if W_hat is not None else None,
            "stiffness": self.stiffness,
            "tolerance": self.tolerance,
            **{k: _num(v) for k, v in cut.items()},
            **{k + "_over_size": _num(v / L) for k, v in cut.items()},
            "phase_of_max_dissipation": float(self.phases[i_max]),
            "grid_convergence_dissipation": _num(self._convergence(self.dissipation_grid)),
            "grid_convergence_stiffness": _num(self._convergence(self.stiffness_grid)),
            "slider_convergence_dissipation": _num(
                self._convergence(self.dissipation_sliders)),
            "fretting_map_total": self.fretting_map_total,
            "fretting_map_smooth_dissipation": _num(self.smooth_dissipation),
            "fretting_map_max_density": _num(float(np.nanmax(self.ring_dissipation))),
            "cache_files": list(self.cache_files),
            "wall_time_s": self.wall_time_s,
        }
        s["units"] = {
            "gamma_sigma": "m", "gamma": "1", "rms_height": "m", "surface_size": "m",
            "bem_grid": "1", "fit_tolerance": "1", "fit_max_deviation": "1",
            "exponential_fit_pressure_range": "Pa", "exponential_fit_load_range": "N",
            "exponential_fit_decades": "1", "dissipation_per_cycle": "J",
            "dissipation_per_area": "J/m^2", "dissipation_per_cycle_exponential": "J",
            "W_hat": "1", "stiffness": "N/m", "tolerance": "1",
            **{k: "m" for k in cut}, **{k + "_over_size": "1" for k in cut},
            "phase_of_max_dissipation": "rad", "grid_convergence_dissipation": "1",
            "grid_convergence_stiffness": "1", "slider_convergence_dissipation": "1",
            "fretting_map_total": "J", "fretting_map_smooth_dissipation": "J",
            "fretting_map_max_density": "J/m^2", "wall_time_s": "s"}
        return s

    def _build_dataset(self) -> xr.Dataset:
        """The study as a Dataset (the only place it is built); units on every variable."""
        law, f = self.law, self.fit
        ds = xr.Dataset(coords={
            "bem_pressure": ("bem_pressure", law.pressure,
                             {"units": "Pa", "long_name": "nominal pressure"}),
            "phase": ("phase", self.phases, {"units": "rad", "long_name": "lag of Q behind P"}),
            "bem_grid": ("bem_grid", self.grids, {"units": "1"}),
            "sliders": ("sliders", self.sliders, {"units": "1"}),
            "short_cutoff": ("short_cutoff", self.short_cutoffs, {"units": "m"}),
            "long_cutoff": ("long_cutoff", self.long_cutoffs, {"units": "m"}),
            "ring_radius": ("ring_radius", self.ring_radius, {"units": "m"})})
        add = [
            ("approach", "bem_pressure", law.approach, "m", "U from first touch"),
            ("mean_gap", "bem_pressure", law.mean_gap, "m", "mean interfacial gap"),
            ("contact_fraction", "bem_pressure", law.contact_fraction, "1", "A_real/A"),
            ("local_gamma_sigma", "bem_pressure", f.local_gamma_sigma, "m", "dU/dln p"),
            ("in_fit_range", "bem_pressure", f.in_range.astype(np.int8), "1",
             "1 where dP/dU = P/(gamma sigma) holds within fit_tolerance"),
            ("dissipation_phase", "phase", self.dissipation_phase, "J", "W(phase)"),
            ("dissipation_per_area_phase", "phase", self.dissipation_phase / self.nominal_area,
             "J/m^2", "W(phase) per unit nominal area"),
            ("dissipation_grid", "bem_grid", self.dissipation_grid, "J", "W"),
            ("stiffness_grid", "bem_grid", self.stiffness_grid, "N/m", "dP/dU at P0"),
            ("gamma_sigma_grid", "bem_grid", self.gamma_sigma_grid, "m", "fitted"),
            ("dissipation_sliders", "sliders", self.dissipation_sliders, "J", "W"),
            ("dissipation_short", "short_cutoff", self.dissipation_short, "J",
             "W, wavelengths below the cut-off removed"),
            ("stiffness_short", "short_cutoff", self.stiffness_short, "N/m", "dP/dU at P0"),
            ("dissipation_long", "long_cutoff", self.dissipation_long, "J",
             "W, wavelengths above the cut-off removed"),
            ("stiffness_long", "long_cutoff", self.stiffness_long, "N/m", "dP/dU at P0"),
            ("ring_area", "ring_radius", self.ring_area, "m^2", "ring area"),
            ("ring_pressure_factor", "ring_radius", self.ring_factor, "1/m^2",
             "local traction / load"),
            ("ring_dissipation", "ring_radius", self.ring_dissipation, "J/m^2",
             "local dissipation per cycle per unit area (rough law)")]
        for name, dim, values, unit, long_name in add:
            ds[name] = (dim, np.asarray(values), {"units": unit, "long_name": long_name})
        # netCDF attributes cannot be null: a missing number is NaN, and a missing fit is
        # said in words (exponential_fit) so that NaN is never mistaken for a result
        ds.attrs.update(gamma_sigma=float(f.gamma_sigma), nominal_area=self.nominal_area,
                        P0=self.P0, dissipation_per_cycle=float(self.dissipation),
                        smooth_dissipation=float(self.smooth_dissipation),
                        exponential_fit=self.exponential_fit)
        return ds

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """``normal_law``, ``cutoff_study``, ``dissipation_vs_phase``, ``fretting_map``."""
        ds = self.to_dataset() if dataset is None else dataset
        return {
            "normal_law": lambda: normal_law(ds, self.fit.gamma_sigma, self.fit.load_range,
                                             self.rms_height),
            "cutoff_study": lambda: cutoff_study(ds, self.dissipation, self.stiffness,
                                                 self.tolerance),
            "dissipation_vs_phase": lambda: dissipation_vs_phase(ds),
            "fretting_map": lambda: fretting_map(ds, self.dissipation / self.nominal_area,
                                                 self.smooth_dissipation),
        }


def _num(v) -> float | None:
    """A JSON number, None for nan."""
    v = float(v)
    return v if np.isfinite(v) else None
