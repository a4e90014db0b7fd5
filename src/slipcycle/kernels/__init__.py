"""Numerical kernels shared by several models (compiled with Numba, ``cache=True``, where
they loop)."""
