"""A compiled entry point for many steady-state runs (basin maps, λ scans).

:func:`steady_state_fast` does what :func:`slipcycle.discrete.steady.simulate` does for a
run that starts from an initial slip state and **keeps every node in contact** — the
setting of the safe-region theory (Barber 2012, §3) — but in one Numba kernel with no Python
work per event, so a 2-node run costs microseconds instead of tens of milliseconds.

Method (same as :mod:`~slipcycle.discrete.evolution`, restricted to contact): on each
linear load segment the rate problem over the *critical* nodes (those at a friction limit)
is the LCP  ġ = a + M u ≥ 0, u ≥ 0, uᵀġ = 0 with u_i = s_i v̇_{j_i} the slip rate in the
direction allowed by the active limit s_i = ±1 and M_ik = (f_i B_{j_i j_k} + s_i A_{j_i j_k}) s_k;
it is solved by Murty's least-index principal pivoting (finite for the P-matrices of a
well-posed model). Events (a stuck node reaching q = ±f p) are located exactly, and
dissipation D_j = −∫ q_j dv_j is integrated exactly on every piece. Steady-state test and
classification follow :func:`~slipcycle.discrete.steady.simulate` exactly (same tolerances).

If a node reaches p = 0 (separation) or the pivoting fails, the kernel stops and the
caller falls back to the general solver; results agree with it (tests).

References: K. G. Murty, *Linear Complementarity, Linear and Nonlinear Programming* (1988)
§4; A. Klarbring, Ingenieur-Archiv 60 (1990) 529–541.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from slipcycle.coupled.cycles import ROUNDOFF, ResidualScale
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import FrictionalSystem
from slipcycle.loading.service import (
    service_force_scale,
    service_slip_tolerance,
    slips_in_cycle,
)

__all__ = ["steady_state_fast", "steady_states_batch", "FAST_CODES"]

EPS = float(np.finfo(float).eps)

#: kernel return codes
STEADY, RATCHET, NOT_CONVERGED, SEPARATION, PIVOT_FAIL, INADMISSIBLE = 0, 1, 2, -1, -2, -3
FAST_CODES = {STEADY: "steady", RATCHET: "ratcheting", NOT_CONVERGED: "not_converged",
              SEPARATION: "separation", PIVOT_FAIL: "pivot_failure",
              INADMISSIBLE: "inadmissible"}


@njit(cache=True)
def _murty(M, a, alpha, eps):
    """Least-index principal pivoting for w = a + M u; returns (u, ok)."""
    k = a.size
    u = np.zeros(k)
    for _ in range(200 + 20 * k * k):
        idx = np.flatnonzero(alpha)
        u[:] = 0.0
        if idx.size:
            Ma = np.empty((idx.size, idx.size))
            ra = np.empty(idx.size)
            for r in range(idx.size):
                ra[r] = -a[idx[r]]
                for c in range(idx.size):
                    Ma[r, c] = M[idx[r], idx[c]]
            ua = np.linalg.solve(Ma, ra)
            for r in range(idx.size):
                u[idx[r]] = ua[r]
        bad = -1
        for i in range(k):
            if alpha[i]:
                if u[i] < -eps:
                    bad = i
                    break
            else:
                wi = a[i]
                for c in range(k):
                    wi += M[i, c] * u[c]
                if wi < -eps:
                    bad = i
                    break
        if bad < 0:
            for i in range(k):
                if u[i] < 0.0:
                    u[i] = 0.0
            return u, True
        alpha[bad] = not alpha[bad]
    return u, False


@njit(cache=True)
def _residual_scale(A, B, f, qabs, pabs, va, vb, service, tol):
    """:meth:`~slipcycle.coupled.cycles.ResidualScale.scale` of the change va → vb of the
    slips of a run in contact (w = 0): max(u_s, δ / tol), δ the largest round-off
    ROUNDOFF ε (|v_j| + (s_q + f_j s_p) / A_jj) of the nodes whose slip changed, s_q and
    s_p the magnitudes of the terms of q_j and p_j [m]."""
    n = va.size
    delta = 0.0
    for j in range(n):
        if va[j] == vb[j]:
            continue
        sq, sp = qabs[j], pabs[j]
        for k in range(n):
            vk = max(np.abs(va[k]), np.abs(vb[k]))
            sq += np.abs(A[j, k]) * vk
            sp += np.abs(B[j, k]) * vk
        vj = max(np.abs(va[j]), np.abs(vb[j]))
        delta = max(delta, ROUNDOFF * EPS * (vj + (sq + f[j] * sp) / A[j, j]))
    return max(service, delta / max(tol, 1e-300))


@njit(cache=True)
def _kernel(A, B, f, theta, qw, pw, v0, cycles, tol, min_cycles, force_tol, disp_scale,
            service, qabs, pabs):
    n = v0.size
    nseg = theta.size - 1
    v = v0.copy()
    q = qw[0] + A @ v
    p = pw[0] + B @ v
    diss = np.zeros(n)
    slip_len = np.zeros(n)
    hist = np.zeros(cycles)
    for j in range(n):
        if p[j] <= force_tol:
            return SEPARATION, 0, np.inf, diss, slip_len, False, v, np.zeros(n), hist
        if np.abs(q[j]) > f[j] * p[j] + force_tol:
            return INADMISSIBLE, 0, np.inf, diss, slip_len, False, v, np.zeros(n), hist
    starts = np.zeros((cycles + 1, n))
    starts[0] = v
    slipping_prev = np.zeros(n, np.int64)     # last slip sign of each node (warm start)
    code = NOT_CONVERGED
    residual = np.inf
    ratchet = np.zeros(n)
    erased = False
    ncyc = 0
    for c in range(cycles):
        diss[:] = 0.0
        slip_len[:] = 0.0
        erased = False
        for kseg in range(nseg):
            dth = theta[kseg + 1] - theta[kseg]
            if dth <= 0:
                continue
            dq = (qw[kseg + 1] - qw[kseg]) / dth
            dp = (pw[kseg + 1] - pw[kseg]) / dth
            t = 0.0
            count = 0
            while True:
                # critical nodes and their admissible slip sign
                crit = np.empty(n, np.int64)
                sgn = np.empty(n)
                nc = 0
                for j in range(n):
                    if p[j] <= force_tol:
                        return SEPARATION, c, residual, diss, slip_len, erased, v, ratchet, hist
                    gp = f[j] * p[j] + q[j]
                    gm = f[j] * p[j] - q[j]
                    if gp <= force_tol:
                        crit[nc] = j
                        sgn[nc] = 1.0
                        nc += 1
                    elif gm <= force_tol:
                        crit[nc] = j
                        sgn[nc] = -1.0
                        nc += 1
                vd = np.zeros(n)
                if nc > 0:
                    a = np.empty(nc)
                    M = np.empty((nc, nc))
                    alpha = np.zeros(nc, np.bool_)
                    amax = 0.0
                    for i in range(nc):
                        ji = crit[i]
                        si = sgn[i]
                        a[i] = f[ji] * dp[ji] + si * dq[ji]
                        amax = max(amax, np.abs(a[i]))
                        alpha[i] = slipping_prev[ji] == si
                        for kk in range(nc):
                            jk = crit[kk]
                            M[i, kk] = (f[ji] * B[ji, jk] + si * A[ji, jk]) * sgn[kk]
                    u, ok = _murty(M, a, alpha, 1e-12 * (amax + 1e-300))
                    if not ok:
                        return PIVOT_FAIL, c, residual, diss, slip_len, erased, v, ratchet, hist
                    for i in range(nc):
                        vd[crit[i]] = sgn[i] * u[i]
                qd = dq + A @ vd
                pd = dp + B @ vd
                # next event
                remaining = dth - t
                dt = remaining
                ev_sep = False
                for j in range(n):
                    if vd[j] == 0.0:
                        gp = f[j] * p[j] + q[j]
                        gm = f[j] * p[j] - q[j]
                        rgp = f[j] * pd[j] + qd[j]
                        rgm = f[j] * pd[j] - qd[j]
                        if gp > force_tol and rgp < 0.0 and gp / -rgp < dt:
                            dt = gp / -rgp
                            ev_sep = False
                        if gm > force_tol and rgm < 0.0 and gm / -rgm < dt:
                            dt = gm / -rgm
                            ev_sep = False
                    if p[j] > force_tol and pd[j] < 0.0 and p[j] / -pd[j] < dt:
                        dt = p[j] / -pd[j]
                        ev_sep = True
                if dt < 0.0:
                    dt = 0.0
                if dt > 0.0:
                    allslip = True
                    for j in range(n):
                        diss[j] -= (q[j] + 0.5 * dt * qd[j]) * vd[j] * dt
                        slip_len[j] += np.abs(vd[j]) * dt
                        # grazing a friction limit (round-off slip) is not slipping
                        if np.abs(vd[j]) * dt <= 1e-10 * disp_scale:
                            allslip = False
                    if allslip:
                        erased = True
                    for j in range(n):
                        v[j] += dt * vd[j]
                        q[j] += dt * qd[j]
                        p[j] += dt * pd[j]
                    t += dt
                for j in range(n):
                    slipping_prev[j] = 0 if vd[j] == 0.0 else (1 if vd[j] > 0 else -1)
                if ev_sep and dt < remaining:
                    return SEPARATION, c, residual, diss, slip_len, erased, v, ratchet, hist
                if dt >= remaining:
                    break
                count += 1
                if count > 20 * n + 200:
                    return PIVOT_FAIL, c, residual, diss, slip_len, erased, v, ratchet, hist
            # resync the reactions exactly at the end of the segment
            q = qw[kseg + 1] + A @ v
            p = pw[kseg + 1] + B @ v
        ncyc = c + 1
        starts[c + 1] = v
        total = 0.0
        for j in range(n):
            total += diss[j]
        hist[c] = total
        xs = _residual_scale(A, B, f, qabs, pabs, starts[c], starts[c + 1], service, tol)
        d1 = starts[c + 1] - starts[c]
        residual = np.max(np.abs(d1)) / xs
        if c + 1 < min_cycles:
            continue
        if residual <= tol:
            code = STEADY
            break
        if c >= 1:
            d0 = starts[c] - starts[c - 1]
            rres = np.max(np.abs(d1 - d0)) / xs
            if rres <= tol:
                ratchet = d1.copy()
                residual = rres
                code = RATCHET
                break
    if code != RATCHET:
        ratchet = starts[ncyc] - starts[ncyc - 1]
    return code, ncyc, residual, diss, slip_len, erased, v, ratchet, hist[:ncyc]


def steady_state_fast(system: FrictionalSystem, load: DiscreteLoad, initial_slip, *,
                      cycles: int = 40, steps_per_cycle: int = 100, tol: float = 1e-8,
                      min_cycles: int = 1, samples=None) -> dict:
    """Run cycles from an initial slip state to the steady state (all nodes in contact).

    Parameters
    ----------
    system : FrictionalSystem
    load : DiscreteLoad
    initial_slip : (N,) array
        v at θ = 0 [m].
    cycles, steps_per_cycle, tol, min_cycles
        As for :func:`~slipcycle.discrete.steady.simulate`.
    samples : tuple (theta, values), optional
        Precomputed ``load.cycle_samples(steps_per_cycle)`` (saves time in loops).

    Returns
    -------
    dict
        ``code`` (see :data:`FAST_CODES`; negative: not handled, fall back),
        ``steady_state``, ``residual``, ``cycles_run``, ``dissipation_per_node`` (N,) [J],
        ``dissipation_per_cycle`` [J], ``slip_length`` (N,) [m], ``memory_erased``,
        ``final_slip`` (N,) [m], ``ratchet_per_cycle`` (N,) [m], ``slipping`` (N,) bool.
    """
    n = system.n_nodes
    theta, vals = samples if samples is not None else load.cycle_samples(steps_per_cycle)
    F = float(np.max(np.abs(vals), initial=0.0)) or 1.0
    disp_scale = F / float(np.max(np.diag(system.K)))
    v0 = np.ascontiguousarray(np.asarray(initial_slip, float))
    code, ncyc, res, diss, slen, erased, v, ratchet, hist = _kernel(
        np.ascontiguousarray(system.A), np.ascontiguousarray(system.B),
        np.ascontiguousarray(system.friction, dtype=float), theta,
        np.ascontiguousarray(vals[:, :n]), np.ascontiguousarray(vals[:, n:]), v0,
        int(cycles), float(tol), int(min_cycles), 1e-10 * service_force_scale(vals, F), disp_scale,
        *_scale_args(system, vals, disp_scale))
    slipping = slips_in_cycle(
        slen, np.abs(ratchet),
        service_slip_tolerance(tol, vals, system.stiffness_scale(), disp_scale),
        code == RATCHET)
    if code == STEADY:
        state = "shakedown" if not slipping.any() else "cyclic_slip"
    else:
        state = FAST_CODES[code]
    return {"code": int(code), "steady_state": state, "residual": float(res),
            "cycles_run": int(ncyc), "dissipation_per_node": diss,
            "dissipation_per_cycle": float(diss.sum()), "slip_length": slen,
            "memory_erased": bool(erased), "final_slip": v, "ratchet_per_cycle": ratchet,
            "slipping": slipping, "dissipation_history": hist}


def _scale_args(system: FrictionalSystem, vals: np.ndarray, disp_scale: float) -> tuple:
    """The kernel's arguments of the residual scale (:class:`ResidualScale`): u_s and the
    largest |q^w|, |p^w| of each node over the cycle."""
    scale = ResidualScale.of(system, vals, disp_scale)
    n = system.n_nodes
    return scale.service, scale.load[:n].copy(), scale.load[n:].copy()


@njit(cache=True, parallel=True)
def _batch(A, B, f, theta, qw, pw, V0, cycles, tol, min_cycles, force_tol, disp_scale,
           service, qabs, pabs):
    m, n = V0.shape
    codes = np.zeros(m, np.int64)
    ncyc = np.zeros(m, np.int64)
    resid = np.zeros(m)
    diss = np.zeros((m, n))
    slen = np.zeros((m, n))
    erased = np.zeros(m, np.bool_)
    vend = np.zeros((m, n))
    drift = np.zeros((m, n))
    for i in prange(m):
        c, k, r, d, s, e, v, dr, _ = _kernel(A, B, f, theta, qw, pw, V0[i].copy(), cycles, tol,
                                            min_cycles, force_tol, disp_scale, service,
                                            qabs, pabs)
        codes[i] = c
        ncyc[i] = k
        resid[i] = r
        diss[i] = d
        slen[i] = s
        erased[i] = e
        vend[i] = v
        drift[i] = dr
    return codes, ncyc, resid, diss, slen, erased, vend, drift


def steady_states_batch(system: FrictionalSystem, load: DiscreteLoad, V0, *,
                        cycles: int = 40, steps_per_cycle: int = 100, tol: float = 1e-8,
                        min_cycles: int = 1) -> dict:
    """:func:`steady_state_fast` for many initial slip states at once (Numba threads).

    Parameters
    ----------
    V0 : (M, N) array
        Initial slip states at θ = 0 [m].

    Returns
    -------
    dict of arrays
        ``code`` (M,), ``cycles_run`` (M,), ``residual`` (M,), ``dissipation_per_node``
        (M, N) [J], ``slip_length`` (M, N) [m], ``memory_erased`` (M,), ``final_slip``
        (M, N) [m], ``slipping`` (M, N) bool, ``steady_state`` (M,) object (str).
        Entries with a negative code were not handled (separation, pivoting failure or
        inadmissible start).
    """
    n = system.n_nodes
    theta, vals = load.cycle_samples(steps_per_cycle)
    F = float(np.max(np.abs(vals), initial=0.0)) or 1.0
    disp_scale = F / float(np.max(np.diag(system.K)))
    V0 = np.ascontiguousarray(np.atleast_2d(np.asarray(V0, float)))
    codes, ncyc, resid, diss, slen, erased, vend, drift = _batch(
        np.ascontiguousarray(system.A), np.ascontiguousarray(system.B),
        np.ascontiguousarray(system.friction, dtype=float), theta,
        np.ascontiguousarray(vals[:, :n]), np.ascontiguousarray(vals[:, n:]), V0,
        int(cycles), float(tol), int(min_cycles), 1e-10 * service_force_scale(vals, F), disp_scale,
        *_scale_args(system, vals, disp_scale))
    slip_tol = service_slip_tolerance(tol, vals, system.stiffness_scale(), disp_scale)
    slipping = slips_in_cycle(slen, np.abs(drift), slip_tol, codes == RATCHET)
    states = np.array([FAST_CODES[int(c)] for c in codes], dtype=object)
    steady = codes == STEADY
    states[steady] = np.where(slipping[steady].any(axis=1), "cyclic_slip", "shakedown")
    return {"code": codes, "cycles_run": ncyc, "residual": resid,
            "dissipation_per_node": diss, "slip_length": slen, "memory_erased": erased,
            "final_slip": vend, "slipping": slipping, "steady_state": states}
