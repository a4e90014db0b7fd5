"""Abaqus and CalculiX matrix exports (text).

Layouts read (Abaqus Analysis User's Guide, "Generating matrices", keywords
``*MATRIX GENERATE`` / ``*MATRIX OUTPUT`` and ``*SUBSTRUCTURE MATRIX OUTPUT``; CalculiX
CrunchiX User's Manual, ``*SUBSTRUCTURE MATRIX OUTPUT`` and ``*FREQUENCY,
SOLVER=MATRIXSTORAGE``):

- **matrix input** (Abaqus ``*MATRIX OUTPUT, FORMAT=MATRIX INPUT``, the default, written as
  ``jobname_STIF<step>.mtx``; CalculiX ``OUTPUT FILE=MATRIX``): one entry per line,
  ``row node, row dof, column node, column dof, value``. Node labels may carry an instance
  prefix (``Part-1-1.12``) when a single instance is exported. A load vector written
  beside it (``jobname_LOAD<step>.mtx``: ``node, dof, value`` per line) is read as the load
  case ``LOAD``.
- **coordinate** (Abaqus ``FORMAT=COORDINATE``; CalculiX ``jobname.sti``): ``row, column,
  value`` with 1-based equation numbers. CalculiX writes ``jobname.dof`` beside it, one
  ``node.dof`` per row (``12.3``: node 12, dof 3); without it a dof map is needed.
- **user element** (Abaqus/CalculiX ``*SUBSTRUCTURE MATRIX OUTPUT, OUTPUT FILE=USER
  DEFINED``): a ``*USER ELEMENT, NODES=n`` header, the node labels in the comment lines
  after ``** ELEMENT NODES``, the active dofs (first data line: the dofs of the first
  node; a later line ``position, dofs...`` changes them from that node on), then
  ``*MATRIX, TYPE=STIFFNESS`` with the lower triangle row by row (the upper triangle
  column by column), continuation lines as needed.

Symmetric matrices are stored as one triangle; the other is filled by symmetry
(:func:`~slipcycle.io.fe_formats.common.from_triplets`). Dof numbers 1–3 are the global
x, y, z translations, 4–6 rotations.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from slipcycle.io.fe_formats.common import (
    RawMatrix,
    check_last_node,
    file_error,
    from_triplets,
)

__all__ = ["read"]

_NUM = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][+-]?\d+)?")
_SPLIT = re.compile(r"[,\s]+")


def _fields(line: str) -> list[str]:
    return [f for f in _SPLIT.split(line.strip()) if f]


def _float(tok: str, where, lineno: int) -> float:
    try:
        return float(tok.replace("D", "E").replace("d", "e"))
    except ValueError:
        raise file_error(where, f"line {lineno}: {tok!r} is not a number") from None


def _int(tok: str, where, lineno: int) -> int:
    try:
        return int(tok)
    except ValueError:
        raise file_error(where, f"line {lineno}: {tok!r} is not an integer") from None


def _read_text(path: Path) -> str:
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise file_error(path, f"cannot read: {exc.strerror or exc}") from None
    if b"\x00" in raw:
        raise file_error(path, "is a binary file, not an Abaqus/CalculiX text matrix")
    return raw.decode("latin-1")


def read(path: Path, fmt: str = "abaqus", *, check_condensed: bool = True) -> RawMatrix:
    """K and its (node, dof) labels from an Abaqus/CalculiX export (see module docstring).

    ``check_condensed``: refuse a CalculiX substructure matrix that is the uncondensed
    retained block (:func:`_refuse_uncondensed`); False reads it as it is.
    """
    path = Path(path)
    text = _read_text(path)
    if "*USER ELEMENT" in text.upper():
        raw = _user_element(text, path, fmt)
        if check_condensed and "GENERATION OF SUBSTRUCTURE" in text[:400].upper():
            _refuse_uncondensed(raw.K, raw.labels, path)
        return raw
    fast = _fast_table(text)
    if fast is not None:                            # plain numbers, one width throughout
        return (_matrix_input if fast.shape[1] == 5 else _coordinate)(None, path, fmt, fast)
    data = [(i + 1, ln.replace(",", " ").split()) for i, ln in enumerate(text.splitlines())
            if ln.strip() and not ln.lstrip().startswith("*")]
    if not data:
        raise file_error(path, "holds no matrix entries")
    widths = {len(f) for _, f in data}
    if widths == {5}:
        return _matrix_input(data, path, fmt)
    if widths == {3}:
        return _coordinate(data, path, fmt)
    if widths == {3, 5}:                            # a 5-field file cut inside its last line
        n5 = sum(len(f) == 5 for _, f in data)
        odd = 3 if n5 * 2 > len(data) else 5
        lineno = next(i for i, f in data if len(f) == odd)
        raise file_error(path, f"line {lineno}: {odd} fields where the other lines have "
                         f"{8 - odd} (file truncated?)")
    lineno, f = next((i, f) for i, f in data if len(f) not in (3, 5))
    raise file_error(path, f"line {lineno}: expected 'node, dof, node, dof, value' or "
                     f"'row, column, value', got {len(f)} fields")


def _node_label(tok: str, where, lineno: int, instances: set) -> int:
    if "." in tok:                                  # Abaqus FORMAT=LABELS: Instance.node
        inst, _, node = tok.rpartition(".")
        instances.add(inst)
        if len(instances) > 1:
            raise file_error(where, f"line {lineno}: nodes of several instances "
                             f"({', '.join(sorted(instances))}); export one instance or "
                             "number the nodes globally")
        tok = node
    return _int(tok, where, lineno)


def _fast_table(text: str):
    """The entries of a keyword-free file of plain numbers as an (n, 3 or 5) array, in one
    pass (large ``.sti`` / matrix-input files), or None to read it line by line."""
    if "*" in text:
        return None
    lines = [ln for ln in text.splitlines() if ln.strip()]
    if not lines:
        return None
    width = len(lines[0].replace(",", " ").split())
    tokens = text.replace(",", " ").split()
    if width not in (3, 5) or len(tokens) != width * len(lines):
        return None
    try:
        arr = np.array(tokens, dtype=float).reshape(-1, width)
    except ValueError:
        return None
    labels = arr[:, :-1]
    return arr if np.array_equal(labels, np.round(labels)) else None


def _table(data, width: int):
    """All fields of ``data`` as one float array (n, width), or None when a field is not a
    plain number (then the line-by-line readers say which)."""
    flat = [t for _, f in data for t in f]
    try:
        arr = np.array(flat, dtype=float)
    except ValueError:
        try:
            arr = np.array([t.replace("D", "E").replace("d", "e") for t in flat], float)
        except ValueError:
            return None
    return arr.reshape(-1, width)


def _matrix_input(data, path: Path, fmt: str, arr=None) -> RawMatrix:
    arr = _table(data, 5) if arr is None else arr   # fast path: plain numbers throughout
    if arr is not None and np.array_equal(arr[:, :4], np.round(arr[:, :4])):
        ent, vals = arr[:, :4].astype(np.int64), arr[:, 4]
    else:
        instances: set = set()
        ent = np.array([(_node_label(f[0], path, i, instances), _int(f[1], path, i),
                         _node_label(f[2], path, i, instances), _int(f[3], path, i))
                        for i, f in data], np.int64)
        vals = np.array([_float(f[4], path, i) for i, f in data])
    keys, inv = np.unique(np.concatenate([ent[:, :2], ent[:, 2:]]), axis=0,
                          return_inverse=True)      # sorted (node, dof)
    inv = inv.ravel()
    rows, cols = inv[:len(ent)], inv[len(ent):]
    index = {(int(a), int(b)): k for k, (a, b) in enumerate(keys)}
    check_last_node(keys, int(ent[-1, 0]), path)
    K = from_triplets(rows, cols, vals, len(keys), path)
    loads = _abaqus_load(path, index, len(keys))
    return RawMatrix(K, labels=keys, loads=loads, format=fmt)


def _abaqus_load(path: Path, index: dict, n: int) -> dict:
    """The load vector ``jobname_LOAD<k>.mtx`` written beside ``jobname_STIF<k>.mtx``."""
    m = re.match(r"(.*)_STIF(\d+)$", path.stem, re.IGNORECASE)
    if not m:
        return {}
    load = path.with_name(f"{m.group(1)}_LOAD{m.group(2)}{path.suffix}")
    if not load.is_file():
        return {}
    f = np.zeros(n)
    instances: set = set()
    for i, ln in enumerate(_read_text(load).splitlines()):
        fl = _fields(ln)
        if not fl or ln.lstrip().startswith("*"):
            continue
        if len(fl) != 3:
            raise file_error(load, f"line {i + 1}: expected 'node, dof, value'")
        key = (_node_label(fl[0], load, i + 1, instances), _int(fl[1], load, i + 1))
        if key not in index:
            raise file_error(load, f"line {i + 1}: node {key[0]} dof {key[1]} is not a row "
                             f"of {path.name}")
        f[index[key]] += _float(fl[2], load, i + 1)
    return {"LOAD": f}


def _dof_file(path: Path, n: int):
    """Labels from CalculiX's ``jobname.dof`` (``node.dof`` per row), or None."""
    dof = path.with_suffix(".dof")
    if not dof.is_file():
        return None
    labels = []
    for i, ln in enumerate(_read_text(dof).splitlines()):
        s = ln.strip()
        if not s:
            continue
        node, sep, d = s.partition(".")
        if not sep:
            raise file_error(dof, f"line {i + 1}: expected node.dof, got {s!r}")
        # written as a real number: trailing zeros of "12.300" are padding (dofs 0-6)
        labels.append((_int(node, dof, i + 1), _int(d.rstrip("0") or "0", dof, i + 1)))
    if len(labels) != n:
        raise file_error(path, f"K has {n} rows but {dof.name} lists {len(labels)} dofs "
                         "(one of the two is truncated, or they are of different runs)")
    return np.array(labels, np.int64)


def _coordinate(data, path: Path, fmt: str, arr=None) -> RawMatrix:
    arr = _table(data, 3) if arr is None else arr
    if arr is not None and np.array_equal(arr[:, :2], np.round(arr[:, :2])):
        rows, cols, vals = (arr[:, 0].astype(np.int64) - 1, arr[:, 1].astype(np.int64) - 1,
                            arr[:, 2])
    else:
        rows = np.array([_int(f[0], path, i) for i, f in data]) - 1
        cols = np.array([_int(f[1], path, i) for i, f in data]) - 1
        vals = np.array([_float(f[2], path, i) for i, f in data])
    if rows.min() < 0 or cols.min() < 0:
        raise file_error(path, "row and column numbers start at 1")
    n = int(max(rows.max(), cols.max())) + 1
    labels = _dof_file(path, n)
    K = from_triplets(rows, cols, vals, n, path)
    # CalculiX always writes jobname.dof beside jobname.sti; Abaqus's COORDINATE has none
    calculix = fmt == "calculix" or path.suffix.lower() == ".sti"
    return RawMatrix(K, labels=labels, format=fmt,
                     missing_labels=path.with_suffix(".dof").name
                     if labels is None and calculix else None)


def _user_element(text: str, path: Path, fmt: str) -> RawMatrix:
    lines = text.splitlines()
    up = [ln.strip().upper() for ln in lines]
    start = next(i for i, u in enumerate(up) if u.startswith("*USER ELEMENT"))
    m = re.search(r"NODES\s*=\s*(\d+)", up[start])
    if not m:
        raise file_error(path, f"line {start + 1}: *USER ELEMENT without NODES=")
    n_nodes = int(m.group(1))
    nodes: list[int] = []
    dof_changes: list[tuple[int, list[int]]] = []
    i = start + 1
    while i < len(lines) and not (up[i].startswith("*") and not up[i].startswith("**")):
        s = lines[i].strip()
        if up[i].startswith("** ELEMENT NODES"):
            i += 1
            while i < len(lines) and up[i].startswith("**") and _NUM.search(up[i]) \
                    and not up[i][2:].strip()[:1].isalpha():
                nodes += [_int(t, path, i + 1) for t in _fields(lines[i].strip()[2:])]
                i += 1
            continue
        if s and not s.startswith("**"):
            ints = [_int(t, path, i + 1) for t in _fields(s)]
            if not dof_changes:
                dof_changes.append((1, ints))
            else:
                dof_changes.append((ints[0], ints[1:]))
        i += 1
    if not dof_changes:
        raise file_error(path, "the *USER ELEMENT lists no active degrees of freedom")
    if not nodes:
        nodes = list(range(1, n_nodes + 1))
    if len(nodes) != n_nodes:
        raise file_error(path, f"*USER ELEMENT has NODES={n_nodes} but the ELEMENT NODES "
                         f"comment lists {len(nodes)}")
    labels = []
    active = dof_changes[0][1]
    changes = dict(dof_changes[1:])
    for pos, node in enumerate(nodes, start=1):
        active = changes.get(pos, active)
        labels += [(node, d) for d in active]
    # the stiffness block
    try:
        k0 = next(j for j in range(i, len(lines))
                  if up[j].startswith("*MATRIX") and "STIFFNESS" in up[j])
    except StopIteration:
        raise file_error(path, "no *MATRIX, TYPE=STIFFNESS block") from None
    block = []
    for j in range(k0 + 1, len(lines)):
        if up[j].startswith("*") and not up[j].startswith("**"):
            break
        if not up[j].startswith("**"):
            block.append(j)
    tokens = " ".join(lines[j] for j in block).replace(",", " ").split()
    try:
        vals = np.array(tokens, dtype=float)
    except ValueError:                              # D exponents, or a bad token: say where
        vals = [_float(t, path, j + 1) for j in block for t in _fields(lines[j])]
    n = len(labels)
    if len(vals) != n * (n + 1) // 2:
        raise file_error(path, f"the *MATRIX block holds {len(vals)} values; a symmetric "
                         f"matrix of the {n} dofs listed needs n(n+1)/2 = {n * (n + 1) // 2}")
    r, c = np.tril_indices(n)                       # row by row, lower triangle
    K = from_triplets(r, c, vals, n, path)
    return RawMatrix(K, labels=np.array(labels, np.int64), format=fmt)


#: the route that gives CalculiX's full stiffness, for the refusal below
STI_ROUTE = ("export the full stiffness with *FREQUENCY, SOLVER=MATRIXSTORAGE (jobname.sti "
             "and .dof; the deck needs *DENSITY) and name the contact nodes")


def _refuse_uncondensed(K, labels: np.ndarray, path: Path) -> None:
    """Refuse a CalculiX substructure matrix that is the uncondensed retained block.

    CalculiX 2.20's ``*SUBSTRUCTURE GENERATE`` + ``*RETAINED NODAL DOFS`` writes the block
    K_bb of the assembled stiffness on the retained dofs, not the condensed (Guyan, Schur
    complement) K_bb − K_bi K_ii⁻¹ K_ib: measured with ccx 2.20 on C3D8 and C3D8I blocks,
    the file equals K_bb to 1e-13 and is 0.3–0.4 (relative) away from the condensed
    matrix, whatever the deck's boundary conditions, solver or ordering. The two are told
    apart without the deck: a body condensed onto its retained nodes couples every retained
    node with every other, so no 3×3 node block of a condensed K is exactly zero, while
    K_bb couples only nodes that share an element (Guyan 1965, AIAA J. 3(2), 380). Retained
    nodes that all share elements cannot be told apart and are let through.
    """
    nodes, node_of = np.unique(labels[:, 0], return_inverse=True)
    if nodes.size < 3:
        return
    C = K.tocoo() if hasattr(K, "tocoo") else None
    rows, cols = (C.row, C.col) if C is not None else np.nonzero(K)
    keep = (C.data != 0) if C is not None else slice(None)
    a, b = node_of[rows[keep]], node_of[cols[keep]]
    coupled = np.zeros((nodes.size, nodes.size), bool)
    coupled[a, b] = True
    free = np.count_nonzero(~coupled[np.triu_indices(nodes.size, 1)])
    if free:
        pairs = nodes.size * (nodes.size - 1) // 2
        raise file_error(path, f"is the uncondensed retained block of CalculiX's "
                         f"*SUBSTRUCTURE MATRIX OUTPUT, not a condensed stiffness ({free} of "
                         f"{pairs} retained node pairs have no coupling at all, which a "
                         f"condensed body never has); {STI_ROUTE}")
