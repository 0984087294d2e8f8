"""What runs: fingerprints of compiled code, to recognise the library's own functions in a submission.

A submission may not hand in the library's function as its own, however it
gets hold of it: importing it (refused by name, :mod:`particles.course.reading.forbidden`,
and by the worker's tripwires), or reading the library's public source and
running it (``exec(compile(inspect.getsource(...)))``, ``open(path).read()``,
``types.FunctionType(lib_fn.__code__, globals())``, ``g.__code__ = ...``,
renamed, with other variable names or docstrings). The last ones define new
functions, unknown to the tripwires and invisible in the notebook's text. This
module recognises them by what runs: their compiled code.

The fingerprint of a code object (:func:`fingerprint`) is a hash of its
bytecode with everything a copy may change normalised away:

* local variables and arguments are their slot numbers (their names never
  reach the bytecode), globals and attributes are numbered in order of first
  use (``check_arguments`` renamed ``chk`` prints the same);
* string constants (docstrings, messages) are one token ``str``; numbers,
  ``None`` and booleans stay (``0.5 h`` is not ``0.25 h``); nested code
  (inner functions, comprehensions, lambdas) enters by its own fingerprint;
* the function's name, file, line numbers and no-op instructions are left out.

A copy with small edits (a line added or moved) still shares most of its
4-instruction shingles (:func:`shingles`); :class:`LibraryPrints` reports a
code object as library code when its fingerprint equals that of a forbidden
library function, or, for functions of at least :data:`FUZZY_MIN` tokens,
when it holds :data:`FUZZY_SHARE` of the library function's shingles and is at
most twice its size. Library code of fewer than :data:`MIN_TOKENS` tokens is
never matched: that short, an honest student writes the same.

Who does what
-------------
The worker (untrusted) reports, for each call, the fingerprints of the code
the called function can reach (:func:`reachable_code`: its own code, the
functions, classes, modules, containers, closures and defaults it refers to,
not descending into the installed library's or Python's own modules) and of
the code that started running during the call (``exec``, ``FunctionType``,
``__code__ =``, seen by an audit hook of the worker's, :func:`recorder`). The
grader (trusted) computes the forbidden functions' fingerprints itself, from
the installed library (:func:`library_prints`), and decides. A hostile worker
could still lie: code that reaches the worker's own objects (frames of the
serving loop) can empty what it reports, and library code created while the
notebook loads and reached only through a computed look-up in an installed
module (``getattr(numpy, "x" + "y")``) is not followed. Both take deliberate
work against the grader itself; the tests of the walls show which of those
doors are shut.
"""

import bisect
import dis
import hashlib
import sys
import types
import zlib

__all__ = ["fingerprint", "tokens", "shingles", "describe", "reachable_code", "recorder", "LibraryPrints",
           "library_prints", "MIN_TOKENS", "FUZZY_MIN", "FUZZY_SHARE"]

MIN_TOKENS = 12
"""Library code shorter than this (in tokens) is never matched: an honest student writes the same."""

FUZZY_MIN = 40
"""Library code at least this long is also recognised with small edits (shared shingles)."""

FUZZY_SHARE = 0.85
"""Share of a library function's shingles that a code object must hold to be recognised as an edited copy."""

_SKIPPED = {"RESUME", "NOP", "CACHE", "EXTENDED_ARG", "PRECALL", "COPY_FREE_VARS", "MAKE_CELL"}
_FLAGS = 0x04 | 0x08 | 0x20 | 0x80 | 0x100 | 0x200  # varargs, varkeywords, generator, coroutine, iterables, async gen
_JUMPS = set(dis.hasjrel) | set(dis.hasjabs)
_CACHE = {}  # id(code) -> (code, tokens, fingerprint): kept alive, so that an id stays its own


def _constant(value, names):
    if isinstance(value, types.CodeType):
        return "code:" + fingerprint(value)
    if isinstance(value, (str, bytes)):
        return type(value).__name__
    if value is None or isinstance(value, (bool, int, float, complex)):
        return repr(value)
    if isinstance(value, tuple):
        return "(" + ",".join(_constant(v, names) for v in value) + ")"
    if isinstance(value, frozenset):
        return "{" + ",".join(sorted(_constant(v, names) for v in value)) + "}"
    return type(value).__name__


def _analyse(code):
    cached = _CACHE.get(id(code))
    if cached is not None and cached[0] is code:
        return cached
    kept = [i for i in dis.get_instructions(code) if i.opname not in _SKIPPED]
    offsets = [i.offset for i in kept]
    names = {}

    def name(text):
        return names.setdefault(text, f"n{len(names)}")

    out = [f"args:{code.co_argcount}/{code.co_posonlyargcount}/{code.co_kwonlyargcount}/{code.co_flags & _FLAGS}"]
    for k, instr in enumerate(kept):
        op, arg = instr.opname, instr.arg
        if instr.opcode in _JUMPS and isinstance(instr.argval, int):
            out.append(f"{op}:{bisect.bisect_left(offsets, instr.argval) - k}")
        elif instr.opcode in dis.hasconst:
            value = instr.argval
            if op == "KW_NAMES" and isinstance(value, tuple):
                out.append(f"{op}:" + ",".join(name(v) for v in value))
            else:
                out.append(f"{op}:{_constant(value, names)}")
        elif instr.opcode in dis.hasname:
            null = "+null" if str(instr.argrepr).startswith("NULL") else ""
            out.append(f"{op}{null}:{name(str(instr.argval))}")
        elif instr.opcode in dis.haslocal or instr.opcode in dis.hasfree:
            out.append(f"{op}:{arg}")
        elif instr.opcode in dis.hascompare:
            out.append(f"{op}:{instr.argrepr}")
        else:
            out.append(op if arg is None else f"{op}:{instr.argrepr or arg}")
    digest = hashlib.sha256("\n".join(out).encode()).hexdigest()[:32]
    entry = (code, out, digest)
    if len(_CACHE) > 20000:
        _CACHE.clear()
    _CACHE[id(code)] = entry
    return entry


def tokens(code):
    """The normalised instructions of `code` (a list of str; nested code appears as its fingerprint)."""
    return list(_analyse(code)[1])


def fingerprint(code):
    """The fingerprint of `code` (32 hex digits): equal for copies that differ only in names, texts, lines.

    Parameters
    ----------
    code : types.CodeType

    Returns
    -------
    str

    Examples
    --------
    >>> def a(f, X, t, h):
    ...     '''One step.'''
    ...     return X + h * f(X, t)
    >>> def b(g, Y, s, dt):
    ...     return Y + dt * g(Y, s)
    >>> fingerprint(a.__code__) == fingerprint(b.__code__)
    True
    """
    if not isinstance(code, types.CodeType):
        raise TypeError(f"code must be a code object, got {type(code).__name__}")
    return _analyse(code)[2]


def shingles(items, k=4):
    """The set of hashes (32-bit ints) of the runs of `k` consecutive tokens of `items`."""
    items = list(items)
    runs = [items[i:i + k] for i in range(max(len(items) - k + 1, 1))]
    return {zlib.crc32("\x1f".join(run).encode()) for run in runs}


def describe(code, with_shingles=True):
    """What the worker reports of one code object: ``{"fp", "size"}``, and ``"shingles"`` when it is long.

    ``size`` counts its tokens and those of the code nested in it.
    """
    _, items, digest = _analyse(code)
    size = len(items) - 1 + sum(describe(c, False)["size"] for c in code.co_consts if isinstance(c, types.CodeType))
    record = {"fp": digest, "size": size}
    if with_shingles and len(items) > FUZZY_MIN:
        record["shingles"] = sorted(shingles(items[1:]))
    return record


def nested(code):
    """`code` and every code object nested in it, outermost first."""
    out, stack = [], [code]
    while stack:
        c = stack.pop()
        out.append(c)
        stack.extend(reversed([k for k in c.co_consts if isinstance(k, types.CodeType)]))
    return out


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
    """True for a function of an installed module (its globals are that module's own dict)."""
    globals_ = function.__globals__
    module = sys.modules.get(globals_.get("__name__")) if isinstance(globals_.get("__name__"), str) else None
    return module is not None and getattr(module, "__dict__", None) is globals_ and _genuine_module(module)


def reachable_code(root, own=(), trusted=(), limit=20000):
    """The code objects that `root` (a function or any callable) can run, as far as its references tell.

    Follows functions (code, nested code, the globals their code names,
    closures, defaults, ``__wrapped__``), methods, ``functools.partial``,
    classes and instances (their methods), modules a submission made (all of
    them; of an installed module only the attributes the code names),
    dicts, lists, tuples and sets. It does not descend into functions of
    installed modules, but reports their code (a library function re-run
    into an installed module's dict is still seen), nor into the functions
    whose code is in `trusted` (ids of the course's own code). Code whose id
    is in `own` (the notebook's own statements, compiled by the worker) is
    followed but not reported.

    Returns
    -------
    list of types.CodeType
        Each once, `own` and `trusted` ones left out.
    """
    import builtins
    import functools

    trusted = set(trusted)
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
                add_code(code)
                if _genuine_function(obj):
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


def recorder(library_prefix):
    """An audit hook that keeps the code objects that start running while it is armed.

    Returns ``(hook, arm, take)``: ``hook`` for :func:`sys.addaudithook`;
    ``arm(flag)`` switches recording on or off; ``take()`` returns the code
    recorded since the last ``take`` and forgets it. Recorded: the code of
    ``exec``/``eval`` (but not the library's own modules being imported:
    the worker's audit policy lets only its loaders run those), of
    ``types.FunctionType(code, ...)`` and of ``function.__code__ = code``.
    The state lives in the closure, not in attributes.
    """
    armed, recorded = [], []
    CodeType = types.CodeType

    def hook(event, args, armed=armed, recorded=recorded, CodeType=CodeType, isinstance=isinstance, len=len,
             library_prefix=library_prefix):
        if not armed:
            return
        if event in ("exec", "function.__new__"):
            code = args[0] if args else None
            if event == "exec" and isinstance(code, CodeType) and code.co_filename.startswith(library_prefix):
                return  # the library's own module, run by the import system (others are refused)
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

    return hook, arm, take


# -- the grader's side ------------------------------------------------------------------------------


class LibraryPrints:
    """The fingerprints of the library functions an exercise forbids, and the verdict on what a worker reports.

    Parameters
    ----------
    functions : iterable of (str, str, types.CodeType)
        ``(label, forbidden name, code)``: e.g. ``("particles.forces.Gravity.add_to",
        "particles.forces.Gravity", code)``.
    """

    def __init__(self, functions):
        self.exact, self.fuzzy = {}, []
        for label, name, code in functions:
            record = describe(code)
            if record["size"] < MIN_TOKENS:
                continue
            self.exact.setdefault(record["fp"], (label, name))
            if "shingles" in record:
                self.fuzzy.append((set(record["shingles"]), record["size"], label, name))
        self._verdicts = {}

    def __len__(self):
        return len(self.exact)

    def match(self, record):
        """``(label, forbidden name)`` when a worker's `record` (see :func:`describe`) is library code, else None."""
        if not isinstance(record, dict) or not isinstance(record.get("fp"), str):
            return None
        fp = record["fp"]
        if fp in self.exact:
            return self.exact[fp]
        if fp in self._verdicts:
            return self._verdicts[fp]
        found = None
        marks, size = record.get("shingles"), record.get("size")
        if isinstance(marks, list) and isinstance(size, int) and len(marks) <= 20000:
            mine = {m for m in marks if isinstance(m, int)}
            best = 0.0
            for theirs, their_size, label, name in self.fuzzy:
                share = len(mine & theirs) / len(theirs)
                if share >= FUZZY_SHARE and size <= 2 * their_size and share > best:
                    best, found = share, (label, name)
            self._verdicts[fp] = found
        return found


def library_prints(forbidden):
    """The :class:`LibraryPrints` of the forbidden library names (dotted names, see
    :func:`particles.course.reading.forbidden.forbidden_code`), computed in this (the grader's) process."""
    from ..reading.forbidden import forbidden_code

    return LibraryPrints(forbidden_code(forbidden))
