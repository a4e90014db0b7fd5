"""Readers of reduced (or full) stiffness matrices exported by finite-element codes.

Each reader returns a :class:`~slipcycle.io.fe_formats.common.RawMatrix` (K in the file's
row order with the file's own (node, dof) labels); :mod:`~slipcycle.io.fe_formats.dofmap`
turns it into the contact blocks A, B, C. The public entry point is
:func:`slipcycle.io.matrices.read_reduced_stiffness`.

========================  ==============================================================
format                    layout
========================  ==============================================================
``npz``                   NumPy ``.npz``: A, B, C (slipcycle's layout) or a full K
``matrix-market``         Matrix Market ``.mtx`` (``%%MatrixMarket`` header), full K
``abaqus``                Abaqus ``*MATRIX OUTPUT`` ``.mtx`` (FORMAT=MATRIX INPUT: node,
                          dof, node, dof, value; FORMAT=COORDINATE: row, column, value)
                          and ``*SUBSTRUCTURE MATRIX OUTPUT`` (``*USER ELEMENT`` layout)
``calculix``              CalculiX ``*SUBSTRUCTURE MATRIX OUTPUT`` ``.mtx`` (USER DEFINED
                          or MATRIX layout) and ``SOLVER=MATRIXSTORAGE`` ``.sti`` with its
                          ``.dof`` file (``node.dof`` per row)
``harwell-boeing``        Harwell–Boeing (ANSYS ``HBMAT``), RSA or RUA, with the
                          ``Fname.mapping`` file of HBMAT's Mapping=YES when present
``matlab``                MATLAB ``.mat`` v5 (:func:`scipy.io.loadmat`) or v7.3 (HDF5)
``nastran-dmig``          Nastran DMIG cards (punch ``.pch`` or bulk data), via pyNastran
========================  ==============================================================
"""

from __future__ import annotations

from pathlib import Path

from slipcycle.io.fe_formats import abaqus, harwell_boeing, matlab, nastran
from slipcycle.io.fe_formats.common import RawMatrix, StiffnessError, file_error
from slipcycle.io.sniff import sniff_format

__all__ = ["FORMATS", "SUFFIX_FORMATS", "detect_format", "read_raw", "RawMatrix", "StiffnessError"]

FORMATS = ("npz", "matrix-market", "abaqus", "calculix", "harwell-boeing", "matlab",
           "nastran-dmig")

#: the format a file suffix names, where its first bytes do not tell
SUFFIX_FORMATS = {".npz": "npz", ".mat": "matlab", ".sti": "calculix", ".hb": "harwell-boeing",
           ".rsa": "harwell-boeing", ".rua": "harwell-boeing", ".hbmat": "harwell-boeing",
           ".pch": "nastran-dmig", ".bdf": "nastran-dmig", ".nas": "nastran-dmig",
           ".blk": "nastran-dmig", ".dmig": "nastran-dmig"}


def detect_format(path: str | Path) -> str:
    """The format of ``path`` from its first bytes, then its suffix.

    Raises
    ------
    StiffnessError
        When neither tells (naming the formats and the ``format`` key).
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096)
    except OSError as exc:
        raise file_error(path, f"cannot read: {exc.strerror or exc}") from None
    fmt = sniff_format(head, path.suffix)
    if fmt is not None:
        return fmt
    if path.suffix.lower() in SUFFIX_FORMATS:
        return SUFFIX_FORMATS[path.suffix.lower()]
    raise file_error(path, "unknown stiffness file format (neither its first bytes nor its "
                     "suffix tell); in a case file name it with the stiffness table's "
                     "`format` key (" + ", ".join(FORMATS) + ")")


def read_raw(path: Path, fmt: str, keys: dict | None) -> RawMatrix:
    """K, labels and loads of an export in format ``fmt`` (not npz / Matrix Market)."""
    if fmt in ("abaqus", "calculix"):
        return abaqus.read(path, fmt)
    if fmt == "harwell-boeing":
        return harwell_boeing.read(path)
    if fmt == "matlab":
        return matlab.read(path, keys)
    if fmt == "nastran-dmig":
        return nastran.read(path, keys)
    raise StiffnessError("format", f"no reader for {fmt!r}")
