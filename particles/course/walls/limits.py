"""The limits of a worker: what a submission may use, with their defaults and units, checked in one place.

Every limit is settable for a whole grading run (``particles grade
--time-limit``, ``--memory-mb``), and the time limit also per test
(``@pytest.mark.time_limit(seconds)``). The worker applies them with the
operating system's resource limits (:func:`particles.course.walls.audit.apply_limits`,
``RLIMIT_AS``, ``RLIMIT_CPU``, ``RLIMIT_FSIZE``); the grader enforces the
wall-clock limits (:class:`particles.course.worker.runner.Submission`).
"""

import math
import numbers

__all__ = ["DEFAULTS", "UNITS", "GRACE", "check_limit", "limits"]

DEFAULTS = {
    "time_limit": 5.0,        # seconds of wall-clock time per call
    "load_time_limit": 10.0,  # seconds per kept statement when loading the notebook
    "memory_mb": 1024,        # address space the submission may add to the worker's, MiB
    "cpu_seconds": 600,       # CPU time of one worker, a backstop if the grader died
    "file_mb": 16,            # largest file the submission may write in its scratch folder, MiB
}
"""Default limits of a worker (all settable per grading run; time limits per test too)."""

UNITS = {"time_limit": "seconds", "load_time_limit": "seconds", "memory_mb": "MiB", "cpu_seconds": "seconds",
         "file_mb": "MiB"}
"""The unit of each limit, for messages."""

GRACE = 2.0
"""Seconds after a soft time limit before the worker is killed."""


def check_limit(name, value):
    """`value` as a float, after checking that it is a finite number > 0.

    Parameters
    ----------
    name : str
        The limit's name, for the message (``"time_limit"``, ``"memory_mb"``, ...).
    value : int or float
        The limit.

    Raises
    ------
    ValueError
        Naming the limit, when `value` is not a real number (a bool is not),
        is infinite or NaN, or is not > 0: a limit of 0 would switch the
        limit off, a negative one breaks the timer.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value) or value <= 0:
        unit = UNITS.get(name)
        raise ValueError(f"{name} must be a finite number > 0{f' ({unit})' if unit else ''}, got {value!r}")
    return float(value)


def limits(**given):
    """The full set of limits: :data:`DEFAULTS`, overridden by the `given` ones that are not None.

    Raises
    ------
    TypeError
        For a limit that does not exist (naming it and the known ones).
    ValueError
        For a value that :func:`check_limit` refuses.
    """
    unknown = sorted(set(given) - set(DEFAULTS))
    if unknown:
        raise TypeError(f"unknown limit {unknown[0]!r}; expected one of {', '.join(DEFAULTS)}")
    chosen = {k: v for k, v in given.items() if v is not None}
    for key, value in chosen.items():
        check_limit(key, value)
    return dict(DEFAULTS, **chosen)
