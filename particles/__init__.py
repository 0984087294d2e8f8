"""particles: a course package for particle systems and mass-spring simulation.

The reference library follows the lecture's animation loop: a state ``X`` of
shape ``(n, 2, d)`` (positions and velocities), forces that add into a force
array, and ODE steppers ``step(f, X, t, h)``.

>>> import particles
>>> from particles.forces import Gravity, Damping
>>> ps = particles.ParticleSystem([[0.0, 0.0]], v=[[1.0, 1.0]], forces=[Gravity([0, -9.81])])
>>> t, X = ps.run(0.5, h=0.01, method="verlet")
"""

from . import constraints, forces, implicit, integrators, massspring, neighbors, springs
from .errors import ConvergenceError, SimulationDiverged
from .integrators import INTEGRATORS, integrate
from .system import ParticleSystem

__version__ = "0.1.0"

__all__ = [
    "ParticleSystem",
    "INTEGRATORS",
    "integrate",
    "SimulationDiverged",
    "ConvergenceError",
    "constraints",
    "forces",
    "implicit",
    "integrators",
    "massspring",
    "neighbors",
    "springs",
]
