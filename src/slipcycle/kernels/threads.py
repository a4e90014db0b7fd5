"""One BLAS thread for small dense linear algebra.

The dense solves of a frictional step (factorisations of the active nodes' block, a few
hundred unknowns) are too small for threaded BLAS: its threads only synchronise, and on a
loaded or oversubscribed machine (two BLAS threads per process, several processes on two
cores) they spin-wait. Measured: the 3-D lap-joint study ran 382 s wall / 180 s CPU with
the default OpenBLAS threads and 33 s / 10 s with one; a 200 × 200 LU of the rods' periodic
solver ran 50 times slower threaded.
"""

from __future__ import annotations

import functools

from threadpoolctl import ThreadpoolController

__all__ = ["single_threaded_blas", "single_threaded"]

_CONTROLLER: list = []


def single_threaded_blas():
    """Context manager limiting BLAS/LAPACK to one thread while it is open."""
    if not _CONTROLLER:
        _CONTROLLER.append(ThreadpoolController())
    return _CONTROLLER[0].limit(limits=1, user_api="blas")


def single_threaded(func):
    """Decorator: ``func`` runs with one BLAS thread (:func:`single_threaded_blas`)."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with single_threaded_blas():
            return func(*args, **kwargs)
    return wrapper
