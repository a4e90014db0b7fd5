"""sphinx-gallery image scraper for the Figures that slipcycle's plot functions return.

``slipcycle.plot`` builds ``matplotlib.figure.Figure`` objects that pyplot does not know
(so that the library never touches a global figure registry), and the default matplotlib
scraper only finds pyplot figures. This scraper looks in the example's globals for Figure
objects it has not saved yet, in the order they were bound, and saves each once.
"""

from __future__ import annotations

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst

#: attribute that marks a Figure as saved (an id could be reused after garbage collection)
_MARK = "_slipcycle_gallery_saved"


def figure_scraper(block, block_vars, gallery_conf, **kwargs):
    """Save the new Figure objects bound in the example's globals; return their rST."""
    paths = []
    iterator = block_vars["image_path_iterator"]
    for value in list(block_vars["example_globals"].values()):
        figs = value if isinstance(value, list | tuple) else [value]
        for fig in figs:
            if isinstance(fig, Figure) and not getattr(fig, _MARK, False):
                setattr(fig, _MARK, True)
                path = next(iterator)
                fig.savefig(path, dpi=90)
                paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
