"""Reduced stiffness files: static reduction of a finite-element model to its contact nodes,
or import of a reduced stiffness from another code (``slipcycle reduce``).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from slipcycle.fe.meshfile3d import MeshSolid, check_reduction_memory, reduce_mesh_case
from slipcycle.fe.model import (
    build_problem,
    discrete3d_case_text,
    discrete_case_text,
    read_discrete_table,
)
from slipcycle.fe.reduction import reduce_problem
from slipcycle.io import CaseError, read_case
from slipcycle.io.matrices import StiffnessError, check_stiffness, read_reduced_stiffness
from slipcycle.io.results import provenance, write_together

__all__ = ["import_stiffness", "reduce_model"]


def _savez(path: Path, arrays: dict) -> None:
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)


def _stiffness_arrays(red, meta: dict) -> dict:
    """The ``.npz`` arrays of a :class:`~slipcycle.io.matrices.ReducedStiffness`, with
    its frames (normal into the body, as the 2-D reduction stores it) and ``metadata``."""
    meta = {**meta, "source": red.source}
    data = dict(red.to_arrays())
    data["dof_order"] = np.array("tangential_first")
    data["tangential_dims"] = np.array(red.tangential_dims)
    if red.normals is not None and red.tangents is not None:
        data["normal"] = -np.asarray(red.normals, float)
        data["tangent"] = np.asarray(red.tangents, float)
    data["metadata"] = np.array(json.dumps(meta))
    return data


def import_stiffness(model: Path, out: Path, dof_order: str | None = None) -> dict:
    """Import a reduced stiffness from another code and write it in slipcycle's layout.

    Parameters
    ----------
    model : Path
        A reduced stiffness in any format :func:`slipcycle.io.matrices.
        read_reduced_stiffness` reads (``.npz``, Matrix Market, Abaqus/CalculiX ``.mtx``,
        Harwell–Boeing, MATLAB ``.mat``, Nastran DMIG).
    out : Path
        The ``.npz`` file written (atomically), with provenance metadata.
    dof_order : {"tangential_first", "interleaved"}, optional
        Ordering of the DOFs of a full K when the file does not state it.

    Returns
    -------
    dict
        ``n_contact_nodes``, ``imported_from``, ``coupling_B_over_A`` (‖B‖/‖A‖).

    Raises
    ------
    CaseError
        A missing file or matrices that are not a valid stiffness (shapes, symmetry,
        positive definiteness), naming the file and key.
    """
    if not model.exists():
        raise CaseError("model", f"file not found: {model}")
    try:  # every export format slipcycle reads (docs/discrete.md), one reader
        red = read_reduced_stiffness(model, dof_map=dof_order)
    except StiffnessError as exc:
        if exc.key not in (str(model), model.name):
            raise CaseError(f"{model.name}:{exc.key}", exc.problem) from None
        # the file itself (unreadable, not the format) or the matrix it holds
        about_k = exc.problem.startswith(("K ", "the reduced K", "the retained"))
        raise CaseError(f"{model.name}:K" if about_k else model.name, exc.problem) from None
    except ValueError as exc:
        raise CaseError(model.name, str(exc)) from None
    meta = provenance("", model.resolve())
    meta["imported_from"] = str(model)
    data = _stiffness_arrays(red, meta)
    write_together([(out, lambda tmp: _savez(tmp, data))])
    n = data["A"].shape[0]
    return {"n_contact_nodes": n, "imported_from": str(model),
            "coupling_B_over_A": float(np.linalg.norm(data["B"]) / np.linalg.norm(data["A"]))}


def reduce_model(model: Path, out: Path, case_out: Path | None = None) -> dict:
    """Static reduction of a finite-element model file to its contact nodes.

    Parameters
    ----------
    model : Path
        TOML model file (``model = "fe"``).
    out : Path
        The ``.npz`` file of A, B, C [N/m] and the load vectors p^w, q^w [N].
    case_out : Path, optional
        Also write a discrete case file referring to ``out``, from ``[fe.discrete]``.
        Both files are written together or not at all.

    Returns
    -------
    dict
        ``geometry``, ``n_dofs``, ``n_contact_nodes``, ``element``, ``condense_seconds``,
        ``load_cases``, ``coupling_B_over_A`` (‖B‖/‖A‖).

    Raises
    ------
    CaseError
        An invalid model, a missing ``[fe.discrete]`` for ``case_out``, or a reduced
        stiffness that is not symmetric positive definite.
    """
    case = read_case(model, models=["fe"])
    problem = build_problem(case)  # validates everything, raises CaseError
    discrete = read_discrete_table(case.section("fe"))
    if case_out is not None and discrete is None:
        raise CaseError("fe.discrete", "required table is missing (needed for --case)")
    if isinstance(problem, MeshSolid):
        return _reduce_solid(case, problem, discrete, out, case_out)
    try:
        reduced = reduce_problem(problem)
    except ValueError as exc:
        raise CaseError("fe", str(exc)) from None
    try:
        check_stiffness({"A": reduced.A, "B": reduced.B, "C": reduced.C})
    except StiffnessError as exc:
        raise CaseError("fe", f"reduced stiffness {exc.problem}") from None
    text = None
    if case_out is not None:
        rel = os.path.relpath(out.resolve(), case_out.resolve().parent)
        text = discrete_case_text(discrete, reduced, rel)
    meta = provenance(case.text, case.path)
    outputs = [(out, lambda tmp: reduced.save(tmp, meta, atomic=False))]
    if text is not None:
        outputs.append((case_out, lambda tmp: tmp.write_text(text, encoding="utf-8")))
    write_together(outputs)
    info = {k: v for k, v in reduced.info.items() if k in (
        "geometry", "n_dofs", "n_contact_nodes", "element", "condense_seconds")}
    info["load_cases"] = reduced.load_cases
    info["coupling_B_over_A"] = float(np.linalg.norm(reduced.B) / np.linalg.norm(reduced.A))
    return info


def _reduce_solid(case, solid: MeshSolid, discrete: dict | None, out: Path,
                  case_out: Path | None) -> dict:
    """:func:`reduce_model` for a tetrahedral mesh file (a ``discrete3d`` case with --case)."""
    check_reduction_memory(solid)
    red, area = reduce_mesh_case(solid)
    meta = provenance(case.text, case.path)
    data = _stiffness_arrays(red, meta)
    outputs = [(out, lambda tmp: _savez(tmp, data))]
    if case_out is not None:
        rel = os.path.relpath(out.resolve(), case_out.resolve().parent)
        text = discrete3d_case_text(discrete, red, rel, area)
        outputs.append((case_out, lambda tmp: tmp.write_text(text, encoding="utf-8")))
    write_together(outputs)
    return {"geometry": "mesh", "n_dofs": solid.n_dofs, "n_contact_nodes": red.n_nodes,
            "element": solid.element, "load_cases": list(red.loads),
            "coupling_B_over_A": float(np.linalg.norm(red.B) / np.linalg.norm(red.A))}
