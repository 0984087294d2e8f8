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

from ..problems import PROBLEMS, get_problem

__all__ = ["RemoteFunction", "remote", "build", "CountingFunction"]

_ATTRIBUTES = ("f", "exact")


def _check_spec(spec):
    if not isinstance(spec, dict) or spec.get("kind") != "problem":
        raise ValueError(f"spec must be a dict with kind 'problem', got {spec!r}")
    if spec.get("name") not in PROBLEMS:
        raise ValueError(f"unknown problem {spec.get('name')!r}; expected one of {', '.join(map(repr, PROBLEMS))}")
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


def build(spec):
    """The function described by `spec`, wrapped in a :class:`CountingFunction`.

    Raises
    ------
    ValueError
        When `spec` names no known problem or attribute.
    """
    _check_spec(spec)
    problem = get_problem(spec["name"], **spec.get("params", {}))
    return CountingFunction(getattr(problem, spec.get("attr", "f")), spec)


class RemoteFunction:
    """A registry function: callable here, sent by name to the worker.

    Parameters
    ----------
    name : str
        A key of :data:`particles.problems.PROBLEMS`.
    attr : str
        ``"f"`` (the right-hand side ``f(X, t)``) or ``"exact"``.
    **params
        Parameters of the problem factory (numbers or lists of numbers).
    """

    def __init__(self, name, attr="f", **params):
        params = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in params.items()}
        params = {k: (float(v) if isinstance(v, np.floating) else v) for k, v in params.items()}
        self.__remote_spec__ = {"kind": "problem", "name": name, "params": params, "attr": attr}
        self._local = build(self.__remote_spec__)

    @property
    def problem(self):
        """The :class:`particles.problems.Problem` this function belongs to."""
        spec = self.__remote_spec__
        return get_problem(spec["name"], **spec["params"])

    def __call__(self, *args, **kwargs):
        return self._local(*args, **kwargs)

    def __repr__(self):
        return repr(self._local)


def remote(name, attr="f", **params):
    """Shorthand for :class:`RemoteFunction`: ``remote("harmonic_oscillator", omega=2.0)``."""
    return RemoteFunction(name, attr, **params)
