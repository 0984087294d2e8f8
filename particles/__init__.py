"""particles: a course package for particle systems and mass-spring simulation.

The reference library follows the lecture's animation loop, and has one
time loop, :meth:`ParticleSystem.run`: a state ``X`` of shape ``(n, 2, d)``
(positions and velocities), forces that add into a force array
(:mod:`particles.forces`), and ODE steppers ``step(f, X, t, h)`` or solver
objects ``solver.step(X, t, h)`` (:mod:`particles.steppers`). On top of it:
collisions with implicit surfaces (:mod:`particles.collisions`), emitters and
particle effects with lifetimes (:mod:`particles.emitters`,
:mod:`particles.effects`, colours in :mod:`particles.colours`), flocks
(:mod:`particles.flocking`), mass-spring models with Provot's constraint,
implicit solvers and cloth self-collision (:mod:`particles.massspring`,
:mod:`particles.constraints`, :mod:`particles.implicit`,
:mod:`particles.selfcollision`), position-based constraints and rigid rods
(:mod:`particles.xpbd`, :mod:`particles.pbdconstraints`, :mod:`particles.rigid`),
cloth as a triangle mesh that never passes through itself (:mod:`particles.mesh`,
:mod:`particles.intersections`, :mod:`particles.proximity`, :mod:`particles.ccd`,
:mod:`particles.clothcollisions`, moving bodies in :mod:`particles.moving`), molecular dynamics in a periodic box
(:mod:`particles.periodic`, :mod:`particles.thermostats`,
:mod:`particles.liquids`, :mod:`particles.statistics`) and drawing
(:mod:`particles.render`, imported on demand because it loads Matplotlib's
pyplot). ``CONTRIBUTING.md`` describes the layout and the data flow of a step.

>>> import particles
>>> from particles.forces import Gravity, Damping
>>> ps = particles.ParticleSystem([[0.0, 0.0]], v=[[1.0, 1.0]], forces=[Gravity([0, -9.81])])
>>> t, X = ps.run(0.5, h=0.01, method="verlet")
"""

from . import (ccd, clothcollisions, collisions, colours, constraints, effects, emitters, flocking, forces, implicit,
               integrators, intersections, liquids, massspring, mesh, moving, neighbors, pbdconstraints, periodic,
               proximity, rigid, selfcollision, springs, statistics, steppers, surfaces, thermostats, xpbd)
from .clothcollisions import ClothCollisions
from .collisions import Collider
from .effects import ParticleEffect
from .errors import ConvergenceError, SimulationDiverged
from .flocking import Flock
from .integrators import INTEGRATORS, integrate
from .system import ParticleSystem


def check(exercise, notebook=None, **options):
    """Run the public tests of `exercise` on your current notebook code (see :func:`particles.course.check.check`)."""
    from .course.check import check as _check

    return _check(exercise, notebook, **options)


__version__ = "0.1.0"

__all__ = [
    "ParticleSystem",
    "INTEGRATORS",
    "integrate",
    "SimulationDiverged",
    "ConvergenceError",
    "Collider",
    "ParticleEffect",
    "Flock",
    "check",
    "constraints",
    "colours",
    "forces",
    "implicit",
    "integrators",
    "massspring",
    "neighbors",
    "springs",
    "surfaces",
    "collisions",
    "emitters",
    "effects",
    "flocking",
    "selfcollision",
    "periodic",
    "thermostats",
    "statistics",
    "liquids",
    "steppers",
    "xpbd",
    "pbdconstraints",
    "rigid",
    "mesh",
    "intersections",
    "proximity",
    "ccd",
    "clothcollisions",
    "ClothCollisions",
    "moving",
]
