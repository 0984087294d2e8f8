"""Position-based dynamics: constraints projected in substeps, with compliance (XPBD) or stiffness (PBD).

As Newton's ``solvers/xpbd``: the constraints, their colouring and the solver
(``from particles.xpbd import XPBD, Distance``).

* :mod:`particles.xpbd.constraints`: the constraint sets :class:`Distance`, :class:`IsometricBending`,
  :class:`IsometricClamp`, :class:`Attachment` and their base :class:`ConstraintSet`;
* :mod:`particles.xpbd.colouring`: groups of constraints that share no particle, for Gauss-Seidel sweeps
  (:func:`color_constraints`);
* :mod:`particles.xpbd.solver`: :class:`XPBD` and :class:`PBD`, the substepped solvers, and
  :func:`constraints_from_system`;
* :mod:`particles.xpbd.stiffness`: PBD's stiffness corrected for the iteration count
  (:func:`iteration_corrected`, ``PBD(..., corrected=True)``).
"""

from .constraints import ConstraintSet
from .solver import (PBD, XPBD, Attachment, Distance, IsometricBending, IsometricClamp, color_constraints,
                     constraints_from_system, distance_pass)
from .stiffness import iteration_corrected

__all__ = ["XPBD", "PBD", "Distance", "IsometricBending", "IsometricClamp", "Attachment", "color_constraints",
           "constraints_from_system", "distance_pass", "ConstraintSet", "iteration_corrected"]
