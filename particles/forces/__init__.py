"""All the forces of the library, in one place to import them from.

A force is a small object with one method::

    force.add_to(F, x, v, t, m)    # F += this force, F shape (n, d)

where ``x`` and ``v`` are positions and velocities (shape (n, d)), ``t`` the
time and ``m`` the masses (shape (n,)). The particle system sums all forces in
one place (:meth:`particles.ParticleSystem.total_force`); ``force(x, v, t, m)``
returns one force alone. Each kind of force lives in its own module of this
package, and the package gathers them (``from particles.forces import Gravity, Springs``).
Reynolds' boids are in :mod:`particles.effects.flocking`.

* :mod:`particles.forces.force`: the :class:`Force` base class and its contract;
* :mod:`particles.forces.fields`: the forces on each particle alone: :class:`Gravity`, :class:`Damping`,
  :class:`Wind`, :class:`Attractor`, :class:`Vortex`, :class:`Field`;
* :mod:`particles.forces.springs`: the formulas of springs, bending and clamps (the damped spring's force and
  its Jacobian, a joint's bending) and their NumPy passes: the reference a student reads;
* :mod:`particles.forces.spring_sets`: :class:`Springs`, :class:`Bending`, :class:`Clamp`, the force objects of
  mass-spring models (index arrays, parameters, backend);
* :mod:`particles.forces.pairs`: :func:`pair_differences`, and the laws of one pair of N-body gravity and
  Lennard-Jones;
* :mod:`particles.forces.nbody`: :class:`NBodyGravity`, all pairs;
* :mod:`particles.forces.lennardjones`: :class:`LennardJones`, short range on the bucket grid
  (:mod:`particles.neighbors`);
* :mod:`particles.forces.surfacewind`: :class:`SurfaceWind`, Provot's wind on the triangles of a surface
  (along each normal, from the air's velocity relative to it).
* :mod:`particles.forces.kernels`: the compiled loops of springs, bending, Lennard-Jones and N-body gravity,
  each inlining its law (loaded only when a force's backend resolves to numba).

The contract every force keeps is tested for every subclass of
:class:`Force` in the package (``tests/library/forces/test_force_contract.py``): it does not
modify its inputs; ``add_to`` adds into ``F`` and leaves its shape and dtype;
a force with a ``potential_energy`` is minus its gradient; a force between
particles conserves the total momentum; ``uses_velocity = False`` and
``uses_time = False`` are true.
"""

from .fields import Attractor, Damping, Field, Gravity, Vortex, Wind
from .force import Force
from .lennardjones import LennardJones
from .nbody import NBodyGravity
from .pairs import pair_differences
from .spring_sets import Bending, Clamp, Springs
from .springs import damped_spring_force, spring_jacobian_blocks
from .surfacewind import SurfaceWind

__all__ = ["Force", "Gravity", "Damping", "Wind", "Attractor", "Vortex", "Field", "Springs", "Bending", "Clamp",
           "NBodyGravity", "LennardJones", "SurfaceWind", "pair_differences", "damped_spring_force",
           "spring_jacobian_blocks"]
