"""particles: a course package for particle systems and mass-spring simulation.

The reference library follows the lecture's animation loop, and has one
time loop, :meth:`ParticleSystem.run`: a state ``X`` of shape ``(n, 2, d)``
(positions and velocities), forces that add into a force array, and ODE
steppers ``step(f, X, t, h)`` or solver objects ``solver.step(X, t, h)``.
One package per area of the lecture, each ``__init__`` docstring its map:

* :mod:`particles.integrators`: steppers, solver forms, the time loop;
* :mod:`particles.forces`: gravity, damping, fields, pair forces, N-body, Lennard-Jones;
* :mod:`particles.massspring`: strings, hair and cloth builders (springs in :mod:`particles.springs`);
* :mod:`particles.implicit`: implicit solvers of stiff springs (Baraff-Witkin, prefactored), statics;
* :mod:`particles.constraints`: Provot's strain limit, rigid rods;
* :mod:`particles.xpbd`: position-based dynamics;
* :mod:`particles.collisions`: surfaces, the particle collider, cloth meshes and their collisions;
* :mod:`particles.effects`: emitters, particle effects, colours, flocks;
* :mod:`particles.md`: molecular dynamics in a periodic box;
* :mod:`particles.explore`: explorations of a parameter with a slider;
* :mod:`particles.backends`: compiled kernels; :mod:`particles.demos`, :mod:`particles.studies`: demos and studies;
* :mod:`particles.course`: release and grading of the exercises.

The root keeps what every area shares: :mod:`particles.system` (:class:`ParticleSystem`, births and deaths
in :mod:`particles.population`), :mod:`particles.springs`, :mod:`particles.neighbors` (bucket grid),
:mod:`particles.problems`, :mod:`particles.errors`, the command line (:mod:`particles.cli`,
:mod:`particles.tour`) and drawing (:mod:`particles.render`, imported on demand because it loads
Matplotlib's pyplot). ``CONTRIBUTING.md`` says where to make a change and describes the data flow of a step.

>>> import particles
>>> from particles.forces import Gravity, Damping
>>> ps = particles.ParticleSystem([[0.0, 0.0]], v=[[1.0, 1.0]], forces=[Gravity([0, -9.81])])
>>> t, X = ps.run(0.5, h=0.01, method="verlet")
"""

from . import (collisions, constraints, effects, forces, implicit, integrators, massspring, md, neighbors, springs,
               xpbd)
from .collisions import ClothCollisions, Collider
from .effects import Flock, ParticleEffect
from .errors import ConvergenceError, SimulationDiverged
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
    "ClothCollisions",
    "ParticleEffect",
    "Flock",
    "check",
    "collisions",
    "constraints",
    "effects",
    "forces",
    "implicit",
    "integrators",
    "massspring",
    "md",
    "neighbors",
    "springs",
    "xpbd",
]
