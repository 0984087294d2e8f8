"""Mass-spring models: strings, hair and cloth, ready to simulate.

Each builder returns a :class:`MassSpringSystem`, a particle system whose
spring sets are labelled by kind, with gravity, damping and pins set up
(``from particles.massspring import string, hair, cloth``); the forces themselves
(springs, bending, clamps) are in :mod:`particles.forces.springs` and :mod:`particles.forces.spring_sets`.

* :mod:`particles.massspring.model`: :class:`MassSpringSystem` and the rules the builders share (scalings,
  dual weights, the common forces); the system's symplectic Euler step, compiled where its springs are;
* :mod:`particles.massspring.strands`: :func:`string` and :func:`hair`;
* :mod:`particles.massspring.cloth`: :func:`cloth`, :func:`cloth_springs` (a cloth's springs, as the slide
  lists them), :func:`cloth_masses`, :func:`cloth_stiffness`;
* :mod:`particles.massspring.compiled_step`: the compiled step: what it does with each force, the blocks of
  particles, the kernel's call (imports numba);
* :mod:`particles.massspring.step_kernels`: its loop, one parallel pass over blocks per step, inlining the
  forces' laws.

Discretization and physical parameters
--------------------------------------
A builder's ``scaling`` says how masses and stiffnesses follow the grid:

* ``"naive"``: every particle has the same mass and every spring of a kind
  the same stiffness, whatever the resolution. This is what the lecture
  warns about: refining the grid adds mass and changes the stiffness of the
  body, so a finer cloth does not behave like a coarser one.
* ``"physical"``: masses and stiffnesses are derived from material
  parameters so that the *body* stays the same under refinement:

  - mass = density x the length (string) or area (cloth) a particle stands
    for (its dual cell: half a segment or cell at the boundary);
  - stiffness by matching elastic energies. A spring of rest length ``L0``
    stretched by a strain ``e`` stores ``k (e L0)^2 / 2``; the piece of
    material it stands for stores ``Y e^2 / 2`` per unit length (string,
    ``Y`` = EA in N) or per unit area (cloth, ``Y`` in N/m). Equal energies
    give ``k = Y / L0`` for a string and ``k = Y A / L0^2`` for a cloth spring
    standing for an area ``A``. On a square grid ``k = Y`` whatever the
    spacing: a 2D spring network keeps its stiffness under refinement while
    its particles get lighter;
  - bending stiffness per joint ``kb = B w / L0`` from a bending modulus ``B``
    (EI in N m^2 for hair; N m for cloth, over a strip of width ``w``), since
    a joint turning by ``theta`` over a segment ``L0`` is a curvature
    ``theta / L0``.

References
----------
.. [1] X. Provot, "Deformation constraints in a mass-spring model to describe
   rigid cloth behavior", Graphics Interface 1995 (structural, shear and
   flexion springs).
"""

from .cloth import cloth, cloth_masses, cloth_springs, cloth_stiffness
from .model import SCALINGS, SYMPLECTIC_LIMIT, MassSpringSystem, SymplecticEulerStep
from .strands import hair, string

__all__ = ["cloth", "cloth_springs", "cloth_masses", "cloth_stiffness", "MassSpringSystem", "SymplecticEulerStep",
           "SCALINGS", "SYMPLECTIC_LIMIT", "string", "hair"]
