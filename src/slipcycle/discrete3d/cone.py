"""The local return map of the isotropic Coulomb cone (Alart–Curnier form).

For one load step the contact conditions of node j are written as the fixed-point
equations of Alart & Curnier (1991) with augmentation parameters ρ_n, ρ_t > 0:

    p_j = max(0, p̂_j),            p̂_j = p_j − ρ_n w_j
    q_j = Proj_{D(f_j p̂_j⁺)}(z_j),  z_j = q_j − ρ_t Δv_j

(D(R) the disk of radius R). They hold iff w_j ≥ 0, p_j ≥ 0, w_j p_j = 0 and
|q_j| ≤ f_j p_j with Δv_j = −γ q_j/|q_j|, γ ≥ 0 (slip opposite to the tangential
reaction, the convention of the 2-D model: positive slip with q = −f p). The sign of the
augmentation makes a sliding node's z_j point along q_j: z = q (1 + ργ/|q|).

Node states from the augmented variables: ``separated`` if p̂_j ≤ 0, ``slip`` if
|z_j| > f_j p̂_j, else ``stick`` (Christensen, Klarbring, Pang & Strömberg 1998, §3).

Generalised Jacobian of a slipping node's residual R_j = q_j − f p_j z_j/|z_j| (w_j = 0):

    dR_j = (I − Φ_j) dq_j − f n_j dp_j + ρ_t Φ_j dΔv_j,   Φ_j = (f p_j/|z_j|)(I − n_j n_jᵀ),

with n_j = z_j/|z_j| (the derivative of the projection onto the disk outside it).

References
----------
P. Alart, A. Curnier, "A mixed formulation for frictional contact problems prone to
Newton like solution methods", Comput. Methods Appl. Mech. Engrg 92 (1991) 353–375.
P. W. Christensen, A. Klarbring, J.-S. Pang, N. Strömberg, "Formulation and comparison of
algorithms for frictional contact problems", Int. J. Numer. Meth. Engng 42 (1998) 145–173.
"""

from __future__ import annotations

import numpy as np

from slipcycle.discrete3d.model import SEPARATED, SLIP, STICK

__all__ = ["disk_projection", "node_states", "slip_linearisation"]


def disk_projection(z: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Project 2-vectors onto disks: (N, 2), (N,) → (N, 2) (radius < 0 taken as 0)."""
    r = np.maximum(radius, 0.0)
    norm = np.linalg.norm(z, axis=1)
    scale = np.where(norm > r, r / np.where(norm > 0, norm, 1.0), 1.0)
    return z * scale[:, None]


def node_states(q, p, dv, w, f, rho_t, rho_n):
    """States of the augmented local problem.

    Parameters
    ----------
    q : (N, 2) array
        Tangential reactions [N].
    p : (N,) array
        Normal reactions [N].
    dv : (N, 2) array
        Slip increment of the step [m].
    w : (N,) array
        Separation [m].
    f, rho_t, rho_n : (N,) arrays
        Friction coefficients and augmentation parameters [N/m].

    Returns
    -------
    modes : (N,) int8 array
        STICK, SLIP or SEPARATED.
    z : (N, 2) array
        Augmented tangential variable q − ρ_t Δv [N].
    znorm : (N,) array
    """
    phat = p - rho_n * w
    z = q - rho_t[:, None] * dv
    zn = np.linalg.norm(z, axis=1)
    modes = np.full(p.shape, STICK, np.int8)
    modes[zn > f * phat] = SLIP
    modes[phat <= 0.0] = SEPARATED
    return modes, z, zn


def slip_linearisation(z, zn, p, f, rho_t):
    """Blocks of the generalised Jacobian of slipping nodes (module docstring).

    Parameters
    ----------
    z : (k, 2) array, zn : (k,) array
        Augmented variables of the slipping nodes (zn > 0).
    p, f, rho_t : (k,) arrays

    Returns
    -------
    phi : (k, 2, 2) array
        Φ_j = (f p/|z|)(I − n nᵀ) (dimensionless).
    nvec : (k, 2) array
        Unit vectors n_j = z_j/|z_j|.
    """
    nvec = z / zn[:, None]
    c = f * p / zn
    phi = c[:, None, None] * (np.eye(2)[None] - nvec[:, :, None] * nvec[:, None, :])
    return phi, nvec
