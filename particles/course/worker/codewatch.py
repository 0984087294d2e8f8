"""The worker's watch on what a call runs: the code it can reach, and the code that starts running in it.

The grader recognises the library's forbidden functions by their compiled
code (:mod:`particles.course.worker.codeprints`); this module, in the worker,
says which code a call of the submission could run besides the notebook's own
statements:

* before the call, :func:`reachable_code` follows the called function's
  references: its code, the globals its code names, closures, defaults,
  ``functools.partial``, methods, classes and their instances, modules the
  submission made (all of them; of an installed module only the attributes
  the code names), dicts, lists, tuples and sets. It reports the code of the
  installed library's and Python's functions it meets but does not descend
  into them;
* during the call, an audit hook (:func:`recorder`) keeps the code that starts
  running: ``exec``/``eval`` of compiled code, ``types.FunctionType(code,
  ...)`` and ``function.__code__ = code`` (the library's own modules run by
  the import system excepted: the worker's audit policy lets no one else run
  them; so are the installed modules, SciPy's or Python's, that the import
  system loads from their own files);
* :class:`CodeWatch` leaves out the code compiled from the notebook's cells
  (known by identity, so a copy compiled under a cell's name is not) and
  sends the fingerprints.

The worker is not trusted, and these are Python-level observations: what a
hostile submission could still do is reach the worker's own objects (the
frames of its serving loop hold the watch) and empty the report, or create
library code while the notebook loads and reach it only through a computed
look-up in an installed module (``getattr(numpy, "x" + "y")``), which the
references do not show. Both take deliberate work against the grader itself,
not a student's shortcut; the grader's verdict, the counts of ``f`` and the
records stay outside the worker whatever it does.
"""

import sys
import types

from .codeprints import FUZZY_MIN, describe, nested

__all__ = ["reachable_code", "recorder", "CodeWatch"]


def _installed_prefixes():
    import os
    import site

    library = os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir, os.pardir)) + os.sep
    prefixes = {sys.prefix, sys.base_prefix, sys.exec_prefix, os.path.dirname(os.__file__)}
    try:
        prefixes.update(site.getsitepackages())
    except AttributeError:
        pass
    return tuple(sorted({os.path.abspath(p) + os.sep for p in prefixes if p} | {library}))


_PREFIXES = None


def _genuine_module(module):
    """True for a module that is the installed one (Python's, NumPy's, the library's) under its own name."""
    global _PREFIXES
    if _PREFIXES is None:
        _PREFIXES = _installed_prefixes()
    name = getattr(module, "__name__", None)
    if not isinstance(name, str) or sys.modules.get(name) is not module:
        return False
    path = getattr(module, "__file__", None)
    return path is None or (isinstance(path, str) and path.startswith(_PREFIXES))


def _genuine_function(function):
    """``"original"`` for a function as its installed module defined it (its globals are that module's own
    dict, its code from that module's file), ``"installed"`` for another function with such globals, else ""."""
    globals_ = function.__globals__
    module = sys.modules.get(globals_.get("__name__")) if isinstance(globals_.get("__name__"), str) else None
    if module is None or getattr(module, "__dict__", None) is not globals_ or not _genuine_module(module):
        return ""
    file = getattr(module, "__file__", None)
    return "original" if file is not None and function.__code__.co_filename == file else "installed"


def reachable_code(root, own=(), trusted=(), created=(), limit=20000):
    """The code objects that `root` (a function or any callable) can run, as far as its references tell.

    Follows functions (code, nested code, the globals their code names,
    closures, defaults, ``__wrapped__``), methods, ``functools.partial``,
    classes and instances (their methods), modules a submission made (all of
    them; of an installed module only the attributes the code names),
    dicts, lists, tuples and sets. It neither reports nor follows the
    functions of installed modules as they defined them (their code is the
    tripwires' and the name check's business), nor the functions whose code
    is in `trusted` (ids of the course's own code); it reports but does not
    follow other functions of an installed module's dict (a library module
    run again into its own dict), and the originals whose code is in
    `created` (ids of code the submission made while the notebook loaded).
    Code whose id is in `own` (the notebook's own statements, compiled by the
    worker) is followed but not reported.

    Returns
    -------
    list of types.CodeType
        Each once, `own` and `trusted` ones left out.
    """
    import builtins
    import functools

    trusted, created = set(trusted), set(created)
    skip = trusted | set(own)
    seen, found, codes = set(), {}, []
    stack = [root]

    def add_code(code):
        for c in nested(code):
            if id(c) not in found and id(c) not in skip:
                found[id(c)] = c
                codes.append(c)

    while stack and len(seen) < limit:
        obj = stack.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        try:
            if isinstance(obj, types.FunctionType):
                code = obj.__code__
                if id(code) in trusted:
                    continue
                kind = _genuine_function(obj)
                if kind == "original" and id(code) not in created:
                    continue
                add_code(code)
                if kind:
                    continue
                names = {n for c in nested(code) for n in c.co_names}
                values = [obj.__globals__[n] for n in names if n in obj.__globals__]
                values += [vars(builtins)[n] for n in names if n not in obj.__globals__ and n in vars(builtins)]
                for module in [v for v in values if isinstance(v, types.ModuleType)]:
                    if _genuine_module(module):  # an installed module: only the attributes the code names
                        values += [vars(module)[n] for n in names if n in vars(module)]
                values += [cell.cell_contents for cell in (obj.__closure__ or ()) if _has_contents(cell)]
                values += list(obj.__defaults__ or ()) + list((obj.__kwdefaults__ or {}).values())
                values += list(vars(obj).values())
                stack.extend(values)
            elif isinstance(obj, types.CodeType):
                add_code(obj)
            elif isinstance(obj, types.MethodType):
                stack.extend([obj.__func__, obj.__self__])
            elif isinstance(obj, functools.partial):
                stack.extend([obj.func, *obj.args, *obj.keywords.values()])
            elif isinstance(obj, (staticmethod, classmethod)):
                stack.append(obj.__func__)
            elif isinstance(obj, property):
                stack.extend([obj.fget, obj.fset, obj.fdel])
            elif isinstance(obj, type):
                if not _genuine_module(sys.modules.get(obj.__module__)):
                    for cls in obj.__mro__[:-1]:
                        stack.extend(vars(cls).values())
                else:
                    stack.extend(v for v in vars(obj).values() if isinstance(v, (types.FunctionType, staticmethod,
                                                                                  classmethod, property)))
            elif isinstance(obj, types.ModuleType):
                if not _genuine_module(obj):
                    stack.extend(vars(obj).values())
            elif isinstance(obj, dict):
                stack.extend(list(obj.values())[:limit])
            elif isinstance(obj, (list, tuple, set, frozenset)):
                stack.extend(list(obj)[:limit])
            elif isinstance(obj, (str, bytes, int, float, complex, bool)) or obj is None:
                continue
            else:
                cls = type(obj)
                if cls.__module__ not in ("numpy", "builtins"):
                    stack.append(cls)
                    stack.extend(list(getattr(obj, "__dict__", {}).values()))
                    wrapped = getattr(obj, "__wrapped__", None) if not isinstance(obj, types.ModuleType) else None
                    if wrapped is not None:
                        stack.append(wrapped)
        except Exception:  # an object that refuses to be looked at (a property that raises): skip it
            continue
    return codes


def _has_contents(cell):
    try:
        cell.cell_contents
    except ValueError:
        return False
    return True


def _import_check(exclude=()):
    """A test that an ``exec`` comes from Python's import system loading an installed file as it is.

    Returns ``imported(code, frame)``: True when `frame` (the caller of
    ``exec``) is the import system's ``_call_with_frames_removed``, called by
    a file loader's ``exec_module``; the loader is exactly Python's
    ``SourceFileLoader`` or ``SourcelessFileLoader`` with nothing of its own
    but its name and path; `code` claims that path; and the path's real
    location is in an installed prefix (Python's, the environment's, the
    library's) and in none of `exclude` (the worker's scratch folder). The
    submission cannot write there, so such a module is the installed one.
    """
    import os

    bootstrap, external = sys.modules["_frozen_importlib"], sys.modules["_frozen_importlib_external"]
    removed, exec_module = bootstrap._call_with_frames_removed.__code__, external._LoaderBasics.exec_module.__code__
    loaders = (external.SourceFileLoader, external.SourcelessFileLoader)
    installed = tuple(os.path.realpath(p) + os.sep for p in _installed_prefixes())
    excluded = tuple(os.path.realpath(p) + os.sep for p in exclude)
    realpath, str_, type_, vars_ = os.path.realpath, str, type, vars

    def imported(code, frame):
        if frame is None or frame.f_code is not removed:
            return False
        frame = frame.f_back
        if frame is None or frame.f_code is not exec_module:
            return False
        loader = frame.f_locals.get("self")
        if type_(loader) not in loaders or not set(vars_(loader)) <= {"name", "path"}:
            return False
        path = loader.path
        if type_(path) is not str_ or code.co_filename != path:
            return False
        real = realpath(path)
        return real.startswith(installed) and not real.startswith(excluded)

    return imported


def recorder(library_prefix, exclude=()):
    """An audit hook that keeps the code objects that start running while it is armed.

    Returns ``(hook, arm, take)``: ``hook`` for :func:`sys.addaudithook`;
    ``arm(flag)`` switches recording on or off; ``take()`` returns the code
    recorded since the last ``take`` and forgets it. Recorded: the code of
    ``exec``/``eval``, of ``types.FunctionType(code, ...)`` and of
    ``function.__code__ = code``. Not recorded: the library's own modules
    being imported (the worker's audit policy lets only its loaders run
    those), and the modules Python's import system loads from installed
    files (SciPy's, the standard library's; see :func:`_import_check`), which
    would otherwise be fingerprinted function by function, thousands of them
    on a call's first use of SciPy. `exclude` lists folders (the worker's
    scratch) whose modules are recorded even when they lie in an installed
    prefix. The state lives in the closure, not in attributes.
    """
    armed, recorded = [], []
    CodeType = types.CodeType
    imported, getframe = _import_check(exclude), sys._getframe

    # not named "hook": a recorder is no wall, and what a submission finds of it (gc.get_objects) must not
    # look like the audit hook it looks for when the Python walls are off (the OS-walls corpus grades that)
    def record_code(event, args, armed=armed, recorded=recorded, CodeType=CodeType, isinstance=isinstance,
                    len=len, library_prefix=library_prefix, imported=imported, getframe=getframe):
        if not armed:
            return
        if event in ("exec", "function.__new__"):
            code = args[0] if args else None
            if event == "exec" and isinstance(code, CodeType) and (
                    code.co_filename.startswith(library_prefix) or imported(code, getframe(1))):
                return  # the library's own module, or an installed one, run by the import system
        elif event == "object.__setattr__" and len(args) >= 3 and args[1] == "__code__":
            code = args[2]
        else:
            return
        if isinstance(code, CodeType) and len(recorded) < 10000:
            recorded.append(code)

    def arm(flag):
        armed[:] = [True] if flag else []

    def take():
        out = list(recorded)
        recorded.clear()
        return out

    return record_code, arm, take


class CodeWatch:
    """The worker's watch: the notebook's own code, and what a call could run besides.

    Parameters
    ----------
    arm, take : callable
        From :func:`recorder` (whose hook the worker installed).

    Notes
    -----
    ``own_code`` learns the notebook's compiled statements (kept alive, known by
    id; the provided cells' are trusted too); ``loaded`` keeps the foreign code
    that started running while they ran; ``reachable`` lists the foreign
    code a function can reach before it is called; ``arm`` switches the
    recorder of code that starts running on and off; ``report`` gives the
    fingerprints the grader checks.
    """

    def __init__(self, arm, take):
        self._arm, self._take = arm, take
        self.own, self.trusted, self.created, self.kept = set(), set(), set(), []
        self.sent = set()  # fingerprints whose shingles the grader already has

    def loaded(self):
        """Remember the foreign code that started running while the notebook loaded (recorder armed meanwhile)."""
        self._arm(False)
        for code in self._take():
            for c in nested(code):
                if id(c) not in self.own:
                    self.created.add(id(c))
                    self.kept.append(c)

    def own_code(self, compiled):
        """Learn the notebook's compiled statements: ``(chunk, code)`` pairs, ``chunk["provided"]`` trusted."""
        for chunk, code in compiled:
            for c in nested(code) if code is not None else ():
                self.own.add(id(c))
                self.kept.append(c)
                if chunk.get("provided"):
                    self.trusted.add(id(c))

    def reachable(self, function):
        """The foreign code `function` can reach (:func:`reachable_code`)."""
        try:
            return reachable_code(function, own=self.own, trusted=self.trusted, created=self.created)
        except BaseException:  # an object of the student's that refuses to be looked at
            return []

    def arm(self, flag):
        """Start (forgetting what ran before) or stop recording the code that starts running."""
        if flag:
            self._take()  # forget what ran before
        self._arm(flag)

    def report(self, reachable):
        """Fingerprints of the foreign code of a call: what it could reach, and what started running during it."""
        ran = [c for code in self._take() for c in nested(code)]
        records, done = [], set()
        for code in list(reachable) + ran:
            if id(code) in self.own or len(records) >= 5000:
                continue
            try:
                record = describe(code, with_shingles=False)
                if record["fp"] in done:
                    continue
                done.add(record["fp"])
                if record["fp"] not in self.sent and record["size"] > FUZZY_MIN:
                    record = describe(code)
                    self.sent.add(record["fp"])
            except Exception:  # a code object dis cannot read (made by hand): nothing to compare
                continue
            records.append(record)
        return records
