"""The suite's own portability: round-off-sensitive tests pass under another BLAS core.

OpenBLAS picks its kernels for the processor it runs on (``DYNAMIC_ARCH``), so the last
bits of a matrix product differ between an AMD and an Intel machine; a test that asserts at
the level of round-off on a chaotic path (a stick-slip run through hundreds of events) is
then a property of one processor. ``OPENBLAS_CORETYPE`` forces another kernel family on this
machine: the tests below, the ones closest to round-off (a residual against its tolerance
after slow-mode steps, quoted numbers of chaotic runs, closed-form dissipations), run in a
subprocess under the Prescott kernels (SSE3 only, no FMA), the most different from the
default ones. Skipped where NumPy does not use OpenBLAS (the variable is then ignored).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

#: the round-off-sensitive tests rerun under another kernel family (about 40 s)
SENSITIVE = (
    "tests/test_discrete_slow_modes.py::"
    "test_a_slow_mode_step_that_runs_past_a_stop_still_ends_on_a_periodic_state",
    "tests/test_discrete_quoted_numbers.py",
    "tests/test_discrete_physics.py",
    "tests/test_halfspace_profiles.py",
)


def _uses_openblas() -> bool:
    config = np.show_config(mode="dicts") if hasattr(np, "show_config") else None
    try:
        blas = config["Build Dependencies"]["blas"]["name"]
    except (TypeError, KeyError):
        return False
    return "openblas" in str(blas).lower()


@pytest.mark.skipif(not _uses_openblas(), reason="NumPy is not linked to OpenBLAS, whose "
                    "OPENBLAS_CORETYPE selects the kernels")
def test_round_off_sensitive_tests_pass_under_another_blas_core_type():
    env = dict(os.environ, OPENBLAS_CORETYPE="Prescott", PYTHONHASHSEED="0")
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:randomly",
                           "-p", "no:cacheprovider", *SENSITIVE], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert " passed" in proc.stdout and "skipped" not in proc.stdout.splitlines()[-1]
