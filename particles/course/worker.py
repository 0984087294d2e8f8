"""The worker process: runs one submission's code, away from the grader.

Started by :class:`particles.course.runner.Worker` as
``python -c BOOTSTRAP CAPTURE_FILE`` (see :data:`BOOTSTRAP`). It talks to the grader over
its original stdin/stdout with the frames of :mod:`particles.course.protocol`;
before any student code runs it moves file descriptors 0, 1 and 2 away (stdin
reads ``/dev/null``, stdout and stderr go to ``CAPTURE_FILE``), so whatever the
student prints never reaches the grader.

Set-up, in this order, from the first frame (the grader's configuration):

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
   the grader's private paths (the project, tests, solutions, results), writing
   outside the scratch directory, starting processes, sockets, signals to other
   processes, ``ctypes``, and raising resource limits.

Then it serves requests: ``load`` (execute the selected statements of the
notebook, each under a time limit) and ``call`` (call a function the
submission defined, on inputs the test chose, under a time limit).

This is a separate process with limits, not a security sandbox: the grader
never trusts it. It decides pass/fail on the data the worker returns, kills
it on a timeout and starts a new one after a crash.
"""

import os
import signal
import sys
import time
import types

__all__ = ["main"]

_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC
_DENIED_EVENTS = {
    "subprocess.Popen": "start other programs",
    "os.system": "start other programs",
    "os.exec": "start other programs",
    "os.posix_spawn": "start other programs",
    "os.spawn": "start other programs",
    "os.fork": "start other processes",
    "os.forkpty": "start other processes",
    "pty.spawn": "start other programs",
    "socket.__new__": "use the network",
    "socket.connect": "use the network",
    "socket.bind": "use the network",
    "socket.getaddrinfo": "use the network",
    "os.kill": "send signals to processes",
    "os.killpg": "send signals to processes",
    "signal.pthread_kill": "send signals to processes",
    "resource.setrlimit": "change the grader's resource limits",
    "resource.prlimit": "change the grader's resource limits",
    "os.symlink": "create links",
    "os.link": "create links",
    "builtins.input": "read keyboard input",
    "webbrowser.open": "open a browser",
}
_PATH_EVENTS = {  # events whose listed argument positions are paths that must lie in the scratch directory
    "os.remove": (0,), "os.rmdir": (0,), "os.mkdir": (0,), "os.rename": (0, 1), "os.replace": (0, 1),
    "os.truncate": (0,), "os.chmod": (0,), "os.chown": (0,), "os.utime": (0,), "shutil.rmtree": (0,),
    "shutil.copyfile": (1,), "shutil.copytree": (1,), "shutil.move": (1,),
}


class Timeout(BaseException):
    """Raised inside student code when its time limit is over."""


class _Policy:
    """What the audit hook allows: decided on real paths, longest prefix wins."""

    def __init__(self, scratch, deny, allow):
        self.scratch = os.path.realpath(scratch)
        self.rules = sorted(
            [(os.path.realpath(p), False) for p in deny] + [(os.path.realpath(p), True) for p in allow],
            key=lambda rule: len(rule[0]), reverse=True,
        )

    @staticmethod
    def _under(path, root):
        return path == root or path.startswith(root.rstrip(os.sep) + os.sep)

    def may_read(self, path):
        for root, allowed in self.rules:
            if self._under(path, root):
                return allowed
        return True

    def may_write(self, path):
        return self._under(path, self.scratch) or path == os.devnull

    def real(self, path):
        if isinstance(path, bytes):
            path = os.fsdecode(path)
        return os.path.realpath(os.path.abspath(path))

    def __call__(self, event, args):
        if event == "open":
            path, mode, flags = (tuple(args) + (None, None, None))[:3]
            if path is None or isinstance(path, int):
                return
            real = self.real(path)
            writing = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
                mode is None and isinstance(flags, int) and flags & _WRITE_FLAGS
            )
            if writing and not self.may_write(real):
                raise PermissionError(f"the grader does not let submissions write outside their working directory ({path})")
            if not writing and not self.may_read(real):
                raise PermissionError(f"the grader does not let submissions read its private files ({path})")
        elif event in ("os.listdir", "os.scandir"):
            if args and args[0] is not None and not isinstance(args[0], int) and not self.may_read(self.real(args[0])):
                raise PermissionError(f"the grader does not let submissions list its private folders ({args[0]})")
        elif event in _DENIED_EVENTS or event.startswith("ctypes."):
            what = _DENIED_EVENTS.get(event, "use ctypes")
            raise PermissionError(f"the grader does not let submissions {what} ({event})")
        elif event in _PATH_EVENTS:
            for k in _PATH_EVENTS[event]:
                if k < len(args) and isinstance(args[k], (str, bytes, os.PathLike)) and not self.may_write(self.real(args[k])):
                    raise PermissionError(f"the grader does not let submissions change files outside their working directory ({args[k]})")


class _Tripwire:
    """Stands in for a forbidden library object: any use raises PermissionError."""

    def __init__(self, name, reason):
        self._name, self._reason = name, reason

    def _fail(self, *args, **kwargs):
        raise PermissionError(f"{self._name} is not allowed in this exercise: {self._reason}")

    __call__ = __getitem__ = __iter__ = __len__ = __contains__ = _fail

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        self._fail()

    def __repr__(self):
        return f"<forbidden {self._name}>"


class _Tripwires:
    """Replaces forbidden library objects by tripwires as soon as their module is loaded.

    (It also makes the plotting modules of :data:`_LAZY` load lazily.) A meta-path finder: every ``particles`` module the submission imports is
    loaded as usual, then the forbidden objects in it, and every alias of them
    in the library's modules and their dicts (``INTEGRATORS``), are swapped for
    tripwires. Modules nobody imports are never loaded, so a worker starts
    with NumPy only.
    """

    def __init__(self, forbidden):
        self.forbidden = dict(forbidden)
        self.targets = {}  # id(original) -> (original, tripwire); the original is kept so its id stays unique
        self.busy = False

    def wire(self):
        library = [m for n, m in list(sys.modules.items()) if n == "particles" or n.startswith("particles.")]
        for name, reason in self.forbidden.items():
            module_name, _, attr = name.rpartition(".")
            module = sys.modules.get(module_name)
            value = vars(module).get(attr) if module is not None else None
            if value is not None and not isinstance(value, _Tripwire) and id(value) not in self.targets:
                self.targets[id(value)] = (value, _Tripwire(name, reason))
        if not self.targets:
            return
        for module in library:  # a loop over modules and their attributes, not over particles
            for key, value in list(vars(module).items()):
                if id(value) in self.targets:
                    setattr(module, key, self.targets[id(value)][1])
                elif type(value) is dict and not key.startswith("__"):
                    for k, v in list(value.items()):
                        if id(v) in self.targets:
                            value[k] = self.targets[id(v)][1]

    def find_spec(self, fullname, path=None, target=None):
        if self.busy or not (fullname.startswith("particles.") or fullname in _LAZY):
            return None
        self.busy = True
        try:
            for finder in sys.meta_path:
                if finder is self or not hasattr(finder, "find_spec"):
                    continue
                spec = finder.find_spec(fullname, path, target)
                if spec is not None:
                    break
            else:
                return None
        finally:
            self.busy = False
        if spec.loader is None:
            return spec
        if fullname in _LAZY:
            import importlib.util

            spec.loader = importlib.util.LazyLoader(spec.loader)
        else:
            spec.loader = _WiringLoader(spec.loader, self)
        return spec


class _WiringLoader:
    """A module loader that wires tripwires after the module ran."""

    def __init__(self, loader, wires):
        self._loader, self._wires = loader, wires

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module):
        self._loader.exec_module(module)
        self._wires.wire()

    def __getattr__(self, name):  # get_source, get_filename, ... for tracebacks and inspect
        return getattr(self._loader, name)


_WIRES = None

_LAZY = {"matplotlib.pyplot", "matplotlib.animation", "IPython.display"}
"""Modules a notebook imports for its plots: loaded only if the graded code uses them.
(``import matplotlib.pyplot as plt`` costs about a second; the grader never draws.)"""


class _LazyPackage(types.ModuleType):
    """The ``particles`` package, initialised on first use (the worker itself needs two modules)."""

    def __getattr__(self, name):
        if name.startswith("__") and name.endswith("__"):
            raise AttributeError(name)
        self.__class__ = types.ModuleType
        self.__spec__.loader.exec_module(self)
        if _WIRES is not None:
            _WIRES.wire()
        return getattr(self, name)


BOOTSTRAP = (
    "import sys, importlib.util as u; spec = u.find_spec('particles'); "
    "sys.modules['particles'] = u.module_from_spec(spec); "
    "from particles.course.worker import run; run(sys.argv[1:])"
)
"""The worker's command line (``python -c BOOTSTRAP CAPTURE_FILE``): it imports the
worker without running ``particles/__init__.py``, which would load SciPy and
the whole library before any student code asks for it."""


def _memory_in_use():
    """Virtual memory size of this process, in bytes (0 when unknown)."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _set_limits(memory_mb, cpu_seconds, file_mb):
    import resource

    def limit(kind, value):
        try:
            resource.setrlimit(kind, (value, value))
        except (ValueError, OSError):
            pass

    if memory_mb:
        limit(resource.RLIMIT_AS, _memory_in_use() + int(memory_mb) * 2**20)
    if cpu_seconds:
        limit(resource.RLIMIT_CPU, int(cpu_seconds))
    if file_mb:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a too-large write fails with OSError instead of killing
        limit(resource.RLIMIT_FSIZE, int(file_mb) * 2**20)
    limit(resource.RLIMIT_CORE, 0)


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
    if isinstance(error, Timeout):
        kind = "Timeout"
        message = str(error)
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
        raise Timeout(f"did not finish within {seconds:g} s")

    signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, float(seconds))


def _cancel_alarm():
    signal.setitimer(signal.ITIMER_REAL, 0.0)


class _Server:
    def __init__(self, proto_in, proto_out):
        self.proto_in, self.proto_out = proto_in, proto_out
        self.namespace = {"__name__": "submission", "__builtins__": __builtins__}
        import builtins

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

    def reply(self, message):
        from .protocol import write_frame

        sys.stdout.flush()
        sys.stderr.flush()
        write_frame(self.proto_out, message, strict=False)

    def load(self, request):
        errors = []
        for chunk in request["chunks"]:
            code = "\n" * (int(chunk["line"]) - 1) + chunk["source"]
            _LABELS.add(f"<{chunk['label']}>")
            try:
                _alarm(request.get("timeout", 5.0))
                try:
                    exec(compile(code, f"<{chunk['label']}>", "exec"), self.namespace)
                finally:
                    _cancel_alarm()
                    self.restore()
            except BaseException as error:  # the student's code may raise anything, even SystemExit
                errors.append(dict(_describe(error), label=chunk["label"]))
        defined = sorted(k for k, v in self.namespace.items() if not k.startswith("__") and callable(v))
        return {"ok": True, "defined": defined, "errors": errors}

    def call(self, request):
        from .registry import CountingFunction

        function = self.namespace.get(request["name"])
        if function is None or not callable(function):
            return {"ok": False, "error": {"type": "NotDefined", "message": request["name"], "where": ""}}
        args, kwargs = list(request.get("args", [])), dict(request.get("kwargs", {}))
        start = time.perf_counter()
        try:
            _alarm(request.get("timeout", 5.0))
            try:
                value = function(*args, **kwargs)
            finally:
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

        counts = {}
        for key, v in list(enumerate(args)) + list(kwargs.items()):
            if isinstance(v, CountingFunction):
                counts[str(key)] = v.calls
        return {
            "ok": True,
            "value": value,
            "seconds": time.perf_counter() - start,
            "args_after": [after(v) for v in args],
            "kwargs_after": {k: after(v) for k, v in kwargs.items()},
            "calls": counts,
        }

    def serve(self):
        from .protocol import read_frame

        while True:
            try:
                request = read_frame(self.read_exactly)
            except EOFError:
                return
            try:
                op = request.get("op")
                if op == "load":
                    answer = self.load(request)
                elif op == "call":
                    answer = self.call(request)
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


def main(argv=None):
    """Run the worker: the protocol on stdin/stdout, the student's prints to ``argv[0]``."""
    argv = sys.argv[1:] if argv is None else argv
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
    global _WIRES
    _WIRES = _Tripwires(config.get("forbidden", {}))
    sys.meta_path.insert(0, _WIRES)
    _WIRES.wire()
    _set_limits(config.get("memory_mb"), config.get("cpu_seconds"), config.get("file_mb"))
    scratch = config["scratch"]
    os.chdir(scratch)
    sys.path[:] = [p for p in sys.path if p not in ("", ".")]
    import site

    allow = [os.path.dirname(os.path.dirname(os.path.abspath(__file__)))]  # the library itself
    allow += [sys.prefix, sys.base_prefix, sys.exec_prefix] + list(site.getsitepackages())
    allow += [os.path.dirname(os.__file__)]
    policy = _Policy(scratch, config.get("deny", []), allow)
    sys.addaudithook(policy)  # from here on, until the process ends
    write_frame(proto_out, {"ok": True, "pid": os.getpid()})
    server.serve()
    return 0


def run(argv):
    """Run :func:`main` and end the process without running the submission's exit handlers."""
    package = sys.modules.get("particles")
    if package is not None and type(package) is types.ModuleType and not hasattr(package, "ParticleSystem"):
        package.__class__ = _LazyPackage
    try:
        code = main(argv)
    except BaseException:
        code = 1
    try:
        sys.stdout.flush()
    finally:
        os._exit(code)


if __name__ == "__main__":
    run(sys.argv[1:])
