"""Checks an exercise test uses to judge a student's result against the reference.

Each check raises :class:`particles.course.runner.GradingFailure` with one
line that says what was called, what came back and what was expected, e.g.::

    euler_step(f, X, t=0.0, h=0.1) on the circle field returned an array of
    shape (2, 1), expected shape (2,)

>>> import numpy as np
>>> expect_array(np.array([1.0, 2.0]), np.array([1.0, 2.0]), "f(x)")
>>> expect_array(np.array([1.0, 2.5]), np.array([1.0, 2.0]), "f(x)")
Traceback (most recent call last):
...
particles.course.runner.GradingFailure: f(x) is off by 0.5 at index (1,): got 2.5, expected 2 (tolerance 2e-10)
"""

import numpy as np

from .protocol import Unsupported
from .runner import GradingFailure, describe_value

__all__ = ["expect_array", "expect_float", "expect_order"]


def _tolerance(expected, rtol, atol):
    return atol + rtol * np.abs(expected)


def expect_array(value, expected, call, rtol=1e-10, atol=1e-12, hints=None):
    """Check that `value` is a float array of the shape of `expected` and close to it.

    Parameters
    ----------
    value : object
        What the student's function returned.
    expected : ndarray
        The reference result.
    call : str
        How the call reads in a message, e.g. ``"euler_step(f, X, t=0, h=0.1)"``.
    rtol, atol : float
        Passes when ``|value - expected| <= atol + rtol |expected|`` everywhere.
    hints : dict, optional
        Label -> array of typical wrong answers (``{"a midpoint step": ...}``);
        when the result matches one, the message says so.

    Raises
    ------
    GradingFailure
        On a wrong type, shape or dtype, a NaN or inf, or a value out of tolerance.
    """
    expected = np.asarray(expected, dtype=float)
    if isinstance(value, Unsupported) or not isinstance(value, np.ndarray):
        raise GradingFailure(f"{call} returned {describe_value(value)}, expected a NumPy array of shape {expected.shape}")
    if value.shape != expected.shape:
        raise GradingFailure(f"{call} returned an array of shape {value.shape}, expected shape {expected.shape}")
    if value.dtype.kind != "f":
        raise GradingFailure(
            f"{call} returned an array of dtype {value.dtype}, expected floating-point numbers (float64)"
        )
    bad = ~np.isfinite(value) & np.isfinite(expected)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise GradingFailure(f"{call} returned {value[index]} at index {index}; expected finite numbers")
    error = np.abs(value - expected)
    tol = _tolerance(expected, rtol, atol)
    if np.any(error > tol):
        index = tuple(int(i) for i in np.unravel_index(np.argmax(error - tol), error.shape))
        message = (f"{call} is off by {error[index]:.3g} at index {index}: got {value[index]:.6g}, "
                   f"expected {expected[index]:.6g} (tolerance {tol[index]:.1g})")
        for label, wrong in (hints or {}).items():
            wrong = np.asarray(wrong, dtype=float)
            if wrong.shape == value.shape and np.all(np.abs(value - wrong) <= _tolerance(wrong, rtol, atol)):
                message += f"; your result matches {label}"
                break
        raise GradingFailure(message)


def expect_float(value, expected, call, rtol=1e-10, atol=1e-12):
    """Check that `value` is a real number (Python or NumPy scalar) close to `expected`.

    Parameters
    ----------
    value : object
        What the student's function returned: an int, a float, a NumPy
        scalar or a 0-d array pass the type check (a bool does not).
    expected : float
        The reference number.
    call : str
        How the call reads in a message, e.g. ``"energy(X, k=2.0)"``.
    rtol, atol : float
        Passes when ``|value - expected| <= atol + rtol |expected|``.

    Raises
    ------
    GradingFailure
        When `value` is not a number, is NaN or inf, or is out of tolerance.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        if isinstance(value, np.ndarray) and value.shape == ():
            value = value[()]
        else:
            raise GradingFailure(f"{call} returned {describe_value(value)}, expected a number")
    expect_array(np.array(float(value)), np.array(float(expected)), call, rtol, atol)


def expect_order(observed, expected, call, tolerance=0.2):
    """Check an observed order of convergence, e.g. ``"converges with order 1.02, expected 2"``.

    Parameters
    ----------
    observed : float
        The order measured from the student's results (e.g. the slope of
        log error against log step size).
    expected : float
        The order of the method (1 for Euler, 2 for midpoint, 4 for RK4).
    call : str
        What was measured, for the message, e.g. ``"midpoint_step"``.
    tolerance : float
        Passes when ``|observed - expected| <= tolerance``.

    Raises
    ------
    GradingFailure
        When `observed` is NaN or inf, or further than `tolerance` from
        `expected`.
    """
    if not np.isfinite(observed) or abs(observed - expected) > tolerance:
        raise GradingFailure(f"{call} converges with order {observed:.2f}, expected {expected:g}")
