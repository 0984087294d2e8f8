"""The worker's walls: what submitted code may not do, and the limits it runs under.

Used by :mod:`particles.course.worker` before it runs any student code:

* :class:`Policy`, an audit hook (:func:`sys.addaudithook`, which cannot be
  removed) that refuses reading the grader's private paths, writing outside
  the scratch folder, starting processes, sockets, signals to other processes,
  ``ctypes`` and raising resource limits;
* :class:`Tripwires`, which replace the library functions an exercise forbids
  by objects that raise ``PermissionError`` when used, as soon as their module
  is imported (and load the plotting modules lazily);
* :func:`set_limits`: address space, CPU time, file size, no core files.

Python offers no real sandbox inside one process: these walls stop honest
mistakes and the usual tricks, and they give a clear reason when they do.
The grader's verdict never depends on them: it is computed in another process
from the data the worker returns.
"""

import os
import signal
import sys
import types

__all__ = ["Policy", "Tripwires", "LazyPackage", "set_limits", "Timeout"]


class Timeout(BaseException):
    """Raised inside student code when its time limit is over."""


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


class Policy:
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
    """Stands in for a forbidden library object: any use raises PermissionError.

    A forbidden *class* may still be a base class or the second argument of
    ``isinstance`` (``__mro_entries__``, ``__instancecheck__``): the library
    subclasses its own classes (``MassSpringSystem(ParticleSystem)``) and must
    keep importing when one of them is forbidden. A submission that subclasses
    a forbidden class names it in its code, which the syntax-tree check of
    :mod:`particles.course.forbidden` reports.
    """

    def __init__(self, name, reason, original=None):
        self._name, self._reason = name, reason
        self._original = original if isinstance(original, type) else None

    def __mro_entries__(self, bases):
        if self._original is None:
            self._fail()
        return (self._original,)

    def __instancecheck__(self, instance):
        return self._original is not None and isinstance(instance, self._original)

    def __subclasscheck__(self, cls):
        return self._original is not None and issubclass(cls, self._original)

    def _fail(self, *args, **kwargs):
        raise PermissionError(f"{self._name} is not allowed in this exercise: {self._reason}")

    __call__ = __getitem__ = __iter__ = __len__ = __contains__ = _fail

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        self._fail()

    def __repr__(self):
        return f"<forbidden {self._name}>"


class Tripwires:
    """Replaces forbidden library objects by tripwires as soon as their module is loaded.

    (It also makes the plotting modules of :data:`_LAZY` load lazily.) A
    meta-path finder: every ``particles`` module the submission imports is
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
                self.targets[id(value)] = (value, _Tripwire(name, reason, value))
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


WIRES = None
"""The worker's :class:`Tripwires`, once installed (the lazy package wires after it runs)."""

_LAZY = {"matplotlib.pyplot", "matplotlib.animation", "IPython.display"}
"""Modules a notebook imports for its plots: loaded only if the graded code uses them.
(``import matplotlib.pyplot as plt`` costs about a second; the grader never draws.)"""


class LazyPackage(types.ModuleType):
    """The ``particles`` package, initialised on first use (the worker itself needs two modules)."""

    def __getattr__(self, name):
        if name.startswith("__") and name.endswith("__"):
            raise AttributeError(name)
        self.__class__ = types.ModuleType
        self.__spec__.loader.exec_module(self)
        if WIRES is not None:
            WIRES.wire()
        return getattr(self, name)


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


def set_limits(memory_mb, cpu_seconds, file_mb):
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
