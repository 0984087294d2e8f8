"""Constraints of mass-spring models: Provot's strain limit and rigid rods.

* :mod:`particles.constraints.provot`: :class:`ProvotConstraint`, springs kept below a strain by moving their
  ends after each step;
* :mod:`particles.constraints.rigid`: :class:`RigidRods`, rods of fixed length by Lagrange multipliers
  (pendulums, chains).

Position-based constraints (distances, bending) are in :mod:`particles.xpbd`.
"""

from .provot import ProjectionResult, ProvotConstraint, color_springs, provot_projection
from .rigid import RigidRods, chain, crossing_period, pendulum, pendulum_period

__all__ = ["ProvotConstraint", "ProjectionResult", "provot_projection", "color_springs", "RigidRods", "pendulum",
           "chain", "pendulum_period", "crossing_period"]
