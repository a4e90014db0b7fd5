"""Diagnostics of a reduced model: coupling measures (import checks).

References
----------
Dundurs, J. (1969). Discussion of "Edge-bonded dissimilar orthogonal elastic wedges under
normal and shear loading". J. Appl. Mech. 36, 650–652.
Barber, J. R. (2018). Contact Mechanics, Springer, §1.4 (the coupling parameter β).
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import legendre

from slipcycle.fe.reduction import ReducedModel
from slipcycle.materials import dundurs_beta

__all__ = ["coupling_ratio", "smooth_coupling", "dundurs_beta"]


def coupling_ratio(model: ReducedModel) -> float:
    """Node-level coupling ‖B‖_F / ‖A‖_F.

    Dominated by the element-scale part of the reduced stiffness, so for a β = 0 pair of
    half-planes it tends to zero only with the discretisation error (exactly zero for
    mirror-image meshes of identical bodies); see :func:`smooth_coupling`.

    Parameters
    ----------
    model : ReducedModel
        Its blocks A (tangential) and B (normal force per unit slip), (N, N) in N/m.

    Returns
    -------
    float
        ‖B‖_F / ‖A‖_F (dimensionless, Frobenius norms).

    References
    ----------
    Barber, J. R. (2012). Frictional systems under periodic loads — history-dependence,
    non-uniqueness and energy dissipation. J. Phys.: Conf. Ser. 382, 012002 (B, the
    normal–tangential coupling of the reduced system). Dundurs, J. (1969). J. Appl. Mech.
    36, 650–652 (β, its continuum counterpart).
    """
    return float(np.linalg.norm(model.B) / np.linalg.norm(model.A))


def smooth_coupling(model: ReducedModel, modes: int = 4) -> float:
    """Coupling of smooth slip/gap patterns: ‖ΦᵀBΦ‖ / (‖ΦᵀAΦ‖ ‖ΦᵀCΦ‖)^{1/2}.

    Φ (N × ``modes``) holds the Legendre polynomials P_0 … P_{modes−1} of the node
    position along t, mapped to [−1, 1] over the contact nodes. ΦᵀBΦ are the generalised
    normal forces that smooth tangential displacement patterns produce with the gap
    patterns held: a mesh-converging measure that vanishes for uncoupled (β = 0) bodies.
    """
    s = model.coords @ model.tangent
    s = 2 * (s - s.min()) / np.ptp(s) - 1
    Phi = np.stack([legendre.legval(s, np.eye(modes)[i]) for i in range(modes)], axis=1)
    B = Phi.T @ model.B @ Phi
    A = Phi.T @ model.A @ Phi
    C = Phi.T @ model.C @ Phi
    return float(np.linalg.norm(B) / np.sqrt(np.linalg.norm(A) * np.linalg.norm(C)))
