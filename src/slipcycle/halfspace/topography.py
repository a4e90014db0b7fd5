"""Normal laws P(U) of nominally flat rough contacts from measured topography.

A measured (or synthetic) height map h(x, y) of the composite surface is pressed against a
flat elastic half-space of contact modulus E* by a boundary-element solver (the
constrained conjugate gradients of Polonsky & Keer 1999 on a periodic FFT half-space,
``ContactMechanics``). For each nominal pressure p̄ the solver returns the gap field; its
mean ḡ is the interfacial separation, and the approach is measured from first touch,

    U(p̄) = ḡ(0) − ḡ(p̄),   ḡ(0) = max h − mean h,

so that the normal law of a joint of nominal area A is P(U) = A p̄(U): the interface
(roughness) compliance, without the bulk compliance of the bodies, which the periodic
half-space leaves out (Persson 2007; Pastewka & Robbins 2014). Reading goes through
``SurfaceTopography`` (instrument formats, units converted to metres).

Where the exponential law of Barber 2012 (§4.6, eq. 10; Akarapu et al. 2011),
dP/dU = P/(γσ), applies is decided from the BEM data: the local γσ(P) = dU/d ln P must stay
within a tolerance (default 10 %) of the least-squares γσ of the widest load window
(:func:`fit_exponential`). The law is fed to the slider bed either as that exponential or
as a dense convex table (:func:`smooth_table`).

Both optional packages are imported inside the functions that need them (the ``topo``
extra); without them :func:`require_topo` raises a one-line
:class:`~slipcycle.errors.InputError` naming ``pip install 'slipcycle[topo]'``.

BEM results are cached on disk (:func:`cache_dir`): a file per (height map, grid, E*,
pressures, tolerance), named by the SHA-256 of those inputs, so a rerun is fast.
"""

from __future__ import annotations

import hashlib
import importlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from slipcycle.errors import InputError, SolverError
from slipcycle.halfspace.profiles import RoughExponential, Tabulated

__all__ = ["TOPO_INSTALL", "BEMLaw", "ExponentialFit", "SurfaceMap", "TopographySource",
           "bem_normal_law", "cache_dir", "cached_bem_normal_law", "convex_minorant",
           "filter_surface", "fit_exponential", "read_surface", "read_table_file",
           "require_topo", "resample", "smooth_table", "synthetic_surface"]

#: how to install the optional packages
TOPO_INSTALL = "pip install 'slipcycle[topo]'"
#: bump when the BEM recipe changes, so old cache files are not reused
_CACHE_VERSION = 1
#: a map whose rms height is below this fraction of its heights' magnitude and of its size
#: is flat: round-off of removing the mean, not roughness
_FLAT = 1e-12


def require_topo(key: str = "topography"):
    """The optional modules ``SurfaceTopography`` and ``ContactMechanics``.

    Returns
    -------
    (module, module)

    Raises
    ------
    InputError
        One line naming the extra, when either package is missing.
    """
    try:
        return (importlib.import_module("SurfaceTopography"),
                importlib.import_module("ContactMechanics"))
    except ImportError as exc:
        raise InputError(key, f"needs the optional package {exc.name or 'SurfaceTopography'!r}"
                         f" (topography and BEM); install it with: {TOPO_INSTALL}") from None


@dataclass(frozen=True)
class SurfaceMap:
    """A periodic height map on a uniform grid (SI units).

    Attributes
    ----------
    heights : (nx, ny) array
        Heights in m, mean removed.
    size : (float, float)
        Physical size (Lx, Ly) in m.
    periodic : bool
        Whether the source was periodic (a non-periodic measurement is mirror-stitched,
        doubling each side, so that the periodic BEM sees no step at the edges).
    """

    heights: np.ndarray
    size: tuple[float, float]
    periodic: bool = True

    def __post_init__(self):
        h = np.asarray(self.heights, float)
        if h.ndim != 2 or min(h.shape) < 4:
            raise InputError("topography", f"needs a 2-D height map of at least 4×4 points, "
                             f"got shape {h.shape}")
        if not np.all(np.isfinite(h)):
            raise InputError("topography", "height map has undefined (nan) points")
        if not all(np.isfinite(s) and s > 0 for s in self.size):
            raise InputError("topography", f"physical size must be > 0, got {self.size}")
        # the magnitude of the heights before the mean is removed: a constant map leaves
        # round-off of that magnitude, which the flatness test must not take for roughness
        object.__setattr__(self, "_magnitude", float(np.max(np.abs(h))))
        object.__setattr__(self, "heights", h - h.mean())
        object.__setattr__(self, "size", (float(self.size[0]), float(self.size[1])))

    @property
    def rms_height(self) -> float:
        """σ, the rms height (m)."""
        return float(np.sqrt(np.mean(self.heights**2)))

    @property
    def flat(self) -> bool:
        """Whether the map is flat to round-off: σ ≤ 1e-12 of the larger of the heights'
        magnitude (before the mean was removed) and the map size."""
        return not self.rms_height > _FLAT * max(self._magnitude, *self.size)

    def complete_contact_pressure(self, contact_modulus: float) -> float:
        """Nominal pressure (Pa) above which the map is in complete contact.

        In complete contact the pressure is p̄ − (E*/2) F⁻¹[|q| ĥ(q)] (linear elasticity of
        the periodic half-space; for h cos(2πx/λ) this is Johnson's p* = πE*h/λ), so
        contact is complete once p̄ reaches the largest value of (E*/2) F⁻¹[|q| ĥ]. Beyond
        it the approach no longer changes and the normal law ends.

        Parameters
        ----------
        contact_modulus : float
            E* in Pa.
        """
        h = self.heights
        (nx, ny), (Lx, Ly) = h.shape, self.size
        qx = 2 * np.pi * np.fft.fftfreq(nx, Lx / nx)
        qy = 2 * np.pi * np.fft.rfftfreq(ny, Ly / ny)
        q = np.hypot(qx[:, None], qy[None, :])
        return float(0.5 * contact_modulus * np.max(np.fft.irfft2(q * np.fft.rfft2(h),
                                                                  s=h.shape)))

    @property
    def grid(self) -> tuple[int, int]:
        return self.heights.shape

    @property
    def pixel(self) -> float:
        """Largest grid spacing (m)."""
        return max(self.size[0] / self.grid[0], self.size[1] / self.grid[1])

    def digest(self) -> str:
        """SHA-256 of the heights and size (the cache key of the surface)."""
        h = hashlib.sha256(np.ascontiguousarray(self.heights).tobytes())
        h.update(np.array([*self.size, *self.grid], float).tobytes())
        return h.hexdigest()


def _to_map(topo, periodic: bool | None = None, fill_undefined: bool = False,
            label: str = "topography") -> SurfaceMap:
    """A SurfaceTopography object as a :class:`SurfaceMap` in metres.

    Undefined points (masked, NaN or ±inf heights) are refused unless ``fill_undefined``,
    which fills them by SurfaceTopography's harmonic interpolation and logs their count.
    """
    if topo.dim != 2:
        raise InputError("topography", "needs a 2-D topography (a height map), got a line "
                         "scan")
    unit = topo.unit
    try:                                  # the conversion is lazy: heights() applies it
        if unit not in (None, "m"):
            topo = topo.to_unit("m")
        h = np.ma.masked_invalid(np.ma.array(topo.heights(), float, copy=True))
    except (ValueError, KeyError) as exc:
        raise InputError("topography", f"height unit {unit!r} is not a length unit "
                         "SurfaceTopography converts (m, mm, µm, nm, ...): "
                         f"{' '.join(str(exc).split())}") from None
    undefined = int(np.ma.count_masked(h))
    if undefined == h.size:   # nothing to interpolate from, with or without fill_undefined
        raise InputError("topography", f"all {h.size} height points are undefined (NaN, "
                         "±inf or masked): the file holds no heights")
    if undefined:
        if not fill_undefined:
            raise InputError("topography", f"{undefined} of {h.size} height points are "
                             "undefined (NaN, ±inf or masked); repair the file, or set "
                             "fill_undefined = true to interpolate them")
        import logging

        from SurfaceTopography import Topography

        logging.getLogger("slipcycle").warning(
            "%s: %d of %d undefined height points filled by interpolation (fill_undefined)",
            label, undefined, h.size)
        topo = Topography(h, topo.physical_sizes, periodic=topo.is_periodic,
                          unit="m").interpolate_undefined_data()
    is_periodic = bool(topo.is_periodic if periodic is None else periodic)
    if not is_periodic:
        # a non-periodic scan: remove the tilt, then mirror it into a periodic map
        topo = topo.detrend("height").mirror_stitch()
    return SurfaceMap(np.array(topo.heights(), float), tuple(topo.physical_sizes),
                      is_periodic)


#: first bytes of the container formats a height map usually comes in
_MAGIC = {b"CDF\x01": "netCDF", b"CDF\x02": "netCDF", b"\x89HDF": "netCDF-4/HDF5",
          b"\x93NUMPY": "NumPy .npy"}
#: first bytes of a netCDF file, classic or netCDF-4 (HDF5)
_NETCDF_MAGIC = (b"CDF", b"\x89HDF")


def _first_bytes(path: str | Path) -> bytes | None:
    """The first 8 bytes of ``path`` (its format's magic), None if it cannot be read."""
    try:
        with open(path, "rb") as f:
            return f.read(8)
    except OSError:
        return None


def _unreadable(path: str | Path, exc: Exception) -> str:
    """One short line for a file no SurfaceTopography reader accepted (the readers'
    own list of failures runs to 1500 characters)."""
    try:
        with open(path, "rb") as f:
            head = f.read(8)
    except OSError as err:
        return f"cannot read topography {path}: {err.strerror or err}"
    kind = next((v for k, v in _MAGIC.items() if head.startswith(k)), None)
    if kind is not None:
        first = " ".join(str(exc).split())[:160]
        return (f"{path} starts as a {kind} file but cannot be read as a topography "
                f"(truncated or damaged?): {first}")
    return (f"{path} is in no format SurfaceTopography reads (netCDF, NPY, instrument "
            "files, plain-text columns); give the height map in one of them")


def _open(st, path: str | Path, key: str, size: tuple[float, float] | None):
    """The file's topography through SurfaceTopography, with the physical size it lacks.

    NPY files and plain-text matrices hold heights only: their size comes from ``size``
    (``topography_size``), and is refused for a file that gives its own.
    """
    try:
        reader = st.open_topography(str(path))
        channel = reader.default_channel
    except Exception as exc:  # noqa: BLE001 - many kinds of reader error; one line
        raise InputError(key, _unreadable(path, exc)) from None
    own = channel.physical_sizes
    if channel.dim != 2:
        raise InputError(key, "needs a 2-D topography (a height map), got a line scan")
    if own is None and size is None:
        kind = type(reader).__name__.removesuffix("Reader")
        raise InputError(key, f"{path} (read as {kind}) holds heights without a physical "
                         "size, as NPY files and plain-text matrices do: give it as "
                         "topography_size = [Lx, Ly] in m")
    if own is not None and size is not None:
        raise InputError("topography_size", f"{path} gives its own size "
                         f"({' x '.join(f'{v:g}' for v in own)} {channel.unit or 'm'}); "
                         "remove topography_size")
    try:
        if size is not None:
            return reader.topography(physical_sizes=tuple(size))
        return reader.topography()
    except Exception as exc:  # noqa: BLE001 - many kinds of reader error; one line
        raise InputError(key, _unreadable(path, exc)) from None


def _check_grid(path: str | Path, key: str) -> None:
    """Refuse height maps whose coordinates are not a uniform grid.

    SurfaceTopography reads netCDF heights without their x, y coordinates and plain-text
    x y z columns only on a grid, so a non-uniform grid would be taken as uniform (netCDF)
    or fail with a message about formats (text).
    """
    head = _first_bytes(path)
    if head is None:
        return                           # the reader says what is wrong
    coords: list[np.ndarray] = []
    if head.startswith(_NETCDF_MAGIC):
        try:
            with xr.open_dataset(path) as ds:
                coords = [np.asarray(ds[c].values, float) for c in ("x", "y")
                          if c in ds.coords and ds[c].ndim == 1 and ds[c].size > 2]
        except Exception:  # noqa: BLE001 - unreadable here: the reader's message follows
            return
    elif b"\x00" not in head:
        try:
            data = np.loadtxt(path, ndmin=2, comments="#")
        except (ValueError, UnicodeDecodeError):
            return
        if data.shape[1] != 3:
            return
        xs, ys = np.unique(data[:, 0]), np.unique(data[:, 1])
        if xs.size * ys.size != data.shape[0]:
            raise InputError(key, f"{path}: its {data.shape[0]} x y z rows are not a grid "
                             f"({xs.size} x values by {ys.size} y values); give the heights "
                             "on a uniform grid")
        coords = [xs, ys]
    for c in coords:
        step = np.diff(c)
        if step.size and np.ptp(step) > 1e-6 * np.abs(step).max():
            raise InputError(key, f"{path}: grid not uniform (spacing from {step.min():.3g} "
                             f"to {step.max():.3g}); give the heights on a uniform grid")


def read_surface(path: str | Path, *, key: str = "topography",
                 fill_undefined: bool = False, label: str | None = None,
                 size: tuple[float, float] | None = None) -> SurfaceMap:
    """Read a topography file through SurfaceTopography (any format it knows).

    Parameters
    ----------
    path : path
        Instrument file, NetCDF written by SurfaceTopography, NPY, plain text, ...
        Heights without a unit are taken as metres.
    key : str
        Case-file key blamed for problems.
    fill_undefined : bool
        Interpolate undefined points (refused by default, with their count).
    label : str, optional
        Dotted case-file key named by the warning about filled points (default ``key``).
    size : (float, float), optional
        (Lx, Ly) in m for files that give no size (NPY, plain-text matrices).

    Returns
    -------
    SurfaceMap

    Raises
    ------
    InputError
        Unreadable file, a line scan, a missing optional package.
    """
    import warnings

    st, _ = require_topo(key)
    with warnings.catch_warnings():
        # SciPy's netCDF reader warns when a memory-mapped file closes with arrays still
        # referring to it; the heights are copied, the warning is noise for the user
        warnings.filterwarnings("ignore", message="Cannot close a netcdf_file")
        _check_grid(path, key)
        topo = _open(st, path, key, size)
        try:
            surface = _to_map(topo, fill_undefined=fill_undefined, label=label or key)
        except InputError as exc:
            raise InputError(key, exc.problem) from None
        finally:
            del topo
            import gc

            gc.collect()
    if surface.flat:
        raise InputError(key, f"{path} is perfectly flat (rms height {surface.rms_height:.3g}"
                         " m, round-off): a flat surface has no rough-contact law; use "
                         "profile = \"flat_punch\" for a flat contact")
    return surface


def synthetic_surface(n: int, size: float, *, hurst: float = 0.8, rms_height: float = 1e-6,
                      short_cutoff: float | None = None, long_cutoff: float | None = None,
                      seed: int = 0):
    """A periodic self-affine surface (SurfaceTopography's Fourier synthesis).

    Parameters
    ----------
    n : int
        Grid points per side.
    size : float
        Side L in m.
    hurst : float
        Hurst exponent H (PSD ∝ q^(−2−2H) between the cut-offs).
    rms_height : float
        σ in m.
    short_cutoff, long_cutoff : float, optional
        Shortest and longest wavelengths (m); below the long one the PSD is flat (roll-off).
    seed : int

    Returns
    -------
    SurfaceTopography Topography
        Periodic, unit m.
    """
    require_topo()
    from SurfaceTopography.Generation import fourier_synthesis  # optional extra

    return fourier_synthesis((n, n), (size, size), hurst, rms_height=rms_height,
                             short_cutoff=short_cutoff, long_cutoff=long_cutoff,
                             rng=np.random.default_rng(seed), unit="m")


def filter_surface(surface: SurfaceMap, short_cutoff: float | None = None,
                   long_cutoff: float | None = None) -> SurfaceMap:
    """Remove wavelengths below ``short_cutoff`` and/or above ``long_cutoff``.

    A sharp isotropic Fourier filter on the periodic map: a component of wave vector q
    (wavelength λ = 2π/|q|) is kept when short_cutoff ≤ λ ≤ long_cutoff.

    Parameters
    ----------
    surface : SurfaceMap
    short_cutoff, long_cutoff : float, optional
        λ_s and λ_l in m (None: no cut).

    Returns
    -------
    SurfaceMap
        Same grid and size.
    """
    h = surface.heights
    (nx, ny), (Lx, Ly) = h.shape, surface.size
    qx = 2 * np.pi * np.fft.fftfreq(nx, Lx / nx)
    qy = 2 * np.pi * np.fft.rfftfreq(ny, Ly / ny)
    q = np.hypot(qx[:, None], qy[None, :])
    keep = np.ones_like(q, bool)
    with np.errstate(divide="ignore"):
        lam = np.where(q > 0, 2 * np.pi / q, np.inf)
    if short_cutoff is not None:
        keep &= lam >= short_cutoff
    if long_cutoff is not None:
        keep &= lam <= long_cutoff
    hq = np.fft.rfft2(h) * keep
    return SurfaceMap(np.fft.irfft2(hq, s=h.shape), surface.size, surface.periodic)


def resample(surface: SurfaceMap, n: int) -> SurfaceMap:
    """The map on an n × n grid by Fourier interpolation (truncation when coarser).

    Exact for a surface band-limited below the new Nyquist wavelength; a coarser grid
    removes the wavelengths it cannot carry (shorter than two of its pixels).
    """
    h = surface.heights
    if h.shape == (n, n):
        return surface
    hq = np.fft.fft2(h)
    nx, ny = h.shape
    out = np.zeros((n, n), complex)
    kx = np.fft.fftfreq(nx, 1 / nx).astype(int)
    ky = np.fft.fftfreq(ny, 1 / ny).astype(int)
    half = n // 2
    sx, sy = np.abs(kx) < half, np.abs(ky) < half
    out[np.ix_(kx[sx] % n, ky[sy] % n)] = hq[np.ix_(sx, sy)]
    heights = np.fft.ifft2(out).real * (n * n) / (nx * ny)
    return SurfaceMap(heights, surface.size, surface.periodic)


@dataclass(frozen=True)
class BEMLaw:
    """The BEM normal law of a periodic rough surface (per unit nominal area).

    Attributes
    ----------
    pressure : (K,) array
        Nominal (mean) pressures p̄ in Pa, increasing.
    approach : (K,) array
        U = ḡ(0) − ḡ(p̄) in m, from first touch.
    mean_gap : (K,) array
        ḡ in m.
    contact_fraction : (K,) array
        Fraction of the grid in contact.
    first_touch_gap : float
        ḡ(0) = max h − mean h (m).
    contact_modulus : float
        E* (Pa).
    grid : (int, int)
    size : (float, float)
        m.
    rms_height : float
        σ (m).
    iterations : int
        Conjugate-gradient iterations over all loads.
    """

    pressure: np.ndarray
    approach: np.ndarray
    mean_gap: np.ndarray
    contact_fraction: np.ndarray
    first_touch_gap: float
    contact_modulus: float
    grid: tuple[int, int]
    size: tuple[float, float]
    rms_height: float
    iterations: int = 0

    def stiffness(self, p: np.ndarray | float) -> np.ndarray:
        """Incremental stiffness per unit area dp̄/dU (Pa/m) at pressures ``p``.

        From the slope of U against ln p̄ (PCHIP through the BEM points):
        dp̄/dU = p̄ / (dU/d ln p̄).
        """
        from scipy.interpolate import PchipInterpolator  # SciPy on use: start-up

        lnp = np.log(self.pressure)
        dU = PchipInterpolator(lnp, self.approach).derivative()(np.log(p))
        return np.asarray(p) / dU

    def local_gamma_sigma(self) -> np.ndarray:
        """γσ(p̄) = p̄ / (dp̄/dU) = dU/d ln p̄ at the BEM pressures (m)."""
        return np.gradient(self.approach, np.log(self.pressure))


def bem_normal_law(surface: SurfaceMap, contact_modulus: float, pressures: np.ndarray, *,
                   tolerance: float = 1e-6, maxiter: int = 20000) -> BEMLaw:
    """Mean gap and contact fraction of a rigid rough surface on an elastic flat.

    Load-controlled constrained conjugate gradients (Polonsky & Keer 1999) on a periodic
    FFT half-space of contact modulus E* (ContactMechanics), each load solved from rest
    (a warm start from the previous load's forces can stall on that load's contact set).

    Parameters
    ----------
    surface : SurfaceMap
        Composite height map (m).
    contact_modulus : float
        E* in Pa.
    pressures : (K,) array
        Nominal pressures p̄ in Pa, increasing, > 0.
    tolerance : float
        Penetration tolerance relative to σ, and force tolerance relative to the mean force
        per grid point.
    maxiter : int
        Iterations allowed per load.

    Returns
    -------
    BEMLaw

    Raises
    ------
    SolverError
        When the solver does not converge at some load.
    """
    require_topo()
    from ContactMechanics import PeriodicFFTElasticHalfSpace  # optional extra
    from ContactMechanics.Optimization import constrained_conjugate_gradients
    from SurfaceTopography import Topography

    p = np.asarray(pressures, float)
    if surface.flat:   # the solver would iterate to maxiter on a map of round-off
        raise InputError("topography", f"the height map is flat (rms height "
                         f"{surface.rms_height:.3g} m): no rough-contact law")
    h = surface.heights
    topo = Topography(h, surface.size, periodic=True)
    sub = PeriodicFFTElasticHalfSpace(h.shape, contact_modulus, surface.size)
    area = surface.size[0] * surface.size[1]
    pentol = tolerance * max(surface.rms_height, 1e-300)
    gaps, frac = np.empty(p.size), np.empty(p.size)
    iters = 0
    for k, pk in enumerate(p):
        F = pk * area
        res = constrained_conjugate_gradients(
            sub, topo, external_force=F, pentol=pentol,
            forcetol=tolerance * F / h.size, maxiter=maxiter)
        if not res.success:
            raise SolverError(f"BEM contact did not converge at nominal pressure {pk:g} Pa "
                              f"({res.message}); reduce bem_grid or the loads")
        iters += int(res.nit)
        gap = np.maximum(res.x - h - res.offset, 0.0)
        gaps[k] = gap.mean()
        frac[k] = float(np.mean(res.jac > 0))
    g0 = float(h.max() - h.mean())
    return BEMLaw(p, g0 - gaps, gaps, frac, g0, float(contact_modulus), h.shape,
                  surface.size, surface.rms_height, iters)


def cache_dir() -> Path:
    """Where BEM laws are cached.

    ``$SLIPCYCLE_CACHE`` if set, else ``$XDG_CACHE_HOME/slipcycle/bem`` (default
    ``~/.cache/slipcycle/bem``).
    """
    env = os.environ.get("SLIPCYCLE_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "slipcycle" / "bem"


def cached_bem_normal_law(surface: SurfaceMap, contact_modulus: float, pressures: np.ndarray,
                          *, tolerance: float = 1e-6, directory: Path | None = None
                          ) -> tuple[BEMLaw, Path | None, bool]:
    """:func:`bem_normal_law`, read from or written to the cache.

    The cache key is the SHA-256 of the height map, its size, E*, the pressures, the
    tolerance and the recipe version. An unwritable cache is skipped silently (the law is
    still returned).

    Returns
    -------
    law : BEMLaw
    path : Path or None
        The cache file (None when it could not be written).
    hit : bool
        Whether the law came from the cache.
    """
    p = np.asarray(pressures, float)
    key = hashlib.sha256((surface.digest() + repr((float(contact_modulus), p.tolist(),
                                                   float(tolerance), _CACHE_VERSION))
                          ).encode()).hexdigest()[:24]
    path = (directory or cache_dir()) / f"bem-{key}.npz"
    if path.is_file():
        try:
            with np.load(path) as z:
                law = BEMLaw(z["pressure"], z["approach"], z["mean_gap"],
                             z["contact_fraction"], float(z["first_touch_gap"]),
                             float(z["contact_modulus"]), tuple(int(v) for v in z["grid"]),
                             tuple(float(v) for v in z["size"]), float(z["rms_height"]),
                             int(z["iterations"]))
            return law, path, True
        except (OSError, KeyError, ValueError):
            pass   # a damaged cache file is recomputed
    law = bem_normal_law(surface, contact_modulus, p, tolerance=tolerance)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
        np.savez(tmp, pressure=law.pressure, approach=law.approach, mean_gap=law.mean_gap,
                 contact_fraction=law.contact_fraction, first_touch_gap=law.first_touch_gap,
                 contact_modulus=law.contact_modulus, grid=np.array(law.grid),
                 size=np.array(law.size), rms_height=law.rms_height,
                 iterations=law.iterations)
        os.replace(tmp, path)
    except OSError:
        return law, None, False
    return law, path, False


@dataclass(frozen=True)
class ExponentialFit:
    """Where dP/dU = P/(γσ) holds in a tabulated law (:func:`fit_exponential`).

    Attributes
    ----------
    gamma_sigma : float
        Least-squares γσ (m) over the load window: the slope of U against ln P.
    load_range : (float, float)
        Window of loads (same unit as the P given) over which the local γσ stays within
        ``tolerance`` of ``gamma_sigma``; (nan, nan) when no window of 3 points does.
    tolerance : float
        The criterion: max |γσ_local/γσ − 1| ≤ tolerance in the window.
    max_deviation : float
        max |γσ_local/γσ − 1| in the window.
    local_gamma_sigma : (K,) array
        dU/d ln P at every point (m).
    in_range : (K,) bool array
    """

    gamma_sigma: float
    load_range: tuple[float, float]
    tolerance: float
    max_deviation: float
    local_gamma_sigma: np.ndarray
    in_range: np.ndarray = field(repr=False)

    @property
    def decades(self) -> float:
        """Width of the window in decades of load."""
        lo, hi = self.load_range
        return float(np.log10(hi / lo)) if np.isfinite(lo) else 0.0


def fit_exponential(P: np.ndarray, U: np.ndarray, tolerance: float = 0.1) -> ExponentialFit:
    """Fit P = P_ref exp(U/γσ) where it applies (Barber 2012, eq. 10).

    The local γσ(P) = dU/d ln P is computed at every point (second-order differences in
    ln P); the fit window is the contiguous run of points that is widest in ln P among
    those whose local γσ all lie within ``tolerance`` of the window's least-squares γσ
    (slope of U against ln P).

    Parameters
    ----------
    P : (K,) array
        Loads (N, or pressures in Pa), > 0, increasing, K ≥ 3.
    U : (K,) array
        Approaches (m), increasing.
    tolerance : float
        Relative band on the local γσ (default 10 %).

    Returns
    -------
    ExponentialFit
    """
    P, U = np.asarray(P, float), np.asarray(U, float)
    x = np.log(P)
    local = np.gradient(U, x)
    best = (-1.0, None)
    K = P.size
    for i in range(K - 2):
        for j in range(K - 1, i + 1, -1):
            if x[j] - x[i] <= best[0]:
                break
            g = np.polyfit(x[i:j + 1], U[i:j + 1], 1)[0]
            dev = np.max(np.abs(local[i:j + 1] / g - 1.0)) if g > 0 else np.inf
            if dev <= tolerance:
                best = (x[j] - x[i], (i, j, g, dev))
                break
    mask = np.zeros(K, bool)
    if best[1] is None:
        return ExponentialFit(float("nan"), (float("nan"), float("nan")), tolerance,
                              float("nan"), local, mask)
    i, j, g, dev = best[1]
    mask[i:j + 1] = True
    return ExponentialFit(float(g), (float(P[i]), float(P[j])), tolerance, float(dev), local,
                          mask)


def convex_minorant(U: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower convex hull of the points (U, P), U increasing (Andrew's monotone chain).

    A slider bed exists only for a convex law (non-decreasing stiffness); rounding noise of a
    dense table is removed this way without moving the points that are on the hull.
    """
    hull: list[int] = []
    for k in range(U.size):
        while len(hull) >= 2:
            a, b = hull[-2], hull[-1]
            # drop b when it lies on or above the chord a–k
            if (P[b] - P[a]) * (U[k] - U[a]) >= (P[k] - P[a]) * (U[b] - U[a]):
                hull.pop()
            else:
                break
        hull.append(k)
    idx = np.array(hull)
    return U[idx], P[idx]


def smooth_table(law: BEMLaw, nominal_area: float, n_points: int) -> Tabulated:
    """A dense convex table P(U) of a BEM law, for the slider bed.

    U(ln p̄) is interpolated by PCHIP through the BEM points (shape preserving), sampled at
    ``n_points`` loads equally spaced between the smallest and largest BEM pressure (equal
    load steps: the slider bed's resolution, as for the exponential law), prefixed with
    first touch (0, 0), and made convex by :func:`convex_minorant`.

    Parameters
    ----------
    law : BEMLaw
    nominal_area : float
        A in m²: P = A p̄.
    n_points : int
        Table points (≈ sliders).

    Returns
    -------
    Tabulated
        P in N, U in m.
    """
    from scipy.interpolate import PchipInterpolator  # SciPy on use: start-up

    interp = PchipInterpolator(np.log(law.pressure), law.approach)
    p = np.linspace(law.pressure[0], law.pressure[-1], max(int(n_points), 2))
    U = np.concatenate([[0.0], interp(np.log(p))])
    P = np.concatenate([[0.0], p * nominal_area])
    U, P = convex_minorant(U, P)
    return Tabulated(U, P)


#: the units a P(U) table's netCDF variables may carry (``units`` attribute), in SI
_TABLE_UNITS = {"U": {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "micron": 1e-6,
                      "nm": 1e-9},
                "P": {"N": 1.0, "kN": 1e3, "mN": 1e-3}}


def _is_netcdf(path: Path) -> bool:
    """Whether ``path`` is a netCDF file (classic or HDF5), by its first bytes, whatever
    its extension."""
    head = _first_bytes(path)
    if head is None:
        return path.suffix.lower() in (".nc", ".nc4", ".netcdf")
    return head.startswith(_NETCDF_MAGIC)


def _in_si(var, units: dict, key: str, path: Path) -> np.ndarray:
    """A table variable in SI units from its ``units`` attribute (none: SI already)."""
    unit = str(var.attrs.get("units", "")).strip()
    if unit and unit not in units:
        raise InputError(key, f"{path.name}: variable {var.name} has units {unit!r}; "
                         f"known: {', '.join(units)}")
    return np.asarray(var.values, float) * units.get(unit, 1.0)


def read_table_file(path: Path, key: str = "table_file") -> tuple[np.ndarray, np.ndarray]:
    """A tabulated P(U) from a CSV (header naming ``U`` and ``P``) or netCDF file.

    Parameters
    ----------
    path : Path
        ``.csv`` with a header line holding columns ``U`` [m] and ``P`` [N] (other columns
        ignored; a leading byte-order mark is skipped), or netCDF (recognised by its
        content) with variables ``U`` and ``P``, in m and N unless their ``units``
        attribute says mm, um, nm / kN, mN.
    key : str
        Case-file key blamed for problems.

    Returns
    -------
    U, P : (K,) arrays
        Unchecked values (the case reader checks them like inline tables).
    """
    try:
        if _is_netcdf(path):
            with xr.open_dataset(path) as ds:
                U = _in_si(ds["U"], _TABLE_UNITS["U"], key, path)
                P = _in_si(ds["P"], _TABLE_UNITS["P"], key, path)
        else:
            # utf-8-sig: a spreadsheet's CSV starts with a byte-order mark
            data = np.genfromtxt(path, delimiter=",", names=True, dtype=float,
                                 deletechars="", autostrip=True, encoding="utf-8-sig")
            names = data.dtype.names or ()
            if "U" not in names or "P" not in names:
                raise ValueError(f"needs a header with columns U and P, found {names}")
            U, P = np.atleast_1d(data["U"]), np.atleast_1d(data["P"])
    except (OSError, ValueError, KeyError) as exc:
        raise InputError(key, f"cannot read P(U) table {path}: "
                         f"{' '.join(str(exc).split())}") from None
    if U.ndim != 1 or U.shape != P.shape or not np.all(np.isfinite(U) & np.isfinite(P)):
        raise InputError(key, f"columns U and P of {path} must be finite and of equal length")
    return U, P


#: bytes per grid point of one BEM solve: the constrained conjugate gradients keep about 20
#: real fields (heights, forces, gaps, residual, direction, ...) and the half-space its
#: Fourier weights and transforms; 2.3 GB were measured on the way up at 4096²
BEM_BYTES_PER_POINT = 256.0


def bem_memory(n: int) -> float:
    """Bytes (order of magnitude) of a BEM solve on an n × n grid."""
    return BEM_BYTES_PER_POINT * float(n) ** 2


def check_bem_memory(key: str, n: int) -> None:
    """Refuse (InputError naming ``key``) a BEM grid of n × n points that would need more
    memory than :func:`slipcycle.io.sizes.memory_limit`, before any work."""
    from slipcycle.io import CaseError
    from slipcycle.io.sizes import check_memory

    try:
        check_memory(key, bem_memory(n), f"BEM grids of {n} x {n} points",
                     advice="reduce bem_grid (Fourier resampling keeps the wavelengths "
                     "longer than two of its pixels)")
    except CaseError as exc:
        raise InputError(key, exc.problem) from None


#: the last map read by :meth:`TopographySource.native` and the key it was read with
_LAST_NATIVE: dict = {}


@dataclass(frozen=True)
class TopographySource:
    """A case's rough interface: topography file, BEM settings and the fit.

    Attributes
    ----------
    path : Path
        Topography file (any SurfaceTopography format).
    nominal_area : float
        A in m² (P = A p̄).
    contact_modulus : float
        E* in Pa (:class:`~slipcycle.halfspace.elastic.ContactElasticity`).
    fit : {"table", "exponential"}
        Feed the slider bed the BEM table or the fitted exponential law.
    bem_grid : int or None
        Grid points per side of the BEM (Fourier resampling); None: the file's grid.
    bem_loads : int
        BEM pressures (log-spaced).
    fit_tolerance : float
        Band on the local γσ for the exponential fit.
    short_cutoff, long_cutoff : float or None
        Wavelength filter (m) applied before the BEM.
    fill_undefined : bool
        Interpolate undefined height points (refused by default).
    size : (float, float) or None
        (Lx, Ly) in m of a file that gives no size (NPY, plain-text matrix).
    label : str
        Dotted case-file key of the file, for the warning about filled points.
    """

    path: Path
    nominal_area: float
    contact_modulus: float
    fit: str = "table"
    bem_grid: int | None = None
    bem_loads: int = 24
    fit_tolerance: float = 0.1
    short_cutoff: float | None = None
    long_cutoff: float | None = None
    fill_undefined: bool = False
    size: tuple[float, float] | None = None
    label: str = field(default="topography_file", compare=False)

    def __post_init__(self):
        for name in ("nominal_area", "contact_modulus"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise InputError(name, f"must be a finite number > 0, got {v!r}")
        if self.fit not in ("table", "exponential"):
            raise InputError("fit", f"must be 'table' or 'exponential', got {self.fit!r}")
        if self.bem_grid is not None and not 8 <= self.bem_grid <= 4096:
            raise InputError("bem_grid", f"must be in [8, 4096], got {self.bem_grid}")
        if not 4 <= self.bem_loads <= 400:
            raise InputError("bem_loads", f"must be in [4, 400], got {self.bem_loads}")
        if not 0 < self.fit_tolerance < 1:
            raise InputError("fit_tolerance", f"must be in (0, 1), got {self.fit_tolerance}")
        lo, hi = self.short_cutoff, self.long_cutoff
        if lo is not None and hi is not None and not lo < hi:
            raise InputError("short_cutoff", f"must be < long_cutoff ({hi:g} m), got {lo:g} "
                             "m: the filter keeps wavelengths between the two and would keep "
                             "none")

    def native(self) -> SurfaceMap:
        """The file's map in m, filtered, on its own grid (read once: the warning about
        filled points is said once however often the map is used)."""
        cached = self.__dict__.get("_native")
        if cached is not None:
            return cached
        # parse_case and the roughness study each build a source of the same case: the
        # last map read is kept, keyed by the file's identity and the settings
        stat = self.path.stat()
        key = (str(self.path.resolve()), stat.st_mtime_ns, stat.st_size, self.fill_undefined,
               self.short_cutoff, self.long_cutoff, self.size)
        if _LAST_NATIVE.get("key") == key:
            object.__setattr__(self, "_native", _LAST_NATIVE["map"])
            return _LAST_NATIVE["map"]
        s = read_surface(self.path, key="topography_file", fill_undefined=self.fill_undefined,
                         label=self.label, size=self.size)
        if self.short_cutoff is not None or self.long_cutoff is not None:
            s = filter_surface(s, self.short_cutoff, self.long_cutoff)
            if s.flat:
                lo = f"{self.short_cutoff:g} m" if self.short_cutoff is not None else "0"
                hi = f"{self.long_cutoff:g} m" if self.long_cutoff is not None else "the map"
                raise InputError("short_cutoff" if self.short_cutoff is not None else
                                 "long_cutoff", f"keeps no wavelength of {self.path.name} "
                                 f"(wavelengths from {lo} to {hi} leave a flat surface; the "
                                 f"map spans {2 * s.pixel:.3g} m to {max(s.size):.3g} m)")
        object.__setattr__(self, "_native", s)   # frozen: the cache is not a field
        _LAST_NATIVE.update(key=key, map=s)
        return s

    def surface(self) -> SurfaceMap:
        """The filtered map on the BEM grid (refused when its BEM would not fit in memory)."""
        s = self.native()
        n = self.bem_grid or max(s.grid)
        check_bem_memory("bem_grid" if self.bem_grid else "topography_file", n)
        return resample(s, self.bem_grid) if self.bem_grid else s

    def pressures(self, p_max: float) -> np.ndarray:
        """BEM pressures: ``bem_loads`` log-spaced over three decades up to 1.25 p_max."""
        hi = 1.25 * p_max
        return np.geomspace(hi * 1e-3, hi, self.bem_loads)

    def check_pressure(self, p_max: float, surface: SurfaceMap | None = None) -> None:
        """Refuse (``nominal_area``) BEM pressures up to 1.25 ``p_max`` (Pa) beyond the
        complete contact of the map on the BEM grid (there the approach stops changing, the
        normal law ends and the BEM cannot converge), or below :data:`MIN_PRESSURE_RATIO`
        × E*."""
        s = self.surface() if surface is None else surface
        if not 1.25 * p_max >= MIN_PRESSURE_RATIO * self.contact_modulus:
            # the BEM's iteration stalls far below (7.5e-20 Pa: no convergence in 20000
            # steps, exit 3); such a contact touches at a few points of the map
            raise InputError("nominal_area", f"the largest nominal pressure, "
                             f"{1.25 * p_max:.3g} Pa (1.25 x largest load / nominal_area), "
                             f"is below {MIN_PRESSURE_RATIO:g} E* "
                             f"({MIN_PRESSURE_RATIO * self.contact_modulus:.3g} Pa): check "
                             "nominal_area (m²) and the units of the loads")
        p_full = s.complete_contact_pressure(self.contact_modulus)
        if 1.25 * p_max >= p_full:
            raise InputError("nominal_area", f"the BEM would press the surface up to "
                             f"{1.25 * p_max:.3g} Pa (1.25 x largest load / nominal_area), "
                             f"beyond its complete contact at {p_full:.3g} Pa, where the "
                             "rough law ends; increase nominal_area or reduce the loads")

    def law(self, P_max: float) -> tuple[BEMLaw, Path | None, bool]:
        """The (cached) BEM law covering loads up to ``P_max`` (N): the one law of the joint
        that ``slipcycle run`` and ``slipcycle roughness`` both use."""
        surface = self.surface()
        self.check_pressure(P_max / self.nominal_area, surface)
        return cached_bem_normal_law(surface, self.contact_modulus,
                                     self.pressures(P_max / self.nominal_area))

    def profile(self, P_max: float, n_points: int):
        """The normal law for the slider bed, covering loads up to ``P_max`` (N).

        Returns
        -------
        Tabulated or RoughExponential
        """
        return self.profile_of(self.law(P_max)[0], n_points)

    def profile_of(self, law: BEMLaw, n_points: int):
        """The slider-bed law of a BEM law: its convex table, or its fitted exponential.

        Returns
        -------
        Tabulated or RoughExponential
        """
        if self.fit == "table":
            return smooth_table(law, self.nominal_area, n_points)
        fit = fit_exponential(law.pressure, law.approach, self.fit_tolerance)
        if not np.isfinite(fit.gamma_sigma):
            raise InputError("fit", "no load window where dP/dU = P/(γσ) holds within "
                             f"{self.fit_tolerance:.0%}; use fit = \"table\"")
        return RoughExponential(fit.gamma_sigma)

    def describe(self, profile) -> dict:
        """What a run's summary says of the surface behind its law ``profile`` (the
        result of :meth:`profile`): the file, the map as read (points, size, σ after the
        wavelength filter), the BEM grid, the fit and, for the exponential fit, γσ (units
        in :data:`SURFACE_UNITS`)."""
        native = self.native()
        entries = {"file": self.path.name,
                   "map_points": [int(k) for k in native.heights.shape],
                   "map_size": [float(v) for v in native.size],
                   "rms_height": native.rms_height,
                   "bem_grid": int(self.bem_grid or max(native.heights.shape)),
                   "nominal_area": self.nominal_area, "fit": self.fit}
        if isinstance(profile, RoughExponential):
            entries["gamma_sigma"] = float(profile.gamma_sigma)
        return entries


#: smallest largest nominal pressure of a BEM law, relative to E* (:meth:`TopographySource.
#: check_pressure`): the BEM converges down to about 1e-17 E* on the example surface
MIN_PRESSURE_RATIO = 1e-12

#: units of the numeric entries of :meth:`TopographySource.describe`
SURFACE_UNITS = {"map_points": "1", "map_size": "m", "rms_height": "m", "bem_grid": "1",
                 "nominal_area": "m2", "gamma_sigma": "m"}


#: keys of ``[halfspace]`` read for ``profile = "topography"`` (besides E, nu, friction, ...)
SOURCE_KEYS = ("topography_file", "nominal_area", "fit", "bem_grid", "bem_loads",
               "fit_tolerance", "short_cutoff", "long_cutoff", "fill_undefined",
               "topography_size")


def read_source(sec, contact_modulus: float) -> TopographySource:
    """The :class:`TopographySource` of a ``[halfspace]`` table (a case-file Section).

    Keys: ``topography_file`` (relative to the case file), ``nominal_area`` [m²], ``fit``
    (``"table"`` default, or ``"exponential"``), ``bem_grid`` (points per side),
    ``bem_loads`` (default 24), ``fit_tolerance`` (default 0.1), ``short_cutoff`` and
    ``long_cutoff`` [m] (wavelength filter), ``fill_undefined`` (default false: undefined
    height points are refused with their count; true interpolates them),
    ``topography_size`` ([Lx, Ly] in m, for NPY files and plain-text matrices, which give no
    size).

    Raises
    ------
    CaseError
        Through ``sec.error``, keyed by the full dotted key.
    """
    def opt_int(key):
        return sec.int(key, ge=1) if sec.has(key) else None

    size = sec.array("topography_size", None, shape=(2,), gt=0.0)
    size = None if size is None else (float(size[0]), float(size[1]))

    settings = dict(
        path=sec.path("topography_file"), nominal_area=sec.float("nominal_area", gt=0.0),
        contact_modulus=contact_modulus,
        fit=sec.string("fit", "table", choices=("table", "exponential")),
        bem_grid=opt_int("bem_grid"), bem_loads=sec.int("bem_loads", 24),
        fit_tolerance=sec.float("fit_tolerance", 0.1),
        short_cutoff=sec.float("short_cutoff", None, gt=0.0),
        long_cutoff=sec.float("long_cutoff", None, gt=0.0),
        fill_undefined=sec.bool("fill_undefined", False), label=sec.key("topography_file"),
        size=size)
    try:
        source = TopographySource(**settings)
        source.surface()            # the file's units, undefined points, flatness: now
    except InputError as exc:
        raise sec.error(exc.key, exc.problem) from None
    return source


def largest_normal_load(normal, protocol: np.ndarray, steps: int) -> float:
    """Largest normal load (N) of a force-controlled history: cycle samples and protocol."""
    theta = np.linspace(0.0, 2 * np.pi, max(int(steps), 8) + 1)
    vals = np.concatenate([np.asarray(normal(theta))[:, 0], np.asarray(protocol)[:, 0]])
    return float(vals.max())


def topography_profile(sec, source: TopographySource, normal, normal_control: str,
                       protocol: np.ndarray, steps: int, n_sliders: int):
    """The slider-bed normal law of a ``profile = "topography"`` case (BEM, cached).

    Parameters
    ----------
    sec : Section
        The ``[halfspace]`` table (for the keys of errors).
    source : TopographySource
    normal : PeriodicLoad
        Normal load P(θ) (N); ``normal_control`` must be ``"force"``.
    protocol : (S, 2) array
        Assembly states (normal, tangential).
    steps : int
        Samples per cycle used to find the largest load.
    n_sliders : int
        Table points of the ``"table"`` fit.

    Returns
    -------
    Tabulated or RoughExponential
    """
    if normal_control != "force":
        raise sec.error("profile", "a topography law needs force control of the normal load "
                        "(P0, P1): the approach is measured from the BEM's first touch")
    P_max = largest_normal_load(normal, protocol, steps)
    if not P_max > 0:
        raise sec.error("profile", "the normal load never compresses the contact")
    try:
        return source.profile(P_max, n_sliders)
    except InputError as exc:
        raise sec.error(exc.key if exc.key in SOURCE_KEYS else "topography_file",
                        exc.problem) from None
