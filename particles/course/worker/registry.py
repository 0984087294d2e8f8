"""Functions a test can hand to a student's code across the process boundary.

A test cannot send a Python function to the worker (that would need pickle).
It sends a *name* instead: ``remote("harmonic_oscillator", omega=3.0)`` is a
:class:`RemoteFunction` that the grader can call locally (to compute the
reference answer) and that the protocol encodes as the spec
``{"kind": "problem", "name": "harmonic_oscillator", "params": {"omega": 3.0},
"attr": "f"}``. The worker rebuilds the same function on its side with
:func:`build`, from :data:`particles.problems.PROBLEMS` only.

Counting evaluations (``remote(..., counted=True)``)
----------------------------------------------------
A test that grades how often the student's code evaluates ``f`` (one
evaluation per Euler step, four per RK4 step) must read a number the
student's code cannot change. Anything kept in the worker can be changed by
the code running there (``f.calls -= 1``, ``setattr``, ``f.__dict__``, a
wrapper, a replaced ``__call__``, another thread), so the count is never
kept there:

* the grader sends a counted function as an *opaque token*
  (``{"kind": "grader", "token": "<random hex>"}``, a new token per call): the
  worker learns neither the problem nor its parameters, so its code cannot
  rebuild ``f`` and evaluate it locally;
* in the worker the token becomes a :class:`GraderFunction`, whose every
  call is one round trip to the grader (an ``{"op": "evaluate"}`` frame,
  answered by :class:`particles.course.worker.process.Worker`): the grader
  computes ``f(X, t)`` and counts the evaluation on its side
  (:meth:`particles.course.worker.runner.Submission.calls_of`);
* the worker's own ``f.calls`` still exists (and may be changed at will) but
  is never sent back: the worker's reply carries no count, and ``calls_of``
  refuses a function that was not counted by the grader.

So the count is the number of values of ``f`` the student's code obtained
during the call, whatever it did to the object ``f``: replacing it, wrapping
it, calling it from threads (the round trips are serialised), or forging its
attributes. What a submission could still do is compute ``f`` itself without
asking (guess the problem from the values it got, and evaluate it locally):
that takes knowing the course's problems and the test's hidden parameters.

>>> f = remote("circle")
>>> f(np.array([1.0, 0.0]), 0.0).tolist()
[-0.0, 1.0]
>>> f.__remote_spec__["name"]
'circle'
"""

import numpy as np

from ...problems import PROBLEMS, get_problem

__all__ = ["RemoteFunction", "remote", "build", "CountingFunction", "GraderFunction", "Token", "answer_evaluation"]

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
    """A function built from a spec that counts its calls (``.calls``).

    In a worker this count is the student's to read and to change; the grader
    never uses it (see the module docstring).
    """

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

    Built in a worker from an opaque token (see the module docstring). Every
    call is a round trip to the grader's process, which computes the value
    and counts the call on its side; about a tenth of a millisecond per call,
    so tests use it for the few calls whose number is the point (evaluations
    per step). ``calls`` counts the calls in the worker, for the student's
    own curiosity: changing it changes nothing the grader sees.
    """

    def __init__(self, token):
        self.token, self.calls = str(token), 0

    def __call__(self, *args, **kwargs):
        if EVALUATE is None:
            raise RuntimeError("this function is evaluated by the grader, which is not connected")
        self.calls += 1
        return EVALUATE(self.token, args, kwargs)

    def __repr__(self):
        return "<f(X, t), evaluated by the grader>"


def build(spec):
    """The function described by `spec`: a :class:`CountingFunction`, or a :class:`GraderFunction`.

    An opaque spec ``{"kind": "grader", "token": ...}`` (what the grader sends
    for a :class:`RemoteFunction` made with ``counted=True``) becomes a
    :class:`GraderFunction`; it exists only in a worker connected to a grader.

    Raises
    ------
    ValueError
        When `spec` names no known problem or attribute, or is a grader's
        token outside a worker.
    """
    if isinstance(spec, dict) and spec.get("kind") == "grader":
        if EVALUATE is None or not isinstance(spec.get("token"), str):
            raise ValueError("a function evaluated by the grader exists only in a worker, built from its token")
        return GraderFunction(spec["token"])
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
    counted : bool
        Evaluate it in the grader, which counts the calls (see the module
        docstring); the worker sees an opaque token and cannot change that
        count. Only such a function has a count
        (:meth:`particles.course.worker.runner.Submission.calls_of`).
    **params
        Parameters of the problem factory (numbers or lists of numbers).
    """

    def __init__(self, name, attr="f", counted=False, **params):
        params = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in params.items()}
        params = {k: (float(v) if isinstance(v, np.floating) else v) for k, v in params.items()}
        self.__remote_spec__ = {"kind": "problem", "name": name, "params": params, "attr": attr}
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


class Token:
    """What the worker receives for a counted function: an opaque token (encoded as a callable spec)."""

    def __init__(self, token):
        self.__remote_spec__ = {"kind": "grader", "token": token}

    def __call__(self, *args, **kwargs):  # never called: only sent
        raise RuntimeError("a token stands for a function the grader evaluates")


def answer_evaluation(counted, frame):
    """The grader's answer to a worker's ``{"op": "evaluate"}`` frame: the value, and one more call counted.

    `counted` maps the tokens of this call to ``[RemoteFunction, count, position]``.
    """
    entry = counted.get(frame.get("token")) if isinstance(frame.get("token"), str) else None
    if entry is None:
        return {"ok": False, "error": "not a function of this call"}
    entry[1] += 1
    args = frame.get("args") if isinstance(frame.get("args"), list) else []
    kwargs = frame.get("kwargs") if isinstance(frame.get("kwargs"), dict) else {}
    try:
        return {"ok": True, "value": entry[0](*args, **kwargs)}
    except Exception as error:  # bad arguments from the student's code: their error, raised in their code
        return {"ok": False, "error": f"{type(error).__name__}: {error}"}
