"""Time integration: ODE steppers ``step(f, X, t, h)``, solver objects, and the one time loop.

As SciPy groups ``integrate/_ivp``: the methods, what they share, and the driver
(``from particles.integrators import rk4, integrate, INTEGRATORS``).

* :mod:`particles.integrators.steppers`: the explicit steppers :func:`euler`, :func:`midpoint`,
  :func:`trapezoid`, :func:`rk4`, :func:`symplectic_euler`, :func:`verlet`, and :data:`INTEGRATORS`;
* :mod:`particles.integrators.implicit_euler`: :func:`implicit_euler`, Newton's method on the backward-Euler
  equation (a dense or a matrix-free Jacobian);
* :mod:`particles.integrators.common`: what steppers share: the decorator that records ``.order``, argument
  checks, the state's halves;
* :mod:`particles.integrators.loop`: :func:`integrate` (the library's one time loop), :func:`step_times`, the
  divergence guard;
* :mod:`particles.integrators.solvers`: the stepper and solver forms of a method (:class:`Solver`,
  :func:`as_stepper`), :func:`after`, which wraps a method with a fix, and :func:`rewrap`, the same fixes
  around another innermost step;
* :mod:`particles.integrators.adaptive`: :func:`step_doubling`, a run whose step adapts to an error estimate
  (one step of ``h`` against two of ``h/2``).
"""

from .adaptive import AdaptiveRun, step_doubling
from .loop import BLOWUP_FACTOR, integrate, step_times
from .implicit_euler import implicit_euler
from .solvers import Solver, after, as_stepper, is_solver, rewrap
from .steppers import INTEGRATORS, euler, midpoint, rk4, symplectic_euler, trapezoid, verlet

__all__ = ["euler", "midpoint", "trapezoid", "rk4", "symplectic_euler", "verlet", "implicit_euler", "INTEGRATORS",
           "integrate", "step_times", "BLOWUP_FACTOR", "Solver", "as_stepper", "is_solver", "after", "rewrap",
           "step_doubling", "AdaptiveRun"]
