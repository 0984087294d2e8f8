"""The worker's walls: what submitted code may not do, and the limits it runs under.

Used by :mod:`particles.course.worker.main` before it runs any student code:

* :class:`Policy`, whose :attr:`Policy.hook` is an audit hook
  (:func:`sys.addaudithook`, which cannot be removed) that refuses reading the
  grader's private paths, writing outside the scratch folder, starting
  processes, sockets, signals to other processes, ``ctypes``, raising resource
  limits, and the look-ups (:mod:`gc`, tracing) that would reach the hook;
* :class:`Tripwires`, which replace the library functions an exercise forbids
  by objects that raise ``PermissionError`` when used, as soon as their module
  is imported (and load the plotting modules lazily);
* :func:`set_limits`: address space, CPU time, file size, no core files.

Python offers no real sandbox inside one process: these walls stop honest
mistakes and the usual tricks, and they give a clear reason when they do.
They are a wall against accidents and casual cheating, not a security
boundary against a determined attacker (code running in the worker can reach
the worker's own objects by enough introspection). The audit hook and the
tripwires keep their state in closures and read-only copies, so the one-line
tricks (``Policy.__call__ = ...``, ``WIRES.targets``) no longer switch them
off. The grader's verdict never depends on them: it is computed in another
process from the data the worker returns, and the records of a pytest session
count only when they carry that session's signature (see
:mod:`particles.course.grading.session`).
"""

import math
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


_INTROSPECTION_EVENTS = {  # events that would reach the worker's own objects (the audit hook, the tripwires)
    "gc.get_objects": "inspect the grader's objects",
    "gc.get_referrers": "inspect the grader's objects",
    "gc.get_referents": "inspect the grader's objects",
    "sys.settrace": "trace the grader's code",
    "sys.setprofile": "trace the grader's code",
}


def _under(path, root):
    return path == root or path.startswith(root.rstrip(os.sep) + os.sep)


def _make_hook(scratch, rules, finder=None):
    """The audit hook: a function that looks nothing up when it is called.

    Every object it uses is bound as a default argument when it is made
    (immutable tuples and read-only mappings, the functions of :mod:`os.path`
    and the built-ins it calls), so that replacing :class:`Policy`, its
    methods, this module's globals or a built-in later does not change what it
    allows. Changing the hook's own attributes (``__defaults__``, ``__code__``)
    is refused, and so are the :mod:`gc` look-ups that would find it.
    """
    sep = os.sep
    rules = tuple((root, root.rstrip(sep) + sep, allowed) for root, allowed in rules)
    scratch_prefix = scratch.rstrip(sep) + sep
    denied = types.MappingProxyType(dict(_DENIED_EVENTS, **_INTROSPECTION_EVENTS))
    path_events = types.MappingProxyType(dict(_PATH_EVENTS))

    trusted = () if finder is None else (_WiringLoader.exec_module.__code__, LazyPackage.__getattr__.__code__)
    library = os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir, os.pardir)) + sep  # the particles package

    def hook(event, args, scratch=scratch, scratch_prefix=scratch_prefix, rules=rules, denied=denied,
             path_events=path_events, trusted=trusted, library=library, getframe=sys._getframe,
             CodeType=types.CodeType, write_flags=_WRITE_FLAGS, devnull=os.devnull,
             realpath=os.path.realpath, abspath=os.path.abspath, fsdecode=os.fsdecode, isinstance=isinstance,
             len=len, any=any, str=str, bytes=bytes, int=int, tuple=tuple, list=list, type=type,
             PathLike=os.PathLike, FunctionType=types.FunctionType, PermissionError=PermissionError):
        def real(path):
            if isinstance(path, bytes):
                path = fsdecode(path)
            return realpath(abspath(path))

        def may_read(path):
            for root, prefix, allowed in rules:
                if path == root or path.startswith(prefix):
                    return allowed
            return True

        def may_write(path):
            return path == scratch or path.startswith(scratch_prefix) or path == devnull

        if event == "open":
            path, mode, flags = (tuple(args) + (None, None, None))[:3]
            if path is None or isinstance(path, int):
                return
            path_real = real(path)
            writing = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
                mode is None and isinstance(flags, int) and flags & write_flags
            )
            if writing and not may_write(path_real):
                raise PermissionError(f"the grader does not let submissions write outside their working directory ({path})")
            if not writing and not may_read(path_real):
                raise PermissionError(f"the grader does not let submissions read its private files ({path})")
        elif event in ("os.listdir", "os.scandir"):
            if args and args[0] is not None and not isinstance(args[0], int) and not may_read(real(args[0])):
                raise PermissionError(f"the grader does not let submissions list its private folders ({args[0]})")
        elif event in denied or event.startswith("ctypes."):
            what = denied.get(event, "use ctypes")
            raise PermissionError(f"the grader does not let submissions {what} ({event})")
        elif event in path_events:
            for k in path_events[event]:
                if k < len(args) and isinstance(args[k], (str, bytes, PathLike)) and not may_write(real(args[k])):
                    raise PermissionError(f"the grader does not let submissions change files outside their working directory ({args[k]})")
        elif event in ("object.__setattr__", "object.__delattr__"):
            target = args[0] if args else None
            if type(target) is FunctionType and str(target.__module__).startswith("particles.course"):
                raise PermissionError(f"the grader does not let submissions change its own functions ({event})")
        elif event == "exec" and trusted and args and isinstance(args[0], CodeType):
            filename = args[0].co_filename
            if isinstance(filename, str) and filename.startswith(library):
                # a module of the library runs: only its loaders that wire tripwires may run it
                frame, depth = getframe(1), 0
                while frame is not None and depth < 12 and frame.f_code not in trusted:
                    frame, depth = frame.f_back, depth + 1
                if frame is None or depth >= 12:
                    raise PermissionError("the grader does not let submissions load the library past its tripwires "
                                          f"(another finder in sys.meta_path, or a loader of their own): {filename}")

    return hook


class Policy:
    """What the audit hook allows: decided on real paths, longest prefix wins.

    Parameters
    ----------
    scratch : path
        The only folder the submission may write in.
    deny, allow : sequence of path
        Folders (or files) it may not read, and exceptions inside them: of
        the rules that hold a path, the longest decides.
    finder : Tripwires, optional
        The worker's tripwires: when given, a module of the library may run
        only from the loaders that wire them (not after another finder was
        put first in ``sys.meta_path``, not from a loader of the submission).

    Notes
    -----
    :attr:`hook` is the function to give to :func:`sys.addaudithook`; it is
    built once, from copies of the rules, and does not call this object, so
    replacing ``Policy.__call__`` or the rules afterwards changes nothing.

    The audit hook is a wall against accidents and casual cheating (reading
    the solutions or a classmate's notebook, writing fake results, starting
    programs), not a security boundary against a determined attacker: code
    that runs inside a Python process can always reach that process's
    objects by enough introspection. What makes grades trustworthy is that
    the verdict is computed outside the worker (see
    :mod:`particles.course.grading.driver`).
    """

    def __init__(self, scratch, deny, allow, finder=None):
        self.scratch = os.path.realpath(scratch)
        self.rules = sorted(
            [(os.path.realpath(p), False) for p in deny] + [(os.path.realpath(p), True) for p in allow],
            key=lambda rule: len(rule[0]), reverse=True,
        )
        self.hook = _make_hook(self.scratch, self.rules, finder)

    @staticmethod
    def _under(path, root):
        return _under(path, root)

    def may_read(self, path):
        """Whether the submission may read the real path `path` (by the rules given at construction)."""
        for root, allowed in self.rules:
            if _under(path, root):
                return allowed
        return True

    def may_write(self, path):
        """Whether the submission may write the real path `path` (only in its scratch folder)."""
        return _under(path, self.scratch) or path == os.devnull

    def real(self, path):
        """The real, absolute form of `path` (str or bytes)."""
        if isinstance(path, bytes):
            path = os.fsdecode(path)
        return os.path.realpath(os.path.abspath(path))

    def __call__(self, event, args):
        self.hook(event, args)


class _Tripwire:
    """Stands in for a forbidden library object: any use raises PermissionError.

    Each tripwire is an instance of its own subclass, made by :func:`_tripwire`,
    whose methods hold what they need in a closure: the tripwire keeps no
    attribute that leads back to the object it replaces.

    A forbidden *class* may still be a base class or the second argument of
    ``isinstance`` (``__mro_entries__``, ``__instancecheck__``): the library
    subclasses its own classes (``MassSpringSystem(ParticleSystem)``) and must
    keep importing when one of them is forbidden. A submission that subclasses
    a forbidden class names it in its code, which the syntax-tree check of
    :mod:`particles.course.reading.forbidden` reports.
    """

    __slots__ = ()


def _trust_state():
    """``trust(codes)`` and ``allowed()``: the course's own code may use forbidden objects.

    The cells a course provides (no solution markers in the master) may build
    what the student may not (exercise 03's curtain is made with ``Springs``).
    ``trust`` is called once, by the worker, with the compiled code objects of
    those cells, before any submitted code runs; later calls change nothing.
    ``allowed()`` is true when the nearest frame outside the library that leads
    to the use is one of those code objects (or nested in one), known by
    identity: a student's function that calls a provided one is fine, a
    student's code that uses the forbidden object itself, or code compiled at
    run time under a provided cell's name, is not.
    """
    library = os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir, os.pardir)) + os.sep
    trusted, kept, done = set(), [], []
    getframe = sys._getframe

    def trust(codes):
        if done:
            return False
        done.append(True)
        stack = list(codes)
        while stack:
            code = stack.pop()
            if isinstance(code, types.CodeType) and id(code) not in trusted:
                trusted.add(id(code))
                kept.append(code)  # alive, so that its id stays its own
                stack.extend(c for c in code.co_consts if isinstance(c, types.CodeType))
        return True

    def allowed():
        if not trusted:
            return False
        frame = getframe(1)
        while frame is not None and frame.f_code.co_filename.startswith(library):
            frame = frame.f_back
        return frame is not None and id(frame.f_code) in trusted

    return trust, allowed


def _tripwire(name, reason, original=None, allowed=lambda: False):
    """A :class:`_Tripwire` for the library object `name`, forbidden because of `reason`.

    When ``allowed()`` says the course's own code is the user, each use is
    passed on to `original`.
    """
    base = original if isinstance(original, type) else None
    message = f"{name} is not allowed in this exercise: {reason}"

    def fail():
        raise PermissionError(message)

    class Tripwire(_Tripwire):
        __slots__ = ()

        def __mro_entries__(self, bases):
            if base is None:
                fail()
            return (base,)

        def __instancecheck__(self, instance):
            return base is not None and isinstance(instance, base)

        def __subclasscheck__(self, cls):
            return base is not None and issubclass(cls, base)

        def __call__(self, *args, **kwargs):
            if original is not None and allowed():
                return original(*args, **kwargs)
            fail()

        def __getitem__(self, key):
            if original is not None and allowed():
                return original[key]
            fail()

        def __iter__(self):
            if original is not None and allowed():
                return iter(original)
            fail()

        def __len__(self):
            if original is not None and allowed():
                return len(original)
            fail()

        def __contains__(self, item):
            if original is not None and allowed():
                return item in original
            fail()

        def __getattr__(self, attr):
            if attr.startswith("_"):
                raise AttributeError(attr)
            if original is not None and allowed():
                return getattr(original, attr)
            fail()

        def __repr__(self):
            return f"<forbidden {name}>"

    Tripwire.__name__ = Tripwire.__qualname__ = "_Tripwire"
    return Tripwire()


def _wiring(forbidden):
    """The ``wire`` function of a :class:`Tripwires`, and the state it keeps in its closure.

    Replaced objects are known by their ids only; a weak reference to each
    forgets its id when it is freed, so that a new object that happens to get
    the same id is never mistaken for it (objects without weak references are
    kept alive instead).
    """
    import weakref

    forbidden = tuple(dict(forbidden).items())
    trust, allowed = _trust_state()
    wired = {}  # id(original) -> its tripwire
    kept = []   # originals that do not support weak references, kept so that their ids stay unique
    watchers = []

    def forget(key):
        return lambda _ref: wired.pop(key, None)

    def wire():
        library = [m for n, m in list(sys.modules.items()) if n == "particles" or n.startswith("particles.")]
        for name, reason in forbidden:
            module_name, _, attr = name.rpartition(".")
            module = sys.modules.get(module_name)
            value = vars(module).get(attr) if module is not None else None
            if value is None or isinstance(value, _Tripwire) or id(value) in wired:
                continue
            key = id(value)
            wired[key] = _tripwire(name, reason, value, allowed)
            try:
                watchers.append(weakref.ref(value, forget(key)))
            except TypeError:
                kept.append(value)
        if not wired:
            return
        for module in library:  # a loop over modules and their attributes, not over particles
            for key, value in list(vars(module).items()):
                if id(value) in wired:
                    setattr(module, key, wired[id(value)])
                elif type(value) is dict and not key.startswith("__"):
                    for k, v in list(value.items()):
                        if id(v) in wired:
                            value[k] = wired[id(v)]

    return wire, trust


class Tripwires:
    """Replaces forbidden library objects by tripwires as soon as their module is loaded.

    (It also makes the plotting modules of :data:`_LAZY` load lazily.) A
    meta-path finder: every ``particles`` module the submission imports is
    loaded as usual, then the forbidden objects in it, and every alias of them
    in the library's modules and their dicts (``INTEGRATORS``), are swapped for
    tripwires. Modules nobody imports are never loaded, so a worker starts
    with NumPy only.

    Parameters
    ----------
    forbidden : dict
        Dotted library name -> why it is forbidden.

    Notes
    -----
    ``Tripwires(forbidden)`` returns an instance of a subclass made for it,
    without attributes: its ``wire`` and ``find_spec`` keep their state (the
    ids of the replaced objects, whether a look-up is under way) in closures,
    out of easy reach of the submission. Like the audit hook, this stops
    honest mistakes and casual look-ups, not a determined attacker; the
    syntax-tree check of :mod:`particles.course.reading.forbidden` comes first.
    """

    __slots__ = ()

    def __new__(cls, forbidden):
        wire, trust = _wiring(forbidden)
        busy = []

        def find_spec(fullname, path=None, target=None):
            if busy or not (fullname.startswith("particles.") or fullname in _LAZY):
                return None
            busy.append(True)
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
                busy.clear()
            if spec.loader is None:
                return spec
            if fullname in _LAZY:
                import importlib.util

                spec.loader = importlib.util.LazyLoader(spec.loader)
            else:
                spec.loader = _WiringLoader(spec.loader, wire)
            return spec

        made = type(cls.__name__, (cls,), {"__slots__": (), "__module__": cls.__module__,
                                           "wire": staticmethod(wire), "find_spec": staticmethod(find_spec),
                                           "trust": staticmethod(trust)})
        self = object.__new__(made)
        return self

    def wire(self):
        """Swap the forbidden objects of the modules loaded so far for tripwires."""
        raise NotImplementedError  # replaced per instance (see __new__)

    def trust(self, codes):
        """Let the code objects `codes` (the course's provided cells, compiled) use forbidden objects.

        Works once (the worker calls it before any submitted code runs); returns whether it did.
        """
        raise NotImplementedError  # replaced per instance (see __new__)

    def find_spec(self, fullname, path=None, target=None):
        """The meta-path finder's look-up: the usual spec, with a loader that wires after loading."""
        raise NotImplementedError  # replaced per instance (see __new__)


class _WiringLoader:
    """A module loader that wires tripwires after the module ran."""

    def __init__(self, loader, wire):
        self._loader, self._wire = loader, wire

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module):
        self._loader.exec_module(module)
        self._wire()

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


def set_limits(memory_mb, cpu_seconds, file_mb, nproc=None):
    """Lower this process's resource limits (the worker calls it before any student code runs).

    Parameters
    ----------
    memory_mb : float or None
        Address space the process may add to what it uses now, MiB
        (``RLIMIT_AS``); a failed allocation then raises ``MemoryError``.
    cpu_seconds : float or None
        CPU time of the whole process, s (``RLIMIT_CPU``): a backstop that
        ends the process with ``SIGXCPU`` if the grader's own timeouts failed.
    file_mb : float or None
        Largest file the process may write, MiB (``RLIMIT_FSIZE``); a larger
        write fails with ``OSError`` (``SIGXFSZ`` is ignored).
    nproc : int or None
        Processes and threads the process's uid may have (``RLIMIT_NPROC``):
        with a uid of its own, how many the worker may start; with the
        grader's uid (already running many), none.

    Notes
    -----
    ``None`` (or 0) leaves that limit as it is; core files are always
    disabled. A limit the system refuses is skipped silently: the grader's
    per-call timeouts and the worker being a separate process still hold.
    Raising the limits again later is refused by the audit hook
    (``resource.setrlimit``).
    """
    import resource

    def limit(kind, value):
        try:
            resource.setrlimit(kind, (value, value))
        except (ValueError, OSError):
            pass

    if memory_mb:
        limit(resource.RLIMIT_AS, _memory_in_use() + int(float(memory_mb) * 2**20))
    if cpu_seconds:
        limit(resource.RLIMIT_CPU, max(1, math.ceil(cpu_seconds)))
    if file_mb:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a too-large write fails with OSError instead of killing
        limit(resource.RLIMIT_FSIZE, int(float(file_mb) * 2**20))
    if nproc:
        limit(resource.RLIMIT_NPROC, int(nproc))
    limit(resource.RLIMIT_CORE, 0)
