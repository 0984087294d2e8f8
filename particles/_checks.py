"""Argument checks shared by the library: clear errors that name the argument."""

import numbers

import numpy as np

__all__ = ["as_float_array", "positive_number", "nonnegative_number", "method_name"]


def as_float_array(value, name, shape=None, ndim=None, finite=True):
    """Return `value` as a float array (a copy only when conversion needs one).

    Parameters
    ----------
    value : array_like
        What the user passed.
    name : str
        The argument's name, used in error messages.
    shape : tuple, optional
        Expected shape; ``None`` entries match any length.
    ndim : int or tuple of int, optional
        Accepted numbers of dimensions.
    finite : bool
        Reject inf and NaN.
    """
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be an array of real numbers, got {type(value).__name__}"
        ) from None
    if ndim is not None:
        allowed = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if a.ndim not in allowed:
            want = " or ".join(str(k) for k in allowed)
            raise ValueError(f"{name} must have {want} dimensions, got shape {a.shape}")
    if shape is not None:
        ok = a.ndim == len(shape) and all(
            s is None or s == k for s, k in zip(shape, a.shape)
        )
        if not ok:
            want = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
            raise ValueError(f"{name} must have shape {want}, got shape {a.shape}")
    if finite and not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, but it contains inf or NaN")
    return a


def _real(value, name, what):
    if isinstance(value, bool) or not isinstance(value, (numbers.Real, np.floating, np.integer)):
        raise ValueError(f"{name} must be {what}, got {value!r}")
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"{name} must be {what}, got {value!r}")
    return value


def positive_number(value, name, unit=""):
    """Return `value` as a float after checking it is finite and > 0."""
    what = "a positive finite number" + (f" (in {unit})" if unit else "")
    value = _real(value, name, what)
    if value <= 0:
        raise ValueError(f"{name} must be {what}, got {value!r}")
    return value


def nonnegative_number(value, name, unit=""):
    """Return `value` as a float after checking it is finite and >= 0."""
    what = "a finite number >= 0" + (f" (in {unit})" if unit else "")
    value = _real(value, name, what)
    if value < 0:
        raise ValueError(f"{name} must be {what}, got {value!r}")
    return value


def method_name(method, table, name="method"):
    """Look a name up in `table`, with an error listing the valid names."""
    if callable(method):
        return method
    if not isinstance(method, str) or method not in table:
        valid = ", ".join(repr(k) for k in table)
        raise ValueError(f"unknown {name} {method!r}; expected one of {valid}")
    return table[method]


def count(value, name, least=0):
    """An integer >= `least` (a count of iterations, steps, particles); floats and bools are refused."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < least:
        raise ValueError(f"{name} must be an integer >= {least}, got {value!r}")
    return int(value)


def finite_real(value, name, unit=""):
    """Return `value` as a float after checking it is a finite real number (a time, a coordinate)."""
    what = "a finite real number" + (f" (in {unit})" if unit else "")
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        value = value[()]
    return _real(value, name, what)


def end_time(t_end, t, owner="system"):
    """`t_end` of a ``run`` from the current time `t`: a finite real number, not before `t`."""
    t_end = finite_real(t_end, "t_end", "seconds")
    if t_end < t:
        raise ValueError(f"t_end must be >= the current time t = {t!r} s of the {owner}, got {t_end!r}")
    return t_end
