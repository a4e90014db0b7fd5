"""Sphinx configuration of the slipcycle documentation (``make docs``).

The API pages (``docs/api/generated/<package>.rst``) are written here from each public package's
``__all__`` at every build, so the reference lists exactly the public names. The gallery
(``examples/gallery/plot_*.py``) is executed by sphinx-gallery at every build.
"""

from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import slipcycle  # noqa: E402

project = "slipcycle"
author = "the slipcycle developers"
copyright = "the slipcycle developers, BSD-3-Clause"
release = version = slipcycle.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "sg_execution_times.rst",
                    "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip"]
templates_path = ["_templates"]

# --- Markdown pages (MyST) -------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
# The user-guide pages are also read on GitHub, where a heading may skip a level.
suppress_warnings = ["myst.header"]

# --- API reference ---------------------------------------------------------------------
#: the documented packages, each with its ``__all__``
API_PACKAGES = {
    "slipcycle": "Top level: ``slipcycle.run`` and the result contract",
    "slipcycle.result": "The result contract shared by every model",
    "slipcycle.halfspace": "Half-space contacts (Ciavarella–Jäger slider bed)",
    "slipcycle.discrete": "Coupled discrete frictional systems",
    "slipcycle.rods": "Two rods with a frictional interface",
    "slipcycle.discrete3d": "Three-dimensional frictional interfaces (the Coulomb cone)",
    "slipcycle.fe": "Static reduction of finite-element models",
    "slipcycle.fe_import": "From a finite-element code's export to a discrete3d case",
    "slipcycle.studies": "Studies above the models (basins, shakedown, maps, limits, sweeps)",
}


def public_names(package: str) -> list[str]:
    """The names of ``package.__all__`` that are not dunder names, in their order."""
    mod = importlib.import_module(package)
    names = getattr(mod, "__all__", None)
    if names is None:
        names = [n for n in vars(mod) if not n.startswith("_")]
    return [n for n in names if not (n.startswith("__") and n.endswith("__"))]


def write_api_pages() -> None:
    """``docs/api/generated/<package>.rst``: the package docstring and an autosummary of
    ``__all__`` (in the ignored build folder, so a changed ``__all__`` leaves no diff)."""
    folder = HERE / "api" / "generated"
    folder.mkdir(parents=True, exist_ok=True)
    for package, title in API_PACKAGES.items():
        names = public_names(package)
        lines = [f"``{package}``", "=" * (len(package) + 4), "", title + ".", "",
                 f".. automodule:: {package}", "   :no-members:", "",
                 f".. currentmodule:: {package}", "", ".. autosummary::",
                 "   :toctree: .", "   :nosignatures:", ""]
        lines += [f"   {name}" for name in names]
        text = "\n".join(lines) + "\n"
        path = folder / f"{package}.rst"
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


write_api_pages()

autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "inherited-members": False}
autodoc_typehints = "none"
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
# Style is checked by review, not by the build: numpydoc reports no validation checks.
numpydoc_validation_checks: set[str] = set()

# --- Gallery -----------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": str(HERE.parent / "examples" / "gallery"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "ignore_pattern": r"__init__\.py",
    "image_scrapers": ("gallery_scraper.figure_scraper", "matplotlib"),
    "within_subsection_order": "FileNameSortKey",
    "remove_config_comments": True,
    "abort_on_example_error": False,
    "only_warn_on_example_error": False,
    "download_all_examples": False,
    "show_memory": False,
    "plot_gallery": "True",
    # the timings are on each example's page; a separate page would join the user guide's
    # glob of top-level pages
    "write_computation_times": False,
}

# --- HTML --------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"slipcycle {release}"
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_theme_options = {
    "navigation_depth": 2,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_show_sourcelink = False
mathjax3_config = {"tex": {"macros": {"d": r"\mathrm{d}"}}}


# --- Plain-text docstrings -----------------------------------------------------------------
# The docstrings write absolute values as |Q| and norms as ‖x‖, which reStructuredText
# would read as substitution references: escape every bar outside ``literals`` and
# outside table lines before numpydoc and autodoc parse them.
def _escape_bars(line: str) -> str:
    stripped = line.lstrip()
    if stripped == "|" or stripped.startswith(("| ", "+-", "+=")):
        return line                                   # an rST line block or grid table
    parts = line.split("``")
    for i in range(0, len(parts), 2):                 # even parts lie outside literals
        parts[i] = parts[i].replace("\\|", "|").replace("|", "\\|")
    return "``".join(parts)


def escape_absolute_values(app, what, name, obj, options, lines):
    """``autodoc-process-docstring`` hook: |x| is an absolute value, not a substitution."""
    lines[:] = [_escape_bars(line) for line in lines]


def setup(app):
    app.connect("autodoc-process-docstring", escape_absolute_values, priority=100)
