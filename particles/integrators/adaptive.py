"""Adaptive step size by step doubling (Witkin and Baraff's notes, "Adaptive stepsizes").

A fixed step must be small enough for the hardest moment of a run: a comet's
close passage of the sun sets the step for the whole orbit, most of which
is a slow drift far away. Step doubling measures the error as it goes and
adapts the step to it::

    X_big   = step(f, X, t, h)                                   # one step of h
    X_small = step(f, step(f, X, t, h/2), t + h/2, h/2)         # two steps of h/2
    e       = |X_small - X_big| / (2^p - 1)                      # error of X_small (order p)

The local error of a method of order ``p`` is ``C h^(p+1)``; the two half
steps make ``2 C (h/2)^(p+1)``, so their difference from the big step is
``(2^p - 1)`` times the error of the small steps, which is ``e``. The step
is accepted (the state becomes ``X_small``) when ``e <= tol``, and repeated
otherwise; either way the next try is::

    h <- h * min(grow, max(shrink, safety * (tol / e)^(1 / (p + 1))))

the step that would have made ``e`` equal to ``safety * tol``. Each try costs
three steps, so where a fixed step is already right everywhere (a circular
orbit), step doubling is about three times dearer; where the hard part is
short (an eccentric orbit), it spends its evaluations there.

References
----------
.. [1] A. Witkin and D. Baraff, "Differential equation basics", in *Physically
   Based Modeling: Principles and Practice*, SIGGRAPH 1997 course notes,
   section 4 (adaptive stepsizes by comparing one step of h with two of h/2).
.. [2] E. Hairer, S. P. Nørsett and G. Wanner, *Solving Ordinary Differential
   Equations I*, 2nd ed., Springer 1993, section II.4 (step size control,
   Richardson extrapolation).
"""

from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array, finite_real, method_name, positive_number
from ..errors import ConvergenceError, SimulationDiverged
from .steppers import INTEGRATORS

__all__ = ["AdaptiveRun", "step_doubling"]


@dataclass
class AdaptiveRun:
    """What :func:`step_doubling` returns.

    Attributes
    ----------
    t : ndarray, shape (K,)
        Times of the accepted steps, from ``t0`` to ``t1``, in seconds.
    X : ndarray, shape (K, ...)
        The state after each accepted step (``X[0]`` the start).
    evaluations : int
        Evaluations of ``f``, rejected tries included.
    rejected : int
        Tries whose error estimate exceeded ``tol``.
    """

    t: np.ndarray
    X: np.ndarray
    evaluations: int
    rejected: int

    @property
    def h(self):
        """The accepted steps, shape (K - 1,), in seconds."""
        return np.diff(self.t)


def step_doubling(f, X0, t0, t1, tol, h0=None, method="rk4", safety=0.9, shrink=0.2, grow=4.0,
                  h_min=None, max_steps=1_000_000):
    """Integrate ``dX/dt = f(X, t)`` from `t0` to `t1` with a step adapted by step doubling.

    Parameters
    ----------
    f : callable
        ``f(X, t)`` returning an array shaped like ``X``.
    X0 : array_like
        Initial state, any shape.
    t0, t1 : float
        Start and end times, in seconds, ``t1 > t0``.
    tol : float
        Largest accepted error estimate per step, ``max |X_small - X_big| / (2^p - 1)``,
        in the units of the state (> 0).
    h0 : float, optional
        First step to try, in seconds (default ``(t1 - t0) / 100``).
    method : str or callable
        A stepper of :data:`~particles.integrators.INTEGRATORS` (or a stepper
        function with ``.order``).
    safety, shrink, grow : float
        The next step is ``h min(grow, max(shrink, safety (tol / e)^(1/(p+1))))``.
    h_min : float, optional
        Smallest step, in seconds (default ``1e-12 (t1 - t0)``); an error
        still above `tol` at that step raises :class:`~particles.ConvergenceError`.
    max_steps : int
        Largest number of tries.

    Returns
    -------
    AdaptiveRun
        Times, states, evaluations of ``f`` and rejected tries.

    Raises
    ------
    ValueError
        For bad arguments, named.
    particles.ConvergenceError
        When the step falls below `h_min` or the tries exceed `max_steps`.
    particles.SimulationDiverged
        When an accepted state is not finite.

    Notes
    -----
    The error estimate is that of the two half steps, which are kept (no
    Richardson extrapolation, so the accepted solution has the stepper's own
    order and stability). The tolerance bounds the error made per step, not
    the global error: over a run the local errors add up (and, for a
    stepper of order ``p``, the steps shrink where the solution's higher
    derivatives are large).

    Examples
    --------
    One revolution of the circle field ``(x, y)' = (-y, x)`` with RK4, each step's error below 1e-8:

    >>> import numpy as np
    >>> run = step_doubling(lambda X, t: np.array([-X[1], X[0]]), [1.0, 0.0], 0.0, 2 * np.pi, tol=1e-8)
    >>> bool(np.abs(run.X[-1] - [1.0, 0.0]).max() < 1e-6), bool(run.t[-1] == 2 * np.pi)
    (True, True)
    """
    step = method_name(method, INTEGRATORS)
    p = getattr(step, "order", None)
    if not callable(step) or not isinstance(p, int) or p < 1:
        raise ValueError(f"method must be a name of INTEGRATORS or a stepper with an integer .order, got {method!r}")
    X = as_float_array(X0, "X0")
    t0, t1 = finite_real(t0, "t0", "seconds"), finite_real(t1, "t1", "seconds")
    if not t1 > t0:
        raise ValueError(f"t1 must be > t0, got t0={t0!r}, t1={t1!r}")
    tol = positive_number(tol, "tol")
    h = (t1 - t0) / 100 if h0 is None else positive_number(h0, "h0", "seconds")
    h_min = 1e-12 * (t1 - t0) if h_min is None else positive_number(h_min, "h_min", "seconds")
    safety, shrink = positive_number(safety, "safety"), positive_number(shrink, "shrink")
    grow = positive_number(grow, "grow")
    calls = [0]

    def counted(X, t):
        calls[0] += 1
        return f(X, t)

    times, states, rejected, t = [t0], [X], 0, t0
    for _ in range(int(max_steps)):  # a loop over tries
        h = min(h, t1 - t)
        big = step(counted, X, t, h)
        small = step(counted, step(counted, X, t, 0.5 * h), t + 0.5 * h, 0.5 * h)
        with np.errstate(invalid="ignore", over="ignore"):
            e = float(np.max(np.abs(small - big))) / (2.0**p - 1.0)
        if e <= tol:
            if not np.all(np.isfinite(small)):
                raise SimulationDiverged(len(times), t, h, getattr(step, "__name__", str(method)))
            t = t1 if t + h >= t1 - 1e-12 * (t1 - t0) else t + h
            X = small
            times.append(t)
            states.append(X)
            if t == t1:
                return AdaptiveRun(np.array(times), np.array(states), calls[0], rejected)
        else:
            rejected += 1
            if h <= h_min:
                raise ConvergenceError(f"step doubling: the error estimate {e:.3g} stays above tol = {tol:g} "
                                       f"at the smallest step h_min = {h_min:.3g} s (t = {t:.6g} s)")
        factor = grow if e == 0.0 else safety * (tol / e) ** (1.0 / (p + 1)) if np.isfinite(e) else shrink
        h = max(h_min, h * min(grow, max(shrink, factor)))
    raise ConvergenceError(f"step doubling: {max_steps} tries did not reach t1 = {t1:g} s (t = {t:.6g} s)")
