"""All the forces of the library, in one place to import them from.

A force is a small object with one method::

    force.add_to(F, x, v, t, m)    # F += this force, F shape (n, d)

where ``x`` and ``v`` are positions and velocities (shape (n, d)), ``t`` the
time and ``m`` the masses (shape (n,)). The particle system sums all forces in
one place (:meth:`particles.ParticleSystem.total_force`); ``force(x, v, t, m)``
returns one force alone. Each kind of force lives in its own module of this
package, and the package gathers them (``from particles.forces import Gravity, LennardJones``).
Springs, bending and clamps of mass-spring models are in :mod:`particles.springs`, Reynolds' boids
in :mod:`particles.effects.flocking`.

* :mod:`particles.forces.fields`: the :class:`Force` base class and the forces on each particle alone:
  :class:`Gravity`, :class:`Damping`, :class:`Wind`, :class:`Attractor`, :class:`Vortex`, :class:`Field`;
* :mod:`particles.forces.pairs`: the kernels of every pair interaction, :func:`pair_differences` and
  :func:`scatter_pair_forces`;
* :mod:`particles.forces.nbody`: :class:`NBodyGravity`, all pairs;
* :mod:`particles.forces.lennardjones`: :class:`LennardJones`, short range on the bucket grid
  (:mod:`particles.neighbors`);
* :mod:`particles.forces.surfacewind`: :class:`SurfaceWind`, Provot's wind on the triangles of a surface
  (along each normal, from the air's velocity relative to it).

The contract every force keeps is tested for every subclass of
:class:`Force` in the package (``tests/library/forces/test_force_contract.py``): it does not
modify its inputs; ``add_to`` adds into ``F`` and leaves its shape and dtype;
a force with a ``potential_energy`` is minus its gradient; a force between
particles conserves the total momentum; ``uses_velocity = False`` and
``uses_time = False`` are true.
"""

from .fields import Attractor, Damping, Field, Force, Gravity, Vortex, Wind
from .lennardjones import LennardJones
from .nbody import NBodyGravity
from .pairs import pair_differences, scatter_pair_forces
from .surfacewind import SurfaceWind

__all__ = ["Force", "Gravity", "Damping", "Wind", "Attractor", "Vortex", "Field", "NBodyGravity", "LennardJones",
           "SurfaceWind", "pair_differences", "scatter_pair_forces"]
