"""Position-based dynamics: constraints projected in substeps, with compliance (XPBD) or stiffness (PBD).

As Newton's ``solvers/xpbd``: the constraints, the solver, and its kernels beside it
(``from particles.xpbd import XPBD, Distance``).

* :mod:`particles.xpbd.distance`: one XPBD solve as the paper writes it: the distance constraint
  (:func:`distance_constraint`), the multiplier's step (:func:`multiplier_step`) and one pass over
  distance constraints (:func:`distance_pass`): the reference;
* :mod:`particles.xpbd.constraint_sets`: the constraint sets :class:`Distance`, :class:`IsometricBending`,
  :class:`IsometricClamp`, :class:`Attachment`, their base :class:`ConstraintSet` and the batches a solver
  projects together (their colour groups come from :mod:`particles.constraints.colouring`);
* :mod:`particles.xpbd.from_springs`: :func:`constraints_from_system`, a mass-spring system's springs as
  constraints;
* :mod:`particles.xpbd.solver`: :class:`XPBD` and :class:`PBD`, the substepped solvers;
* :mod:`particles.xpbd.stiffness`: PBD's stiffness corrected for the iteration count
  (:func:`iteration_corrected`, ``PBD(..., corrected=True)``);
* :mod:`particles.xpbd.compiled_substep`: a Gauss-Seidel substep in one compiled call (imports numba);
* :mod:`particles.xpbd.kernels`: the compiled projections, inlining :func:`multiplier_step`.
"""

from .constraint_sets import Attachment, ConstraintSet, Distance, IsometricBending, IsometricClamp
from .distance import distance_constraint, distance_pass, multiplier_step
from .from_springs import constraints_from_system
from .solver import PBD, XPBD
from .stiffness import iteration_corrected

__all__ = ["XPBD", "PBD", "Distance", "IsometricBending", "IsometricClamp", "Attachment", "ConstraintSet",
           "constraints_from_system", "distance_pass", "distance_constraint", "multiplier_step",
           "iteration_corrected"]
