"""Compiled loops of the 3-D step solver (:class:`slipcycle.discrete3d.evolution.StepSolver`).

The node classification and the active residual are the formulas of
:mod:`slipcycle.discrete3d.cone` (Alart & Curnier 1991) in one pass over the nodes, without
the temporaries of the array form. The Newton iteration of a load step touches only the
rows of the dense stiffness K (3N × 3N, symmetric) belonging to the active (slipping and
separated) nodes; these loops read those rows in place instead of copying them out with
NumPy fancy indexing, whose temporary copy of an m × 3N block costs more than the
arithmetic. The Newton rounds themselves (the chord iterations with the kept LU factors,
the update of every reaction, the classification of the next round) and the step
control's bookkeeping are compiled too: with small active sets the cost of a load step
was the interpreter's, not the arithmetic's. Python keeps the caches per active set and
calls LAPACK to factorise a new Newton matrix.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["add_rows", "copy_block", "row_terms", "gather_block", "classify_nodes",
           "active_residual", "lu_solve",
           "chord_newton", "fix_nodes", "add_at", "step_dissipation", "doubling_error",
           "book_step", "event_values", "event_crossings", "slip_jacobian",
           "active_newton", "slip_rounds"]


@njit(cache=True, nogil=True)
def add_rows(K, rows, coef, out):  # pragma: no cover - compiled
    """``out += coef @ K[rows]`` in place (K symmetric: the columns K[:, rows] @ coef),
    without copying the rows.

    Parameters
    ----------
    K : (R, M) C-contiguous float array
    rows : (m,) int array
    coef : (m,) float array
    out : (M,) float array, modified
    """
    size = out.size
    for k in range(rows.size):
        c = coef[k]
        if c != 0.0:
            row = K[rows[k]]
            for i in range(size):
                out[i] += c * row[i]


@njit(cache=True, nogil=True)
def row_terms(r, rows, row_abs, xmax):  # pragma: no cover - compiled
    """max over ``rows`` of |r_i| + row_abs_i · xmax: the size of the terms of those rows
    of r = r^w + K x (``StepSolver._tolerance``)."""
    out = 0.0
    for k in range(rows.size):
        i = rows[k]
        v = abs(r[i]) + row_abs[i] * xmax
        if v > out:
            out = v
    return out


@njit(cache=True, nogil=True)
def copy_block(dst, dst_rows, dst_cols, src, src_rows, src_cols):  # pragma: no cover
    """``dst[ix_(dst_rows, dst_cols)] = src[ix_(src_rows, src_cols)]`` without the
    index arrays and copies of fancy indexing."""
    for a in range(dst_rows.size):
        d = dst[dst_rows[a]]
        s = src[src_rows[a]]
        for b in range(dst_cols.size):
            d[dst_cols[b]] = s[src_cols[b]]


@njit(cache=True, nogil=True)
def gather_block(K, rows, cols):  # pragma: no cover - compiled
    """The block ``K[rows][:, cols]`` ((len(rows), len(cols)) array)."""
    out = np.empty((rows.size, cols.size))
    for a in range(rows.size):
        row = K[rows[a]]
        for b in range(cols.size):
            out[a, b] = row[cols[b]]
    return out


@njit(cache=True, nogil=True)
def classify_nodes(x, r, x0, f, rho_t, rho_n, modes, fix_t, fix_n, slip,
                   sep):  # pragma: no cover
    """Node states of the augmented local problem at the iterate ``x`` of a step from
    ``x0``, as :func:`slipcycle.discrete3d.cone.node_states` (same formulas, one pass).

    Parameters
    ----------
    x, r, x0 : (3N,) arrays
        Iterate [v, w] [m], its reactions [q, p] [N], start of the step [m].
    f, rho_t, rho_n : (N,) arrays
    modes : (N,) int8 array, out
        0 stick, 1 slip, 2 separated.
    fix_t, fix_n : (N,) bool arrays, out
        Stuck nodes with a non-zero slip increment, closed nodes with w ≠ 0 (their
        Newton rows are the identity).
    slip, sep : (N,) int arrays, out
        The slipping and the separated nodes, ascending, in their first entries.

    Returns
    -------
    count : int
        Number of nodes flagged in ``fix_t`` or ``fix_n``.
    ns, npp : int
        Numbers of slipping and separated nodes.
    """
    n = f.size
    count = 0
    ns = 0
    npp = 0
    for j in range(n):
        dv1 = x[2 * j] - x0[2 * j]
        dv2 = x[2 * j + 1] - x0[2 * j + 1]
        w = x[2 * n + j]
        phat = r[2 * n + j] - rho_n[j] * w
        z1 = r[2 * j] - rho_t[j] * dv1
        z2 = r[2 * j + 1] - rho_t[j] * dv2
        zn = np.sqrt(z1 * z1 + z2 * z2)
        if phat <= 0.0:
            modes[j] = 2
            sep[npp] = j
            npp += 1
        elif zn > f[j] * phat:
            modes[j] = 1
            slip[ns] = j
            ns += 1
        else:
            modes[j] = 0
        fix_t[j] = modes[j] == 0 and (dv1 != 0.0 or dv2 != 0.0)
        fix_n[j] = modes[j] != 2 and w != 0.0
        if fix_t[j] or fix_n[j]:
            count += 1
    return count, ns, npp


@njit(cache=True, nogil=True)
def active_residual(xU, rV, v0S, fS, rhoS, rhoP, ns, npp, R, zs, zsn):  # pragma: no cover
    """Residual of the active rows (Alart–Curnier form, :mod:`slipcycle.discrete3d.cone`)
    with the active set held fixed.

    Parameters
    ----------
    xU : (m,) array
        Unknowns of the ``ns`` slipping (t1, t2) then ``npp`` separated (t1, t2, n) nodes.
    rV : (m + ns,) array
        Their reactions, then the normal reactions of the slipping nodes [N].
    v0S : (ns, 2) array
        Slips of the slipping nodes at the start of the step [m].
    fS, rhoS : (ns,) arrays
    rhoP : (npp,) array
    R : (m,) array, out
        q − f p z/|z| on the slipping rows, (q, p) on the separated ones [N].
    zs : (ns, 2) array, out
        Augmented variables z = q − ρ_t Δv.
    zsn : (ns,) array, out
        |z| (a zero replaced by 1e-300).

    Returns
    -------
    res : float
        max |R| [N].
    changed : bool
        Some node left its state (a slipping node stuck or opened, a separated one
        closed).
    """
    m = 2 * ns + 3 * npp
    res = 0.0
    changed = False
    for i in range(ns):
        q1 = rV[2 * i]
        q2 = rV[2 * i + 1]
        p = rV[m + i]
        z1 = q1 - rhoS[i] * (xU[2 * i] - v0S[i, 0])
        z2 = q2 - rhoS[i] * (xU[2 * i + 1] - v0S[i, 1])
        zn = np.sqrt(z1 * z1 + z2 * z2)
        if p <= 0.0 or zn <= fS[i] * p:
            changed = True
        if zn <= 0.0:
            zn = 1e-300
        zs[i, 0] = z1
        zs[i, 1] = z2
        zsn[i] = zn
        c = fS[i] * p / zn
        R[2 * i] = q1 - c * z1
        R[2 * i + 1] = q2 - c * z2
        res = max(res, abs(R[2 * i]), abs(R[2 * i + 1]))
    for k in range(2 * ns, m):
        R[k] = rV[k]
        res = max(res, abs(R[k]))
    for i in range(npp):
        k = 2 * ns + 3 * i + 2
        if rV[k] - rhoP[i] * xU[k] > 0.0:
            changed = True
    return res, changed


@njit(cache=True, nogil=True)
def lu_solve(lu, piv, b):  # pragma: no cover - compiled
    """Solve J x = b with the factors of LAPACK ``getrf`` (as
    :func:`scipy.linalg.lapack.dgetrf` returns them: ``lu`` (m, m), unit-lower L and U
    packed; ``piv`` (m,) zero-based row interchanges). Column-oriented, for the Fortran
    order of ``lu``."""
    m = b.size
    x = b.copy()
    for i in range(m):
        p = piv[i]
        if p != i:
            t = x[i]
            x[i] = x[p]
            x[p] = t
    for k in range(m):
        xk = x[k]
        if xk != 0.0:
            for i in range(k + 1, m):
                x[i] -= lu[i, k] * xk
    for k in range(m - 1, -1, -1):
        x[k] /= lu[k, k]
        xk = x[k]
        if xk != 0.0:
            for i in range(k):
                x[i] -= lu[i, k] * xk
    return x


@njit(cache=True, nogil=True)
def _elim_step(R, ns, m, lu, piv, KSP, phi, nvec, fS, y):  # pragma: no cover
    """The slip part dS (2 ns,) of the Newton step of the condensed system (the separated
    rows eliminated: ``StepSolver._separated_block``), and whether ``y`` = K_PP⁻¹ R_P
    enters it: it does while R_P ≠ 0 (before the first step: the separated rows are
    linear and solved exactly by it); an empty ``y``: R_P is within the Newton tolerance
    and is left as it is. The separated unknowns follow as dP = −W dS (− y)."""
    s = 2 * ns
    rhs = -R[:s]
    ry = False
    for k in range(s, m if y.size else s):
        if R[k] != 0.0:
            ry = True
            break
    if ry:
        z = np.dot(KSP, y)                           # K_{VS,P} K_PP⁻¹ R_P
        for i in range(ns):
            z1, z2 = z[2 * i], z[2 * i + 1]
            rhs[2 * i] += (z1 - phi[i, 0, 0] * z1 - phi[i, 0, 1] * z2
                           - fS[i] * z[s + i] * nvec[i, 0])
            rhs[2 * i + 1] += (z2 - phi[i, 1, 0] * z1 - phi[i, 1, 1] * z2
                               - fS[i] * z[s + i] * nvec[i, 1])
    return lu_solve(lu, piv, rhs), ry


@njit(cache=True, nogil=True)
def _elim_update(xU, rV, D, dS, ry, ns, npp, W, Kt, KSP, y, ya):  # pragma: no cover
    """Apply the condensed step: x_S += dS; the reactions of the slip rows (tangential,
    then normal) change by K̃ dS − K_{VS,P} y (K̃ = K_{VS,S} − K_{VS,P} W: the
    separated unknowns follow the step, dP = −W dS − y), those of the separated rows
    become zero; of the separated unknowns only the normal separations are followed
    (the closing test of :func:`active_residual`), the rest is :func:`_elim_finish`'s.
    O((3 ns + npp) 2 ns) per step instead of O(m²): W and K_{VS,P} are not touched
    after the first step."""
    s = 2 * ns
    m = s + 3 * npp
    for k in range(s):
        D[k] += dS[k]
        xU[k] += dS[k]
    u = np.dot(Kt, dS)
    if ry:
        u -= np.dot(KSP, y)
        ya[0] = 1
    for k in range(s):
        rV[k] += u[k]
    for i in range(ns):
        rV[m + i] += u[s + i]
    for k in range(s, m):
        rV[k] = 0.0
    for i in range(npp):
        k = 3 * i + 2
        w = -np.dot(W[k], dS)
        if ry:
            w -= y[k]
        xU[s + k] += w


@njit(cache=True, nogil=True)
def _elim_finish(D, ns, W, y, ya):  # pragma: no cover - compiled
    """The separated unknowns' change of the round, dP = −W D_S (− y once, if it
    entered: ``ya``), from the accumulated slip change D_S (the first 2 ns of D)."""
    s = 2 * ns
    dP = -np.dot(W, D[:s])
    if ya[0]:
        dP -= y
    for k in range(dP.size):
        D[s + k] = dP[k]


@njit(cache=True, nogil=True)
def chord_newton(kind, xU, rV, D, v0S, fS, rhoS, rhoP, ns, npp, KVU, lu, piv, W, KSP,
                 Kt, phi, nvec, y, ya, has_lu, fresh, it, max_iter, res_prev, stepped,
                 force_tol, chord_rate, R, zs, zsn):  # pragma: no cover - compiled
    """Newton iterations on the active unknowns with the active set held fixed and one
    factorised Newton matrix (chord steps): the loop of ``StepSolver._local_newton``.

    ``kind`` 0: LU factors (``lu``, ``piv``) of the whole active Jacobian; 2: the
    separated rows eliminated (``W``, ``KSP``, ``Kt`` = K̃, ``y`` = K_PP⁻¹ R_P at the
    start, and ``lu``/``piv`` of the condensed slip Jacobian with its ``phi``,
    ``nvec``): the steps change only the slip unknowns of D (and the separated
    nodes' separations in ``xU``), ``ya[0]`` is set once ``y`` has entered, and the
    caller completes D (:func:`_elim_finish`). The
    iteration stops before a step that needs a new matrix (none yet, or the residual
    fell less than ``chord_rate`` per step): the caller factorises at the current
    iterate and calls again with ``fresh``. Dense products by BLAS (``np.dot``).

    Returns
    -------
    status : int
        0 converged, 1 a node of the active set changed state, 2 ``max_iter`` reached,
        3 a new Newton matrix is needed, 4 a non-finite Newton step.
    it, res_prev, stepped
        The loop's counters, to resume it.
    """
    m = 2 * ns + 3 * npp
    s = 2 * ns
    while True:
        res, changed = active_residual(xU, rV, v0S, fS, rhoS, rhoP, ns, npp, R, zs, zsn)
        if stepped and changed:
            return 1, it, res_prev, stepped
        if res <= force_tol:
            return 0, it, res_prev, stepped
        if it >= max_iter:
            return 2, it, res_prev, stepped
        if not fresh and (not has_lu or res > chord_rate * res_prev):
            return 3, it, res_prev, stepped
        fresh = False
        it += 1
        if kind == 2:
            dS, ry = _elim_step(R, ns, m, lu, piv, KSP, phi, nvec, fS, y)
            for k in range(s):
                if not np.isfinite(dS[k]):
                    return 4, it, res_prev, stepped
            res_prev = res
            stepped = True
            # the separated rows are solved exactly by the step (K_PS dS + K_PP dP =
            # −R_P): their reactions are zero and the slip rows follow K̃
            _elim_update(xU, rV, D, dS, ry, ns, npp, W, Kt, KSP, y, ya)
            continue
        delta = lu_solve(lu, piv, -R)
        for k in range(m):
            if not np.isfinite(delta[k]):
                return 4, it, res_prev, stepped
        res_prev = res
        stepped = True
        for k in range(m):
            D[k] += delta[k]
            xU[k] += delta[k]
        rV += np.dot(KVU, delta)


@njit(cache=True, nogil=True)
def fix_nodes(K, x, x0, r, fix_t, fix_n):  # pragma: no cover - compiled
    """Set the slip increment of the flagged stuck nodes (``fix_t``) and the separation
    of the flagged closed nodes (``fix_n``) to zero, with their reactions:
    r += K[:, cols] δ (K symmetric: its rows), the tangential columns first."""
    n = fix_t.size
    cols = np.empty(3 * n, np.int64)
    k = 0
    for j in range(n):
        if fix_t[j]:
            cols[k] = 2 * j
            cols[k + 1] = 2 * j + 1
            k += 2
    kt = k
    for j in range(n):
        if fix_n[j]:
            cols[k] = 2 * n + j
            k += 1
    cols = cols[:k]
    delta = np.empty(k)
    for i in range(k):
        delta[i] = x0[cols[i]] - x[cols[i]] if i < kt else -x[cols[i]]
    for i in range(k):
        x[cols[i]] += delta[i]
    add_rows(K, cols, delta, r)


@njit(cache=True, nogil=True)
def add_at(K, cols, d, x, r):  # pragma: no cover - compiled
    """x[cols] += d and r += K[:, cols] d (K symmetric: its rows)."""
    for k in range(cols.size):
        x[cols[k]] += d[k]
    add_rows(K, cols, d, r)


@njit(cache=True, nogil=True)
def step_dissipation(x0, r0, x1, r1, n):  # pragma: no cover - compiled
    """Σ_j −½(q_j⁰ + q_j¹)·Δv_j [J] of a step from (x0, r0) to (x1, r1) (trapezoidal)."""
    d = 0.0
    for j in range(n):
        a, b = 2 * j, 2 * j + 1
        d -= (0.5 * (r0[a] + r1[a]) * (x1[a] - x0[a])
              + 0.5 * (r0[b] + r1[b]) * (x1[b] - x0[b]))
    return d


@njit(cache=True, nogil=True)
def doubling_error(x0, r0, xf, rf, x1, r1, x2, r2, n):  # pragma: no cover - compiled
    """The step-doubling estimates of an interval from (x0, r0) solved as one step
    (xf, rf) and as two half steps (x1, r1), (x2, r2): max |xf − x2| [m] and the
    dissipations of the one step and of the two [J]."""
    err = 0.0
    for i in range(xf.size):
        err = max(err, abs(xf[i] - x2[i]))
    d_full = step_dissipation(x0, r0, xf, rf, n)
    d_half = step_dissipation(x0, r0, x1, r1, n) + step_dissipation(x1, r1, x2, r2, n)
    return err, d_full, d_half


@njit(cache=True, nogil=True)
def book_step(x0, r0, x1, r1, drw, modes, f, dissipation, slip_length, separated,
              slipped):  # pragma: no cover - compiled
    """Bookkeeping of a committed step (``Evolution3D._commit``): adds each node's
    dissipation −½(q⁰ + q¹)·Δv [J] (none at a frictionless node, f_j = 0, whose q is
    zero up to round-off) and, for a slipping node, its slip length |Δv| [m]; flags
    separated and slipping nodes.

    Returns
    -------
    work : float
        ½(x⁰ + x¹)·Δr^w [J].
    normal_work : float
        Σ ½(p⁰ + p¹)Δw [J].
    none_stuck : bool
        No node sticks at the end of the step.
    """
    n = modes.size
    work = 0.0
    for i in range(x0.size):
        work += 0.5 * (x0[i] + x1[i]) * drw[i]
    normal_work = 0.0
    none_stuck = True
    for j in range(n):
        a, b, k = 2 * j, 2 * j + 1, 2 * n + j
        d1, d2 = x1[a] - x0[a], x1[b] - x0[b]
        if f[j] > 0.0:
            dissipation[j] -= 0.5 * (r0[a] + r1[a]) * d1 + 0.5 * (r0[b] + r1[b]) * d2
        normal_work += 0.5 * (r0[k] + r1[k]) * (x1[k] - x0[k])
        if modes[j] == 1:
            slip_length[j] += np.sqrt(d1 * d1 + d2 * d2)
            slipped[j] = True
        elif modes[j] == 2:
            separated[j] = True
        else:
            none_stuck = False
    return work, normal_work, none_stuck


@njit(cache=True, nogil=True)
def event_values(x0, x, r, f, rho_t, rho_n):  # pragma: no cover - compiled
    """The event functions (2N,) [N] of ``Evolution3D._event_values``: φ_j = p_j − ρ_n w_j,
    then ψ_j = |q_j − ρ_t Δv_j| − f_j φ_j."""
    n = f.size
    g = np.empty(2 * n)
    for j in range(n):
        phi = r[2 * n + j] - rho_n[j] * x[2 * n + j]
        z1 = r[2 * j] - rho_t[j] * (x[2 * j] - x0[2 * j])
        z2 = r[2 * j + 1] - rho_t[j] * (x[2 * j + 1] - x0[2 * j + 1])
        g[j] = phi
        g[n + j] = np.hypot(z1, z2) - f[j] * phi
    return g


@njit(cache=True, nogil=True)
def event_crossings(g0, g1, stops, tol):  # pragma: no cover - compiled
    """Indices of the events crossed between the event values g0 and g1 (2N,)
    (``Evolution3D._crossings``): a sign change of φ_j, and if ``stops`` one of ψ_j from
    below for a node closed at both ends; values within ``tol`` are at their event."""
    n = g0.size // 2
    out = np.empty(2 * n, np.int64)
    k = 0
    for i in range(2 * n):
        a, b = g0[i], g1[i]
        if abs(a) <= tol or abs(b) <= tol or (a > 0) == (b > 0):
            continue
        if i >= n:
            j = i - n
            if not (stops and g0[j] > tol and g1[j] > tol and a < 0):
                continue
        out[k] = i
        k += 1
    return out[:k]


@njit(cache=True, nogil=True)
def slip_jacobian(KVU, ns, npp, phi, nvec, fS, rhoS):  # pragma: no cover - compiled
    """Generalised Jacobian (m × m) of the active rows (``StepSolver._factorise``): on the
    slipping rows (I − Φ_i) K_q − f n_i K_p + ρ_t Φ_i on the node's own slip columns
    (:mod:`slipcycle.discrete3d.cone`), the rows of K on the separated ones.

    Parameters
    ----------
    KVU : (m + ns, m) array
        Rows of K of the active unknowns, then the normal rows of the slipping nodes.
    phi : (ns, 2, 2) array, nvec : (ns, 2) array, fS, rhoS : (ns,) arrays
    """
    m = 2 * ns + 3 * npp
    J = np.empty((m, m))
    for i in range(ns):
        for a in range(2):
            row = 2 * i + a
            p0, p1 = phi[i, a, 0], phi[i, a, 1]
            fn = fS[i] * nvec[i, a]
            for c in range(m):
                J[row, c] = (KVU[row, c] - (p0 * KVU[2 * i, c] + p1 * KVU[2 * i + 1, c])
                             - fn * KVU[m + i, c])
            J[row, 2 * i] += rhoS[i] * p0
            J[row, 2 * i + 1] += rhoS[i] * p1
    for k in range(2 * ns, m):
        for c in range(m):
            J[k, c] = KVU[k, c]
    return J


@njit(cache=True, nogil=True)
def _slip_start(x0, U, ns):  # pragma: no cover - compiled
    """Slips (ns, 2) at the start of the step of the slipping nodes, whose unknowns are
    the first 2 ns entries of U."""
    v0S = np.empty((ns, 2))
    for i in range(ns):
        v0S[i, 0] = x0[U[2 * i]]
        v0S[i, 1] = x0[U[2 * i + 1]]
    return v0S


@njit(cache=True, nogil=True)
def _apply_change(K, U, D, x, r):  # pragma: no cover - compiled
    """x[U] += D and r += K[:, U] D if D ≠ 0; whether it is."""
    for k in range(D.size):
        if D[k] != 0.0:
            add_at(K, U, D, x, r)
            return True
    return False


@njit(cache=True, nogil=True)
def active_newton(kind, K, x, r, x0, U, V, first, xU, rV, D, fS, rhoS, rhoP, KVU, lu, piv,
                  W, KSP, Kt, phi, nvec, y, ya, has_lu, fresh, it, max_iter, res_prev,
                  stepped, force_tol, chord_rate, R, zs, zsn):  # pragma: no cover - compiled
    """One round of the Newton iteration on an active set (``StepSolver._local_newton``):
    with ``first`` the active unknowns ``xU`` = x[U] and reactions ``rV`` = r[V] are
    gathered, then :func:`chord_newton` runs; unless it needs a new matrix (status 3) or
    failed (4), the change D of x[U] is applied to x and, through the rows of K, to
    every reaction r.

    Returns
    -------
    status, it, res_prev, stepped
        As :func:`chord_newton`.
    moved : bool
        D ≠ 0 (applied).
    """
    ns, npp = fS.size, rhoP.size
    if first:
        for k in range(U.size):
            xU[k] = x[U[k]]
        for k in range(V.size):
            rV[k] = r[V[k]]
    v0S = _slip_start(x0, U, ns)
    status, it, res_prev, stepped = chord_newton(
        kind, xU, rV, D, v0S, fS, rhoS, rhoP, ns, npp, KVU, lu, piv, W, KSP, Kt, phi, nvec,
        y, ya, has_lu, fresh, it, max_iter, res_prev, stepped, force_tol, chord_rate, R, zs,
        zsn)
    if kind == 2 and status <= 2:
        _elim_finish(D, ns, W, y, ya)
    moved = status <= 2 and _apply_change(K, U, D, x, r)
    return status, it, res_prev, stepped, moved


@njit(cache=True, nogil=True)
def slip_rounds(K, x, r, x0, f, rho_t, rho_n, modes, fix_t, fix_n, slip, sep, U, V, first,
                fixed, xU, rV, D, fS, rhoS, KVU, lu, piv, has_lu, fresh, it, rounds,
                max_iter, res_prev, stepped, force_tol, chord_rate, R, zs,
                zsn):  # pragma: no cover - compiled
    """The rounds of ``StepSolver._newton`` while the active set is the same set of
    slipping nodes (no separated node): each round the chord iterations
    (:func:`chord_newton`, the whole active Jacobian), the change applied to x and r,
    then the classification of every node (:func:`classify_nodes`, :func:`fix_nodes`),
    as the Python loop does, without returning to it between rounds.

    ``first``: the round starts (gather x[U], r[V]); else the chord loop resumes with
    ``res_prev``, ``stepped`` (after the caller factorised: ``fresh``). ``fixed``: the
    classification of this round fixed nodes.

    Returns
    -------
    code : int
        3 a new Newton matrix is needed (as :func:`chord_newton`), 4 failed (a
        non-finite step, or the iteration limits reached), 5 converged (the step is x, r
        with the node states ``modes``), 6 the next round's active set differs (its
        classification done: ``slip``, ``sep``, and its nodes fixed).
    it, rounds, res_prev, stepped
        The counters, to resume.
    count, ns, npp
        The last classification (:func:`classify_nodes`) when code is 6.
    """
    ns = fS.size
    no_w = np.empty((0, 0))
    no_phi = np.empty((0, 2, 2))
    no_nvec = np.empty((0, 2))
    no_p = np.empty(0)
    no_ya = np.zeros(1, np.int64)
    v0S = _slip_start(x0, U, ns)
    while True:
        if first:
            for k in range(U.size):
                xU[k] = x[U[k]]
                D[k] = 0.0
            for k in range(V.size):
                rV[k] = r[V[k]]
            res_prev, stepped = np.inf, False
        status, it, res_prev, stepped = chord_newton(
            0, xU, rV, D, v0S, fS, rhoS, no_p, ns, 0, KVU, lu, piv, no_w, no_w, no_w,
            no_phi, no_nvec, no_p, no_ya, has_lu, fresh, it, max_iter, res_prev, stepped,
            force_tol, chord_rate, R, zs, zsn)
        if status >= 3:
            return status, it, rounds, res_prev, stepped, 0, 0, 0
        moved = _apply_change(K, U, D, x, r)
        if status == 0 and not fixed and not moved:
            return 5, it, rounds, res_prev, stepped, 0, 0, 0
        if not (it < max_iter and rounds < max_iter):
            return 4, it, rounds, res_prev, stepped, 0, 0, 0
        rounds += 1
        count, ns2, npp2 = classify_nodes(x, r, x0, f, rho_t, rho_n, modes, fix_t, fix_n,
                                          slip, sep)
        fixed = count > 0
        if fixed:
            fix_nodes(K, x, x0, r, fix_t, fix_n)
        same = npp2 == 0 and ns2 == ns
        for i in range(ns2 if same else 0):
            if 2 * slip[i] != U[2 * i]:
                same = False
                break
        if not same:
            return 6, it, rounds, res_prev, stepped, count, ns2, npp2
        first, fresh = True, False
