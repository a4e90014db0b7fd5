"""Static reduction of 2-D plane-strain finite-element models to contact nodes (SPEC §3)."""
