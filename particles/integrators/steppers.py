"""ODE steppers for dX/dt = f(X, t).

Every stepper has the same signature::

    X_new = step(f, X, t, h)

and never modifies ``X``, which must be finite (inf or NaN raise ValueError;
:func:`integrate` turns a state that blows up into
:class:`~particles.SimulationDiverged`). ``f(X, t)`` returns an array of the
same shape as ``X``. The generic steppers (:func:`euler`, :func:`midpoint`, :func:`trapezoid`,
:func:`rk4`, and :func:`~particles.integrators.implicit_euler.implicit_euler`, in a module of
its own) accept any array shape, so they work on a
scalar ODE, on the circle field ``f = (-y, x)`` and on a particle system alike.
:func:`symplectic_euler` and :func:`verlet` need the second-order layout
``X.shape == (n, 2, d)`` where ``X[:, 0]`` are positions and ``X[:, 1]``
velocities, and ``f`` of the form ``(v, a(x, v, t))``.

Each stepper carries ``.order``, its order of global accuracy: halving ``h``
divides the error at a fixed end time by about ``2**order``, and ``.fsal``
("first same as last"): True when its last evaluation of ``f`` is at the
positions the next step starts from (:func:`verlet`). For forces that depend
on the positions only, that evaluation *is* the next step's first one, and
:meth:`particles.ParticleSystem.run` reuses it (one force evaluation per
step instead of two); the stepper itself keeps the generic signature.

References
----------
.. [1] A. Witkin and D. Baraff, "Physically Based Modeling: Principles and
   Practice", SIGGRAPH 1997 course notes, section "Differential equation basics".
.. [2] E. Hairer, C. Lubich and G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer, 2006, sections I.1 and VI.3 (symplectic Euler, Verlet).
"""

import numpy as np

from .common import check_arguments, evaluate, split_state, stepper
from .implicit_euler import implicit_euler

__all__ = [
    "euler",
    "midpoint",
    "trapezoid",
    "rk4",
    "symplectic_euler",
    "verlet",
    "INTEGRATORS",
]


@stepper(order=1)
def euler(f, X, t, h):
    """Explicit (forward) Euler step: ``X + h f(X, t)``.

    Parameters
    ----------
    f : callable
        Right-hand side ``f(X, t) -> ndarray`` of the same shape as ``X``.
    X : ndarray, any shape
        State at time `t`. Not modified.
    t : float
        Time, in seconds.
    h : float
        Time step, in seconds, > 0.

    Returns
    -------
    ndarray, shape of `X`
        State at ``t + h``.

    Raises
    ------
    ValueError
        When `X` is not an array of finite real numbers, `t` not a finite
        real number, or `h` not a positive finite number. Every stepper makes
        these checks, so that a NaN never passes silently from step to step.

    Notes
    -----
    First order. On the undamped oscillator ``x'' = -w**2 x`` it is unstable for
    every ``h > 0``: each step multiplies the amplitude by ``sqrt(1 + (w h)**2)``.
    Stable for a decaying mode ``x' = -lambda x`` only when ``h < 2 / lambda``.

    Examples
    --------
    >>> import numpy as np
    >>> euler(lambda X, t: -X, np.array([1.0]), 0.0, 0.1)
    array([0.9])
    """
    X, h = check_arguments(X, t, h)
    return X + h * evaluate(f, X, t)


@stepper(order=2)
def midpoint(f, X, t, h):
    """Explicit midpoint step: half an Euler step, evaluate there, full step.

    ``X_m = X + h/2 f(X, t)``, then ``X_new = X + h f(X_m, t + h/2)``.

    Parameters and return value as for :func:`euler`.

    Notes
    -----
    Second order, two evaluations of ``f`` per step. On the undamped oscillator
    the amplitude grows by ``sqrt(1 + (w h)**4 / 4)`` per step: slowly unstable.
    """
    X, h = check_arguments(X, t, h)
    X_m = X + 0.5 * h * evaluate(f, X, t)
    return X + h * evaluate(f, X_m, t + 0.5 * h)


@stepper(order=2)
def trapezoid(f, X, t, h):
    """Explicit trapezoid (Heun) step: Euler step, evaluate there, average.

    ``f_0 = f(X, t)``, ``f_1 = f(X + h f_0, t + h)``, ``X_new = X + h (f_0 + f_1) / 2``.

    Parameters and return value as for :func:`euler`.

    Notes
    -----
    Second order, two evaluations of ``f`` per step. For linear problems it
    gives the same result as :func:`midpoint`.
    """
    X, h = check_arguments(X, t, h)
    f_0 = evaluate(f, X, t)
    f_1 = evaluate(f, X + h * f_0, t + h)
    return X + 0.5 * h * (f_0 + f_1)


@stepper(order=4)
def rk4(f, X, t, h):
    """Classical fourth-order Runge-Kutta step.

    ``k1 = f(X, t)``, ``k2 = f(X + h/2 k1, t + h/2)``, ``k3 = f(X + h/2 k2, t + h/2)``,
    ``k4 = f(X + h k3, t + h)``, ``X_new = X + h (k1 + 2 k2 + 2 k3 + k4) / 6``.

    Parameters and return value as for :func:`euler`.

    Notes
    -----
    Fourth order, four evaluations of ``f`` per step. On the undamped oscillator
    it is stable for ``w h <= 2 sqrt(2) ~ 2.83`` (with slow amplitude decay below
    that limit).
    """
    X, h = check_arguments(X, t, h)
    k1 = evaluate(f, X, t)
    k2 = evaluate(f, X + 0.5 * h * k1, t + 0.5 * h)
    k3 = evaluate(f, X + 0.5 * h * k2, t + 0.5 * h)
    k4 = evaluate(f, X + h * k3, t + h)
    return X + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


@stepper(order=1, second_order_layout=True)
def symplectic_euler(f, X, t, h):
    """Symplectic (semi-implicit) Euler step: new velocity first, then position.

    ``v_new = v + h a(x, v, t)``, then ``x_new = x + h v_new``.

    Parameters
    ----------
    f : callable
        ``f(X, t)`` of the second-order form ``(v, a)``; only its acceleration
        part ``f(X, t)[:, 1]`` is used.
    X : ndarray, shape (n, 2, d)
        ``X[:, 0]`` positions (m), ``X[:, 1]`` velocities (m/s). Not modified.
    t, h : float
        Time and time step, in seconds.

    Returns
    -------
    ndarray, shape (n, 2, d)

    Notes
    -----
    First order, one evaluation of ``f`` per step, symplectic for forces that
    depend on position only: on the undamped oscillator it is stable for
    ``w h < 2`` and the energy error stays bounded (it oscillates, it does not
    drift) over arbitrarily long runs [2]_. A system may take this step in a
    compiled form of its own, chosen where it runs
    (:meth:`particles.massspring.MassSpringSystem.stepper`): this function
    is the reference, and knows nothing of it.
    """
    X, h = check_arguments(X, t, h)
    x, v = split_state(X)
    a = evaluate(f, X, t)[:, 1]
    X_new = np.empty_like(X)
    X_new[:, 1] = v + h * a
    X_new[:, 0] = x + h * X_new[:, 1]
    return X_new


@stepper(order=2, second_order_layout=True, fsal=True)
def verlet(f, X, t, h):
    """Velocity Verlet step (kick, drift, kick).

    ``v_half = v + h/2 a(x, v, t)``, ``x_new = x + h v_half``,
    ``v_new = v_half + h/2 a(x_new, v*, t + h)``.

    Parameters and return value as for :func:`symplectic_euler`.

    Notes
    -----
    Second order, two evaluations of ``f`` per step, symplectic and
    time-reversible for position-only forces: on the undamped oscillator it is
    stable for ``w h < 2`` with bounded energy error [2]_. The second
    evaluation is at the new positions, where the next step starts
    (``verlet.fsal`` is True): a particle system whose forces depend on the
    positions only reuses it, so that a run costs one force evaluation per
    step (see :meth:`particles.ParticleSystem.run`).

    When the force depends on velocity (damping, drag) the final kick needs a
    velocity at ``t + h`` before it is known. We use the Euler predictor
    ``v* = v + h a(x, v, t)``, which keeps the method second order; for
    position-only forces ``v*`` is never used and the method is the classical
    velocity Verlet.
    """
    X, h = check_arguments(X, t, h)
    x, v = split_state(X)
    a = evaluate(f, X, t)[:, 1]
    v_half = v + 0.5 * h * a
    X_pred = np.empty_like(X)
    X_pred[:, 0] = x + h * v_half
    X_pred[:, 1] = v + h * a
    a_new = evaluate(f, X_pred, t + h)[:, 1]
    X_new = np.empty_like(X)
    X_new[:, 0] = X_pred[:, 0]
    X_new[:, 1] = v_half + 0.5 * h * a_new
    return X_new


INTEGRATORS = {
    "euler": euler,
    "midpoint": midpoint,
    "trapezoid": trapezoid,
    "rk4": rk4,
    "symplectic_euler": symplectic_euler,
    "verlet": verlet,
    "implicit_euler": implicit_euler,
}
"""Stepper by name, in teaching order."""


