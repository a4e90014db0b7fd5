"""The example case files shipped with slipcycle.

Each ``*.toml`` file of this folder is a complete case (``slipcycle run``, ``shakedown``,
``limits``, ``map``, ``reduce``, ...; the first comment lines say which). They are
installed with the package, so they can be listed, read and copied from any installation:

>>> import slipcycle
>>> "halfspace_sphere" in slipcycle.list_examples()
True
>>> text = slipcycle.example_path("halfspace_sphere").read_text()

``slipcycle examples`` lists them on the command line and ``slipcycle examples --copy DIR``
copies them into a folder for editing. This module imports nothing but the standard
library.
"""

from __future__ import annotations

import re
import shutil
from importlib import resources
from pathlib import Path

__all__ = ["list_examples", "example_path", "example_text", "example_summary",
           "example_command",
           "copy_examples"]


#: data files shipped beside the cases (package-data in pyproject.toml)
_DATA_SUFFIXES = ("nc", "csv", "inp")


def _folder():
    return resources.files(__name__)


def list_examples() -> list[str]:
    """Names of the shipped example cases (file names without ``.toml``), sorted.

    Returns
    -------
    list of str
    """
    return sorted(p.name[:-5] for p in _folder().iterdir()
                  if p.name.endswith(".toml") and p.is_file())


def example_path(name: str) -> Path:
    """Path of the shipped example case ``name`` (with or without ``.toml``).

    Parameters
    ----------
    name : str
        One of :func:`list_examples`.

    Returns
    -------
    pathlib.Path
        The installed file (read it, or pass it to :func:`slipcycle.run`).

    Raises
    ------
    KeyError
        For a name that is not a shipped example (the message lists them).
    """
    stem = name[:-5] if name.endswith(".toml") else name
    if stem not in list_examples():
        raise KeyError(f"no example {name!r}; the examples are: "
                       + ", ".join(list_examples()))
    return Path(str(_folder().joinpath(f"{stem}.toml")))


def example_text(name: str) -> str:
    """TOML text of the shipped example case ``name`` (see :func:`example_path`)."""
    return example_path(name).read_text(encoding="utf-8")


#: the end of a sentence: . ? or ! before a space or the end, not after an abbreviation
_SENTENCE_END = re.compile(r"(?<!\bFig)(?<!\be\.g)(?<!\bi\.e)(?<!\bal)(?<!\bEq)[.?!](?=\s|$)")


def example_summary(name: str) -> str:
    """The first sentence of the opening comment of example ``name`` (what the case is),
    joined across comment lines, without ``#``; never cut mid-sentence."""
    words: list[str] = []
    for line in example_text(name).splitlines():
        if not line.startswith("#"):
            if line.strip() or words:
                break
            continue
        line = line.lstrip("#").strip()
        if words and words[-1][-1:] not in ",;:-(" and line[:1].isupper():
            break                   # the first line was a title without a full stop
        words.append(line)
        end = _SENTENCE_END.search(" ".join(words))
        if end:
            return " ".join(words)[:end.start() + 1]
    return " ".join(words)


def example_command(name: str) -> list[str]:
    """The command line that runs example ``name`` from a folder holding its copy.

    ``run`` for every model it solves; ``map`` for a case with a ``[map]`` table;
    ``reduce`` for a finite-element model without ``[fe.discrete]`` (it reduces to an
    ``.npz``) and for a model file of an FE export (to a folder).
    """
    import tomllib

    data = tomllib.loads(example_text(name))
    model = data.get("model")
    if model == "fe_import":
        return ["reduce", f"{name}.toml", "--out", f"{name}_reduced"]
    if model == "fe" and "discrete" not in data.get("fe", {}):
        return ["reduce", f"{name}.toml", "--out", f"{name}.npz"]
    if "map" in data:
        return ["map", f"{name}.toml", "--out", f"{name}_results"]
    return ["run", f"{name}.toml", "--out", f"{name}_results"]


def copy_examples(target: str | Path, names: list[str] | None = None, *,
                  overwrite: bool = False) -> list[Path]:
    """Copy shipped example cases into the folder ``target`` (created if needed).

    Parameters
    ----------
    target : path
        Destination folder.
    names : list of str, optional
        Examples to copy; default all of :func:`list_examples`.
    overwrite : bool
        Replace files of the same name already in ``target`` (default: keep them and
        raise :class:`FileExistsError`).

    Returns
    -------
    list of Path
        The files written: the cases and the data files they read (topographies,
        tables).
    """
    target = Path(target)
    sources = [example_path(n) for n in (names if names is not None else list_examples())]
    # the data files a case names (a measured topography, a table) travel with it
    texts = [p.read_text(encoding="utf-8") for p in sources]
    sources += [Path(str(p)) for p in _folder().iterdir()
                if p.is_file() and p.name.rsplit(".", 1)[-1] in _DATA_SUFFIXES
                and any(p.name in t for t in texts)]
    clashes = [target / p.name for p in sources if (target / p.name).exists()]
    if clashes and not overwrite:
        raise FileExistsError(f"{clashes[0]} exists (use --force to replace the examples "
                              "already there)")
    target.mkdir(parents=True, exist_ok=True)
    written = []
    for src in sources:
        shutil.copyfile(src, target / src.name)
        written.append(target / src.name)
    return written
