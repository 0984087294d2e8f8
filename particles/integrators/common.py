"""What every stepper shares: the decorator that records its kind, the checks of its arguments, the state's halves.

A stepper ``step(f, X, t, h)`` of :mod:`particles.integrators.steppers` (or of another module, such as the
thermostats of :mod:`particles.md.thermostats`) is marked with :func:`stepper` (its ``.order``, whether it
is explicit, whether it needs the second-order layout, whether its last evaluation is the next step's
first), checks its arguments with :func:`check_arguments`, calls ``f`` through :func:`evaluate` and splits
a second-order state with :func:`split_state`.
"""

import math

import numpy as np

from .._checks import as_float_array, finite_real, positive_number

__all__ = ["stepper", "check_arguments", "evaluate", "split_state"]


def stepper(order, explicit=True, second_order_layout=False, fsal=False):
    """Decorator recording a stepper's order and kind as attributes."""

    def mark(step):
        step.order = order
        step.explicit = explicit
        step.second_order_layout = second_order_layout
        step.fsal = fsal
        return step

    return mark


def check_arguments(X, t, h):
    """Check a stepper's arguments: `X` finite reals, `t` a finite real, `h` > 0.

    Returns ``X`` as a float array (no copy for a float array) and ``h`` as a
    float; `t` is only checked, and reaches ``f`` as the caller gave it.
    One pass of ``np.isfinite`` over ``X``: cheap next to evaluating ``f``.
    """
    X = as_float_array(X, "X", finite=False)
    if not np.isfinite(X).all():
        raise ValueError("X must be finite, but it contains inf or NaN")
    if not (type(t) is int or isinstance(t, float) and math.isfinite(t)):  # fast path first
        finite_real(t, "t", "seconds")
    return X, positive_number(h, "h", "seconds")


def evaluate(f, X, t):
    """Call f(X, t) and check that it returns an array shaped like X."""
    dX = np.asarray(f(X, t), dtype=float)
    if dX.shape != X.shape:
        raise ValueError(
            f"f(X, t) must return an array of the same shape as X {X.shape}, "
            f"got shape {dX.shape}"
        )
    return dX


def split_state(X):
    """Positions and velocities of a second-order state of shape (n, 2, ...)."""
    if X.ndim < 2 or X.shape[1] != 2:
        raise ValueError(
            "X must have the second-order layout (n, 2, d) with X[:, 0] positions "
            f"and X[:, 1] velocities, got shape {X.shape}"
        )
    return X[:, 0], X[:, 1]
