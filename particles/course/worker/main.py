"""The worker process: runs one submission's code, away from the grader.

Started by :class:`particles.course.worker.process.Worker` as
``python -c BOOTSTRAP CAPTURE_FILE`` (see :data:`BOOTSTRAP`). It talks to the grader over
its original stdin/stdout with the frames of :mod:`particles.course.worker.protocol`;
before any student code runs it moves file descriptors 0, 1 and 2 away (stdin
reads ``/dev/null``, stdout and stderr go to ``CAPTURE_FILE``), so whatever the
student prints never reaches the grader.

Set-up, in this order, from the first frame (the grader's configuration);
the walls themselves live in :mod:`particles.course.walls.audit`:

1. import NumPy and the test-problem registry (the student's code may not
   need more; anything else it imports is read from the Python installation);
2. arrange for the library functions the exercise forbids to be replaced by
   tripwires that raise ``PermissionError`` when used, as soon as their module
   is imported (the grader's syntax-tree check is the first line of defence,
   this one catches dynamic look-ups);
3. resource limits (``resource.setrlimit``): address space (``memory_mb`` on
   top of what the worker uses at start), CPU time, size of written files, no
   core files;
4. change into the scratch directory and install an audit hook
   (:func:`sys.addaudithook`, which cannot be removed) that refuses: reading
   the grader's private paths (the project, tests, solutions, results, and
   ``/proc`` of other processes, e.g. the grader's memory), writing
   outside the scratch directory, starting processes, sockets, signals to other
   processes, ``ctypes``, raising resource limits, the :mod:`gc` and tracing
   look-ups that would reach the hook, and running a module of the library
   past the tripwires (from another finder or a loader of its own).

Then it serves requests: ``load`` (execute the selected statements of the
notebook, each under a time limit) and ``call`` (call a function the
submission defined, on inputs the test chose, under a time limit). A call's
reply carries the fingerprints of the foreign code it could run
(:mod:`particles.course.worker.codewatch`), and no count of ``f``: a counted
``f`` is evaluated by the grader (:mod:`particles.course.worker.registry`).

This is a separate process with limits, not a security sandbox: the grader
never trusts it. It decides pass/fail on the data the worker returns, kills
it on a timeout and starts a new one after a crash.
"""

import os
import signal
import sys
import time
import types

from ..walls import audit as sandbox
from . import codewatch

__all__ = ["main"]

BOOTSTRAP = (
    "import sys, importlib.util as u; spec = u.find_spec('particles'); "
    "sys.modules['particles'] = u.module_from_spec(spec); "
    "from particles.course.worker.main import run; run(sys.argv[1:])"
)
"""The worker's command line (``python -c BOOTSTRAP CAPTURE_FILE``): it imports the
worker without running ``particles/__init__.py``, which would load SciPy and
the whole library before any student code asks for it."""


UID_VARIABLE = "PARTICLES_WORKER_UID"
"""Environment variable naming the uid a worker switches to before anything else (when the grader is root)."""

_LABELS = set()  # file names "<code cell 3>" of the submission's statements


def _where(error):
    """'code cell 3, line 5, in euler_step' for the innermost frame of student code."""
    tb, found = error.__traceback__, None
    while tb is not None:
        filename = tb.tb_frame.f_code.co_filename
        if filename in _LABELS:
            name = tb.tb_frame.f_code.co_name
            found = f"{filename[1:-1]}, line {tb.tb_lineno}" + ("" if name == "<module>" else f", in {name}")
        tb = tb.tb_next
    return found or ""


def _describe(error):
    import errno

    if isinstance(error, sandbox.Timeout):
        kind = "Timeout"
        message = str(error)
    elif isinstance(error, OSError) and error.errno == errno.EFBIG:
        # a write past RLIMIT_FSIZE: the student's prints fill the capture file (fds 1 and 2), or a file of theirs
        import resource

        try:
            limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
            full = limit != resource.RLIM_INFINITY and os.fstat(1).st_size >= limit - 4096
        except (OSError, ValueError):
            limit, full = resource.RLIM_INFINITY, False
        size = f"{limit / 2**20:g} MiB" if limit != resource.RLIM_INFINITY else "the limit"
        if full:
            kind, message = "OutputLimit", (f"your code printed more than {size} (the limit); "
                                            "remove the prints inside loops")
        else:
            kind, message = "FileTooLarge", f"your code wrote a file larger than {size} (the limit)"
    else:
        kind = type(error).__name__
        try:
            message = str(error)
        except BaseException:
            message = ""
    if len(message) > 300:
        message = message[:297] + "..."
    return {"type": kind, "message": message, "where": _where(error)}


def _alarm(seconds):
    def handler(signum, frame):
        raise sandbox.Timeout(f"did not finish within {seconds:g} s")

    signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, float(seconds))


def _cancel_alarm():
    signal.setitimer(signal.ITIMER_REAL, 0.0)


class _Server:
    def __init__(self, proto_in, proto_out):
        self.proto_in, self.proto_out = proto_in, proto_out
        self.namespace = {"__name__": "submission", "__builtins__": __builtins__}
        from ..reading.ipython_shim import get_ipython_for  # a stand-in shell for the magics, as Jupyter reads them

        self.namespace["get_ipython"] = get_ipython_for(self.namespace)
        import builtins

        from . import registry

        import threading

        self.evaluating = threading.Lock()
        registry.EVALUATE = self.evaluate  # functions the grader evaluates (and counts) on its side
        self.builtins = vars(builtins)
        self.pristine = dict(self.builtins)  # student code may replace builtins the worker itself needs

    def restore(self):
        """Put back any built-in the student's code replaced; return their names."""
        changed = [k for k, v in self.pristine.items() if self.builtins.get(k) is not v]
        changed += [k for k in self.builtins if k not in self.pristine]
        self.builtins.clear()
        self.builtins.update(self.pristine)
        return sorted(set(changed))

    def read_exactly(self, n):
        chunks, remaining = [], n
        while remaining:
            chunk = os.read(self.proto_in, min(remaining, 1 << 20))
            if not chunk:
                raise EOFError
            chunks.append(chunk)
            remaining -= len(chunk)
        return b"".join(chunks)

    def evaluate(self, token, args, kwargs):
        """Have the grader evaluate its function `token` on `args` (one round trip); return the value.

        The round trips of several threads are serialised (one lock), so that
        their frames never interleave on the pipe.
        """
        from .protocol import ProtocolError, read_frame, write_frame

        with self.evaluating:
            try:
                write_frame(self.proto_out, {"op": "evaluate", "token": token, "args": list(args),
                                             "kwargs": dict(kwargs)})
            except ProtocolError as error:
                raise TypeError(f"f must be called with numbers and NumPy arrays: {error}") from None
            answer = read_frame(self.read_exactly)
        if not isinstance(answer, dict) or not answer.get("ok"):
            message = answer.get("error") if isinstance(answer, dict) else "no answer"
            raise ValueError(f"f could not be evaluated: {message}")
        return answer.get("value")

    def reply(self, message):
        from .protocol import write_frame

        sys.stdout.flush()
        sys.stderr.flush()
        write_frame(self.proto_out, message, strict=False)

    def load(self, request, watch=None):
        errors, compiled = [], []
        for chunk in request["chunks"]:  # all compiled first: the course's own cells are trusted before any runs
            source = "\n" * (int(chunk["line"]) - 1) + chunk["source"]
            _LABELS.add(f"<{chunk['label']}>")
            try:
                compiled.append((chunk, compile(source, f"<{chunk['label']}>", "exec")))
            except BaseException as error:  # a statement the grader's parser took but this Python does not
                compiled.append((chunk, None))
                errors.append(dict(_describe(error), label=chunk["label"]))
        if watch is not None:  # the notebook's own code: never reported as the library's
            watch.own_code(compiled)
            watch.arm(True)  # and what else starts running while it loads
        if sandbox.WIRES is not None:  # the cells the course provides may use what the exercise forbids
            sandbox.WIRES.trust([code for chunk, code in compiled if code is not None and chunk.get("provided")])
        for chunk, code in compiled:
            if code is None:
                continue
            try:
                _alarm(request.get("timeout", 5.0))
                try:
                    exec(code, self.namespace)
                finally:
                    _cancel_alarm()
                    self.restore()
            except BaseException as error:  # the student's code may raise anything, even SystemExit
                errors.append(dict(_describe(error), label=chunk["label"]))
        if watch is not None:
            watch.loaded()
        defined = sorted(k for k, v in self.namespace.items() if not k.startswith("__") and callable(v))
        return {"ok": True, "defined": defined, "errors": errors}

    def call(self, request, watch=None):
        function = self.namespace.get(request["name"])
        if function is None or not callable(function):
            return {"ok": False, "error": {"type": "NotDefined", "message": request["name"], "where": ""}}
        args, kwargs = list(request.get("args", [])), dict(request.get("kwargs", {}))
        reachable = watch.reachable(function) if watch is not None else []
        start = time.perf_counter()
        try:
            _alarm(request.get("timeout", 5.0))
            try:
                if watch is not None:
                    watch.arm(True)
                value = function(*args, **kwargs)
            finally:
                if watch is not None:
                    watch.arm(False)
                _cancel_alarm()
                changed = self.restore()
        except BaseException as error:
            self.restore()
            return {"ok": False, "error": _describe(error), "seconds": time.perf_counter() - start}
        if changed:
            message = f"it replaced Python's built-in {', '.join(changed)}"
            return {"ok": False, "error": {"type": "ReplacedBuiltins", "message": message, "where": ""}}
        import numpy as np

        def after(v):
            return v if isinstance(v, np.ndarray) else None

        return {
            "ok": True,
            "value": value,
            "seconds": time.perf_counter() - start,
            "args_after": [after(v) for v in args],
            "kwargs_after": {k: after(v) for k, v in kwargs.items()},
            "code": watch.report(reachable) if watch is not None else [],
        }  # no count of f: the grader counts the evaluations it answered (see registry)

    def serve(self, watch=None):
        """Answer requests until the grader closes the pipe; `watch` (a ``CodeWatch``) lives in this frame only,
        not on the server, which the submission can reach (``registry.EVALUATE.__self__``)."""
        from .protocol import read_frame

        while True:
            try:
                request = read_frame(self.read_exactly)
            except EOFError:
                return
            try:
                op = request.get("op")
                if op == "load":
                    answer = self.load(request, watch)
                elif op == "call":
                    answer = self.call(request, watch)
                elif op == "ping":
                    answer = {"ok": True, "pid": os.getpid()}
                elif op == "exit":
                    return
                else:
                    answer = {"ok": False, "error": {"type": "WorkerError", "message": f"unknown op {op!r}", "where": ""}}
            except BaseException as error:  # never let the worker's own loop die on a student's exception
                answer = {"ok": False, "error": _describe(error)}
            try:
                self.reply(answer)
            except BaseException as error:
                self.reply({"ok": False, "error": dict(_describe(error), type="UnsendableResult")})


def _build_walls(config, scratch):
    """The operating system's walls, in order, before any student code; returns the layers now active.

    The uid of its own came first (:func:`main`); then the limits, Landlock
    (it needs no privilege) and ``no_new_privs``. A wall the grader asked for
    that cannot be built ends the worker: it never runs student code with
    less than it was told.
    """
    from ..walls import syscalls as isolation  # the system calls only: the worker needs no more

    sandbox.set_limits(config.get("memory_mb"), config.get("cpu_seconds"), config.get("file_mb"),
                       config.get("nproc"))
    layers = {"namespaces": bool(config.get("namespaces")), "rlimits": True, "landlock": 0, "uid": None}
    if config.get("landlock"):
        # its own /proc entry (Python and NumPy read a few files there); nothing of any other process
        read = list(config.get("read", [])) + [f"/proc/{os.getpid()}"]
        layers["landlock"] = isolation.apply_landlock(read, [scratch, os.devnull])
    layers["no_new_privs"] = isolation.no_new_privs()
    if os.geteuid() == 0:  # no uid of its own could be had: root without capabilities
        layers["capabilities_dropped"] = isolation.drop_capabilities()
        if not layers["capabilities_dropped"]:
            raise PermissionError("could not drop the capabilities of a worker running as root")
    if config.get("uid") is not None:
        if os.getuid() != int(config["uid"]):
            raise PermissionError(f"the worker does not run as uid {config['uid']}")
        layers["uid"] = os.getuid()
    return layers


def main(argv=None):
    """Run the worker: the protocol on stdin/stdout, the student's prints to ``argv[0]``."""
    argv = sys.argv[1:] if argv is None else argv
    parent, uid = os.getppid(), os.environ.pop(UID_VARIABLE, None)
    from ..walls.syscalls import die_with_parent, drop_privileges

    # first of all: the uid of its own (the grader is root; the scratch folder is the uid's)
    if uid is not None and not drop_privileges(int(uid)):
        return 1
    die_with_parent(parent)  # no worker outlives its session; after the uid, which clears it
    proto_in, proto_out = os.dup(0), os.dup(1)
    null = os.open(os.devnull, os.O_RDONLY)
    os.dup2(null, 0)
    capture = os.open(argv[0], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.dup2(capture, 1)
    os.dup2(capture, 2)
    os.close(null)
    os.close(capture)

    import numpy  # noqa: F401  (imported before the limits, as every submission needs it)

    from . import registry  # noqa: F401
    from .protocol import read_frame, write_frame

    server = _Server(proto_in, proto_out)
    try:
        config = read_frame(server.read_exactly)
    except EOFError:
        return 0
    watch = None
    if config.get("forbidden"):  # the foreign code of each call: the grader checks it is not the library's
        library = os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir, os.pardir)) + os.sep
        hook, arm, take = codewatch.recorder(library, exclude=[config["scratch"]])
        sys.addaudithook(hook)
        watch = codewatch.CodeWatch(arm, take)
    wires = sandbox.WIRES = sandbox.Tripwires(config.get("forbidden", {}))
    sys.meta_path.insert(0, wires)
    wires.wire()
    scratch = config["scratch"]
    layers = _build_walls(config, scratch)
    os.chdir(scratch)
    sys.path[:] = [p for p in sys.path if p not in ("", ".")]
    if config.get("audit_hook", True):
        import site

        allow = [os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir, os.pardir))]  # the library itself
        allow += [sys.prefix, sys.base_prefix, sys.exec_prefix] + list(site.getsitepackages())
        allow += [os.path.dirname(os.__file__)]
        # /proc of other processes would show the grader's memory and environment; its own is fine
        allow += [f"/proc/{os.getpid()}", "/proc/meminfo", "/proc/cpuinfo"]
        allow += [scratch]  # its own folder, even when a denied folder holds it
        # the hook is a function built from copies of the rules: replacing Policy or its methods later
        # changes nothing
        sys.addaudithook(sandbox.Policy(scratch, list(config.get("deny", [])) + ["/proc"], allow, finder=wires).hook)
    layers["audit_hook"] = bool(config.get("audit_hook", True))
    del wires
    write_frame(proto_out, {"ok": True, "pid": os.getpid(), "layers": layers})
    server.serve(watch)
    del watch
    return 0


def run(argv):
    """Run :func:`main` and end the process without running the submission's exit handlers."""
    package = sys.modules.get("particles")
    if package is not None and type(package) is types.ModuleType and not hasattr(package, "ParticleSystem"):
        package.__class__ = sandbox.LazyPackage
    try:
        code = main(argv)
    except BaseException:
        import traceback

        traceback.print_exc()  # into the capture file (or /dev/null before it exists): for the instructor's log
        code = 1
    try:
        sys.stdout.flush()
    finally:
        os._exit(code)


if __name__ == "__main__":
    run(sys.argv[1:])
