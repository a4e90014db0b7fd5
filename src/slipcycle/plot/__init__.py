"""Figures (matplotlib, Agg backend). One module per model."""
