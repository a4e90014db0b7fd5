"""Mesh convergence of a scalar result: observed order and Richardson extrapolation.

A quantity computed on meshes of node spacing h₁ > h₂ > h₃ (coarse → fine) is modelled
as f(h) = c + k hᵖ (Richardson 1911; Roache 1998, *Verification and Validation in
Computational Science and Engineering*, ch. 5; Celik et al. 2008, J. Fluids Eng. 130,
078001). From the last three meshes the observed order p solves

    (h₁ᵖ − h₂ᵖ) / (h₂ᵖ − h₃ᵖ) = (f₂ − f₁) / (f₃ − f₂),

which reduces to p = ln[(f₂ − f₁)/(f₃ − f₂)] / ln r for a constant refinement ratio
r = h₁/h₂ = h₂/h₃ (the left-hand side is increasing in p, so the root is unique); the
extrapolated value is c = f₃ + (f₃ − f₂)/((h₂/h₃)ᵖ − 1) and the estimated relative
error of the finest value is |f₃ − c| / |c|. With two meshes the same extrapolation
assumes p = 1 (the order of linear elements in the contact tractions' integral; flagged
in the message). A sequence whose differences change sign is not in the asymptotic
range: it is reported as not converged, with no order and no extrapolation.

A dissipation that extrapolates to zero (or through it) vanishes under refinement: the
finest value is then a discretisation effect, and its relative error is infinite.

Meshes that differ too little say nothing about the error: two pre-asymptotic meshes of
nearly the same spacing can agree by chance. A sequence whose refinement ratios (between
the meshes the estimate uses) fall below :data:`MIN_RATIO` = 1.3 (Celik et al. 2008) is
never called converged and gets no order and no extrapolation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from slipcycle.errors import InputError

__all__ = ["MeshConvergence", "mesh_convergence", "P_BRACKET", "MIN_RATIO"]

#: smallest refinement ratio h_coarse/h_fine of an error estimate (Celik et al. 2008)
MIN_RATIO: float = 1.3

#: observed orders searched for; beyond it the order is reported as not measurable
P_BRACKET: float = 30.0
#: differences smaller than this fraction of the largest |value| count as zero (round-off)
_ZERO_DIFF: float = 1e-12
#: an extrapolated value below this fraction of the finest one is zero (the extrapolation
#: amplifies round-off of the differences)
_ZERO_LIMIT: float = 1e-9


@dataclass(frozen=True)
class MeshConvergence:
    """A quantity on a sequence of meshes and what it says about mesh convergence.

    Attributes
    ----------
    spacing : tuple of float
        Node spacing h of each mesh [m], coarse → fine (strictly decreasing).
    values : tuple of float
        The quantity on each mesh (e.g. dissipation per cycle [J or J/m]).
    observed_order : float or None
        Order p from the last three meshes; None with two meshes, for a non-monotone
        sequence, or where no order in [−30, 30] fits.
    extrapolated : float or None
        Richardson extrapolation to h → 0; None where it is meaningless (non-monotone or
        diverging sequence).
    relative_error : float or None
        Estimated relative error of the finest value, |f_fine − c|/|c| (inf where c is
        zero or of the opposite sign: the quantity vanishes under refinement).
    converged : bool
        ``relative_error ≤ rtol`` and a positive order (observed, or assumed first order
        with two meshes).
    message : str
        One sentence for summaries and reports.
    unit : str
        Unit of ``values`` and ``extrapolated`` (for summaries).
    """

    spacing: tuple[float, ...]
    values: tuple[float, ...]
    observed_order: float | None
    extrapolated: float | None
    relative_error: float | None
    converged: bool
    message: str
    unit: str = "J"

    @property
    def order_assumed(self) -> bool:
        """Whether the extrapolation assumed first order (two meshes only)."""
        return len(self.values) == 2

    def summary(self, prefix: str = "") -> dict:
        """A flat dictionary for a result's ``summary()``, with its ``units`` map.

        Parameters
        ----------
        prefix : str, optional
            Prepended to every key (e.g. ``"dissipation_"``).

        Returns
        -------
        dict
            ``mesh_spacing`` [m], ``mesh_values`` [unit], ``observed_order`` [1],
            ``extrapolated`` [:attr:`unit`], ``relative_error`` [1], ``mesh_converged``,
            ``mesh_order_assumed``, ``mesh_message`` (each with ``prefix``) and ``units``.
        """
        p, unit = prefix, self.unit
        out = {
            f"{p}mesh_spacing": list(self.spacing),
            f"{p}mesh_values": list(self.values),
            f"{p}observed_order": self.observed_order,
            f"{p}extrapolated": self.extrapolated,
            f"{p}relative_error": self.relative_error,
            f"{p}mesh_converged": bool(self.converged),
            f"{p}mesh_order_assumed": self.order_assumed,
            f"{p}mesh_message": self.message,
        }
        out["units"] = {f"{p}mesh_spacing": "m", f"{p}mesh_values": unit,
                        f"{p}observed_order": "1", f"{p}extrapolated": unit,
                        f"{p}relative_error": "1"}
        return out


def _log_ratio(p: float, a: float, b: float) -> float:
    """ln[(h₁ᵖ − h₂ᵖ)/(h₂ᵖ − h₃ᵖ)] with a = ln(h₁/h₂), b = ln(h₂/h₃) (increasing in p)."""
    if p == 0.0:
        return math.log(a / b)
    return p * b + _log_abs_expm1(p * a) - _log_abs_expm1(p * b)


def _log_abs_expm1(x: float) -> float:
    """ln|eˣ − 1| without overflow."""
    if x > 30.0:
        return x + math.log1p(-math.exp(-x))
    return math.log(abs(math.expm1(x)))


def _observed_order(h: Sequence[float], log_target: float) -> float:
    """The order p with _log_ratio(p) = log_target, by bisection (±inf beyond ±P_BRACKET)."""
    a, b = math.log(h[0] / h[1]), math.log(h[1] / h[2])
    lo, hi = -P_BRACKET, P_BRACKET
    if log_target < _log_ratio(lo, a, b):
        return -math.inf
    if log_target > _log_ratio(hi, a, b):
        return math.inf
    for _ in range(200):  # the function is monotone: bisection to a few ulp
        mid = 0.5 * (lo + hi)
        if _log_ratio(mid, a, b) < log_target:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 4e-16 * max(1.0, abs(mid)):
            break
    return 0.5 * (lo + hi)


def _check(spacing, values, rtol) -> tuple[tuple[float, ...], tuple[float, ...]]:
    h = tuple(float(x) for x in spacing)
    f = tuple(float(x) for x in values)
    if len(h) != len(f):
        raise InputError("values", f"{len(h)} spacings but {len(f)} values")
    if len(h) < 2:
        raise InputError("spacing", "mesh convergence needs at least two meshes")
    if not all(math.isfinite(x) and x > 0 for x in h):
        raise InputError("spacing", f"node spacings must be finite and > 0: {h}")
    if any(h1 <= h2 for h1, h2 in zip(h, h[1:], strict=False)):
        raise InputError("spacing", f"must decrease strictly, coarse → fine: {h}")
    if not all(math.isfinite(x) for x in f):
        raise InputError("values", f"must be finite: {f}")
    if not (math.isfinite(rtol) and rtol > 0):
        raise InputError("rtol", f"must be > 0, got {rtol}")
    return h, f


def _relative_error(fine: float, c: float) -> float:
    """|fine − c|/|c|; inf where c is zero (to round-off) or of the other sign than fine."""
    other_sign = fine != 0.0 and math.copysign(1.0, c) != math.copysign(1.0, fine)
    if abs(c) <= _ZERO_LIMIT * abs(fine) or other_sign:
        return math.inf
    return abs(fine - c) / abs(c)


def mesh_convergence(spacing: Sequence[float], values: Sequence[float], *,
                     rtol: float = 0.05, unit: str = "J") -> MeshConvergence:
    """Observed order, Richardson extrapolation and convergence verdict of a mesh sequence.

    Parameters
    ----------
    spacing : sequence of float, shape (m,), m ≥ 2
        Node spacing h of each mesh [m], coarse → fine (strictly decreasing).
    values : sequence of float, shape (m,)
        The quantity on each mesh (e.g. dissipation per cycle).
    rtol : float, optional
        Largest estimated relative error of the finest value for ``converged``.
    unit : str, optional
        Unit of ``values``, used in the message.

    Returns
    -------
    MeshConvergence

    Raises
    ------
    InputError
        Fewer than two meshes, lengths that differ, spacings that are not positive and
        strictly decreasing, non-finite values, or rtol ≤ 0.

    Notes
    -----
    Model f(h) = c + k hᵖ from the last three meshes (Roache 1998, ch. 5; Celik et al.
    2008, J. Fluids Eng. 130, 078001, which also covers non-constant refinement ratios).
    Non-monotone sequences (differences of both signs over all meshes) are not in the
    asymptotic range: not converged, no order, no extrapolation.
    """
    h, f = _check(spacing, values, rtol)
    scale = max(abs(x) for x in f)
    tiny = _ZERO_DIFF * scale
    diffs = [f2 - f1 for f1, f2 in zip(f, f[1:], strict=False)]
    d = [0.0 if abs(x) <= tiny else x for x in diffs]
    n = len(f)
    fine = f[-1]

    used = h[-3:] if n >= 3 else h[-2:]
    ratio = min(a / b for a, b in zip(used, used[1:], strict=False))

    def result(order, c, rel, converged, message):
        if ratio < MIN_RATIO * (1.0 - 1e-9):
            # an estimate from such meshes would look precise and mean nothing
            return MeshConvergence(
                h, f, None, None, None, False,
                f"NOT shown mesh-converged: the meshes are too close to estimate the error "
                f"(refinement ratio {ratio:.3g} < {MIN_RATIO:g}, Celik et al. 2008); values "
                f"{_fmt(f)} {unit}; use meshes at least {MIN_RATIO:g} times apart", unit)
        return MeshConvergence(h, f, order, c, rel, bool(converged), message, unit)

    def verdict(rel: float) -> str:
        if math.isinf(rel):
            return (f"the value extrapolates to {c:.4g} {unit} (zero or opposite sign): it "
                    f"vanishes under refinement and the finest value {fine:.4g} {unit} is "
                    "a discretisation effect")
        return (f"finest value {fine:.4g} {unit}, extrapolated {c:.4g} {unit}, estimated "
                f"relative error {rel:.2g} (tolerance {rtol:g})")

    if all(x == 0.0 for x in d):
        return result(None, fine, 0.0, True,
                      f"mesh-converged: the same value {fine:.4g} {unit} on all {n} meshes")
    signs = {math.copysign(1.0, x) for x in d if x != 0.0}
    if len(signs) > 1 or (n >= 3 and d[-2] == 0.0):
        return result(None, None, None, False,
                      f"NOT mesh-converged: the values {_fmt(f)} {unit} are not monotone "
                      "under refinement (not in the asymptotic range); refine further")
    if n == 2:
        c = fine + d[-1] / (h[0] / h[1] - 1.0)
        rel = _relative_error(fine, c)
        ok = rel <= rtol
        word = "mesh-converged" if ok else "NOT mesh-converged"
        return result(None, c, rel, ok,
                      f"{word} (two meshes, first order assumed): {verdict(rel)}")
    h3 = h[-3:]
    if d[-1] == 0.0:
        # the finest two meshes agree to round-off: faster than any measurable order
        return result(None, fine, 0.0, True,
                      f"mesh-converged: the finest two meshes agree ({fine:.4g} {unit})")
    p = _observed_order(h3, math.log(d[-2] / d[-1]))
    if p == math.inf:  # converging faster than any order within the bracket
        rel = abs(d[-1]) / abs(fine) if fine else math.inf
        ok = rel <= rtol
        return result(None, fine, rel, ok,
                      f"{'mesh-converged' if ok else 'NOT mesh-converged'}: the last change "
                      f"is {rel:.2g} of the finest value {fine:.4g} {unit} (order > "
                      f"{P_BRACKET:g}, not measurable)")
    if p <= 0.0:
        shown = f"{p:.3g}" if math.isfinite(p) else f"< -{P_BRACKET:g}"
        return result(p if math.isfinite(p) else None, None, None, False,
                      f"NOT mesh-converged: the differences grow under refinement "
                      f"(observed order {shown}); values {_fmt(f)} {unit}")
    c = fine + d[-1] / math.expm1(p * math.log(h3[1] / h3[2]))
    rel = _relative_error(fine, c)
    ok = rel <= rtol
    word = "mesh-converged" if ok else "NOT mesh-converged"
    return result(p, c, rel, ok, f"{word} (observed order {p:.3g}): {verdict(rel)}")


def _fmt(values: Sequence[float]) -> str:
    return "[" + ", ".join(f"{x:.4g}" for x in values) + "]"
