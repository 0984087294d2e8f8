"""Test problems with exact solutions, for convergence studies and grading.

Each :class:`Problem` bundles a right-hand side ``f(X, t)``, an initial state,
a time interval and the exact solution, so that the error of a stepper can be
measured. :data:`PROBLEMS` maps names to factories; parameters can be changed,
e.g. ``harmonic_oscillator(omega=3.0)``, which is how hidden tests draw random
instances.
"""

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ._checks import as_float_array, nonnegative_number, positive_number

__all__ = [
    "Problem",
    "harmonic_oscillator",
    "forced_oscillator",
    "circle",
    "projectile_drag",
    "PROBLEMS",
    "get_problem",
]


@dataclass(frozen=True)
class Problem:
    """An initial value problem dX/dt = f(X, t), X(t0) = X0, with its exact solution.

    Attributes
    ----------
    name : str
    f : callable
        ``f(X, t)``, same shape as `X0`.
    X0 : ndarray
        Initial state.
    t0, t1 : float
        Time interval, in seconds.
    exact : callable
        ``exact(t)``: the exact state at time ``t`` (a float).
    second_order : bool
        True when ``X0`` has the layout (n, 2, d) so that symplectic steppers apply.
    """

    name: str
    f: Callable
    X0: np.ndarray
    t0: float
    t1: float
    exact: Callable
    second_order: bool

    def error(self, X, t=None):
        """Max-norm error of state `X` at time `t` (default `t1`)."""
        t = self.t1 if t is None else t
        return float(np.max(np.abs(np.asarray(X) - self.exact(t))))


def harmonic_oscillator(omega=1.0, x0=1.0, v0=0.0, t1=5.0):
    """Undamped oscillator ``x'' = -omega^2 x`` in the layout (1, 2, 1).

    Exact solution ``x = x0 cos(w t) + v0/w sin(w t)``. The default end time is
    not a whole number of periods: over exactly one period the errors of
    symplectic Euler cancel to second order, which would hide its true order.
    """
    w = positive_number(omega, "omega", "rad/s")
    x0, v0 = float(x0), float(v0)

    def f(X, t):
        return np.stack([X[:, 1], -(w**2) * X[:, 0]], axis=1)

    def exact(t):
        x = x0 * np.cos(w * t) + v0 / w * np.sin(w * t)
        v = -x0 * w * np.sin(w * t) + v0 * np.cos(w * t)
        return np.array([[[x], [v]]])

    return Problem("harmonic_oscillator", f, exact(0.0), 0.0, float(t1), exact, True)


def forced_oscillator(omega=2.0, amplitude=1.0, frequency=1.0, x0=1.0, v0=0.0, t1=5.0):
    """A driven oscillator ``x'' = -omega^2 x + A cos(Omega t)``, layout (1, 2, 1).

    The right-hand side depends on the time ``t``, so a stepper that evaluates
    ``f`` at the wrong time is caught. It applies to any state of shape
    ``(n, 2, d)``: every coordinate is an independent driven oscillator.

    Parameters
    ----------
    omega : float
        Natural angular frequency ``omega``, in rad/s, > 0.
    amplitude : float
        Driving acceleration ``A``, in m/s^2.
    frequency : float
        Driving angular frequency ``Omega``, in rad/s, > 0, different from `omega`.
    x0, v0 : float
        Initial position (m) and velocity (m/s).
    t1 : float
        End time, in seconds.

    Notes
    -----
    Exact solution, with ``B = A / (omega^2 - Omega^2)``:
    ``x = (x0 - B) cos(omega t) + v0/omega sin(omega t) + B cos(Omega t)``.

    Examples
    --------
    >>> p = forced_oscillator(omega=2.0, amplitude=1.0, frequency=1.0)
    >>> bool(abs(p.f(p.exact(0.3), 0.3)[0, 1, 0] - (-4 * p.exact(0.3)[0, 0, 0] + np.cos(0.3))) < 1e-12)
    True
    """
    w = positive_number(omega, "omega", "rad/s")
    W = positive_number(frequency, "frequency", "rad/s")
    A = float(as_float_array(amplitude, "amplitude", ndim=0))
    if abs(w - W) <= 1e-6 * w:
        raise ValueError(
            f"frequency must differ from omega (resonance has no bounded solution), got {W!r} and {w!r}"
        )
    x0, v0 = float(x0), float(v0)
    B = A / (w**2 - W**2)

    def f(X, t):
        return np.stack([X[:, 1], -(w**2) * X[:, 0] + A * np.cos(W * t)], axis=1)

    def exact(t):
        x = (x0 - B) * np.cos(w * t) + v0 / w * np.sin(w * t) + B * np.cos(W * t)
        v = -(x0 - B) * w * np.sin(w * t) + v0 * np.cos(w * t) - B * W * np.sin(W * t)
        return np.array([[[x], [v]]])

    return Problem("forced_oscillator", f, exact(0.0), 0.0, float(t1), exact, True)


def circle(X0=(1.0, 0.0), t1=5.0):
    """The lecture's circle field ``f(x, y) = (-y, x)``: rotation at unit speed.

    Exact solution: ``X0`` rotated by the angle ``t``.
    """
    X0 = as_float_array(X0, "X0", shape=(2,))

    def f(X, t):
        return np.array([-X[1], X[0]])

    def exact(t):
        c, s = np.cos(t), np.sin(t)
        return np.array([c * X0[0] - s * X0[1], s * X0[0] + c * X0[1]])

    return Problem("circle", f, X0.copy(), 0.0, float(t1), exact, False)


def projectile_drag(g=9.81, c=0.5, v0=(3.0, 8.0), t1=1.5):
    """A projectile with linear drag: ``x'' = (0, -g) - c x'``, layout (1, 2, 2).

    Exact solution ``v = v_inf + (v0 - v_inf) e^(-c t)``, ``v_inf = (0, -g/c)``,
    ``x = v_inf t + (v0 - v_inf)(1 - e^(-c t)) / c``.
    """
    g = nonnegative_number(g, "g", "m/s^2")
    c = positive_number(c, "c", "1/s")
    v0 = as_float_array(v0, "v0", shape=(2,))
    v_inf = np.array([0.0, -g / c])

    def f(X, t):
        a = np.array([0.0, -g]) - c * X[:, 1]
        return np.stack([X[:, 1], a], axis=1)

    def exact(t):
        decay = np.exp(-c * t)
        v = v_inf + (v0 - v_inf) * decay
        x = v_inf * t + (v0 - v_inf) * (1.0 - decay) / c
        return np.array([[x, v]])

    return Problem("projectile_drag", f, exact(0.0), 0.0, float(t1), exact, True)


PROBLEMS = {
    "harmonic_oscillator": harmonic_oscillator,
    "forced_oscillator": forced_oscillator,
    "circle": circle,
    "projectile_drag": projectile_drag,
}
"""Problem factories by name."""


def get_problem(name, **params):
    """Build the problem `name` of :data:`PROBLEMS` with the given parameters."""
    if name not in PROBLEMS:
        raise ValueError(f"unknown problem {name!r}; expected one of {', '.join(map(repr, PROBLEMS))}")
    return PROBLEMS[name](**params)
