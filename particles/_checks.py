"""Argument checks shared by the library: clear errors that name the argument."""

import numbers

import numpy as np

__all__ = [
    "as_float_array", "positive_number", "nonnegative_number", "method_name", "count", "finite_real", "end_time",
    "pinned_indices", "index_array", "per_item", "mass_array", "restitution_coefficient",
]


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


def pinned_indices(pinned, n):
    """Sorted unique particle indices from indices or a boolean mask of length `n`, checked.

    Parameters
    ----------
    pinned : array_like of int or bool
        Indices (negative ones count from the end) or a mask of shape (n,).
    n : int
        Number of particles.

    Returns
    -------
    ndarray of int, shape (p,)
    """
    p = np.asarray(pinned)
    if p.dtype == bool:
        if p.shape != (n,):
            raise ValueError(f"pinned as a boolean mask must have shape ({n},), got {p.shape}")
        return np.flatnonzero(p)
    if p.size == 0:
        return np.zeros(0, dtype=int)
    if p.ndim != 1 or not np.issubdtype(p.dtype, np.integer):
        raise ValueError(f"pinned must be a list of particle indices or a boolean mask, got {pinned!r}")
    if np.any((p < -n) | (p >= n)):
        raise ValueError(f"pinned indices must lie in [0, {n}), got {p.tolist()}")
    return np.unique(p % n)


def index_array(value, name, width):
    """Particle indices of shape (s, width) (pairs of a spring, triples of a joint), all >= 0, as int64."""
    a = np.asarray(value)
    if a.size == 0:
        return np.zeros((0, width), dtype=np.int64)
    if a.ndim != 2 or a.shape[1] != width or not np.issubdtype(a.dtype, np.integer):
        raise ValueError(f"{name} must be an integer array of shape (s, {width}), got {a.dtype} {a.shape}")
    if np.any(a < 0):
        raise ValueError(f"{name} must hold particle indices >= 0")
    return a.astype(np.int64)


def indices_fit(highest, n, name):
    """Index arrays must point at particles of the system they act on (NumPy would clip or misplace)."""
    if highest >= n:
        raise ValueError(f"{name} refer to particle {highest}, but the system has only {n} particles")


def per_item(value, name, size, positive=False):
    """A number or an array of length `size` (one value per spring, joint, ...), >= 0 (> 0), as a float array."""
    a = as_float_array(value, name, ndim=(0, 1))
    if a.ndim == 1 and a.shape != (size,):
        raise ValueError(f"{name} must be a number or have shape ({size},), got shape {a.shape}")
    if np.any(a < 0) or (positive and np.any(a == 0)):
        raise ValueError(f"{name} must be {'> 0' if positive else '>= 0'}")
    return np.broadcast_to(a, (size,)).copy()


def mass_array(m, n):
    """Masses as a read-only array of shape (n,), from a number or an array of shape (n,), all > 0 kg."""
    m = as_float_array(m, "m")
    if m.shape not in ((), (n,)):
        raise ValueError(f"m must be a number or have shape ({n},), got shape {m.shape}")
    if np.any(m <= 0):
        raise ValueError("m must be positive: every mass must be > 0 kg")
    return np.broadcast_to(m, (n,))


def restitution_coefficient(value):
    """A coefficient of restitution ``eps`` in [0, 1] (1: elastic, 0: no bounce)."""
    eps = nonnegative_number(value, "restitution")
    if eps > 1:
        raise ValueError(f"restitution must lie in [0, 1] (1: elastic, 0: no bounce), got {value!r}")
    return eps
