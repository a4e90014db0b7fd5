"""The three-dimensional coupled discrete frictional system with the isotropic Coulomb cone.

N contact nodes of a 3-D elastic body, statically reduced to the contact degrees of
freedom: two tangential slips v_j = (v_j1, v_j2) in the local tangent plane (t1, t2) and
one normal separation w_j ≥ 0 per node (J. R. Barber, "Frictional systems under periodic
loads", J. Phys.: Conf. Ser. 382 (2012) 012002, §3, for the 2-D form; A. Klarbring, Int. J.
Engng Sci. 37 (1999) 987–1002 and Andersson, Barber & Ahn (2013) for the 3-D setting):

    q = q^w(θ) + A v + Bᵀ w      tangential reactions, (2N,), node-major pairs
    p = p^w(θ) + B v + C w       normal reactions (N,), compressive positive

A is 2N×2N, B is N×2N, C is N×N; ``K = [[A, Bᵀ], [B, C]]`` (3N×3N) must be symmetric
positive definite. Tangential vectors are *node-major*: entries 2j, 2j+1 are the t1, t2
components of node j (the ordering of :func:`slipcycle.io.matrices.read_reduced_stiffness`).

At every node: contact ``w ≥ 0, p ≥ 0, w p = 0`` (a separated node carries p = 0, q = 0),
the isotropic Coulomb cone ``|q_j| ≤ f_j p_j``, and at the limit the slip rate is opposite
to the tangential reaction, ``v̇_j = −γ_j q_j/|q_j|``, γ_j ≥ 0 (maximum dissipation). With
one tangential direction this is the sign convention of the 2-D model (positive slip with
q = −f p). The dissipation of node j is ``D_j = −∫ q_j · dv_j ≥ 0``.

State and reaction vectors are stored tangential first: ``x = [v, w]`` (3N,) and
``r = [q, p]`` (3N,), so that ``r = r^w + K x``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from slipcycle.coupled.system import CoupledSystem, coupled_stiffness, friction_per_node
from slipcycle.discrete3d.wellposed import critical_friction_3d
from slipcycle.errors import ModelError

__all__ = ["FrictionalSystem3D", "ModelError3D", "STICK", "SLIP", "SEPARATED", "STATE_NAMES",
           "embed_2d"]

#: node states of the 3-D model (``node_state`` codes of results and field files)
STICK, SLIP, SEPARATED = 0, 1, 2
STATE_NAMES = ("stick", "slip", "separated")


class ModelError3D(ModelError):
    """An invalid 3-D model, with the optional remedy of :class:`slipcycle.errors.ModelError`.

    Parameters
    ----------
    name : str
        The matrix or parameter at fault (``"A"``, ``"B"``, ``"C"``, ``"friction"``,
        ``"coordinates"``, ...); also ``key``.
    problem : str
        What is wrong, in words.
    remedy : (str, bool, str), optional
        ``(field, value, purpose)``: another field that lets the model through.
    """


def _matrix(name: str, M, shape: tuple) -> np.ndarray:
    try:
        M = np.asarray(M, dtype=float)
    except (TypeError, ValueError):
        raise ModelError3D(name, "must be a matrix of numbers") from None
    if M.shape != shape:
        want = "×".join(map(str, shape))
        raise ModelError3D(name, f"must be {want}, got shape {M.shape}")
    if not np.all(np.isfinite(M)):
        raise ModelError3D(name, "must contain only finite numbers (found nan or inf)")
    return M


def _check_spd(name: str, M: np.ndarray, rtol: float = 1e-10) -> np.ndarray:
    """Symmetric part of M after checking symmetry and positive definiteness (Cholesky;
    the eigenvalues only for the message)."""
    scale = max(float(np.max(np.abs(M))), np.finfo(float).tiny)
    asym = np.abs(M - M.T)
    if np.max(asym) > rtol * scale:
        i, j = np.unravel_index(np.argmax(asym), M.shape)
        raise ModelError3D(name, f"must be symmetric: entries [{i}][{j}] = {M[i, j]:.6g} and "
                                 f"[{j}][{i}] = {M[j, i]:.6g} differ")
    S = 0.5 * (M + M.T)
    try:
        L = np.linalg.cholesky(S)
        ok = np.min(np.diag(L)) ** 2 > rtol * np.max(np.diag(S))
    except np.linalg.LinAlgError:
        ok = False
    if not ok:
        eig = np.linalg.eigvalsh(S)
        raise ModelError3D(name, f"must be positive definite: smallest eigenvalue "
                                 f"{eig[0]:.6g} (largest {eig[-1]:.6g})")
    return S


def _optional(name: str, value, shape: tuple) -> np.ndarray | None:
    if value is None:
        return None
    return _matrix(name, value, shape)


@dataclass(frozen=True)
class FrictionalSystem3D(CoupledSystem):
    """A validated 3-D coupled discrete frictional system (isotropic Coulomb cone).

    Parameters
    ----------
    A : (2N, 2N) array_like
        Tangential stiffness [N/m], symmetric positive definite, node-major (t1, t2) pairs.
    B : (N, 2N) array_like
        Normal–tangential coupling [N/m]: ``B[j, 2i + a]`` is the normal reaction at node j
        per unit slip of node i in direction t_a. ``B = 0`` is the uncoupled case.
    C : (N, N) array_like
        Normal stiffness [N/m], symmetric positive definite.
    friction : float or (N,) array_like
        Coulomb coefficient f ≥ 0 of each node.
    coordinates : (N, 3) array_like, optional
        Node positions [m] (default: the nodes on a line, x = j).
    normals : (N, 3) array_like, optional
        Unit outward normals n of the nodes (default e_z).
    tangents : (N, 2, 3) array_like, optional
        Unit tangents t1, t2 of the nodes (default e_x, e_y); with ``normals`` they give
        the global components of slip and traction in the field files.
    area : float or (N,) array_like, optional
        Tributary area of each node [m²] (default 1), for dissipation per unit area.
    accept_ill_posed : bool, optional
        ``False`` (default): refuse f ≥ the sampled critical friction coefficient of
        :func:`~slipcycle.discrete3d.wellposed.critical_friction_3d`. ``True``: run
        anyway (the incremental solver may then stop with a ``SolverError``).

    Raises
    ------
    ModelError3D
        Naming the matrix or parameter and the failed property.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    friction: np.ndarray
    coordinates: np.ndarray | None = None
    normals: np.ndarray | None = None
    tangents: np.ndarray | None = None
    area: np.ndarray | float = 1.0
    accept_ill_posed: bool = field(default=False, compare=False)
    K: np.ndarray = field(init=False, repr=False, compare=False)

    ERROR = ModelError3D
    ILL_POSED = ("the incremental problem is ill posed (P-matrix condition on the cone's "
                 "slip directions)")

    def __post_init__(self):
        try:
            C = np.asarray(self.C, dtype=float)
        except (TypeError, ValueError):
            raise ModelError3D("C", "must be a square matrix of numbers") from None
        if C.ndim != 2 or C.shape[0] != C.shape[1] or C.shape[0] < 1:
            raise ModelError3D("C", f"must be a square N×N matrix with N >= 1, got shape "
                                    f"{np.shape(C)}")
        n = C.shape[0]
        A = _check_spd("A", _matrix("A", self.A, (2 * n, 2 * n)))
        C = _check_spd("C", _matrix("C", C, (n, n)))
        B = _matrix("B", self.B, (n, 2 * n))
        K = coupled_stiffness(A, B, C, ModelError3D)
        f = friction_per_node(self.friction, n, ModelError3D)
        coords = _optional("coordinates", self.coordinates, (n, 3))
        if coords is None:
            coords = np.column_stack([np.arange(n, dtype=float), np.zeros(n), np.zeros(n)])
        normals = _optional("normals", self.normals, (n, 3))
        tangents = _optional("tangents", self.tangents, (n, 2, 3))
        if normals is None:
            normals = np.tile([0.0, 0.0, 1.0], (n, 1))
        if tangents is None:
            tangents = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), (n, 1, 1))
        frame = np.concatenate([tangents, normals[:, None, :]], axis=1)   # (N, 3, 3)
        gram = np.einsum("nij,nkj->nik", frame, frame)
        if np.max(np.abs(gram - np.eye(3)[None])) > 1e-6:
            j = int(np.argmax(np.max(np.abs(gram - np.eye(3)[None]), axis=(1, 2))))
            raise ModelError3D("tangents", f"node {j}: t1, t2, n must be orthonormal unit "
                                           "vectors")
        try:
            area = np.broadcast_to(np.asarray(self.area, dtype=float), (n,)).copy()
        except ValueError:
            raise ModelError3D("area", f"must be a number or a list of {n} numbers") from None
        if not np.all(np.isfinite(area)) or np.any(area <= 0):
            raise ModelError3D("area", "must be finite and > 0")
        self._store(A=A, B=B, C=C, friction=f, K=K, coordinates=coords, normals=normals,
                    tangents=tangents, area=area)
        if not self.accept_ill_posed:
            self._check_well_posed()

    @cached_property
    def critical_friction(self):
        """The sampled critical friction coefficient of the cone and its certified lower
        bound (:class:`~slipcycle.discrete3d.wellposed.CriticalFriction3D`)."""
        return critical_friction_3d(self.A, self.B, self.C, self.friction)


def embed_2d(A2, B2, C2, friction, *, accept_ill_posed: bool = True) -> FrictionalSystem3D:
    """The 3-D system of a 2-D one (A, B, C all N×N): slips along t1 as in 2-D, the t2
    components elastically uncoupled (A_t2t2 = A) and never loaded.

    With loads along t1 only, every t2 slip and reaction stays zero and the cone reduces
    to |q_j| ≤ f p_j of the 2-D model (the special case of one tangential direction).

    Parameters
    ----------
    A2, B2, C2 : (N, N) arrays
        The 2-D model's blocks, N/m.
    friction : float or (N,) array
        Friction coefficients.
    accept_ill_posed : bool
        As :class:`FrictionalSystem3D`.

    Returns
    -------
    FrictionalSystem3D
    """
    A2, B2 = np.asarray(A2, float), np.asarray(B2, float)
    n = A2.shape[0]
    A = np.kron(A2, np.eye(2))
    B = np.zeros((n, 2 * n))
    B[:, 0::2] = B2
    return FrictionalSystem3D(A, B, C2, friction, accept_ill_posed=accept_ill_posed)
