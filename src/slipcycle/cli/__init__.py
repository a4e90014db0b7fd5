"""The ``slipcycle`` command line."""
