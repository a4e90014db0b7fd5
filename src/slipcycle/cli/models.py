"""Kept for callers of ``slipcycle.cli.models.run_model``: the registry of the models now
lives in :mod:`slipcycle.registry` (below every other layer); use it instead."""

from __future__ import annotations

from slipcycle.registry import MODEL_RUNNERS, run_model

__all__ = ["MODEL_RUNNERS", "run_model"]
