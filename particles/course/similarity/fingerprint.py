"""Fingerprints of Python functions: a normalized syntax tree, hashed, and a score of two of them.

:mod:`particles.course.similarity.compare` compares the functions of submissions, of
the masters and of the library with these fingerprints (read its docstring
for what is compared, how candidate pairs are found and how clusters are made).

Normalization
    The body's syntax tree is written as a pre-order stream of node tokens.
    Parameters (in signature order), then local names (in order of first
    appearance) become ``v0, v1, ...``; the function's own name becomes
    ``<self>``; other functions and classes of the same notebook or module,
    and those of the library, become ``<def>`` (a pasted function calls its
    pasted helpers under new names, or imports them from the library);
    other global names stay. An attribute chain on an imported module becomes
    its full dotted name (``np.sqrt``, ``numpy.sqrt`` and ``from numpy import
    sqrt`` all give ``numpy.sqrt``). Docstrings, comments, annotations, and
    the function's decorators go; operators stay in their node's token
    (``BinOp:Add``). Two levels are hashed: *exact* (with the constants) and
    *structure* (every number and string a placeholder). Nothing is sorted
    or folded.

Scoring
    Functions with the same structure hash score 1 ("identical" when their
    exact hashes agree too, else "identical up to constants"). Other pairs
    score ``difflib.SequenceMatcher.ratio`` of their structure token
    sequences, 2 x matching tokens / all tokens: the library's midpoint (36
    nodes) pasted with an ``assert`` (5 nodes) added scores 72 / 77 = 0.94.
    Only candidate pairs are scored: equal structures meet in dict buckets;
    MinHash signatures of the token 3-grams of the distinct structures are
    banded (24 bands of 2 rows), and pairs sharing a band are candidates (a
    pair with 3-gram Jaccard similarity 0.4 is one with probability 0.98,
    0.3 with 0.9), then bounded by length and by tokens in common before
    difflib runs. Functions with fewer than `min_nodes` nodes (default 10:
    the one-line Euler step ``return X + h * f(X, t)`` has 9) are ignored,
    and counted by name in the report.
"""

import ast
import difflib
import hashlib
import numbers
from collections import defaultdict
from dataclasses import dataclass, field

__all__ = ["Function", "Context", "module_context", "normalize", "stub_part", "make_function", "fingerprint",
           "score"]

_SKIP = {"ctx", "type_comment", "kind", "annotation", "returns", "op", "ops", "asname", "type_params"}
_LITERAL_NAMES = (ast.alias, ast.keyword, ast.Attribute, ast.ImportFrom)
_COMPOUND = (ast.If, ast.Try)


@dataclass(eq=False)
class Function:
    """One normalized function: whose, where, and its fingerprints.

    Attributes
    ----------
    owner : str
        The student, ``"library"`` or ``"master"``.
    kind : str
        ``"student"``, ``"library"`` or ``"master"``.
    exercise, name : str
        The exercise (empty for the library) and the function's name
        (dotted for the library, e.g. ``particles.integrators.midpoint``).
    path, cell : str
        The notebook or source file, and the code cell (empty for a file).
    line : int
        Line of the ``def`` in the cell or file (below its decorators).
    role : str
        ``"asked"`` (the stub asks for it), ``"helper"`` (used by one) or ``"reference"``.
    size : int
        Normalized nodes (the length of `tokens`).
    exact, structure : str
        Hashes of the normalized body with and without its constants.
    tokens : tuple of str
        The structure-level token sequence the fuzzy score compares.
    """

    owner: str
    kind: str
    exercise: str
    name: str
    path: str
    cell: str
    line: int
    role: str
    size: int
    exact: str
    structure: str
    tokens: tuple = field(repr=False)

    @property
    def where(self):
        """``"path, code cell 3, line 1"`` or ``"particles/x.py, line 12"``."""
        return ", ".join(p for p in (self.path, self.cell, f"line {self.line}") if p)

    @property
    def label(self):
        """``owner: name`` as the report prints it."""
        return f"{self.owner}: {self.name}"



# -- normalization -------------------------------------------------------------------------------------

@dataclass
class Context:
    """Module-level names of a notebook or source file."""

    aliases: dict
    defs: set
    package: str = ""
    library: tuple = (frozenset(), {})  # the library's top-level defs and classes, and its re-exports


def _absolute(node, package):
    if not node.level:
        return node.module or ""
    base = package.split(".")[: len(package.split(".")) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def _add_imports(aliases, node, package=""):
    if isinstance(node, ast.Import):
        for a in node.names:
            aliases[a.asname or a.name.split(".")[0]] = a.name if a.asname else a.name.split(".")[0]
    elif isinstance(node, ast.ImportFrom):
        module = _absolute(node, package)
        for a in node.names:
            if a.name != "*":
                aliases[a.asname or a.name] = f"{module}.{a.name}"


def module_context(statements, package="", library=(frozenset(), {})):
    aliases, defs = {}, set()
    for stmt in statements:
        if isinstance(stmt, _COMPOUND):  # imports under if and try too (a function's own: see _Normalizer)
            for node in ast.walk(stmt):
                _add_imports(aliases, node, package)
        _add_imports(aliases, stmt, package)
        if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            defs.add(stmt.name)
    return Context(aliases, defs, package, library)


def _is_docstring(node):
    return isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)


def _constant(value):
    if isinstance(value, bool) or value is None or value is Ellipsis:
        return f"C:{value!r}"
    if isinstance(value, numbers.Number):
        return f"#{value!r}"
    return f"${value!r}"  # str and bytes


def _blur(token):
    """The structure-level token: a number or string constant becomes its placeholder."""
    return token[0] if token[0] in "#$" else token


class _Normalizer:
    """Writes statements of one function as token streams, naming its locals in order of appearance.

    Locals are the names bound inside the function (parameters, assignment
    targets, nested ``def`` s, ``except ... as``), minus those declared
    ``global`` or ``nonlocal``; its own imports extend the module's aliases.
    """

    def __init__(self, func, context):
        self.own, self.context, self.names, self.used = func.name, context, {}, set()
        self.aliases, bound, free = dict(context.aliases), set(), set()
        for node in ast.walk(func):
            if isinstance(node, ast.Name):
                if not isinstance(node.ctx, ast.Load):
                    bound.add(node.id)
            elif isinstance(node, ast.arg):
                bound.add(node.arg)
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and node is not func:
                bound.add(node.name)
            elif isinstance(node, ast.ExceptHandler) and node.name:
                bound.add(node.name)
            elif isinstance(node, (ast.Global, ast.Nonlocal)):
                free.update(node.names)
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                _add_imports(self.aliases, node, context.package)
        self.locals = bound - free
        a = func.args
        for arg in [*a.posonlyargs, *a.args, a.vararg, *a.kwonlyargs, a.kwarg]:
            if arg is not None:
                self.resolve(arg.arg)

    def resolve(self, name):
        if name in self.locals:
            return self.names.setdefault(name, f"v{len(self.names)}")
        if name == self.own:
            return "<self>"
        if name in self.aliases:
            return self._qualified(self.aliases[name])
        if name in self.context.defs:
            self.used.add(name)
            return "<def>"
        return name

    def _qualified(self, dotted):
        """`dotted`, or ``<def>`` for a function or class of the library (as its own module sees it)."""
        defs, reexports = self.context.library
        for _ in range(3):  # particles.string -> particles.massspring.string
            dotted = reexports.get(dotted, dotted)
        return "<def>" if dotted in defs else dotted

    def _module_chain(self, node):
        parts = []
        while isinstance(node, ast.Attribute):
            parts.append(node.attr)
            node = node.value
        if isinstance(node, ast.Name) and node.id not in self.locals and node.id in self.aliases:
            return self._qualified(".".join([self.aliases[node.id], *reversed(parts)]))
        return None

    def emit(self, node, out):
        """Append the pre-order token stream of `node` to `out` (lists bracketed, None as ``_``)."""
        if isinstance(node, ast.Name):
            out.append("N:" + self.resolve(node.id))
            return
        if isinstance(node, ast.Constant):
            out.append(_constant(node.value))
            return
        if isinstance(node, ast.Attribute):
            chain = self._module_chain(node)
            if chain:
                out.append("N:" + chain)
                return
        head, children = [type(node).__name__], []
        if isinstance(getattr(node, "op", None), ast.AST):
            head.append(type(node.op).__name__)
        if isinstance(node, ast.Compare):
            head.append(",".join(type(op).__name__ for op in node.ops))
        for name, value in ast.iter_fields(node):
            if name in _SKIP:
                continue
            if isinstance(value, list) and value and isinstance(value[0], str):  # global, nonlocal
                head.append(",".join(map(self.resolve, value)))
            elif isinstance(value, list):
                children.append([v for v in value if not _is_docstring(v)])
            elif isinstance(value, str):
                head.append(value if isinstance(node, _LITERAL_NAMES) else self.resolve(value))
            elif value is None or isinstance(value, ast.AST):
                children.append(value)
            else:  # an int: ImportFrom.level, comprehension.is_async, FormattedValue.conversion
                head.append(repr(value))
        out.append(":".join(head))
        for child in children:
            if isinstance(child, list):
                out.append("[")
                for item in child:
                    self.emit(item, out) if item is not None else out.append("_")
                out.append("]")
            elif child is None:
                out.append("_")
            else:
                self.emit(child, out)


    def statement(self, stmt):
        """Structure hash of one statement on its own (locals numbered after the parameters only)."""
        names, stream = dict(self.names), []
        self.emit(stmt, stream)
        self.names = names
        return _digest(map(_blur, stream))


def _digest(stream):
    return hashlib.blake2b("\n".join(stream).encode(), digest_size=8).hexdigest()


def _body(func):
    return [s for s in func.body if not _is_docstring(s)]


def stub_part(func, context):
    """The statements of a stub's function body: statement type -> structure hashes."""
    normalizer, out = _Normalizer(func, context), defaultdict(set)
    for stmt in _body(func):
        out[type(stmt).__name__].add(normalizer.statement(stmt))
    return dict(out)


def normalize(func, context, shared=None):
    """Exact hash, structure hash, structure tokens of `func`'s body, and the module's functions it uses.

    Statements equal to one in `shared` (see :func:`stub_part`) are left out.
    """
    normalizer, body = _Normalizer(func, context), _body(func)
    if shared:
        body = [s for s in body if type(s).__name__ not in shared or normalizer.statement(s) not in
                shared[type(s).__name__]]
    stream = []
    for stmt in body:
        normalizer.emit(stmt, stream)
    blurred = [_blur(t) for t in stream]
    tokens = tuple(t for t in blurred if t not in ("[", "]", "_"))
    return _digest(stream), _digest(blurred), tokens, normalizer.used


def make_function(func, context, shared=None, **where):
    exact, structure, tokens, used = normalize(func, context, shared)
    f = Function(line=func.lineno, size=len(tokens), exact=exact, structure=structure, tokens=tokens, **where)
    return f, used


def fingerprint(source, name=None):
    """The normalized :class:`Function` of a ``def`` in Python source.

    Parameters
    ----------
    source : str
        Module source (imports in it resolve attribute chains).
    name : str, optional
        The function; default the last top-level ``def``.

    Returns
    -------
    Function
        With ``owner="source"``; its `exact` and `structure` hashes and `tokens`.

    Examples
    --------
    >>> a = fingerprint("import numpy as np\\ndef f(x):\\n    '''doc'''\\n    y = np.sqrt(x)\\n    return y + 1")
    >>> b = fingerprint("import numpy\\ndef g(u):\\n    w = numpy.sqrt(u)  # a comment\\n    return w + 2")
    >>> a.structure == b.structure, a.exact == b.exact
    (True, False)
    """
    tree = ast.parse(source)
    defs = [s for s in tree.body if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef))]
    func = next(d for d in reversed(defs) if name in (None, d.name))
    return make_function(func, module_context(tree.body), owner="source", kind="source", exercise="", name=func.name,
                     path="", cell="", role="reference")[0]


def score(a, b):
    """Similarity of two :class:`Function` s, from 0 to 1: 1 for equal structure, else the difflib ratio.

    The ratio is ``2 M / (len(a.tokens) + len(b.tokens))`` with ``M`` the
    tokens in matching blocks of the structure-level token sequences.
    """
    if a.structure == b.structure:
        return 1.0
    return difflib.SequenceMatcher(None, a.tokens, b.tokens, autojunk=False).ratio()


