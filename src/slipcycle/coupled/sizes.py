"""Memory estimates of discrete analyses, checked before any work.

Sizes that validation accepts (a count of load steps, of λ values, of starts, of grid
points, or the node count of a stiffness file) but that cannot be allocated are refused up
front, naming the key or option, with the estimated memory. The estimates are upper
bounds of the dominant arrays (float64 = 8 bytes), not measurements; they only have to be
right to within a small factor to tell a feasible size from one that would exhaust memory.
"""

from __future__ import annotations

from slipcycle.io.sizes import MEMORY_LIMIT, check_memory, format_bytes

__all__ = ["MEMORY_LIMIT", "check_memory", "format_bytes", "run_bytes", "system_bytes",
           "cells_bytes", "check_case_sizes"]

#: bytes per node and load sample of a recorded run: x, r (2N float64 each) in the result
#: and again in the Dataset, friction limit, node modes (int8, twice)
_RECORD_BYTES_PER_NODE_SAMPLE = 8 * (2 + 2) * 2 + 8 + 2

#: bytes per stored cell of a sweep-like analysis besides its per-node arrays: the Python
#: record in the main process, the Zarr chunk buffers and the Dataset copy
_CELL_BYTES = 2048


def system_bytes(n_nodes: int) -> float:
    """Dense matrices of an N-node system: A, B, C, K = [[A, Bᵀ], [B, C]] (4N²), its
    Cholesky factor and eigenvalue work, the rate-problem inverses [bytes]."""
    return 8.0 * n_nodes**2 * (3 + 4 * 4)


def run_bytes(n_nodes: int, steps_per_cycle: int, cycles: int, record: bool = True) -> float:
    """One steady-state run: the load samples of a cycle ((steps + 1, 2N) several times)
    and, when the histories are recorded (``slipcycle run``), every cycle's samples."""
    samples = float(steps_per_cycle + 1)
    out = 8.0 * samples * (2 * n_nodes + 1) * 4
    out += 8.0 * (cycles + 1) * 2 * n_nodes * 2     # start-of-cycle states, histories
    if record:
        out += float(cycles) * samples * n_nodes * _RECORD_BYTES_PER_NODE_SAMPLE
    return out


def cells_bytes(cells: float, n_nodes: int) -> float:
    """Stored results of ``cells`` runs (dissipation per node and initial slip: 2N floats
    each, plus the fixed cost of a cell) [bytes]."""
    return float(cells) * (_CELL_BYTES + 16.0 * n_nodes)


def check_case_sizes(sec, rn, matrix_key: str, n_nodes: int, run, *, dofs_per_node: int = 1,
                     record: bool = True) -> None:
    """Refuse, before any work, a discrete case whose system or run exceeds the memory
    budget, naming the key the user set.

    Parameters
    ----------
    sec, rn : Section
        The model's table (its ``stiffness_file``, else ``matrix_key``, is blamed for the
        system) and the ``[run]`` table (``cycles`` when only it is set, else
        ``steps_per_cycle``; both appear in the message).
    matrix_key : str
        The inline matrix that sets the node count (``A`` in 2-D, ``C`` in 3-D).
    n_nodes : int
        Contact nodes N.
    run : RunSettings
    dofs_per_node : int
        Tangential directions per node: the estimates (two unknowns per 2-D node) are
        taken for ``dofs_per_node`` × N nodes, an upper bound in 3-D (2).
    record : bool
        Whether every cycle is recorded (``slipcycle run``).
    """
    m = dofs_per_node * n_nodes
    check_memory(sec.key("stiffness_file" if sec.has("stiffness_file") else matrix_key),
                 system_bytes(m), f"{n_nodes} contact nodes")
    steps, cycles = run.steps_per_cycle, run.cycles
    key = "cycles" if rn.has("cycles") and not rn.has("steps_per_cycle") else "steps_per_cycle"
    check_memory(rn.key(key), run_bytes(m, steps, cycles, record),
                 f"{steps:g} steps per cycle × up to {cycles:g} cycles "
                 f"({n_nodes} nodes{', every cycle recorded' if record else ''})")
