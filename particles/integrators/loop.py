"""The time loop: the steps of a run, the divergence guard, the recorded states.

:func:`integrate` is the one loop over time steps of the library (:meth:`particles.ParticleSystem.run`
calls it): it takes the steps of :func:`step_times` with a stepper ``step(f, X, t, h)``, checks once per
step that the state did not blow up (inf, NaN, or a growth by :data:`BLOWUP_FACTOR`; then
:class:`~particles.SimulationDiverged`), runs the fixes of ``after_step`` and records every ``every``-th
state.
"""

import math

import numpy as np

from .._checks import as_float_array, finite_real, method_name, positive_number
from ..errors import SimulationDiverged
from .common import split_state
from .steppers import INTEGRATORS

__all__ = ["integrate", "step_times", "BLOWUP_FACTOR"]


def _name_of(step):
    return next((k for k, s in INTEGRATORS.items() if s is step), getattr(step, "__name__", "?"))


def step_times(t0, t1, h):
    """Times ``t0, t0 + h, ...`` ending exactly at ``t1`` (last step shortened).

    A last step shorter than ``1e-9 h`` is merged into the one before, so that
    ``(t1 - t0) / h`` equal to an integer up to round-off gives equal steps.

    Parameters
    ----------
    t0, t1 : float
        Start and end times, in seconds, finite, ``t1 >= t0``.
    h : float
        Time step, in seconds, > 0.

    Returns
    -------
    ndarray, shape (K,)
        The times, in seconds: ``K - 1`` steps, ``K = 1`` (only `t0`) when
        ``t1 == t0``. All steps but the last are exactly `h`.

    Raises
    ------
    ValueError
        When a time is not a finite real number, ``t1 < t0`` or ``h <= 0``.

    Examples
    --------
    >>> step_times(0.0, 0.25, 0.1).tolist()
    [0.0, 0.1, 0.2, 0.25]
    """
    t0 = finite_real(t0, "t0", "seconds")
    t1 = finite_real(t1, "t1", "seconds")
    if t1 < t0:
        raise ValueError(f"t1 must be >= t0, got t0={t0!r}, t1={t1!r}")
    h = positive_number(h, "h", "seconds")
    if t1 == t0:
        return np.array([t0])
    n_steps = max(1, math.ceil((t1 - t0) / h - 1e-9))
    inner = t0 + h * np.arange(1, n_steps)
    # far from 0, t0 + k h rounds: an inner time can land on (or within 1e-9 h of) t1 and leave a step of
    # length zero; such a time is merged into the last step
    inner = inner[inner < t1 - 1e-9 * h]
    return np.concatenate([[t0], inner, [t1]])


BLOWUP_FACTOR = 1e12
"""Default growth rule of integrate(): stop when max|X| exceeds this factor times (1 + max|X0|)."""


def _blowup_factor(blowup):
    """The `blowup` option of integrate(): None, or a factor > 1."""
    if blowup is None:
        return None
    blowup = positive_number(blowup, "blowup")
    if blowup <= 1.0:
        raise ValueError(f"blowup must be None or a growth factor > 1, got {blowup!r}")
    return blowup


def _diverged(k, times, h, step, X_start, size, factor):
    """SimulationDiverged for step k, saying whether the state overflowed or grew too much."""
    method = _name_of(step)
    err = SimulationDiverged(k, times[k - 1], float(h), method)
    if not np.isfinite(size):
        err.args = (str(err) + " (The state became inf or NaN.)",)
        return err
    start = float(np.max(np.abs(X_start), initial=0.0))
    grown = size / (1.0 + start)
    err.args = (
        f"the simulation diverged at step {k} (t = {times[k - 1]:.6g} s): the state is still "
        f"finite but grew too much: its largest entry went from {start:.3g} to {size:.3g} "
        f"({grown:.3g} times 1 + max|X0|), past the growth limit blowup = {factor:.3g}. Either "
        f"h = {float(h):.6g} s is above the stability limit of {method!r} for this system "
        "(reduce h, add damping, or use an implicit method), or the true solution grows this "
        "much (e.g. exponential growth): then pass blowup=None (stop only on inf or NaN) or a "
        "larger factor.",
    )
    return err


def _empty_frames(K, X):
    """An empty array of K states, each stored in the memory order of X.

    A Fortran-ordered state (see :class:`particles.ParticleSystem`) gets
    frames that are Fortran-ordered too, so recording a frame is a plain copy.
    """
    if X.flags.f_contiguous and not X.flags.c_contiguous:
        return np.empty((K,) + X.shape[::-1]).transpose(0, *range(X.ndim, 0, -1))
    return np.empty((K,) + X.shape)


def integrate(f, X0, t0, t1, h, method="rk4", every=1, blowup=BLOWUP_FACTOR, after_step=None, record=None,
              **options):
    """Integrate dX/dt = f(X, t) from `t0` to `t1` with fixed steps of size `h`.

    Parameters
    ----------
    f : callable
        ``f(X, t) -> ndarray`` of the shape of ``X0``.
    X0 : array_like, any shape
        Initial state. Not modified.
    t0, t1 : float
        Start and end times, in seconds, ``t1 >= t0``.
    h : float
        Time step, in seconds. The last step is shortened to land on `t1`.
    method : str or callable
        A key of :data:`INTEGRATORS` or a stepper ``step(f, X, t, h)``.
    every : int
        Record every `every`-th state (the first and last are always recorded).
    blowup : float or None
        Growth rule of the divergence guard: stop when ``max|X|`` exceeds
        ``blowup * (1 + max|X0|)``, which catches an instability before it
        overflows. Default :data:`BLOWUP_FACTOR` (``1e12``). A solution that
        truly grows that much (``x' = x`` over 30 s grows ``e^30 ~ 1e13``-fold)
        needs a larger factor, or ``None``: stop only on inf or NaN.
    after_step : callable, optional
        ``after_step(X, t0, t1) -> X``, called after every step that passed
        the divergence guard, with the state at the step's end ``t1`` (``t0``:
        its start). It returns the state the next step starts from: `X`
        itself, a corrected copy, or a state with another number of rows
        (particles born or removed). :meth:`particles.ParticleSystem.run`
        calls its ``between_steps`` hooks from here.
    record : callable, optional
        ``record(X, t) -> frame``, called at every recorded time; the frames
        are then returned in a list instead of the stacked states.
    **options
        Passed to the stepper (e.g. ``jac=`` for ``"implicit_euler"``).

    Returns
    -------
    t : ndarray, shape (K,)
        Recorded times, ``t[0] == t0`` and ``t[-1] == t1``.
    X : ndarray, shape (K,) + X0.shape, or list
        ``X[k]`` is the state at ``t[k]`` (with `record`, its frame).

    Raises
    ------
    SimulationDiverged
        When the state becomes inf or NaN, or (unless ``blowup=None``) grows
        beyond ``blowup`` times ``1 + max|X0|``, naming the step, the time and
        which of the two happened (with the growth factor reached).

    Notes
    -----
    A stepper may take several steps in one call: one with a method
    ``steps(f, X, times, limit)`` is given the steps up to the next recorded
    state at once, with the divergence guard (``max|X| <= limit``, finite)
    inside the call, and returns ``(X, steps that passed, size of the last
    state)``, or None where it does not apply (the steps are then taken one
    at a time). A mass-spring system's compiled symplectic Euler step
    (:mod:`particles.massspring.compiled_step`) is one; nothing runs between
    its steps, so a run with `after_step` or stepper `options` takes one step
    per call.

    Examples
    --------
    >>> import numpy as np
    >>> t, X = integrate(lambda X, t: -X, [1.0], 0.0, 1.0, 0.01)
    >>> bool(abs(X[-1, 0] - np.exp(-1.0)) < 1e-9)
    True

    Exponential growth is not an instability; the growth rule must be lifted:

    >>> t, X = integrate(lambda X, t: X, [1.0], 0.0, 30.0, 0.01, blowup=None)
    >>> bool(abs(X[-1, 0] / np.exp(30.0) - 1) < 1e-8)
    True
    """
    step = method_name(method, INTEGRATORS)
    X = as_float_array(X0, "X0")
    times = step_times(t0, t1, h)
    factor = _blowup_factor(blowup)
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
        raise ValueError(f"every must be a positive integer, got {every!r}")
    if getattr(step, "second_order_layout", False):
        split_state(X)
    keep = list(range(0, len(times), every))
    if keep[-1] != len(times) - 1:
        keep.append(len(times) - 1)
    if record is None:
        out = _empty_frames(len(keep), X)
        out[0] = X
    else:
        out = [record(X, times[0])]
    slot = 1
    X_start = X
    # a state that grows (by default) a trillion-fold has blown up, even before it overflows
    limit = np.inf if factor is None else factor * (1.0 + np.max(np.abs(X), initial=0.0))
    # a stepper that takes several steps in one call takes those up to the next recorded state, with the guard
    # inside, when nothing runs between the steps (see the Notes)
    many = getattr(step, "steps", None) if after_step is None and not options else None
    k = 1
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        while k < len(times):
            taken = None if many is None else many(f, X, times[k - 1:keep[slot] + 1], limit)
            if taken is not None:
                X, passed, size = taken
                if k + passed <= keep[slot]:
                    raise _diverged(k + passed, times, h, step, X_start, size, factor)
                k = keep[slot]
            else:
                many = None  # it does not apply: every later step is taken by itself
                X = step(f, X, times[k - 1], times[k] - times[k - 1], **options)
                size = max(X.max(initial=0.0), -X.min(initial=0.0))  # max|X| without a temporary (NaN stays NaN)
                if not size <= limit or size == np.inf:  # "not <=" is also true for NaN
                    raise _diverged(k, times, h, step, X_start, size, factor)
                if after_step is not None:
                    X = after_step(X, times[k - 1], times[k])
            if slot < len(keep) and keep[slot] == k:
                if record is not None:
                    out.append(record(X, times[k]))
                elif X.shape != out.shape[1:]:
                    raise ValueError(f"the state's shape changed between two steps, from {out.shape[1:]} to "
                                     f"{X.shape} (particles born or removed): pass record= to record it")
                else:
                    out[slot] = X
                slot += 1
            k += 1
    return times[keep], out
