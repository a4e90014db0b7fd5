"""``slipcycle reduce MODEL.toml --out reduced.npz``: static reduction to the contact nodes.

MODEL may also be a reduced stiffness from another code (``.mtx`` or ``.npz``): it is
then imported, checked (shapes, symmetric, positive definite) and written in
slipcycle's ``.npz`` layout. ``--case discrete.toml`` writes a discrete case file that
refers to the output, built from the model's ``[fe.discrete]`` table.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from slipcycle.io.results import write_together


def add_parser(sub) -> None:
    p = sub.add_parser("reduce", help="reduce a finite-element model (or import reduced "
                       "matrices) to A, B, C and p^w, q^w in an .npz file", description=__doc__)
    p.add_argument("model", type=Path, help="model file (TOML, model = \"fe\") or .mtx/.npz")
    p.add_argument("--out", type=Path, required=True, help="output .npz file")
    p.add_argument("--dof-order", choices=("tangential_first", "interleaved"), default=None,
                   help="ordering of the DOFs of an imported full K, if the file does not "
                        "state it (default tangential_first)")
    p.add_argument("--case", type=Path, default=None,
                   help="also write a discrete case file using [fe.discrete]")
    p.add_argument("--quiet", action="store_true", help="print nothing on success")
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.io import CaseError
    from slipcycle.io.results import provenance

    if args.out.suffix.lower() != ".npz":
        raise CaseError("--out", f"must name an .npz file, got {args.out}")
    suffix = args.model.suffix.lower()
    if suffix in (".mtx", ".npz"):
        if args.case is not None:
            raise CaseError("--case", "needs a model file with [fe.discrete], "
                                      "not imported matrices")
        info = _import(args, provenance)
    else:
        info = _reduce(args, provenance)
    if not args.quiet:
        print(json.dumps(info, indent=2))
        print(f"reduced model written to {args.out}")
    return 0


def _savez(path: Path, arrays: dict) -> None:
    import numpy as np

    with open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)


def _import(args, provenance) -> dict:
    import numpy as np

    from slipcycle.io import CaseError
    from slipcycle.io.matrices import StiffnessError, read_stiffness

    if not args.model.exists():
        raise CaseError("model", f"file not found: {args.model}")
    try:
        data = read_stiffness(args.model, args.dof_order)
    except StiffnessError as exc:
        raise CaseError(f"{args.model.name}:{exc.key}", exc.problem) from None
    except ValueError as exc:
        raise CaseError(args.model.name, str(exc)) from None
    meta = provenance("", args.model.resolve())
    meta["imported_from"] = str(args.model)
    data = {k: v for k, v in data.items() if k != "metadata"}
    data["dof_order"] = np.array("tangential_first")
    data["metadata"] = np.array(json.dumps(meta))
    write_together([(args.out, lambda tmp: _savez(tmp, data))])
    n = data["A"].shape[0]
    return {"n_contact_nodes": n, "imported_from": str(args.model),
            "coupling_B_over_A": float(np.linalg.norm(data["B"]) / np.linalg.norm(data["A"]))}


def _reduce(args, provenance) -> dict:
    import numpy as np

    from slipcycle.fe.model import build_problem, discrete_case_text, read_discrete_table
    from slipcycle.fe.reduction import reduce_problem
    from slipcycle.io import CaseError, read_case
    from slipcycle.io.matrices import StiffnessError, check_stiffness

    case = read_case(args.model, models=["fe"])
    problem = build_problem(case)  # validates everything, raises CaseError
    discrete = read_discrete_table(case.section("fe"))
    if args.case is not None and discrete is None:
        raise CaseError("fe.discrete", "required table is missing (needed for --case)")
    try:
        reduced = reduce_problem(problem)
    except ValueError as exc:
        raise CaseError("fe", str(exc)) from None
    try:
        check_stiffness({"A": reduced.A, "B": reduced.B, "C": reduced.C})
    except StiffnessError as exc:
        raise CaseError("fe", f"reduced stiffness {exc.problem}") from None
    text = None
    if args.case is not None:
        rel = os.path.relpath(args.out.resolve(), args.case.resolve().parent)
        text = discrete_case_text(discrete, reduced, rel)
    meta = provenance(case.text, case.path)
    outputs = [(args.out, lambda tmp: reduced.save(tmp, meta, atomic=False))]
    if text is not None:
        outputs.append((args.case, lambda tmp: tmp.write_text(text, encoding="utf-8")))
    write_together(outputs)
    info = {k: v for k, v in reduced.info.items() if k in (
        "geometry", "n_dofs", "n_contact_nodes", "element", "condense_seconds")}
    info["load_cases"] = reduced.load_cases
    info["coupling_B_over_A"] = float(np.linalg.norm(reduced.B) / np.linalg.norm(reduced.A))
    return info
