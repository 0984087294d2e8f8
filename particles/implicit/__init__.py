"""Implicit integration of stiff mass-spring systems.

Stiff springs force explicit methods to tiny steps (``h < 2 / omega_max``).
Two implicit answers, both *solver objects*: built with the
:class:`~particles.massspring.MassSpringSystem` whose springs, masses and
pins they use, they take a step with ``solver.step(X, t, h)`` (no ``f``: they
do not call one) and carry ``.order``; ``system.run(T, h, method=solver)``
runs them in the library's loop (see :mod:`particles.integrators.solvers`):

* :class:`BaraffWitkin`: backward Euler, starting with the step of Baraff
  and Witkin (1998) linearized once. With ``K = dF/dx`` and ``D = dF/dv``
  (sparse) and ``A = M - h D - h^2 K``, it solves

      A dv = h (F + h K v),    v += dv,    x += h v,

  then (by default) one Newton iteration ``A dv = -G`` on the residual
  ``G = M (v' - v) - h F(x', v')`` of the backward-Euler equations, and more
  while the step would gain energy; each solve by block-Jacobi
  preconditioned conjugate gradients or a sparse factorization. Compressed
  springs drop the transverse part of ``K`` so that ``A`` stays positive
  definite; pinned particles are filtered out of the system.

* :class:`Prefactored`: the local/global solver of Liu et al. (2013). Each
  spring's energy ``k (|x_i - x_j| - L0)^2 / 2`` is the smallest value of
  ``k |x_i - x_j - d|^2 / 2`` over vectors ``d`` of length ``L0``. Alternately
  fixing ``d`` (local step: ``d = L0 (x_i - x_j) / |x_i - x_j|``) and ``x``
  (global step: a linear system whose matrix ``M + h^2 L`` never changes)
  minimizes the implicit-Euler objective. The matrix is factorized once;
  each iteration costs a few back-substitutions, and a step iterates (with
  Anderson acceleration, from the last step's answer) until the objective's gradient is small. With
  ``backend="numba"`` (or ``"auto"`` on large systems) the local step, the
  back-substitutions and the residual run compiled
  (:mod:`particles.implicit.compiled_factorization`, over :mod:`particles.implicit.kernels`).

Both are first order and dissipate energy (numerical damping grows with
``h``), and both are stable at time steps far above the explicit limit.

:func:`relax` finds the static equilibrium of a mass-spring system with the same linear algebra.

* :mod:`particles.implicit.baraffwitkin`: :class:`BaraffWitkin`, backward Euler with Newton iterations;
* :mod:`particles.implicit.prefactored`: :class:`Prefactored`, the local/global solver with a matrix
  factorized once;
* :mod:`particles.implicit.acceleration`: the mixing of :class:`Prefactored`'s iterates (Anderson,
  Chebyshev);
* :mod:`particles.implicit.sparse`: their base class and sparse pieces (the free degrees of freedom,
  factorizations);
* :mod:`particles.implicit.statics`: :func:`relax`, the static equilibrium (a hanging cloth at rest);
* :mod:`particles.implicit.compiled_factorization`: :class:`Prefactored`'s iteration compiled, over one
  factorization (imports numba);
* :mod:`particles.implicit.kernels`: its loops: the local step (inlining the springs' formulas), the
  triangular solves over the Cholesky factor, the residual.

Implicit Euler for any ODE, :func:`particles.integrators.implicit_euler`, is a stepper of
:mod:`particles.integrators`.

References
----------
.. [1] D. Baraff and A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998.
.. [2] T. Liu, A. W. Bargteil, J. F. O'Brien and L. Kavan, "Fast simulation of
   mass-spring systems", ACM Transactions on Graphics 32(6), 2013.
.. [3] K.-J. Choi and H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
.. [4] Y. Peng, B. Deng, J. Zhang, F. Geng, W. Qin and L. Liu, "Anderson
   acceleration for geometry optimization and physics simulation", ACM
   Transactions on Graphics 37(4), 2018.
"""

from .baraffwitkin import BaraffWitkin
from .prefactored import Prefactored
from .statics import relax

__all__ = ["BaraffWitkin", "Prefactored", "relax"]
