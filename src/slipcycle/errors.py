"""The two kinds of error a user can meet.

- :class:`InputError`: the input is invalid (a key of a case file, a command-line option, a
  matrix of a model, a file). ``key`` names what is at fault, ``problem`` says why. The
  command line prints ``error: <key>: <problem>`` on one line and exits with code 2.
  :class:`CaseError` (a key of a case file; also :class:`slipcycle.io.CaseError`),
  :class:`slipcycle.sweep.SweepError`,
  :class:`slipcycle.io.matrices.StiffnessError` and :class:`ModelError` (a model object,
  with an optional remedy) are its kinds.
- :class:`SolverError`: a valid model on which a solver could not proceed (exit code 3).
"""

__all__ = ["InputError", "CaseError", "ModelError", "SolverError", "InadmissibleInitialState"]


def _rebuilt(cls, args: tuple, state: dict) -> BaseException:
    """An exception of class ``cls`` with ``args`` and attributes ``state``, its
    ``__init__`` not called (:meth:`_Picklable.__reduce__`)."""
    exc = cls.__new__(cls)
    exc.args = args
    exc.__dict__.update(state)
    return exc


class _Picklable:
    """Pickled as its message and attributes: the default pickling of an exception calls
    ``cls(*args)``, which fails where ``__init__`` takes other arguments than the message,
    so an error raised in a worker process (sweeps, protocol runs) reached its parent as
    a pickling error instead of itself."""

    def __reduce__(self):
        return _rebuilt, (type(self), self.args, dict(self.__dict__))


class InputError(_Picklable, ValueError):
    """Invalid input. ``key`` names the offending key, option, matrix or file."""

    def __init__(self, key: str, problem: str):
        self.key = key
        self.problem = problem
        super().__init__(f"{key}: {problem}" if key else problem)


class CaseError(InputError):
    """A case file (or a file or option of a command) is invalid. ``key`` is the dotted
    path of the offending key (``halfspace.radius``) or the option (``--out``).

    It lives here, beside :class:`InputError`, so that every reader and checker of
    :mod:`slipcycle.io` can raise it without importing :mod:`slipcycle.io.case`.
    """


class ModelError(InputError):
    """An invalid model object (the discrete models' matrices and parameters).

    Parameters
    ----------
    name : str
        The matrix or parameter at fault (``"A"``, ``"friction"``); also ``key``.
    problem : str
        What is wrong, in words.
    remedy : (str, bool, str), optional
        ``(field, value, purpose)``: setting another field would let the model through
        (``accept_ill_posed``, ``True``, ``"run anyway"``). ``problem`` then ends with
        ``Pass field=value to purpose``; :attr:`detail` is ``problem`` without it, so that
        a case-file reader can name its own key instead
        (:func:`slipcycle.io.case.case_error_of`).
    """

    def __init__(self, name: str, problem: str, *, remedy: tuple | None = None):
        self.detail = problem
        self.remedy = remedy
        if remedy is not None:
            field_name, value, purpose = remedy
            problem = f"{problem}. Pass {field_name}={value!r} to {purpose}"
        super().__init__(name, problem)
        self.name = name


class SolverError(RuntimeError):
    """A valid model on which a solver could not proceed (e.g. an accepted ill-posed
    rate problem that has no solution). The CLI reports it as one line, exit code 3."""


class InadmissibleInitialState(_Picklable, ValueError):
    """An initial slip state that violates a friction or contact inequality at θ = 0
    (discrete models): ``node``, its ``margin`` (N; f p − |q|, or the contact margin) and
    whether the node is open (``separated``: w > 0 at θ = 0, so it carries no reaction)."""

    def __init__(self, node: int, margin: float, what: str, separated: bool = False):
        self.node = node
        self.margin = margin
        self.separated = separated
        super().__init__(f"node {node} {what} (margin {margin:.6g} N)")
