"""``slipcycle reduce MODEL.toml --out reduced.npz``: static reduction to the contact nodes.

A model file with ``model = "fe_import"`` names the stiffness export(s) of another FE code
and the mesh; ``--out`` is then a directory, which receives a runnable ``discrete3d``
case (``case.toml``), its ``stiffness.npz`` and ``report.txt`` (docs/from_fe_code.md).

MODEL may also be a reduced stiffness from another code (``.mtx`` or ``.npz``): it is
then imported, checked (shapes, symmetric, positive definite) and written in
slipcycle's ``.npz`` layout. ``--case discrete.toml`` writes a discrete case file that
refers to the output, built from the model's ``[fe.discrete]`` table.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_parser(sub) -> None:
    p = sub.add_parser("reduce", help="reduce a finite-element model (or import reduced "
                       "matrices) to A, B, C and p^w, q^w in an .npz file", description=__doc__)
    p.add_argument("model", type=Path, help="model file (TOML, model = \"fe\") or .mtx/.npz")
    p.add_argument("--out", type=Path, required=True,
                   help="output .npz file (a directory for an fe_import model file)")
    p.add_argument("--dof-order", choices=("tangential_first", "interleaved"), default=None,
                   help="ordering of the DOFs of an imported full K, if the file does not "
                        "state it (default tangential_first)")
    p.add_argument("--case", type=Path, default=None,
                   help="also write a discrete case file using [fe.discrete]")
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.fe.files import import_stiffness, reduce_model
    from slipcycle.fe_import import is_import_model, reduce_import
    from slipcycle.io import CaseError
    from slipcycle.io.case import read_case
    from slipcycle.io.fe_formats import SUFFIX_FORMATS
    from slipcycle.io.results import to_jsonable

    if args.model.suffix.lower() not in (".mtx", ".npz") and is_import_model(args.model):
        if args.case is not None or args.dof_order is not None:
            raise CaseError("--case" if args.case is not None else "--dof-order",
                            "does not apply to an fe_import model file (it writes its "
                            "case into the --out directory)")
        info = reduce_import(args.model, args.out)
        if not args.quiet:
            print(f"{info['contact_nodes']} contact nodes, load cases "
                  f"{', '.join(info['load_cases']) or 'none'}; written to {args.out}: "
                  f"{', '.join(Path(w).name for w in info['written'])}")
        return 0
    suffix = args.model.suffix.lower()
    fmt = SUFFIX_FORMATS.get(suffix)
    if fmt is None and suffix not in (".mtx", ".npz"):
        # a model file that is not valid TOML (is_import_model said False) is refused
        # for itself before the --out it would be written to is looked at
        read_case(args.model)
    if fmt not in (None, "npz"):
        raise CaseError(str(args.model), f"a {fmt} stiffness export is reduced through a "
                        "model file (model = \"fe_import\", naming it and its mesh: "
                        "docs/from_fe_code.md) or named as stiffness_file in a discrete or "
                        "discrete3d case")
    if args.out.suffix.lower() != ".npz":
        raise CaseError("--out", f"must name an .npz file, got {args.out}")
    _refuse_same_files(args, CaseError)
    if suffix in (".mtx", ".npz"):
        if args.case is not None:
            raise CaseError("--case", "needs a model file with [fe.discrete], "
                                      "not imported matrices")
        info = import_stiffness(args.model, args.out, args.dof_order)
    else:
        if args.dof_order is not None:  # an FE model knows its own DOF order
            raise CaseError("--dof-order", "applies to imported .mtx/.npz matrices only, "
                            f"not to a model file ({args.model})")
        info = reduce_model(args.model, args.out, args.case)
    if not args.quiet:
        print(json.dumps(to_jsonable(info), indent=2, default=str))
        print(f"reduced model written to {args.out}")
    return 0


def _same(a: Path, b: Path) -> bool:
    """Whether two paths name the same file (resolved: ./x.npz and x.npz are one)."""
    return a.expanduser().resolve() == b.expanduser().resolve()


def _refuse_same_files(args: argparse.Namespace, error) -> None:
    """``--case`` must not be the ``--out``: the case file would replace the .npz and name
    itself as its stiffness_file (``--out`` equal to the input is refused where it is
    written, like ``--case`` equal to the input)."""
    if args.case is not None and _same(args.case, args.out):
        raise error("--case", f"is the same file as --out ({args.out}); give the case "
                    "file its own name (e.g. discrete.toml)")
