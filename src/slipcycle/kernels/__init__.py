"""Compiled kernels shared by several models (Numba, ``cache=True``)."""
