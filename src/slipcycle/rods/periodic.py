"""Periodic steady state of the discrete modal model by semismooth Newton on δ(t).

The time-stepping scheme of :mod:`slipcycle.rods.modal` (exact modal step for forcing
linear over the step, implicit end-of-step interface torque) is linear time-invariant in
everything but the interface bed. Over a periodic sequence of K steps its periodic
response is therefore exact in the discrete Fourier domain (harmonic j, E_j = e^{2πij/K}):
mode k obeys z_{s+1} = A_k z_s + B0_k f_s + B1_k f_{s+1} with f_s = −b_k T_s − g_k Θ̈_s, so

    ẑ_j = (E_j I − A_k)⁻¹ (B0_k + B1_k E_j) f̂_j,
    δ̂_j = Θ̂_j + r_Θ Θ̈̂_j − Σ_k b_k Q_k(E_j) (b_k T̂_j + g_k Θ̈̂_j) − R T̂_j
        = Δ̂_j − Ĥ_j T̂_j,

(Q_k: the q-row of the modal transfer function). The steady state of the scheme — the
state that cycling converges to — is the periodic sequence δ_s, s = 0…K−1, with

    r(δ) = δ − Δ + h ⊛ 𝓗(δ) = 0,        h = IDFT(Ĥ)  (circular convolution),

where 𝓗 is the bed of Jenkins elements run over the periodic δ (the hysteresis operator,
evaluated exactly in the time domain: the alternating frequency/time idea of Cameron &
Griffin 1989, here without truncation of harmonics, so the discrete solution is reproduced
exactly, not approximated). 𝓗 is piecewise linear, so r is piecewise affine and the
semismooth Newton method x ← x − J⁻¹ r, J = I + H D (H the circulant of h, D = ∂𝓗/∂δ on
the current stick/slip pattern) lands on the root once the pattern of the iterate is the
final one (Qi & Sun 1993).

Which periodic state. A bed element that never reaches its capacity during the cycle keeps
the offset σ_i = t_i − κ_i δ it had when it stopped slipping: the periodic states form a
family (shakedown depends on the history; Barber 2012; Ahn, Bertocchi & Barber 2008 on
coupled frictional systems). 𝓗 starts from the element state of the cycling run at the moment
Newton is called and keeps those offsets, so the solver returns the periodic state that
cycling reaches from the same start (tested against cycling). Every member of the family
has the same dissipation and the same ranges of T and δ; the offsets shift the mean
torque, so the peak torque depends on the history (by up to a few 1e-4 in lightly damped
microslip; docs/rods.md). The caller verifies
every Newton solution by one ordinary cycle of the time-stepping scheme with the
steadiness test of cycling; a solution that fails it is not used.

References
----------
Cameron, T. M. & Griffin, J. H. (1989). An alternating frequency/time domain method for
calculating the steady-state response of nonlinear dynamic systems. J. Appl. Mech. 56,
149–154. Qi, L. & Sun, J. (1993). A nonsmooth version of Newton's method. Math. Program.
58, 353–367. Barber, J. R. (2012). Frictional systems under periodic loads — history-
dependence, non-uniqueness and energy dissipation. J. Phys. Conf. Ser. 382, 012002.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.linalg import lu_factor, lu_solve

__all__ = ["PeriodicOperator", "periodic_operator", "newton_periodic", "NewtonResult",
           "NEWTON_RTOL"]

#: relative residual max|r|/scale at which the Newton iterate is accepted [1]
NEWTON_RTOL = 1e-12
LINE_SEARCH_CUTS = 12


@dataclass(frozen=True)
class PeriodicOperator:
    """The periodic response of the discrete modal scheme, per frequency (K harmonics).

    Attributes
    ----------
    K : int
        Steps per cycle.
    h : (K,) array
        Circular convolution kernel of δ with respect to T [rad/(N m)]:
        δ = Δ − h ⊛ T.
    H : (K,) complex array
        Its DFT Ĥ_j.
    drive_theta, drive_acc : (K,) complex arrays
        Δ̂_j = drive_theta_j Θ̂_j + drive_acc_j Θ̈̂_j (drive_theta ≡ 1).
    Q, V : (m, K) complex arrays
        Modal transfer functions q̂_kj = Q_kj f̂_kj, v̂_kj = V_kj f̂_kj.
    b, g : (m,) arrays
        Interface and base-acceleration participations of the (condensed) basis.
    R : float
        Residual compliance of the basis [rad/(N m)].
    free : (4, m, K) complex array
        E_j (E_j I − A_k)⁻¹ entries (qq, qv, vq, vv): the periodic response to a state
        jump once per cycle.
    b1 : (2, m) array
        Step coefficients b1q, b1v (response to the end-of-step force).
    bfree, free_sum, bbQ
        Derived at construction for :meth:`project`: b_k × ``free[0:2]`` (2, m, K), the sums
        of ``free`` over harmonics (4, m) and Σ_k b_k² Q_kj (K,).
    """

    K: int
    h: np.ndarray
    H: np.ndarray
    drive_acc: np.ndarray
    Q: np.ndarray
    V: np.ndarray
    b: np.ndarray
    g: np.ndarray
    R: float
    free: np.ndarray
    b1: np.ndarray
    bfree: np.ndarray = None
    free_sum: np.ndarray = None
    bbQ: np.ndarray = None

    def __post_init__(self):
        # the sums over harmonics and modes that every projection needs
        b = self.b[:, None]
        object.__setattr__(self, "bfree", np.stack([b * self.free[0], b * self.free[1]]))
        object.__setattr__(self, "free_sum", np.sum(self.free, axis=2))
        object.__setattr__(self, "bbQ", (self.b * self.b) @ self.Q if self.b.size
                           else np.zeros(self.K, complex))

    def project(self, k: float, e: np.ndarray) -> np.ndarray:
        """(I − S(k)^K)⁻¹ e for the stuck linear interface of stiffness k (inf: rigid).

        S(k) is the one-step map of the modal state (q, v) with T = k δ
        (:func:`slipcycle.rods.modal._stuck_step_matrix`); its periodic orbit with a jump e
        once per cycle is, per harmonic, ẑ_j = E_j (E_j I − A)⁻¹ e + the response to
        T̂_j = β Σ_k b_k q̂_kj, β = k/(1 + k R): one scalar equation per harmonic, O(K m)
        instead of a dense 2m × 2m power and factorisation.

        Parameters
        ----------
        k : float
            Interface stiffness [N m/rad].
        e : (2m,) array
            Jump of (q, v) per cycle.

        Returns
        -------
        (2m,) array
        """
        m = self.b.size
        beta = 1.0 / self.R if not math.isfinite(k) else k / (1.0 + k * self.R)
        # the last step of the cycle ends before the jump: its end-of-step torque is
        # β b·(q_0 − e_q), i.e. the jump also adds B1 b β (b·e_q) to that step's forcing
        corr = beta * float(self.b @ e[:m]) * self.b
        eq = e[:m] + self.b1[0] * corr
        ev = e[m:] + self.b1[1] * corr
        # T̂_j (1 + β Σ_k b² Q_kj) = β Σ_k b_k q̂_free,kj ; the forcing −b T̂ acts on every mode
        That = beta * (eq @ self.bfree[0] + ev @ self.bfree[1]) / (1.0 + beta * self.bbQ)
        q = self.free_sum[0] * eq + self.free_sum[1] * ev - self.b * (self.Q @ That)
        v = self.free_sum[2] * eq + self.free_sum[3] * ev - self.b * (self.V @ That)
        return np.concatenate([np.real(q), np.real(v)]) / self.K

    def drive(self, theta: np.ndarray, theta_dd: np.ndarray) -> np.ndarray:
        """Δ_s, the relative rotation of the scheme's periodic response with T ≡ 0 (rad).

        Parameters
        ----------
        theta, theta_dd : (K,) arrays
            Θ_s [rad] and Θ̈_s [rad/s²] at the steps s = 0…K−1.

        Returns
        -------
        (K,) array
        """
        return np.real(np.fft.ifft(np.fft.fft(theta) + self.drive_acc * np.fft.fft(theta_dd)))

    def convolve(self, T: np.ndarray) -> np.ndarray:
        """h ⊛ T (rad) for a periodic torque sequence T (K,) (N m)."""
        return np.real(np.fft.ifft(self.H * np.fft.fft(T)))

    def modal_state(self, T: np.ndarray, theta_dd: np.ndarray):
        """(q, v) at step 0 of the periodic orbit driven by T and Θ̈ (both (K,))."""
        Th = np.fft.fft(T)
        Wh = np.fft.fft(theta_dd)
        f = -self.b[:, None] * Th[None, :] - self.g[:, None] * Wh[None, :]
        q = np.real(np.sum(self.Q * f, axis=1)) / self.K
        v = np.real(np.sum(self.V * f, axis=1)) / self.K
        return q, v


def periodic_operator(basis, coef: np.ndarray, K: int) -> PeriodicOperator | None:
    """:class:`PeriodicOperator` of a (condensed) basis and its step coefficients.

    Parameters
    ----------
    basis : ModalBasis
        The modal basis the step uses (after condensation of unresolved modes).
    coef : (8, m) array
        Step coefficients a11, a12, a21, a22, b0q, b0v, b1q, b1v
        (:func:`slipcycle.rods.modal.step_coefficients`).
    K : int
        Steps per cycle.

    Returns
    -------
    PeriodicOperator or None
        None when a harmonic of the drive meets an undamped mode (E_j an eigenvalue of a
        modal step matrix): the periodic problem has no unique solution there.
    """
    a11, a12, a21, a22, b0q, b0v, b1q, b1v = (c[:, None] for c in coef)
    E = np.exp(2j * math.pi * np.arange(K) / K)[None, :]
    det = (E - a11) * (E - a22) - a12 * a21
    if basis.size and float(np.min(np.abs(det))) < 1e-9:
        return None
    uq = b0q + b1q * E
    uv = b0v + b1v * E
    Q = ((E - a22) * uq + a12 * uv) / det
    V = (a21 * uq + (E - a11) * uv) / det
    b = basis.b[:, None]
    g = basis.g[:, None]
    H = basis.R + np.sum(b * b * Q, axis=0) if basis.size else np.full(K, basis.R + 0j)
    acc = basis.r_theta - (np.sum(b * g * Q, axis=0) if basis.size else 0.0)
    h = np.real(np.fft.ifft(H))
    free = np.stack([E * (E - a22), E * a12, E * a21, E * (E - a11)]) / det
    return PeriodicOperator(K, h, H, acc * np.ones(K), Q, V, basis.b.copy(), basis.g.copy(),
                            float(basis.R), free, np.array([coef[6], coef[7]]))


@njit(cache=True)
def _bed_periodic(delta, t_start, d_start, kappa, cap_unit, N, T, t_end, kdiag, ref, kref):
    """Run the bed over the periodic δ (K,) twice; record the second pass and its tangent.

    The elements start at state ``t_start`` reached at the relative rotation ``d_start``
    and are moved to δ_0, then over two cycles (the first makes every element that slips
    periodic, the one that never slips keeps its offset). Returns the number of elements
    at a capacity in the second pass; ``T`` (K,) is the torque of the second pass at the
    steps s = 1…K (index s mod K), ``t_end`` the element state at δ_0.

    Tangent: at step s, T_s = Σ_stuck κ_i δ_s − Σ_stuck κ_i δ_{ρ_i} + const, ρ_i the last
    step where element i was at its capacity (or none: frozen offset). The diagonal is
    ``kdiag[s]``; the references are accumulated per distinct ρ in ``ref[s, :]`` (indices,
    −1 = none) and ``kref[s, :]`` (stiffness sums).
    """
    K = delta.size
    n = kappa.size
    t = t_start.copy()
    rho = np.full(n, -1)
    c0 = N[0] if N[0] > 0.0 else 0.0
    for i in range(n):
        x = t[i] + kappa[i] * (delta[0] - d_start)
        c = cap_unit[i] * c0
        if x > c:
            x = c
            rho[i] = 0
        elif x < -c:
            x = -c
            rho[i] = 0
        t[i] = x
    nslip = 0
    maxref = ref.shape[1]
    for p in range(2):
        for s1 in range(1, K + 1):
            s = s1 % K
            dd = delta[s] - delta[s1 - 1]
            Ns = N[s] if N[s] > 0.0 else 0.0
            tot = 0.0
            kd = 0.0
            if p == 1:
                for r in range(maxref):
                    ref[s, r] = -1
                    kref[s, r] = 0.0
            for i in range(n):
                x = t[i] + kappa[i] * dd
                c = cap_unit[i] * Ns
                if x > c:
                    x = c
                    rho[i] = s
                    if p == 1:
                        nslip += 1
                elif x < -c:
                    x = -c
                    rho[i] = s
                    if p == 1:
                        nslip += 1
                elif p == 1:
                    kd += kappa[i]
                    if rho[i] >= 0:
                        # group the references by ρ (few distinct values per step)
                        placed = False
                        for r in range(maxref):
                            if ref[s, r] == rho[i] or ref[s, r] == -1:
                                ref[s, r] = rho[i]
                                kref[s, r] += kappa[i]
                                placed = True
                                break
                        if not placed:
                            return -1  # more distinct references than room: caller widens
                t[i] = x
                tot += x
            if p == 1:
                T[s] = tot
                kdiag[s] = kd
    for i in range(n):
        t_end[i] = t[i]
    return nslip


@njit(cache=True)
def _add_shifted(J, h, s, col, w):
    """J[:, col] += w h[(p − s) mod K] for every row p (column s of the circulant)."""
    K = h.size
    for p in range(s, K):
        J[p, col] += w * h[p - s]
    for p in range(s):
        J[p, col] += w * h[p - s + K]


@njit(cache=True)
def _jacobian(h, kdiag, ref, kref, J):
    """J = I + H D with H the circulant of h and D the bed tangent (sparse, see above)."""
    K = h.size
    J[:, :] = 0.0
    for p in range(K):
        J[p, p] = 1.0
    for s in range(K):
        if kdiag[s] != 0.0:
            _add_shifted(J, h, s, s, kdiag[s])
        for r in range(ref.shape[1]):
            c = ref[s, r]
            if c < 0:
                break
            _add_shifted(J, h, s, c, -kref[s, r])


@dataclass
class NewtonResult:
    """Outcome of :func:`newton_periodic`.

    Attributes
    ----------
    converged : bool
        max|r|/scale ≤ :data:`NEWTON_RTOL` reached.
    iterations : int
    delta, T : (K,) arrays
        Periodic relative rotation (rad) and torque (N m) at the steps s = 0…K−1.
    t_el : (n,) array
        Element torques at step 0 (N m).
    residual : float
        Final max|r|/scale.
    """

    converged: bool
    iterations: int
    delta: np.ndarray
    T: np.ndarray
    t_el: np.ndarray
    residual: float


def newton_periodic(op: PeriodicOperator, drive: np.ndarray, kappa: np.ndarray,
                    cap_unit: np.ndarray, N: np.ndarray, delta0: np.ndarray,
                    t_start: np.ndarray, d_start: float, max_iter: int = 20
                    ) -> NewtonResult:
    """Semismooth Newton on r(δ) = δ − Δ + h ⊛ 𝓗(δ) (see module docstring).

    Parameters
    ----------
    op : PeriodicOperator
        The scheme's periodic response at this frequency and step.
    drive : (K,) array
        Δ_s = :meth:`PeriodicOperator.drive` (rad).
    kappa, cap_unit : (n,) arrays
        Bed stiffnesses κ_i (N m/rad, finite) and capacities per unit normal force (m).
    N : (K,) array
        Normal force at the steps s = 0…K−1 (N; clipped at 0).
    delta0 : (K,) array
        Starting iterate, e.g. the last cycle's δ (rad).
    t_start : (n,) array
        Element state (N m) of the run that Newton continues, reached at ``d_start`` (rad):
        it fixes the offsets of elements that never slip.
    max_iter : int
        Newton iterations allowed.

    Returns
    -------
    NewtonResult
    """
    K = drive.size
    n = kappa.size
    T = np.empty(K)
    t_end = np.empty(n)
    kdiag = np.empty(K)
    width = 4
    ref = np.empty((K, width), dtype=np.int64)
    kref = np.empty((K, width))
    J = np.empty((K, K))
    delta = np.array(delta0, dtype=float)
    scale = max(float(np.max(np.abs(delta))), float(np.max(np.abs(drive))), 1e-300)

    def evaluate(d):
        nonlocal ref, kref, width
        while True:
            st = _bed_periodic(d, t_start, d_start, kappa, cap_unit, N, T, t_end, kdiag,
                               ref, kref)
            if st >= 0:
                break
            width *= 2
            ref = np.empty((K, width), dtype=np.int64)
            kref = np.empty((K, width))
        return d - drive + op.convolve(T)

    r = evaluate(delta)
    res = float(np.max(np.abs(r))) / scale
    merit = float(r @ r)
    it = 0
    lu = None
    while it < max_iter and res > NEWTON_RTOL:
        it += 1
        fresh = lu is None
        if fresh:
            _jacobian(op.h, kdiag, ref, kref, J)
            try:
                lu = lu_factor(J, check_finite=False)
            except (np.linalg.LinAlgError, ValueError):
                break
        step = -lu_solve(lu, r, check_finite=False)
        if not np.all(np.isfinite(step)):
            break
        # backtracking on |r|²: a full step is exact once the stick/slip pattern is right
        alpha = 1.0
        accepted = False
        for _ in range(LINE_SEARCH_CUTS):
            trial = delta + alpha * step
            r_new = evaluate(trial)
            merit_new = float(r_new @ r_new)
            if merit_new < (1.0 - 1e-4 * alpha) * merit or merit_new == 0.0:
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            evaluate(delta)  # restore T, t_end of the last accepted iterate
            if fresh:
                break
            lu = None  # the reused factorisation has gone stale: refactorise
            continue
        # keep the factorisation (a chord step) while it halves the residual
        if alpha < 1.0 or merit_new > 0.25 * merit:
            lu = None
        delta, r, merit = trial, r_new, merit_new
        res = float(np.max(np.abs(r))) / scale
    return NewtonResult(res <= NEWTON_RTOL, it, delta, T.copy(), t_end.copy(), res)
