"""Constraints of mass-spring models: Provot's strain limit, rigid rods, and the colouring of constraint solvers.

* :mod:`particles.constraints.colouring`: :func:`color_constraints`, groups of constraints that share no
  particle (Luby's rounds, vectorized), for every Gauss-Seidel sweep of the library (Provot's pass, XPBD,
  the cloth's contacts);
* :mod:`particles.constraints.provot`: Provot's formula (:func:`provot_excess`), one pass
  (:func:`provot_pass`) and the repeated passes of a projection (:func:`provot_projection`): the reference;
* :mod:`particles.constraints.provot_constraint`: :class:`ProvotConstraint`, springs kept below a strain by
  moving their ends after each step of a run;
* :mod:`particles.constraints.kernels`: Provot's projection compiled, every pass in one call (loaded only when
  the constraint's backend resolves to numba);
* :mod:`particles.constraints.rigid`: :class:`RigidRods`, rods of fixed length by Lagrange multipliers
  (pendulums, chains).

Position-based constraints (distances, bending) are in :mod:`particles.xpbd`.
"""

from .colouring import check_groups, color_constraints
from .provot import ProjectionResult, provot_excess, provot_pass, provot_projection
from .provot_constraint import ProvotConstraint
from .rigid import RigidRods, chain, crossing_period, pendulum, pendulum_period

__all__ = ["ProvotConstraint", "ProjectionResult", "provot_projection", "provot_pass", "provot_excess",
           "color_constraints", "check_groups", "RigidRods", "pendulum", "chain", "pendulum_period",
           "crossing_period"]
