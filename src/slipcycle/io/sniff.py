"""Recognise a matrix export from its first bytes (no heavy imports: the case reader uses
it to say what a file is when it is given where a case file is expected)."""

from __future__ import annotations

import re
from pathlib import Path

__all__ = ["sniff_format", "describe", "looks_like_harwell_boeing", "looks_like_abaqus"]

#: format word → what a user calls such a file
DESCRIPTIONS = {
    "npz": "a NumPy .npz archive",
    "matrix-market": "a Matrix Market matrix file",
    "abaqus": "an Abaqus/CalculiX matrix file",
    "calculix": "a CalculiX matrix file",
    "harwell-boeing": "a Harwell-Boeing matrix file (e.g. ANSYS HBMAT)",
    "matlab": "a MATLAB .mat file",
    "nastran-dmig": "a Nastran DMIG matrix file",
}

_HB_TYPE = re.compile(r"^[RCP][SUHZR][AE]$", re.IGNORECASE)
_SPLIT = re.compile(r"[,\s]+")


def looks_like_harwell_boeing(text: str) -> bool:
    """Whether ``text`` starts with a Harwell–Boeing header (counts, type, formats)."""
    lines = text.splitlines()
    if len(lines) < 4:
        return False
    try:
        counts = [int(t) for t in lines[1].split()]
    except ValueError:
        return False
    sizes = lines[2].split()
    return (len(counts) in (4, 5) and len(sizes) >= 4 and bool(_HB_TYPE.match(sizes[0]))
            and lines[3].lstrip().startswith("("))


def looks_like_abaqus(text: str) -> bool:
    """Whether ``text`` reads as an Abaqus/CalculiX matrix export (keywords, or lines of
    ``node, dof, node, dof, value`` / ``row, column, value`` numbers)."""
    up = text.upper()
    if "*USER ELEMENT" in up or "*MATRIX" in up:
        return True
    lines = [ln for ln in text.splitlines()[:20] if ln.strip() and not ln.startswith("*")]
    full = lines[:-1] or lines                      # the last line may be cut off
    if not full:
        return False
    for ln in full:
        f = [t for t in _SPLIT.split(ln.strip()) if t]
        if len(f) not in (3, 5):
            return False
        try:
            [float(t.replace("D", "E")) for t in f]
        except ValueError:
            if len(f) != 5:                         # Abaqus FORMAT=LABELS: Part-1.12
                return False
    return True


def sniff_format(head: bytes, suffix: str = "") -> str | None:
    """The format word of a file from its first bytes (and suffix), or None."""
    text = head.decode("latin-1")
    suffix = suffix.lower()
    if head.startswith(b"PK") and suffix in (".npz", ""):
        return "npz"
    if head.startswith(b"MATLAB") or head.startswith(b"\x89HDF"):
        return "matlab"
    if text.startswith("%%MatrixMarket"):
        return "matrix-market"
    if b"\x00" in head:
        return None
    if re.search(r"^DMIG", text, re.MULTILINE) and suffix not in (".mtx", ".sti"):
        return "nastran-dmig"
    if looks_like_harwell_boeing(text):
        return "harwell-boeing"
    if looks_like_abaqus(text):
        up = text.upper()
        return "calculix" if (suffix == ".sti" or "GENERATION OF SUBSTRUCTURE" in up) \
            else "abaqus"
    return None


def describe(path: str | Path, head: bytes) -> str | None:
    """"a Harwell-Boeing matrix file (...)" when ``head`` is a matrix export, else None."""
    fmt = sniff_format(head, Path(path).suffix)
    return DESCRIPTIONS.get(fmt) if fmt else None
