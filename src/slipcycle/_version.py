"""The version of slipcycle, in one place: the package metadata (``pyproject.toml`` reads
it at build time), ``slipcycle --version``, ``slipcycle.__version__``, the documentation and
the provenance of every result file all take it from here. A leaf module: results and the
command line read it without importing the package's public API.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
