"""Measured studies behind the exercises, the lectures and ``particles study``.

Each study is a function returning data (arrays and tables); plotting and
writing files are separate, so the same study serves a test, a lecture and
the command line.

* :mod:`~particles.studies.order`: convergence orders of the steppers;
* :mod:`~particles.studies.stability`: the largest stable time step against
  stiffness, numerical damping of implicit Euler, the cost of a simulated second;
* :mod:`~particles.studies.provot`: the hanging curtain with and without
  Provot's constraint;
* :mod:`~particles.studies.discretization`: the same cloth at several
  resolutions, with naive and physical parameters;
* :mod:`~particles.studies.bounce`: a dropped ball, restitution, and the
  two fixes of the overshooting problem (projection and backtracking);
* :mod:`~particles.studies.pbd`: PBD and XPBD on the curtain and the stiff
  cloth of lecture 7 (effective stiffness against iterations and the step,
  substeps against iterations).
* :mod:`~particles.studies.report`: the figures and tables of ``particles study``, written to files.
"""

from .order import convergence_study, fit_order, format_table, global_error, plot_convergence

__all__ = ["convergence_study", "fit_order", "format_table", "global_error", "plot_convergence"]
