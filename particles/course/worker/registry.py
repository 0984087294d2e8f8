"""Functions a test can hand to a student's code across the process boundary.

A test cannot send a Python function to the worker (that would need pickle).
It sends a *name* instead: ``remote("harmonic_oscillator", omega=3.0)`` is a
:class:`RemoteFunction` that the grader can call locally (to compute the
reference answer) and that the protocol encodes as the spec
``{"kind": "problem", "name": "harmonic_oscillator", "params": {"omega": 3.0},
"attr": "f"}``. The worker rebuilds the same function on its side with
:func:`build`, from :data:`particles.problems.PROBLEMS` only, and counts how
often the student's code calls it.

>>> f = remote("circle")
>>> f(np.array([1.0, 0.0]), 0.0).tolist()
[-0.0, 1.0]
>>> f.__remote_spec__["name"]
'circle'
"""

import numpy as np

from ...problems import PROBLEMS, get_problem

__all__ = ["RemoteFunction", "remote", "build", "CountingFunction", "GraderFunction"]

_ATTRIBUTES = ("f", "exact")


def _check_spec(spec):
    if not isinstance(spec, dict) or spec.get("kind") != "problem":
        raise ValueError(f"spec must be a dict with kind 'problem', got {spec!r}")
    if spec.get("name") not in PROBLEMS:
        raise ValueError(f"unknown problem {spec.get('name')!r}; expected one of {', '.join(map(repr, PROBLEMS))}")
    if spec.get("evaluate", "worker") not in ("worker", "grader"):
        raise ValueError(f"evaluate must be 'worker' or 'grader', got {spec.get('evaluate')!r}")
    if spec.get("attr", "f") not in _ATTRIBUTES:
        raise ValueError(f"attr must be one of {_ATTRIBUTES}, got {spec.get('attr')!r}")
    if not isinstance(spec.get("params", {}), dict):
        raise ValueError("params must be a dict of keyword arguments")


class CountingFunction:
    """A function built from a spec that counts its calls (``.calls``)."""

    def __init__(self, function, spec):
        self._function, self.spec, self.calls = function, spec, 0

    def __call__(self, *args, **kwargs):
        self.calls += 1
        return self._function(*args, **kwargs)

    def __repr__(self):
        params = ", ".join(f"{k}={v!r}" for k, v in self.spec.get("params", {}).items())
        return f"<{self.spec['name']}({params}).{self.spec.get('attr', 'f')}>"


EVALUATE = None
"""In a worker: the function that sends an evaluation to the grader (set by the worker's server).

Called as ``EVALUATE(spec, args, kwargs)``; returns the value the grader computed."""


class GraderFunction:
    """A registry function evaluated by the grader, not in the worker: the grader counts its calls.

    A submission cannot change that count: every call is a round trip to the
    grader's process (``{"op": "evaluate"}`` frames, see
    :class:`particles.course.worker.process.Worker`), which computes the value and
    counts the call on its side. Slower than a :class:`CountingFunction`
    (about a tenth of a millisecond per call), so tests use it for the few
    calls whose number is the point (evaluations per step).
    """

    __slots__ = ("spec",)

    def __init__(self, spec):
        self.spec = spec

    def __call__(self, *args, **kwargs):
        if EVALUATE is None:
            raise RuntimeError("this function is evaluated by the grader, which is not connected")
        return EVALUATE(self.spec, args, kwargs)

    def __repr__(self):
        params = ", ".join(f"{k}={v!r}" for k, v in self.spec.get("params", {}).items())
        return f"<{self.spec['name']}({params}).{self.spec.get('attr', 'f')}>"


def build(spec):
    """The function described by `spec`: a :class:`CountingFunction`, or a :class:`GraderFunction`.

    A spec with ``"evaluate": "grader"`` (a :class:`RemoteFunction` made with
    ``counted=True``) becomes a :class:`GraderFunction` in a worker.

    Raises
    ------
    ValueError
        When `spec` names no known problem or attribute.
    """
    _check_spec(spec)
    problem = get_problem(spec["name"], **spec.get("params", {}))
    if spec.get("evaluate") == "grader" and EVALUATE is not None:
        return GraderFunction(spec)
    return CountingFunction(getattr(problem, spec.get("attr", "f")), spec)


class RemoteFunction:
    """A registry function: callable here, sent by name to the worker.

    Parameters
    ----------
    name : str
        A key of :data:`particles.problems.PROBLEMS`.
    attr : str
        ``"f"`` (the right-hand side ``f(X, t)``) or ``"exact"``.
    counted : bool
        Evaluate it in the grader, which counts the calls (see
        :class:`GraderFunction`); the worker cannot change that count.
    **params
        Parameters of the problem factory (numbers or lists of numbers).
    """

    def __init__(self, name, attr="f", counted=False, **params):
        params = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in params.items()}
        params = {k: (float(v) if isinstance(v, np.floating) else v) for k, v in params.items()}
        self.__remote_spec__ = {"kind": "problem", "name": name, "params": params, "attr": attr}
        if counted:
            self.__remote_spec__["evaluate"] = "grader"
        self.counted = bool(counted)
        _check_spec(self.__remote_spec__)
        self._local = CountingFunction(getattr(get_problem(name, **params), attr), self.__remote_spec__)

    @property
    def problem(self):
        """The :class:`particles.problems.Problem` this function belongs to."""
        spec = self.__remote_spec__
        return get_problem(spec["name"], **spec["params"])

    def __call__(self, *args, **kwargs):
        return self._local(*args, **kwargs)

    def __repr__(self):
        return repr(self._local)


def remote(name, attr="f", counted=False, **params):
    """Shorthand for :class:`RemoteFunction`: ``remote("harmonic_oscillator", omega=2.0)``."""
    return RemoteFunction(name, attr, counted, **params)
