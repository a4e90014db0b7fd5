"""Loads and run settings read from case tables: one reader for the 2-D ``discrete`` and the
3-D ``discrete3d`` models, whose per-node loads differ only in the number of tangential
components per node (1 or 2, node-major).
"""

from __future__ import annotations

import numpy as np

from slipcycle.io.case import Section, read_steady_tol
from slipcycle.loading import HarmonicLoad, TabulatedLoad
from slipcycle.loading.nodal import LoadCase

__all__ = ["time_function", "node_vector", "periodic_load", "protocol_states", "load_cases",
           "run_settings"]


def _shape(name: str, n: int, components: int) -> tuple[int, ...]:
    """Per-node shape of load ``name``: p (N,); q (N,) in 2-D, (N, 2) in 3-D."""
    return (n,) if name == "p" or components == 1 else (n, components)


def node_vector(sec: Section, key: str, n: int, components: int = 1,
                default=None) -> np.ndarray | None:
    """A per-node vector of ``components`` values per node, flattened node-major.

    A bare number fills every entry. None if absent and no default.
    """
    shape = (n,) if components == 1 else (n, components)
    arr = sec.array(key, default, shape=shape, scalar_ok=True)
    return None if arr is None else arr.reshape(n * components)


def periodic_load(sec: Section, name: str, n: int, lam: float,
                  components: int = 1) -> HarmonicLoad | TabulatedLoad:
    """Per-node periodic load ``name`` (``"p"`` or ``"q"``) of the ``[loading]`` table.

    Harmonic: ``name0`` (mean), ``name1`` (amplitude per node, or one row per harmonic),
    ``name1_phase`` (rad); or tabulated: ``theta`` (rad) and ``name_table`` (one row per
    angle). The mean normal load ``p0`` is required; the others default to zero.

    Parameters
    ----------
    sec : Section
        The ``[loading]`` table.
    name : {"p", "q"}
    n : int
        Number of contact nodes.
    lam : float
        Load factor λ of the periodic part.
    components : int
        Tangential components per node (1 in 2-D, 2 in 3-D: ``q`` values are
        ``[q_t1, q_t2]`` per node).

    Returns
    -------
    HarmonicLoad or TabulatedLoad
        Of size N (p) or ``components`` N (q, node-major), N.
    """
    shape = _shape(name, n, components)
    size = int(np.prod(shape))
    mean = sec.array(f"{name}0", np.zeros(shape) if name == "q" else None, shape=shape,
                     scalar_ok=True)
    if mean is None:
        raise sec.error(f"{name}0", "required key is missing (mean normal load per node)")
    mean = mean.reshape(size)
    table_key, amp_key = f"{name}_table", f"{name}1"
    if sec.has(table_key):
        if sec.has(amp_key):
            raise sec.error(amp_key, f"give either {amp_key} (harmonic) or {table_key} "
                                     "(tabulated), not both")
        theta = sec.array("theta", shape=(None,), ge=0.0, lt=2 * np.pi)
        if theta.size < 2 or np.any(np.diff(theta) <= 0):
            raise sec.error("theta", "must have at least 2 strictly increasing angles in "
                                     "[0, 2π)")
        vals = sec.array(table_key, shape=(theta.size, *shape))
        return TabulatedLoad(theta, vals.reshape(theta.size, size), mean, lam)
    raw = sec.array(amp_key, np.zeros(shape))
    amp = (sec.coerce_array(amp_key, raw, shape=shape)[None] if raw.ndim == len(shape)
           else sec.coerce_array(amp_key, raw, shape=(None, *shape)))
    amp = amp.reshape(-1, size)
    phase_key = f"{name}1_phase"
    ph = sec.array(phase_key, 0.0)
    if ph.ndim == 0:
        ph = np.full(amp.shape, float(ph))
    elif ph.ndim == len(shape) and amp.shape[0] == 1:
        ph = sec.coerce_array(phase_key, ph, shape=shape).reshape(1, size)
    else:
        ph = sec.coerce_array(phase_key, ph, shape=(amp.shape[0], *shape)).reshape(amp.shape)
    return HarmonicLoad(mean, amp, ph, lam)


def protocol_states(sec: Section, n: int, components: int = 1) -> np.ndarray | None:
    """The assembly protocol ``[[<model>.protocol]]``: load states passed through in order.

    Each table gives ``p_w`` (N,) and optionally ``q_w`` (zero by default).

    Returns
    -------
    numpy.ndarray, shape (S, (components + 1) N), or None
        Rows [q_w; p_w] (N), None without a protocol.
    """
    tables = sec.tables("protocol", None)
    if not tables:
        return None
    states = []
    for ps in tables:
        p = ps.array("p_w", shape=(n,), scalar_ok=True)
        q = node_vector(ps, "q_w", n, components, np.zeros(_shape("q", n, components)))
        states.append(np.concatenate([q, p]))
        ps.finish()
    return np.array(states)


def load_cases(ld: Section, n: int, lam: float, components: int = 1,
               file_case=None) -> tuple[LoadCase, ...]:
    """The basic load cases ``[[loading.load_case]]``, each with its time function.

    A case gives per-node ``p`` and ``q`` (zero by default), or ``file_case``: a load case
    of the stiffness file, resolved by ``file_case(section) -> (p, q)``.

    Returns
    -------
    tuple of LoadCase
    """
    cases = []
    for cs in ld.tables("load_case", None):
        if cs.has("file_case"):
            if file_case is None:
                raise cs.error("file_case", "needs a stiffness_file with load cases")
            pvec, qvec = file_case(cs)
        else:
            pvec = cs.array("p", np.zeros(n), shape=(n,))
            qvec = node_vector(cs, "q", n, components, np.zeros(_shape("q", n, components)))
        cases.append(LoadCase(p=pvec, q=qvec, time=time_function(cs, lam)))
        cs.finish()
    return tuple(cases)


def run_settings(rn: Section, **extra) -> dict:
    """The ``[run]`` table of the discrete models: ``cycles`` (40), ``steps_per_cycle``
    (100), ``steady_tol`` (1e-8; alias ``tolerance``) and ``min_cycles`` (1), plus
    ``extra`` settings ``name=(key, reader)`` with ``reader(section, key)``."""
    run = {
        "cycles": rn.int("cycles", 40, ge=1),
        "steps_per_cycle": rn.int("steps_per_cycle", 100, ge=1),
        "tol": read_steady_tol(rn, 1e-8),
        "min_cycles": rn.int("min_cycles", 1, ge=1),
    }
    for name, (key, reader) in extra.items():
        run[name] = reader(rn, key)
    return run


def time_function(sec: Section, lam: float) -> HarmonicLoad | TabulatedLoad:
    """Scalar time function g(θ) = mean + λ g̃(θ) of a basic load case, from its table.

    Parameters
    ----------
    sec : Section
        The ``[[loading.case]]`` table: ``mean``, and either ``amplitude``/``phase`` (one
        per harmonic, rad) or tabulated ``theta`` (rad, strictly increasing in [0, 2π)) and
        ``values``.
    lam : float
        Load factor λ of the periodic part.

    Returns
    -------
    HarmonicLoad or TabulatedLoad
        Of size 1, dimensionless.
    """
    mean = sec.float("mean", 0.0)
    if sec.has("theta"):
        theta = sec.array("theta", shape=(None,), ge=0.0, lt=2 * np.pi)
        if theta.size < 2 or np.any(np.diff(theta) <= 0):
            raise sec.error("theta", "must have at least 2 strictly increasing angles in "
                                     "[0, 2π)")
        vals = sec.array("values", shape=(theta.size,))
        return TabulatedLoad(theta, vals[:, None], [mean], lam)
    amp = np.atleast_1d(sec.array("amplitude", 0.0))
    if amp.ndim != 1:
        raise sec.error("amplitude", "must be a number or a list (one per harmonic)")
    phase = np.atleast_1d(sec.array("phase", 0.0))
    if phase.size == 1:
        phase = np.full(amp.shape, float(phase[0]))
    elif phase.shape != amp.shape:
        raise sec.error("phase", f"must be a number or a list of {amp.size} phases")
    return HarmonicLoad([mean], amp[:, None], phase[:, None], lam)
