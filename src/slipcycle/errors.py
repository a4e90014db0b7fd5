"""Errors a user can meet, besides invalid case files (:class:`slipcycle.io.CaseError`)."""

__all__ = ["SolverError"]


class SolverError(RuntimeError):
    """A valid model on which a solver could not proceed (e.g. an accepted ill-posed
    rate problem that has no solution). The CLI reports it as one line, exit code 3."""
