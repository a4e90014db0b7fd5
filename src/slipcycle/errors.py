"""The two kinds of error a user can meet.

- :class:`InputError`: the input is invalid (a key of a case file, a command-line option, a
  matrix of a model, a file). ``key`` names what is at fault, ``problem`` says why. The
  command line prints ``error: <key>: <problem>`` on one line and exits with code 2.
  :class:`slipcycle.io.CaseError`, :class:`slipcycle.sweep.SweepError`,
  :class:`slipcycle.io.matrices.StiffnessError` and
  :class:`slipcycle.discrete.model.ModelError` are its kinds.
- :class:`SolverError`: a valid model on which a solver could not proceed (exit code 3).
"""

__all__ = ["InputError", "SolverError"]


class InputError(ValueError):
    """Invalid input. ``key`` names the offending key, option, matrix or file."""

    def __init__(self, key: str, problem: str):
        self.key = key
        self.problem = problem
        super().__init__(f"{key}: {problem}" if key else problem)


class SolverError(RuntimeError):
    """A valid model on which a solver could not proceed (e.g. an accepted ill-posed
    rate problem that has no solution). The CLI reports it as one line, exit code 3."""
