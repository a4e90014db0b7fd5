"""The installed version of slipcycle (a leaf module: results and the command line read it
without importing the package's public API)."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("slipcycle")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
