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
           "run_settings", "check_run", "check_some_contact", "check_load_scale",
           "step_tolerance", "MIN_STEPS_PER_CYCLE", "MAX_ENERGY_SCALE"]

#: smallest accepted relative step tolerance: the state is known to about 1e-16 relative,
#: and the steps' error estimate to some 1e6 times that after the Newton solves, so a step
#: control asked for less subdivides without end (1e-300 was a run still going at 180 s)
MIN_STEP_TOLERANCE = 1e-10


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
    angle). The mean normal load ``p0`` is required with a harmonic ``p``; with a table
    it defaults to zero (the table then carries the whole load); the others default to
    zero.

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
    table_key = f"{name}_table"
    # a table may carry the whole normal load: p0 then defaults to 0 (it adds to the table)
    optional = name == "q" or sec.has(table_key)
    mean = sec.array(f"{name}0", np.zeros(shape) if optional else None, shape=shape,
                     scalar_ok=True)
    if mean is None:
        raise sec.error(f"{name}0", "required key is missing (mean normal load per node; "
                                    "or give the whole normal load as theta and p_table)")
    mean = mean.reshape(size)
    amp_key = f"{name}1"
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
    (100), ``steady_tol`` (1e-8; alias ``tolerance``), ``min_cycles`` (1) and ``accelerate``
    (None when not given: the driver's rule; ``false`` plain cycling), plus
    ``extra`` settings ``name=(key, reader)`` with ``reader(section, key)``."""
    run = {
        "cycles": rn.int("cycles", 40, ge=1),
        "steps_per_cycle": rn.int("steps_per_cycle", 100, ge=1),
        "tol": read_steady_tol(rn, 1e-8),
        "min_cycles": rn.int("min_cycles", 1, ge=1),
        "accelerate": rn.bool("accelerate") if rn.has("accelerate") else None,
    }
    for name, (key, reader) in extra.items():
        run[name] = reader(rn, key)
    return run


#: fewest load samples per cycle: below, a cycle cannot resolve a harmonic load (one
#: sample sees a constant load: shakedown with D = 0 whatever the loads); the
#: ``[fe.discrete]`` table that writes discrete cases has the same floor
MIN_STEPS_PER_CYCLE = 4


def check_run(rn: Section, run) -> None:
    """Refuse ``[run]`` settings of a discrete model (2-D or 3-D) that cannot give a
    meaningful cycle, naming the key.

    Parameters
    ----------
    rn : Section
        The ``[run]`` table.
    run : RunSettings
        Its settings (:func:`run_settings`).

    Raises
    ------
    CaseError
        ``steps_per_cycle`` below :data:`MIN_STEPS_PER_CYCLE`, or ``min_cycles`` above
        ``cycles`` (the run would stop at ``cycles`` and call a steady cycle
        "not converged").
    """
    if run.steps_per_cycle < MIN_STEPS_PER_CYCLE:
        raise rn.error("steps_per_cycle", f"must be >= {MIN_STEPS_PER_CYCLE} (load samples "
                       f"per cycle; fewer cannot follow a periodic load), got "
                       f"{run.steps_per_cycle}")
    if run.min_cycles > run.cycles:
        raise rn.error("min_cycles", f"must be <= cycles ({run.cycles}): the run stops after "
                       f"{run.cycles} cycles, got {run.min_cycles}")


#: largest elastic energy scale F²/k [J] a discrete model is computed with: the engines
#: form energies (work of the loads, dissipation, their step-error estimates) as products
#: of forces and displacements of this size, and a double overflows at 1.8e308
MAX_ENERGY_SCALE = 1e300

#: the ``[loading]`` keys that set the size of the loads (the largest is blamed)
_LOAD_KEYS = ("p0", "q0", "p1", "q1", "p_table", "q_table", "lam")


def check_load_scale(ld: Section, samples: np.ndarray, stiffness: float) -> None:
    """Refuse loads whose elastic energy cannot be represented in double precision.

    Parameters
    ----------
    ld : Section
        The ``[loading]`` table.
    samples : numpy.ndarray
        The loads [q^w, p^w] [N] at the samples of a cycle (and of the protocol).
    stiffness : float
        The largest diagonal entry of the reduced stiffness K [N/m].

    Raises
    ------
    CaseError
        When F²/k exceeds :data:`MAX_ENERGY_SCALE` (F the largest load): a run would meet
        overflow (inf, nan) in its energies. Blames the ``[loading]`` key holding the
        largest number (``lam`` when the factor is the big one).
    """
    force = float(np.max(np.abs(samples), initial=0.0))
    energy = force * (force / stiffness) if stiffness > 0 else 0.0
    if not energy > MAX_ENERGY_SCALE:   # also false for nan: that is refused elsewhere
        return

    def size(key: str) -> float:
        try:
            return float(np.max(np.abs(np.asarray(ld.data[key], float)), initial=0.0))
        except (TypeError, ValueError):
            return 0.0

    given = [k for k in _LOAD_KEYS if ld.has(k)]
    key = max(given, key=size) if given else "load_case"
    size_text = f"about {energy:.3g} J" if np.isfinite(energy) else "over 1.8e308 J"
    raise ld.error(key, f"loads up to {force:.3g} N on a stiffness of {stiffness:.3g} N/m "
                        f"store an elastic energy F²/k of {size_text}, beyond what double "
                        f"precision can compute with ({MAX_ENERGY_SCALE:g} J at most): check "
                        "the units of the loads")


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


def check_some_contact(ld: Section, p_w: np.ndarray) -> None:
    """Refuse a normal load that leaves every node open for the whole cycle.

    Parameters
    ----------
    ld : Section
        The ``[loading]`` table (its key is blamed).
    p_w : numpy.ndarray, shape (S, N)
        Normal loads of the nodes at the cycle's samples [N]; compressive is positive.

    Raises
    ------
    CaseError
        When no node is ever pressed (p^w <= 0 everywhere): nothing is in contact, so
        there is no friction and the run would report a void "shakedown".
    """
    p_w = np.asarray(p_w, float)
    if p_w.size and np.all(p_w <= 0.0):
        key = ("p_table" if ld.has("p_table") else "p0" if ld.has("p0") else "load_case")
        raise ld.error(key, f"every node is open for the whole cycle (largest normal load "
                            f"p^w = {float(p_w.max()):.6g} N; compressive is positive): "
                            "nothing is in contact, so there is no friction to compute; "
                            "press the nodes (p^w > 0 somewhere in the cycle)")


def step_tolerance(rn: Section, key: str = "step_tolerance", default: float = 1e-7) -> float:
    """The relative step tolerance of a ``[run]`` table, in [1e-10, 1).

    Below :data:`MIN_STEP_TOLERANCE` the step control asks for a relative error under the
    round-off of the state (about 1e-16 of it, times the growth over a step) and would
    subdivide forever: refused with that estimate.
    """
    tol = rn.float(key, default, gt=0.0, lt=1.0)
    if tol < MIN_STEP_TOLERANCE:
        raise rn.error(key, f"must be >= {MIN_STEP_TOLERANCE:g}, got {tol:g}: the error "
                            "estimate of a step is itself round-off (about 1e-16 of the "
                            "state, amplified by the Newton solves) below that, so the step "
                            f"control would subdivide without end; the default is {default:g}")
    return tol
