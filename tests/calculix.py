"""Run CalculiX (``ccx``) from the tests: write a deck, run it in a directory, return paths.

CalculiX CrunchiX 2.20 (Debian package ``calculix-ccx``, ``make test`` installs it where
the package manager can). Tests that need it call :func:`require_ccx` (or use the
``ccx`` fixture pattern ``pytest.mark.skipif(CCX is None, reason=CCX_MISSING)``), so that
they are skipped with the reason said where ``ccx`` is absent.

Decks used here are written in SI units (m, Pa, kg/m³); a frequency step with
``SOLVER=MATRIXSTORAGE`` needs ``*DENSITY`` (CalculiX refuses the step without a mass).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

__all__ = ["CCX", "CCX_MISSING", "CcxRun", "require_ccx", "run_ccx", "block_deck"]

#: the ccx executable (``SLIPCYCLE_CCX`` overrides), or None when it is not installed
CCX = os.environ.get("SLIPCYCLE_CCX") or shutil.which("ccx")
CCX_MISSING = ("CalculiX (ccx) is not installed: `apt-get install calculix-ccx` "
               "(make test does this where the package manager can)")


def require_ccx() -> str:
    """The ccx executable, or skip the calling test with the reason; in CI (``CI`` set) a
    missing ccx fails the test instead: the CalculiX tests must run there."""
    if CCX is None:
        if os.environ.get("CI"):
            pytest.fail(CCX_MISSING + " (CI is set: the CalculiX tests must run)")
        pytest.skip(CCX_MISSING)
    return CCX


@dataclass(frozen=True)
class CcxRun:
    """The files of one ccx run: ``deck`` (``jobname.inp``) and ``out(suffix)``."""

    deck: Path
    log: str

    def out(self, suffix: str) -> Path:
        """``jobname<suffix>`` beside the deck (``".sti"``, ``".dof"``, ``".mtx"``, ...)."""
        return self.deck.with_suffix(suffix)


def run_ccx(deck_text: str, directory: Path, jobname: str = "job",
            timeout: float = 120.0) -> CcxRun:
    """Write ``deck_text`` to ``directory/jobname.inp``, run ``ccx -i jobname`` there.

    Raises AssertionError (with the end of ccx's output) when ccx fails or does not say
    "Job finished"; skips the test when ccx is not installed.
    """
    exe = require_ccx()
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    deck = directory / f"{jobname}.inp"
    deck.write_text(deck_text, encoding="ascii")
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_STIFFNESS="1",
               CCX_NPROC_EQUATION_SOLVER="1")
    proc = subprocess.run([exe, "-i", jobname], cwd=directory, capture_output=True,
                          text=True, timeout=timeout, env=env)
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "Job finished" in log, \
        f"ccx failed (exit {proc.returncode}):\n{log[-2000:]}"
    return CcxRun(deck, log)


def block_deck(nx: int = 4, ny: int = 4, nz: int = 2, size=(0.01, 0.01, 0.005),
               element: str = "C3D8", E: float = 210e9, nu: float = 0.3,
               density: float = 7800.0, step: str = "sti", origin=(0.0, 0.0, 0.0)) -> str:
    """A CalculiX deck of a box meshed by nx × ny × nz hexahedra (C3D8 or C3D8I).

    Node sets ``BOTTOM`` (z = 0), ``TOP`` (z = height), ``SIDE`` (x = 0, not on the top or
    bottom); element-face surfaces ``SBOTTOM`` (faces S1 on z = 0) and ``STOP`` (S2 on the
    top); no ``*BOUNDARY`` (the ``.sti`` route wants the full K). ``step="sti"`` writes the
    ``*FREQUENCY, SOLVER=MATRIXSTORAGE`` step; ``None`` no step. The box's lowest corner
    is at ``origin`` (m).
    """
    Lx, Ly, H = size
    x0, y0, z0 = origin
    xs, ys, zs = (x0 + np.linspace(0.0, Lx, nx + 1), y0 + np.linspace(0.0, Ly, ny + 1),
                  z0 + np.linspace(0.0, H, nz + 1))
    node = {}
    lines = ["*HEADING", f"box {Lx} x {Ly} x {H} m, {nx}x{ny}x{nz} {element}",
             "*NODE, NSET=NALL"]
    k = 1
    for iz, z in enumerate(zs):
        for iy, y in enumerate(ys):
            for ix, x in enumerate(xs):
                node[ix, iy, iz] = k
                # shortest round-trip text: ccx reads at most 20 characters a field
                lines.append(f"{k}, {float(x)!r}, {float(y)!r}, {float(z)!r}")
                k += 1
    lines.append(f"*ELEMENT, TYPE={element}, ELSET=EALL")
    bottom_el, top_el = [], []
    e = 1
    for iz in range(nz):
        for iy in range(ny):
            for ix in range(nx):
                c = [node[ix, iy, iz], node[ix + 1, iy, iz], node[ix + 1, iy + 1, iz],
                     node[ix, iy + 1, iz], node[ix, iy, iz + 1], node[ix + 1, iy, iz + 1],
                     node[ix + 1, iy + 1, iz + 1], node[ix, iy + 1, iz + 1]]
                lines.append(f"{e}, " + ", ".join(map(str, c)))
                if iz == 0:
                    bottom_el.append(e)
                if iz == nz - 1:
                    top_el.append(e)
                e += 1

    def nset(name, ids):
        out = [f"*NSET, NSET={name}"]
        ids = list(ids)
        out += [", ".join(map(str, ids[i:i + 10])) for i in range(0, len(ids), 10)]
        return out

    lines += nset("BOTTOM", (node[ix, iy, 0] for iy in range(ny + 1) for ix in range(nx + 1)))
    lines += nset("TOP", (node[ix, iy, nz] for iy in range(ny + 1) for ix in range(nx + 1)))
    lines += nset("SIDE", (node[0, iy, iz] for iz in range(1, nz) for iy in range(ny + 1)))
    lines += ["*ELSET, ELSET=EBOTTOM"] + [str(i) for i in bottom_el]
    lines += ["*ELSET, ELSET=ETOP"] + [str(i) for i in top_el]
    lines += ["*SURFACE, NAME=SBOTTOM, TYPE=ELEMENT", "EBOTTOM, S1",
              "*SURFACE, NAME=STOP, TYPE=ELEMENT", "ETOP, S2",
              "*MATERIAL, NAME=STEEL", "*ELASTIC", f"{float(E)!r}, {float(nu)!r}",
              "*DENSITY", f"{float(density)!r}",
              "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"]
    if step == "sti":
        lines += ["*STEP", "*FREQUENCY, SOLVER=MATRIXSTORAGE", "*END STEP"]
    return "\n".join(lines) + "\n"
