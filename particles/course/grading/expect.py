"""Checks an exercise test uses to judge a student's result against the reference.

Each check raises :class:`particles.course.worker.runner.GradingFailure` with one
line that says what was called, what came back and what was expected, e.g.::

    euler_step(f, X, t=0.0, h=0.1) on the circle field returned an array of
    shape (2, 1), expected shape (2,)

>>> import numpy as np
>>> expect_array(np.array([1.0, 2.0]), np.array([1.0, 2.0]), "f(x)")
>>> expect_array(np.array([1.0, 2.5]), np.array([1.0, 2.0]), "f(x)")
Traceback (most recent call last):
...
particles.course.worker.runner.GradingFailure: f(x) is off by 0.5 at index (1,): got 2.5, expected 2 (tolerance 2e-10)
"""

import numpy as np

from ..worker.protocol import Unsupported
from ..worker.runner import GradingFailure, describe_value

__all__ = ["expect_array", "expect_float", "expect_order", "diagnose", "LN10"]


LN10 = float(np.log(10.0))

_FACTORS = (  # factor -> what a result that far off (everywhere) most likely is
    (LN10, "your result is the expected one times ln(10) = 2.303 everywhere: log10 and ln mixed "
           "(use the same logarithm for every quantity)"),
    (1 / LN10, "your result is the expected one divided by ln(10) = 2.303 everywhere: log10 and ln mixed "
               "(use the same logarithm for every quantity)"),
    (-1.0, "your result has the wrong sign everywhere"),
    (2.0, "your result is twice the expected one everywhere: a factor 2 too many (a missing 1/2?)"),
    (0.5, "your result is half the expected one everywhere: a factor 1/2 too many"),
)


def _tolerance(expected, rtol, atol):
    return atol + rtol * np.abs(expected)


def _matches(value, wrong, rtol, atol):
    """Whether `value` equals the wrong answer `wrong`: an array, or a predicate (its str result is a label)."""
    if callable(wrong):
        try:
            with np.errstate(all="ignore"):
                verdict = wrong(value)
        except Exception:  # noqa: BLE001 - a predicate that cannot judge this value does not match
            return False
        return verdict if isinstance(verdict, str) else bool(verdict)
    with np.errstate(all="ignore"):
        try:
            wrong = np.asarray(wrong, dtype=float)
        except (TypeError, ValueError):
            return False
        return bool(wrong.shape == value.shape and np.all(np.abs(value - wrong) <= _tolerance(wrong, rtol, atol)))


def _hint(value, hints, rtol, atol):
    """The clause of the first hint `value` matches (``"your result matches <label>"``), else None.

    `hints` is a dict, None, or a function of no arguments returning one: computed here, only for a
    value that failed.
    """
    if callable(hints):
        hints = hints()
    for label, wrong in (hints or {}).items():
        verdict = _matches(value, wrong, rtol, atol)
        if verdict:
            label = verdict if isinstance(verdict, str) else label
            return label if label.startswith("your ") else f"your result matches {label}"
    return None


def diagnose(value, expected, rtol=1e-10, atol=1e-12):
    """One clause saying what a wrong numeric `value` most likely is, or ``""`` (also when it is not wrong).

    Recognises single precision (a float32 array, or float64 numbers that were
    rounded to float32 on the way: every wrong value is exactly a float32 and
    within 1e-4 of the reference) and a constant factor between `value` and
    `expected` (ln(10), 1/ln(10), -1, 2, 1/2; any other factor for arrays of
    two or more numbers).

    >>> diagnose(np.array([2.0, 4.0]) * np.log(10), np.array([2.0, 4.0]))
    'your result is the expected one times ln(10) = 2.303 everywhere: log10 and ln mixed (use the same logarithm for every quantity)'
    >>> diagnose(np.float32([1 / 3]), np.array([1 / 3]))[:42]
    'your result is float32 (single precision, '
    """
    value = np.asarray(value)
    expected = np.asarray(expected, dtype=float)
    if value.shape != expected.shape or value.dtype.kind != "f" or value.size == 0:
        return ""
    with np.errstate(all="ignore"):
        wrong = np.abs(value - expected) > _tolerance(expected, rtol, atol)
        if not wrong.any():
            return ""
        close = np.all(np.abs(value - expected) <= 1e-4 * np.abs(expected) + 1e-12)
        if value.dtype.itemsize < 8:
            return (f"your result is {value.dtype} (single precision, about 7 significant digits): compute in "
                    "float64, NumPy's default (look for dtype=np.float32 or .astype(np.float32))")
        as_single = value.astype(np.float32).astype(float)
        if wrong.any() and close and np.all(as_single[wrong] == value[wrong]):
            return ("your numbers were rounded to single precision (float32) on the way: every wrong value is "
                    "exactly a float32 number; keep float64 throughout (look for np.float32)")
        ratio = value / expected
        usable = np.isfinite(ratio) & (np.abs(expected) > 10 * _tolerance(expected, rtol, atol))
        if not usable.any():
            return ""
        r = ratio[usable]
        if not np.all(np.abs(r - r[0]) <= 1e-6 * abs(r[0])) or abs(r[0] - 1) < 1e-6:
            return ""
        for factor, text in _FACTORS:
            if abs(r[0] / factor - 1) <= 1e-6:
                return text if value.size > 1 else text.replace(" everywhere", "")
        if r.size >= 2:
            return (f"your result is {r[0]:.4g} times the expected one everywhere: a constant factor is "
                    "wrong or missing")
    return ""


def expect_array(value, expected, call, rtol=1e-10, atol=1e-12, hints=None, show_values=True):
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
    hints : dict or callable, optional
        Label -> a typical wrong answer: an array (``{"a midpoint step": ...}``,
        matched to the same tolerance, also when its shape is not the
        expected one) or a predicate ``wrong(value)`` (a pattern, e.g. a
        first record that is not X0) returning a bool, or a str: the label
        itself, when it depends on the value. The first hint the result
        matches ends the message: ``"; your result matches a midpoint
        step"``, or the label alone when it starts with ``"your "``
        (``"; your first record is not X0: ..."``). When it matches none,
        :func:`diagnose` may still name a pattern (float32, a factor ln(10)).
        A function of no arguments returning such a dict
        (``hints=lambda: {"a midpoint step": midpoint(f, X, t, h)}``) is
        called only when the value is wrong: typical wrong answers that take
        time to compute cost nothing for a right one.
    show_values : bool
        Print the error, the value got and the value expected at the worst
        index (default). Hidden tests pass False: the message then gives the
        relative error (two digits) and the index only, so that no random
        input shows through (a result of zeros is off by the expected value,
        which may be an input).

    Raises
    ------
    GradingFailure
        On a wrong type, shape or dtype, a NaN or inf, or a value out of tolerance.
    """
    expected = np.asarray(expected, dtype=float)
    if isinstance(value, Unsupported) or not isinstance(value, np.ndarray):
        raise GradingFailure(f"{call} returned {describe_value(value)}, expected a NumPy array of shape {expected.shape}")
    if value.shape != expected.shape:
        label = _hint(value, hints, rtol, atol) if value.dtype.kind in "fiu" else None
        raise GradingFailure(f"{call} returned an array of shape {value.shape}, expected shape {expected.shape}"
                             + (f"; {label}" if label else ""))
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
        if show_values:
            message = (f"{call} is off by {error[index]:.3g} at index {index}: got {value[index]:.6g}, "
                       f"expected {expected[index]:.6g} (tolerance {tol[index]:.1g})")
        elif expected[index] != 0:  # two digits at most: no input of a hidden test can show through
            message = (f"{call} is off by a relative error of {error[index] / abs(expected[index]):.2g} at index "
                       f"{index} (tolerance {tol[index]:.1g})")
        else:
            message = (f"{call} is off by {error[index]:.2g} at index {index}, where 0 is expected "
                       f"(tolerance {tol[index]:.1g})")
        label = _hint(value, hints, rtol, atol)
        if label:
            message += f"; {label}"
        else:
            clause = diagnose(value, expected, rtol, atol)
            if clause:
                message += f"; {clause}"
        raise GradingFailure(message)


def expect_float(value, expected, call, rtol=1e-10, atol=1e-12, hints=None, show_values=True):
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
    hints, show_values
        As for :func:`expect_array` (a hint is a number, or a predicate of the value as a 0-d array).

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
    kind = np.asarray(value).dtype
    number = np.asarray(value, dtype=kind if kind.kind == "f" else float)
    expect_array(number, np.array(float(expected)), call, rtol, atol, hints=hints, show_values=show_values)


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
