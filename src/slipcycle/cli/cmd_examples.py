"""``slipcycle examples [--copy DIR]``: the example cases shipped with slipcycle.

Without options, lists every shipped case file with the command that runs it (``run``,
``map`` or ``reduce``) and the first sentence of its comment; ``--copy DIR``
copies them (or only the ``NAME``s given) into DIR to edit and run, e.g.
``slipcycle examples --copy cases && slipcycle run cases/halfspace_sphere.toml --out r``.
``--path NAME`` prints where the installed file of one example is.
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_parser(sub) -> None:
    p = sub.add_parser("examples", help="list the shipped example cases, or copy them to edit",
                       description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("names", nargs="*", metavar="NAME", help="examples to copy (default: all)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--copy", type=Path, default=None, metavar="DIR",
                   help="copy the example case files into DIR")
    g.add_argument("--path", action="store_true",
                   help="print the installed path of each NAME")
    p.add_argument("--force", action="store_true",
                   help="with --copy: replace files of the same name in DIR")
    p.set_defaults(execute=execute, writes_results=False)


def execute(args: argparse.Namespace) -> int:
    from slipcycle.errors import InputError as CaseError
    from slipcycle.examples import (
        copy_examples,
        example_command,
        example_path,
        example_summary,
        list_examples,
    )

    names = [n.removesuffix(".toml") for n in args.names]
    unknown = [n for n in names if n not in list_examples()]
    if unknown:
        raise CaseError(unknown[0], "is not a shipped example; 'slipcycle examples' lists "
                        "them")
    if args.force and args.copy is None:
        raise CaseError("--force", "only applies with --copy DIR (it replaces the files of "
                        "the same name there)")
    if args.copy is not None:
        if args.copy.exists() and not args.copy.is_dir():
            raise CaseError("--copy", f"{args.copy} is a file, not a folder; give a folder "
                            "to copy the examples into")
        try:
            written = copy_examples(args.copy, names or None, overwrite=args.force)
        except FileExistsError as exc:
            raise CaseError("--copy", str(exc)) from None
        except OSError as exc:
            raise CaseError(str(args.copy), f"cannot write: {exc.strerror or exc}") from None
        if not args.quiet:
            print(copied_message(written, args.copy))
        return 0
    if args.path:
        for name in names or list_examples():
            print(example_path(name))
        return 0
    if not args.quiet:
        width = max(len(n) for n in list_examples())
        for name in names or list_examples():
            command = example_command(name)[0]
            print(f"{name:<{width}}  {command:<7} {example_summary(name)}")
        print("\nCOMMAND runs a copy: slipcycle examples --copy DIR NAME; cd DIR; "
              "slipcycle COMMAND NAME.toml --out OUT (OUT an .npz file for reduce of a "
              "2-D FE model)")
    return 0


def copied_message(written: list[Path], folder: Path) -> str:
    """The line of ``--copy``: the case files (``.toml``) counted apart from the data files
    they read (a mesh deck, a topography, a table), which are not cases to run."""
    cases = sum(p.suffix == ".toml" for p in written)
    data = sorted(p.name for p in written if p.suffix != ".toml")
    text = f"{cases} example case file{'s' * (cases != 1)}"
    if data:
        text += f" and {len(data)} data file{'s' * (len(data) != 1)} they read ({', '.join(data)})"
    return f"{text} copied to {folder}/"
