"""Imported once by the fork server of local sweep workers (:func:`slipcycle.sweep.core.
pool_context`), never by user code: it initialises Numba's CPU target (type system and
code generator, 0.5-1 s) in the server, so that each worker, forked from the server,
starts with it ready and only loads its compiled kernels from Numba's on-disk cache.

No thread is started here: forking a process that runs Numba's parallel threads would be
unsafe, initialising the target starts none.
"""

from __future__ import annotations

from numba.core.registry import cpu_target

# the registry builds both contexts on first access; refresh() loads every registered
# implementation (what the first compilation or cache load would do in each worker)
cpu_target.typing_context.refresh()
cpu_target.target_context.refresh()
