"""The shell shared by the coupled discrete models (``discrete``, 2-D, and ``discrete3d``).

The two models differ in their evolution engines only (the exact event-driven 2-D engine,
the step-controlled 3-D cone engine); everything around them lives here, once:

- :mod:`~slipcycle.coupled.system`: the system methods (``n_nodes``, ``uncoupled``,
  reactions, stiffness scale) and the well-posedness report;
- :mod:`~slipcycle.coupled.settings`: :class:`RunSettings`, the typed run settings, and
  :class:`SolverStats`, the typed solver statistics;
- :mod:`~slipcycle.coupled.solution`: the fields and properties of a steady-state run and
  the classification of its last cycle;
- :mod:`~slipcycle.coupled.case`: the run result, its summary and the
  solve_model/solve_case/run_case template.

Reference: J. R. Barber, "Frictional systems under periodic loads — history-dependence,
non-uniqueness and energy dissipation", J. Phys.: Conf. Ser. 382 (2012) 012002.
"""

from slipcycle.coupled.settings import RunSettings, SolverStats

__all__ = ["RunSettings", "SolverStats"]
