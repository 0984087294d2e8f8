"""The two forms of a time-stepping method, and how fixes compose with them.

:meth:`particles.ParticleSystem.run` is the slide's loop; at each step it
calls one method, which comes in one of two forms, each with a signature that
says what it uses:

* a **stepper** ``step(f, X, t, h) -> X_new`` (:mod:`particles.integrators`)
  knows nothing of the system: it only evaluates ``f(X, t)``, the right-hand
  side ``(v, F / m)``;
* a **solver** object with ``solver.step(X, t, h) -> X_new`` and ``.order``
  (:class:`particles.implicit.BaraffWitkin`, :class:`particles.implicit.Prefactored`)
  is built with the system whose model it uses (springs, their Jacobians,
  masses, pins); it takes no ``f`` because it does not call one.

:func:`as_stepper` turns a name, a stepper or a solver into the stepper form
the loop calls. :func:`after` wraps a method so that every step ends with a
fix ``fix(X_old, X_new, t, h) -> X_new``: collisions with bodies
(:meth:`particles.collisions.Collider.stepper`), Provot's constraint
(:meth:`particles.constraints.ProvotConstraint.stepper`), cloth
self-collision (:meth:`particles.collisions.selfcollision.SelfCollision.stepper`). A
wrapped method is a method again, so wrappers nest, and a step that blew up
goes through them untouched, for the loop's divergence guard to report.
:func:`rewrap` puts the same fixes around another innermost step (a system
that runs symplectic Euler as a compiled step of its own, where it is run:
:meth:`particles.massspring.MassSpringSystem.stepper`).
"""

import numpy as np

from .._checks import method_name
from .steppers import INTEGRATORS

__all__ = ["Solver", "as_stepper", "is_solver", "after", "rewrap"]

_ATTRIBUTES = ("order", "explicit", "second_order_layout", "solver")


class Solver:
    """Base class of the solver objects: built with a system, a step is ``solver.step(X, t, h)``.

    A subclass defines :meth:`step` and ``order``. Its signature says what
    it uses: the state, the time and the step, and the model of the system
    it was built with (``self.system``), never an ``f``.

    Parameters
    ----------
    system : ParticleSystem
        The system whose model (forces, masses, pins) the solver uses.

    Attributes
    ----------
    order : int
        Order of global accuracy.
    """

    order = None
    explicit = False
    second_order_layout = True

    def __init__(self, system):
        self.system = system

    def step(self, X, t, h):
        """The state at ``t + h`` from `X` at `t`, shape (n, 2, d); `X` is not modified."""
        raise NotImplementedError

    def __call__(self, f, X, t, h):
        """The stepper form ``solver(f, X, t, h)``, kept for older code: `f` is not used (see :meth:`step`)."""
        return self.step(X, t, h)

    def _state(self, X):
        """`X` as a float array, checked to have the shape of the system's state."""
        X = np.asarray(X, dtype=float)
        if X.shape != self.system.X.shape:
            raise ValueError(f"X must have the shape of the system's state {self.system.X.shape}, got {X.shape}")
        return X


def is_solver(method):
    """Whether `method` is a solver object: a :class:`Solver`, or an object whose class has ``step(X, t, h)``.

    A callable object that is not a :class:`Solver` (a thermostat wrapping a
    stepper) is a stepper, whatever attributes it has.
    """
    return isinstance(method, Solver) or (callable(getattr(type(method), "step", None)) and not callable(method))


def as_stepper(method):
    """The stepper ``step(f, X, t, h)`` that advances by `method`, a name, a stepper or a solver.

    Parameters
    ----------
    method : str, callable or solver
        A key of :data:`particles.integrators.INTEGRATORS`, a stepper
        ``step(f, X, t, h)``, or a solver object with ``step(X, t, h)``
        and ``order``.

    Returns
    -------
    callable
        `method` itself for a stepper; for a solver, a stepper that calls
        ``solver.step(X, t, h)`` (the solver brings its own model, so `f` is
        not passed on), with the solver's ``order`` and ``solver`` set to it
        (:meth:`particles.ParticleSystem.run` checks that the solver was
        built for the system it runs).

    Raises
    ------
    ValueError
        For an unknown name.
    """
    if is_solver(method):
        solver = method

        def solve(f, X, t, h):
            return solver.step(X, t, h)

        solve.order = getattr(solver, "order", None)
        solve.explicit = getattr(solver, "explicit", False)
        solve.second_order_layout = getattr(solver, "second_order_layout", True)
        solve.solver = solver
        solve.__name__ = type(solver).__name__
        return solve
    return method_name(method, INTEGRATORS)


def after(method, fix, name):
    """A stepper that takes a step of `method`, then applies ``fix(X_old, X_new, t, h) -> X_new``.

    Parameters
    ----------
    method : str, callable or solver
        What takes the step (see :func:`as_stepper`).
    fix : callable
        ``fix(X_old, X_new, t, h)`` returns the corrected end state; it may
        change `X_new` in place (a fresh array the inner step returned) but
        never `X_old`.
    name : str
        Name of the fix, for the wrapper's ``__name__`` (``"name(inner)"``),
        which error messages quote.

    Returns
    -------
    callable
        ``step(f, X, t, h, **options)``, with the ``order``,
        ``second_order_layout`` and ``solver`` of the inner method, and
        ``inner``, ``fix`` and ``fix_name`` (for :func:`rewrap`). A step
        whose result is not finite is returned unchanged: the fix is skipped
        and the run's divergence guard reports the blow-up.
    """
    inner = as_stepper(method)

    def fixed(f, X, t, h, **options):
        X_new = inner(f, X, t, h, **options)
        if not np.isfinite(X_new).all():  # a blow-up: left for the run's divergence guard to report
            return X_new
        return fix(X, X_new, t, h)

    for attr in _ATTRIBUTES:
        setattr(fixed, attr, getattr(inner, attr, None))
    fixed.__name__ = f"{name}({getattr(inner, '__name__', type(inner).__name__)})"
    fixed.inner, fixed.fix, fixed.fix_name = inner, fix, name
    return fixed


def rewrap(method, replace):
    """`method` with its innermost step replaced by ``replace(step)``, inside the same fixes of :func:`after`.

    Parameters
    ----------
    method : callable
        A stepper, possibly wrapped by :func:`after` (several times).
    replace : callable
        ``replace(step)`` returns the stepper to take the innermost step instead (`step` itself to keep it).

    Returns
    -------
    callable
        `method` itself when nothing is replaced; else new wrappers with the same fixes, in the same
        order, around the replaced step.
    """
    inner = getattr(method, "inner", None)
    if inner is None:
        return replace(method)
    new = rewrap(inner, replace)
    return method if new is inner else after(new, method.fix, method.fix_name)
