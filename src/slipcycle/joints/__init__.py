"""Joints built from finite-element models and solved: reduction, frictional steady state,
mesh convergence and assembly protocols.

This package sits above the model packages: it builds a model with :mod:`slipcycle.fe`,
reduces it to its contact nodes and solves the reduced model with
:mod:`slipcycle.discrete` (2-D) or :mod:`slipcycle.discrete3d` (3-D).
"""
