"""The grader's side of a worker: start it, load a submission, call its functions.

:class:`Submission` is what an exercise test sees (as the ``student`` fixture)::

    X_new = student.call("euler_step", remote("circle"), X, 0.0, 0.1)

Every way a call can go wrong becomes a :class:`GradingFailure` (an
``AssertionError``, so pytest records a failed test) with one line the student
can act on: the function is missing or uses a forbidden library call, it runs
a forbidden library function's code read from the library's source (known by
its compiled code, :mod:`particles.course.worker.codeprints`), it raised, it
ran past its time limit, it ended or crashed the worker, or it returned
something the protocol cannot carry. After a timeout or a crash the
worker is killed and the next call starts a fresh one.
"""

import functools
import os
import secrets
import shutil
import signal
import tempfile
from pathlib import Path

import numpy as np

from ..walls import isolation as walls
from ..reading.submission import SubmissionCode, read_submission
from ..walls.limits import DEFAULTS, GRACE, check_limit, limits as all_limits
from .process import Worker, WorkerDied, WorkerTimeout
from .protocol import ProtocolError, Unsupported
from .codeprints import library_prints
from .registry import RemoteFunction, Token, answer_evaluation

__all__ = ["GradingFailure", "Submission", "DEFAULTS", "describe_value", "check_limit"]

_GRACE = GRACE  # seconds after a soft time limit before the worker is killed


class GradingFailure(AssertionError):
    """A test failed for a reason the student can act on (``str()`` is one line)."""


def _exit_reason(returncode):
    if returncode is None:
        return "stopped answering"
    if returncode >= 0:
        hint = " (a call to os._exit?); a function must return its result" if returncode == 0 else ""
        if returncode == 1:
            hint = (" (it probably replaced a function of Python or NumPy that the grader needs, "
                    "or closed the worker's files)")
        return f"ended the worker process with exit status {returncode}{hint}"
    try:
        name = signal.Signals(-returncode).name
    except ValueError:
        name = f"signal {-returncode}"
    hints = {
        "SIGKILL": " (killed: probably out of memory)",
        "SIGXCPU": " (its CPU time limit was exceeded)",
        "SIGSEGV": " (a crash in compiled code, or recursion far too deep)",
    }
    return f"crashed the worker process with {name}{hints.get(name, '')}"


def _where(error):
    return f" at {error['where']}" if error.get("where") else ""


class Submission:
    """A submission's code, run in a worker on demand; the tests' handle on it.

    Parameters
    ----------
    source : path or SubmissionCode
        A notebook file, or code already analysed.
    forbidden : dict, optional
        Dotted library name -> why it is forbidden, e.g.
        ``{"particles.integrators.euler": "it is the step you are asked to write"}``.
    deny : sequence of path, optional
        Paths the submission may not read (solutions, tests, results).
    time_limit, load_time_limit, memory_mb, cpu_seconds, file_mb : optional
        Limits, see :data:`DEFAULTS` (``None``: the default); each must be a
        finite number > 0.
    scratch : path, optional
        Parent of the workers' scratch folders (default: a new temporary folder).
    isolation : Plan or str, optional
        The operating system's walls (see :mod:`particles.course.walls.isolation`):
        a :class:`~particles.course.walls.isolation.Plan`, ``"auto"`` (default: the
        strongest available), ``"strict"`` or a list of layers such as
        ``"no-namespaces,uid,landlock"``.
    audit_hook : bool
        Install the worker's audit hook (default). Only the tests of the
        operating system's walls switch it off, to show that they hold alone.

    Raises
    ------
    ValueError
        When a limit is not a finite number > 0 (naming it, see :func:`check_limit`).
    TypeError
        On a keyword that is not a limit.

    Attributes
    ----------
    code : SubmissionCode
    restarts : int
        How many workers were started (1 when nothing went wrong).
    layers : dict
        The walls active in the last worker (reported by the worker itself,
        see :func:`particles.course.walls.isolation.describe`).
    last : dict
        Details of the last successful call: ``seconds``, and ``calls``
        (argument position -> how often the student's code evaluated the
        function passed there with ``remote(..., counted=True)``, as the
        grader counted it).
    """

    def __init__(self, source, forbidden=None, deny=(), scratch=None, python=None, isolation=None,
                 audit_hook=True, **limits):
        self.code = source if isinstance(source, SubmissionCode) else read_submission(source)
        self.plan = walls.plan("auto") if isolation is None else (
            isolation if isinstance(isolation, walls.Plan) else walls.Plan.from_option(isolation))
        self.audit_hook = bool(audit_hook)
        self.layers = {}
        self.forbidden = dict(forbidden or {})
        self.deny = [str(p) for p in deny]
        self.limits = all_limits(**limits)
        self._own_scratch = scratch is None
        self.scratch = Path(tempfile.mkdtemp(prefix="particles-grade-") if scratch is None else scratch)
        if self.plan.separate_uid:  # workers of their own uid must pass through (not list) the parent
            os.chmod(self.scratch, 0o711)
        self.python = python
        self.worker = None
        self.restarts = 0
        self.load_errors = []
        self.load_failure = None
        self.last = {}
        self.called = []  # the functions the tests called, in order (the plugin empties it before each test)

    # -- the worker ------------------------------------------------------------------
    def _start(self):
        config = {
            "memory_mb": self.limits["memory_mb"], "cpu_seconds": self.limits["cpu_seconds"],
            "file_mb": self.limits["file_mb"], "deny": self.deny, "forbidden": self.forbidden,
            "audit_hook": self.audit_hook,
        }
        self.restarts += 1
        scratch = self.scratch / f"worker-{self.restarts}"
        if scratch.exists():
            shutil.rmtree(scratch, ignore_errors=True)
        self.worker = Worker(scratch, config, python=self.python, isolation=self.plan)
        self.layers = dict(self.worker.layers)
        chunks = [{"label": c.label, "line": c.line, "source": c.source, "provided": c.provided}
                  for c in self.code.chunks]
        limit = float(self.limits["load_time_limit"])
        try:
            # each statement has its own alarm in the worker; this deadline is the backstop for one that
            # hangs in compiled code, and grows with the number of statements (up to two minutes)
            deadline = min(limit * max(len(chunks), 1), 120.0) + 5.0 + _GRACE
            reply = self.worker.request({"op": "load", "chunks": chunks, "timeout": limit}, deadline)
        except WorkerTimeout:
            self.load_failure = f"loading your notebook did not finish within {limit:g} s per statement"
            raise GradingFailure(self.load_failure) from None
        except WorkerDied as died:
            self.load_failure = f"loading your notebook {_exit_reason(died.returncode)}"
            raise GradingFailure(self.load_failure) from None
        except ProtocolError as error:
            self.load_failure = f"loading your notebook failed: {error}"
            raise GradingFailure(self.load_failure) from None
        self.load_errors = reply.get("errors", [])

    def _ensure_worker(self):
        if self.load_failure:
            raise GradingFailure(self.load_failure)
        if self.worker is None or not self.worker.alive:
            self._start()

    def close(self):
        """Stop the worker and remove the scratch folders this object created."""
        if self.worker is not None:
            self.worker.close()
            self.worker = None
        if self._own_scratch:
            shutil.rmtree(self.scratch, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- messages ---------------------------------------------------------------------
    def _not_defined(self, name):
        why = self.code.explain_missing(name, self.load_errors)  # skipped (and why), or raised while loading
        if why:
            return f"`{name}` is not defined: {why}"
        for error in self.load_errors:
            return (f"`{name}` is not defined; loading your notebook failed at {error['label']}"
                    f"{_where(error) and ' (' + error['where'] + ')'}: {error['type']}: {error['message']}")
        if self.code.syntax_errors:
            label, message = self.code.syntax_errors[0]
            return f"`{name}` is not defined; {label} has a syntax error ({message}) and was not run"
        return f"`{name}` is not defined in your notebook; define a function called `{name}`"

    def _raised(self, name, error, limit):
        kind, message = error.get("type", "Exception"), error.get("message", "")
        where = _where(error)
        if kind == "NotDefined":
            return self._not_defined(name)
        if kind == "NameError" and message.startswith("name '") and message.count("'") >= 2:
            missing = message.split("'")[1]  # a global the function reads: did the grader skip its definition?
            why = self.code.explain_missing(missing, self.load_errors)
            if why:
                return f"`{name}` raised NameError{where}: `{missing}` is not defined: {why}"
        if kind == "Timeout":
            return (f"`{name}` did not finish within {limit:g} s{where} (an endless loop, or far too much work); "
                    "it was stopped")
        if kind == "NotImplementedError":
            helper = self._raising_helper(name, error)
            if helper:
                return f"`{name}` calls {helper}, which is not implemented yet: it raised NotImplementedError{where}"
            return f"`{name}` is not implemented yet: it raised NotImplementedError{where}"
        if kind == "SystemExit":
            return f"`{name}` raised SystemExit{where} (sys.exit() or exit() was called); a function must return its result"
        if kind == "KeyboardInterrupt":
            return f"`{name}` raised KeyboardInterrupt{where}; do not raise or simulate interrupts in your code"
        if kind in ("OutputLimit", "FileTooLarge") or (kind == "OSError" and "File too large" in message):
            size = f"{self.limits['file_mb']:g} MiB"  # the worker's RLIMIT_FSIZE, which holds its prints too
            if kind == "OutputLimit":
                return (f"`{name}`: your code printed more than {size} (the limit){where}; "
                        "remove the prints inside loops")
            if kind == "FileTooLarge":
                return f"`{name}` wrote a file larger than {size} (the limit){where}; write less, or nothing at all"
            return (f"`{name}` printed or wrote more than {size} (the limit){where}; remove the prints inside loops "
                    "and large files")
        if kind == "MemoryError":
            return (f"`{name}` ran out of memory{where} (the limit is {self.limits['memory_mb']} MiB); "
                    "it allocates far more than the problem needs")
        if kind == "ReplacedBuiltins":
            return f"`{name}` changed Python itself: {message}; the grader restored them and does not accept the result"
        if kind == "PermissionError" and "grader does not let" in message:
            return f"`{name}` did something the grader forbids{where}: {message}"
        if kind == "PermissionError" and "not allowed in this exercise" in message:
            return f"`{name}` used a forbidden library function{where}: {message}"
        return f"`{name}` raised {kind}{where}: {message}" if message else f"`{name}` raised {kind}{where}"

    def _raising_helper(self, name, error):
        """"`rk4_step`" (or "`rk4_step` (through `convergence_errors`)") when the error was raised in another
        function of the notebook that `name` uses, else ""."""
        from ..grading.blame import helpers

        where = error.get("where") or ""
        helper = where.rsplit(", in ", 1)[1].strip() if ", in " in where else ""
        if not helper or helper == name:
            return ""
        chain = helpers(self.code, name).get(helper)
        if chain is None:
            return ""
        through = [n for n in chain[1:-1] if n in helpers(self.code, name)]
        return f"`{helper}`" + (f" (through `{'`, `'.join(through)}`)" if through else "")

    # -- calls ------------------------------------------------------------------------
    def call(self, name, *args, timeout=None, check_inputs=False, **kwargs):
        """Call the submission's function `name` in the worker and return its result.

        Parameters
        ----------
        name : str
            The function the exercise asks for.
        *args, **kwargs
            Inputs: numbers, strings, lists, tuples, dicts, NumPy arrays and
            registry functions (:func:`particles.course.worker.registry.remote`).
        timeout : float, optional
            Wall-clock limit of this call, in seconds (default: the
            submission's ``time_limit``).
        check_inputs : bool
            Fail when the function modified an array it was given.

        Returns
        -------
        object
            The decoded return value (arrays come back as ``ndarray``; values
            the protocol cannot carry as :class:`particles.course.worker.protocol.Unsupported`).

        Raises
        ------
        GradingFailure
            With one line saying what went wrong.
        """
        self.called.append(name)
        self.last = {}  # a count is never read from an earlier call
        if self.load_failure:
            raise GradingFailure(self.load_failure)
        uses = self.code.forbidden_uses(name, self.forbidden)
        if uses:
            used, via = uses[0]
            chain = f" (through {' -> '.join(via)})" if len(via) > 1 else ""
            raise GradingFailure(f"`{name}` uses `{used}`{chain}, which this exercise forbids: {self.forbidden[used]}")
        if name not in self.code.defines():
            raise GradingFailure(self._not_defined(name))
        limit = check_limit("timeout" if timeout is not None else "time_limit",
                            self.limits["time_limit"] if timeout is None else timeout)
        self._ensure_worker()
        counted = {}
        args = [self._count(key, value, counted) for key, value in enumerate(args)]
        kwargs = {key: self._count(key, value, counted) for key, value in kwargs.items()}
        self.worker.evaluate = functools.partial(answer_evaluation, counted)
        request = {"op": "call", "name": name, "args": list(args), "kwargs": kwargs, "timeout": limit}
        try:
            reply = self.worker.request(request, limit + _GRACE)
        except WorkerTimeout:
            raise GradingFailure(
                f"`{name}` did not finish within {limit:g} s (an endless loop, or far too much work); it was stopped"
            ) from None
        except WorkerDied as died:
            raise GradingFailure(f"`{name}` {_exit_reason(died.returncode)}") from None
        except ProtocolError as error:
            raise GradingFailure(f"`{name}` returned a value the grader could not read: {error}") from None
        if not reply.get("ok"):
            raise GradingFailure(self._raised(name, reply.get("error", {}), limit))
        self._check_library_code(name, reply.get("code"))
        if check_inputs:
            self._check_inputs(name, args, kwargs, reply)
        # only the grader's own count: the evaluations it answered during this call (the worker sends none)
        calls = {entry[2]: entry[1] for entry in counted.values()}
        self.last = {"seconds": reply.get("seconds"), "calls": calls}
        value = reply.get("value")
        return value

    @staticmethod
    def _count(key, value, counted):
        """A counted registry function as sent for this call (an opaque token of its own), else `value`."""
        if isinstance(value, RemoteFunction) and value.counted:
            token = secrets.token_hex(12)
            counted[token] = [value, 0, str(key)]
            return Token(token)
        return value

    def calls_of(self, position):
        """How often the last call evaluated the counted function passed at `position` (int or keyword).

        The grader's own count: the evaluations it answered during that call
        (:mod:`particles.course.worker.registry`), nothing the worker says.

        Raises
        ------
        ValueError
            When no function made with ``remote(..., counted=True)`` was
            passed at `position` in the last call (or that call failed): a
            count kept in the worker is never used for grading.
        """
        calls = self.last.get("calls", {})
        if str(position) not in calls:
            raise ValueError(f"calls_of({position!r}): the last call got no function counted by the grader at "
                             f"position {position!r}; pass remote(..., counted=True) there")
        return calls[str(position)]

    def _check_library_code(self, name, records):
        """Fail when the call could run a forbidden library function's code, however it was loaded (the worker
        reports fingerprints, the library's are computed here: :mod:`particles.course.worker.codeprints`)."""
        if not self.forbidden or not isinstance(records, list):
            return
        prints = library_prints(tuple(sorted(self.forbidden)))
        for record in records[:5000]:
            hit = prints.match(record)
            if hit:
                label, forbidden = hit
                raise GradingFailure(
                    f"`{name}` runs the library's code, not yours: this is the library's `{label}` (recognised by "
                    f"its compiled code, however it was loaded), which this exercise forbids: "
                    f"{self.forbidden[forbidden]}"
                )

    def _check_inputs(self, name, args, kwargs, reply):
        params = self.code.parameters(name) or []
        after = list(zip(range(len(args)), args, reply.get("args_after", [])))
        after += [(k, v, reply.get("kwargs_after", {}).get(k)) for k, v in kwargs.items()]
        for key, before, now in after:
            if not isinstance(before, np.ndarray) or now is None:
                continue
            same = isinstance(now, np.ndarray) and now.shape == before.shape and np.array_equal(now, before, equal_nan=True)
            if not same:
                label = params[key] if isinstance(key, int) and key < len(params) else (key if isinstance(key, str) else f"number {key + 1}")
                raise GradingFailure(
                    f"`{name}` modified its input `{label}` in place; leave the arrays it is given unchanged "
                    f"and return a new array (e.g. start from `{label}.copy()` or build the result with `+`)"
                )


def describe_value(value):
    """A short description of a returned value, for failure messages."""
    if isinstance(value, Unsupported):
        return f"a {value.type_name}"
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    if value is None:
        return "None (did you forget `return`?)"
    return f"a {type(value).__name__}"

