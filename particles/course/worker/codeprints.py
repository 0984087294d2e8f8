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
the call could run that the notebook's own cells did not define
(:mod:`particles.course.worker.codewatch`). The grader (trusted) computes the
forbidden functions' fingerprints itself, from the installed library
(:func:`library_prints`), and decides (:class:`LibraryPrints`). Code compiled
from the notebook's own cells is the student's, even when it is shaped like
the library's: only code that came from elsewhere (the library's files, read
and run) is reported. What a hostile worker could still do is said in
:mod:`particles.course.worker.codewatch`.
"""

import bisect
import dis
import functools
import hashlib
import types
import zlib

__all__ = ["fingerprint", "tokens", "shingles", "describe", "nested", "LibraryPrints", "library_prints",
           "MIN_TOKENS", "FUZZY_MIN", "FUZZY_SHARE"]

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


@functools.lru_cache(maxsize=16)
def library_prints(forbidden):
    """The :class:`LibraryPrints` of the forbidden library names, computed in this (the grader's) process.

    Parameters
    ----------
    forbidden : tuple of str
        Dotted names (see :func:`particles.course.reading.forbidden.forbidden_code`); a tuple, so that each
        exercise's are computed once.
    """
    from ..reading.forbidden import forbidden_code

    return LibraryPrints(forbidden_code(forbidden))
