"""Similarity report: submitted functions structurally equal to the library, a master or a classmate.

Forbidden-use checks (:mod:`~particles.course.forbidden`) catch calls to the
library; they do not catch its source pasted under another name, nor a
classmate's notebook. ``particles similarity DIR`` reads syntax trees
(nothing is run) and reports the functions that match.

What is compared
    From each submission, the functions the released stub asks for (those
    whose body holds ``### BEGIN SOLUTION`` in the master) as the student
    wrote them (the last ``def`` of the name), plus the notebook's own
    functions they use, directly or through each other. A helper equal to a
    function the stub already gives is dropped. So are the parts every
    submission shares with the stub: signature, docstring, and any statement
    of the stub's body (``raise NotImplementedError``). References: every
    function and method of the library (``particles/`` except
    ``particles/course/``) and the masters' solutions.

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

Clusters are the connected components of the matches. Each lists every
member once: against the first student of its identical group, or as one
similar link. Candidates are scored most similar first, and two students'
groups already in one cluster are not scored again, so the similar links
are a spanning tree (plus every link to a library function or a master): a
cluster of 200 identical answers has 199 rows, not 19900.
"""

import ast
import csv
import difflib
import hashlib
import numbers
import time
import zlib
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from .code import notebook_cells
from .paths import project_root
from .release import BEGIN, release_notebook

from .discovery import find_submissions

__all__ = ["Function", "Pair", "Cluster", "SimilarityReport", "fingerprint", "score", "library_functions",
           "similarity", "format_table", "write_report"]

_SKIP = {"ctx", "type_comment", "kind", "annotation", "returns", "op", "ops", "asname", "type_params"}
_LITERAL_NAMES = (ast.alias, ast.keyword, ast.Attribute, ast.ImportFrom)
_COMPOUND = (ast.If, ast.Try)
_K, _BANDS, _ROWS = 3, 24, 2
_PRIME = np.uint64((1 << 61) - 1)
_RNG = np.random.default_rng(20261201)
_A = _RNG.integers(1, 1 << 31, size=_BANDS * _ROWS, dtype=np.uint64)
_B = _RNG.integers(0, 1 << 31, size=_BANDS * _ROWS, dtype=np.uint64)


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


@dataclass
class Pair:
    """Two functions of different owners that match.

    Attributes
    ----------
    a, b : Function
        `a` is a student's; `b` a classmate's, a library function or a master.
    score : float
        1 for equal structure, else the difflib ratio (see :func:`score`).
    match : str
        ``"identical"``, ``"identical up to constants"`` or ``"similar"``.
    """

    a: Function
    b: Function
    score: float
    match: str


@dataclass
class Cluster:
    """Functions linked by matches.

    Attributes
    ----------
    number : int
        Its rank in the report, from 1.
    members : list of Function
        Students' functions first.
    pairs : list of Pair
        Each member once (see the module docstring), best score first.
    score : float
        The best score of its pairs.
    """

    number: int
    members: list
    pairs: list
    score: float

    @property
    def students(self):
        """The distinct students in the cluster."""
        return sorted({m.owner for m in self.members if m.kind == "student"})


@dataclass
class SimilarityReport:
    """What :func:`similarity` found, and what it left out.

    Attributes
    ----------
    clusters : list of Cluster
        Sorted by score, then those holding a library function, then the fewest students.
    submissions, compared : int
        Notebooks read (unreadable ones are in `problems`), and their functions compared (asked ones
        and helpers, short ones left out).
    references : Counter
        Reference functions compared, by kind (``"library"``, ``"master"``).
    short, unwritten : Counter
        ``"NN_topic name"`` -> number of submissions whose function was trivially short
        (fewer than `min_nodes` nodes), or left as the released stub.
    problems : list of str
        Notebooks or cells not read (unreadable, syntax errors, unknown exercise).
    threshold : float
    min_nodes : int
    seconds : float
        Wall time of :func:`similarity`.
    stats : dict
        Work done: ``functions``, distinct ``structures``, MinHash ``candidates``,
        pairs ``scored`` with difflib, similar ``links`` found, ``read_seconds``.
    """

    clusters: list
    submissions: int
    compared: int
    references: Counter
    short: Counter
    unwritten: Counter
    problems: list
    threshold: float
    min_nodes: int
    seconds: float = 0.0
    stats: dict = field(default_factory=dict)

    @property
    def pairs(self):
        """All reported pairs, cluster by cluster."""
        return [p for c in self.clusters for p in c.pairs]


# -- normalization -------------------------------------------------------------------------------------

@dataclass
class _Context:
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


def _context(statements, package="", library=(frozenset(), {})):
    aliases, defs = {}, set()
    for stmt in statements:
        if isinstance(stmt, _COMPOUND):  # imports under if and try too (a function's own: see _Normalizer)
            for node in ast.walk(stmt):
                _add_imports(aliases, node, package)
        _add_imports(aliases, stmt, package)
        if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            defs.add(stmt.name)
    return _Context(aliases, defs, package, library)


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


def _shared(func, context):
    """The statements of a stub's function body: statement type -> structure hashes."""
    normalizer, out = _Normalizer(func, context), defaultdict(set)
    for stmt in _body(func):
        out[type(stmt).__name__].add(normalizer.statement(stmt))
    return dict(out)


def _normalize(func, context, shared=None):
    """Exact hash, structure hash, structure tokens of `func`'s body, and the module's functions it uses.

    Statements equal to one in `shared` (see :func:`_shared`) are left out.
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


def _function(func, context, shared=None, **where):
    exact, structure, tokens, used = _normalize(func, context, shared)
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
    return _function(func, _context(tree.body), owner="source", kind="source", exercise="", name=func.name,
                     path="", cell="", role="reference")[0]


def score(a, b):
    """Similarity of two :class:`Function` s, from 0 to 1: 1 for equal structure, else the difflib ratio.

    The ratio is ``2 M / (len(a.tokens) + len(b.tokens))`` with ``M`` the
    tokens in matching blocks of the structure-level token sequences.
    """
    if a.structure == b.structure:
        return 1.0
    return difflib.SequenceMatcher(None, a.tokens, b.tokens, autojunk=False).ratio()


# -- what is compared ----------------------------------------------------------------------------------

def _parse_cells(cells):
    """Top-level statements ``(cell label, statement)`` of the code cells that define or import something,
    and the labels of those that do not parse."""
    out, bad = [], []
    for label, source in cells:
        if source.lstrip().startswith("%%") or not any(word in source for word in ("def ", "class ", "import")):
            continue  # a cell magic (not run by the grader either), or a cell of experiments and plots
        source = "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in source.split("\n"))
        try:
            tree = ast.parse(source)
        except (SyntaxError, ValueError):  # ValueError: a null byte
            bad.append(label)
            continue
        out.extend((label, stmt) for stmt in tree.body)
    return out, bad


def _defs(statements):
    """Last top-level ``def`` of each name: name -> (cell label, node)."""
    return {s.name: (label, s) for label, s in statements if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef))}


@dataclass
class _Exercise:
    name: str
    asked: list
    shared: dict
    given: set
    masters: list


def _exercise(root, name, library):
    path = Path(root) / "solutions" / f"{name}.ipynb"
    cells = notebook_cells(path)
    statements, _ = _parse_cells(cells)
    sources = dict(cells)
    asked = [n for n, (label, node) in _defs(statements).items()
             if BEGIN in "\n".join(sources[label].split("\n")[node.lineno - 1:node.end_lineno])]
    import nbformat  # the stub, as `particles release` writes it

    stub = release_notebook(nbformat.read(str(path), as_version=4), name)
    stub_cells = [(f"code cell {k}", c.source) for k, c in
                  enumerate((c for c in stub.cells if c.cell_type == "code"), start=1)]
    stub_statements, _ = _parse_cells(stub_cells)
    stub_context, stub_defs = _context([s for _, s in stub_statements], library=library), _defs(stub_statements)
    shared = {n: _shared(stub_defs[n][1], stub_context) for n in asked if n in stub_defs}
    given = {_normalize(node, stub_context)[1] for n, (_, node) in stub_defs.items() if n not in asked}
    context, defs = _context([s for _, s in statements], library=library), _defs(statements)
    masters = [_function(defs[n][1], context, shared.get(n), owner="master", kind="master", exercise=name,
                         name=n, path=f"solutions/{name}.ipynb", cell=defs[n][0], role="reference")[0]
               for n in asked]
    return _Exercise(name, asked, shared, given, masters)


def _submission(unit, info, path, library):
    """A submission's functions (asked ones and the helpers they use), and the asked names not written."""
    statements, bad = _parse_cells(notebook_cells(unit.notebook))
    context, defs = _context([s for _, s in statements], library=library), _defs(statements)
    out, unwritten, queue, seen = [], [], [n for n in info.asked if n in defs], set()
    while queue:  # the asked functions, then the notebook's functions they use
        name = queue.pop(0)
        if name in seen:
            continue
        seen.add(name)
        label, node = defs[name]
        asked = name in info.asked
        f, used = _function(node, context, info.shared.get(name), owner=unit.student, kind="student",
                            exercise=unit.exercise, name=name, path=path, cell=label,
                            role="asked" if asked else "helper")
        if not asked and f.structure in info.given:
            continue  # the stub gives this function to everyone
        if f.size == 0:
            unwritten.append(name)
            continue
        out.append(f)
        queue += sorted(used & defs.keys() - seen)
    return out, unwritten, bad


@lru_cache(maxsize=4)
def _library(folder):
    """The library's functions, and (its top-level defs and classes, its re-exports) for :class:`_Context`."""
    folder, modules, defs, reexports = Path(folder), [], set(), {}
    for path in sorted(folder.rglob("*.py")):
        rel = path.relative_to(folder.parent)
        if "course" in rel.parts[1:-1] or "__pycache__" in rel.parts:
            continue
        module = ".".join(rel.with_suffix("").parts).removesuffix(".__init__")
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        tree = ast.parse(path.read_text(encoding="utf-8"))
        modules.append((rel, module, tree, _context(tree.body, package)))
        defs |= {f"{module}.{name}" for name in modules[-1][3].defs}
        reexports.update((f"{module}.{name}", target) for name, target in modules[-1][3].aliases.items())
    index, out = (frozenset(defs), reexports), []
    for rel, module, tree, context in modules:
        context.library = index
        stack = [(module, tree.body)]
        while stack:  # functions and methods at any depth: a loop over scopes
            prefix, body = stack.pop()
            for node in body:
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    out.append(_function(node, context, owner="library", kind="library", exercise="",
                                         name=f"{prefix}.{node.name}", path=str(rel), cell="",
                                         role="reference")[0])
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    stack.append((f"{prefix}.{node.name}", node.body))
    return tuple(out), index


def library_functions(folder=None):
    """Normalized functions and methods of the library's source (``particles/`` except ``particles/course/``).

    Parameters
    ----------
    folder : path, optional
        The package folder (default: the installed ``particles``).

    Returns
    -------
    tuple of Function
        With ``owner="library"`` and dotted names, e.g. ``particles.integrators.midpoint``.
    """
    return _library(_package(folder))[0]


def _package(folder):
    return str(Path(folder or Path(__file__).resolve().parents[1]).resolve())


# -- comparison ----------------------------------------------------------------------------------------

def _minhash(tokens):
    k = min(_K, len(tokens)) or 1
    grams = {zlib.crc32("\x1f".join(tokens[i:i + k]).encode()) for i in range(max(len(tokens) - k + 1, 1))}
    x = np.fromiter(grams, dtype=np.uint64, count=len(grams))
    return ((_A[:, None] * x[None, :] + _B[:, None]) % _PRIME).min(axis=1)


def _candidates(groups, has_student):
    """Pairs of groups sharing a MinHash band, at least one with a student, most bands shared first.

    Returns
    -------
    list of (int, int)
        Indices ``i < j`` into `groups`.
    """
    n = len(groups)
    signatures = np.stack([_minhash(g[0].tokens) for g in groups])
    codes = [np.zeros(0, dtype=np.int64)]
    for band in range(_BANDS):  # a loop over bands, then over the buckets of a band that hold a pair
        columns = signatures[:, band * _ROWS:(band + 1) * _ROWS]
        key = columns[:, 0] * np.uint64(0x9E3779B97F4A7C15) ^ columns[:, 1]
        order = np.argsort(key, kind="stable")
        for bucket in np.split(order, np.flatnonzero(np.diff(key[order])) + 1):
            if len(bucket) > 1:
                bucket = np.sort(bucket).astype(np.int64)
                i, j = np.triu_indices(len(bucket), 1)
                codes.append(bucket[i] * n + bucket[j])
    pairs, hits = np.unique(np.concatenate(codes), return_counts=True)
    i, j = pairs // n, pairs % n
    student = np.asarray(has_student, dtype=bool)
    keep = student[i] | student[j]
    i, j, hits = i[keep], j[keep], hits[keep]
    order = np.lexsort((i, j, -hits))
    return list(zip(i[order].tolist(), j[order].tolist()))


def _pick(A, B):
    """Members a of A and b of B of different owners, one a student's, preferring the first ones; or None."""
    for a in A:
        for b in B:
            if a.owner != b.owner and "student" in (a.kind, b.kind):
                return (a, b) if a.kind == "student" else (b, a)
    return None


def _order(members):
    return sorted(members, key=lambda f: (f.kind != "student", f.owner, f.name))


def _clusters(functions, threshold, stats):
    """Clusters of matching functions; counts of the work done go into `stats`."""
    by_structure = defaultdict(list)
    for f in functions:
        by_structure[f.structure].append(f)
    groups = [_order(g) for g in by_structure.values()]
    has_student = [g[0].kind == "student" for g in groups]
    parent = list(range(len(groups)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    candidates = _candidates(groups, has_student) if groups else []
    bags = [Counter(g[0].tokens) for g in groups]
    links, scored = [], 0
    # most similar first (most bands shared); two student groups already in one cluster are not scored
    # again, so a cluster's links are a spanning tree of its students plus their links to references
    for i, j in candidates:
        if has_student[i] and has_student[j] and find(i) == find(j):
            continue
        a, b = groups[i][0].tokens, groups[j][0].tokens
        total = threshold * (len(a) + len(b))
        if 2 * min(len(a), len(b)) < total or _pick(groups[i], groups[j]) is None:
            continue
        ca, cb = bags[i], bags[j]  # the bound of quick_ratio: tokens in common, counted with multiplicity
        if 2 * sum(min(ca[t], cb[t]) for t in ca.keys() & cb.keys()) < total:
            continue
        scored += 1
        ratio = difflib.SequenceMatcher(None, a, b, autojunk=False).ratio()
        if ratio >= threshold:
            links.append((i, j, ratio))
            parent[find(i)] = find(j)
    stats.update(functions=len(functions), structures=len(groups), candidates=len(candidates), scored=scored,
                 links=len(links))
    pairs, members = defaultdict(list), defaultdict(list)
    for k, group in enumerate(groups):
        anchor = group[0]
        members[find(k)] += group
        for other in group[1:]:
            if other.owner != anchor.owner and "student" in (anchor.kind, other.kind):
                match = "identical" if other.exact == anchor.exact else "identical up to constants"
                pairs[find(k)].append(Pair(anchor, other, 1.0, match))
    for i, j, ratio in links:
        a, b = _pick(groups[i], groups[j])
        pairs[find(i)].append(Pair(a, b, ratio, "similar"))
    out = []
    for root, found in pairs.items():
        found.sort(key=lambda p: (-p.score, p.match, p.a.owner, p.b.owner, p.a.name))
        out.append(Cluster(0, _order(members[root]), found, max(p.score for p in found)))
    out.sort(key=lambda c: (-c.score, all(m.kind != "library" for m in c.members), len(c.students),
                            c.members[0].exercise, c.members[0].name, c.members[0].owner))
    for number, cluster in enumerate(out, start=1):
        cluster.number = number
    return out


def _check_threshold(threshold):
    if isinstance(threshold, bool) or not isinstance(threshold, numbers.Real) or not 0 <= threshold <= 1:
        raise ValueError(f"threshold must be a number from 0 to 1, got {threshold!r}")
    return float(threshold)


def similarity(paths, *, threshold=0.8, exercise=None, root=None, min_nodes=10, library=None):
    """Compare the submissions' functions with the library, the masters and each other.

    Parameters
    ----------
    paths : sequence of path
        Notebooks or folders of them, read as ``find_submissions``
        does (``DIR/<student>/*.ipynb`` or ``DIR/<student>_NN_topic.ipynb``).
    threshold : float
        Smallest score (0 to 1) reported; 1 reports identical structure only.
    exercise : str, optional
        Read every notebook as this exercise (as ``particles grade --exercise``).
    root : path, optional
        The course folder with ``solutions/`` (default: found from the current directory).
    min_nodes : int
        Functions with fewer normalized nodes are ignored (and counted in ``short``).
    library : path, optional
        The library package folder (default: the installed ``particles``).

    Returns
    -------
    SimilarityReport

    Raises
    ------
    ValueError
        When a path does not exist, `threshold` is not in [0, 1], `min_nodes`
        is not a non-negative integer, or `exercise` has no master.
    """
    start = time.perf_counter()
    threshold = _check_threshold(threshold)
    if isinstance(min_nodes, bool) or not isinstance(min_nodes, numbers.Integral) or min_nodes < 0:
        raise ValueError(f"min_nodes must be a non-negative integer, got {min_nodes!r}")
    for given in map(Path, paths):
        if not given.exists():
            raise ValueError(f"DIR {given} does not exist (expected a folder of submitted notebooks)")
    root = Path(root).resolve() if root else project_root()
    names = sorted(p.stem for p in (root / "solutions").glob("*.ipynb"))
    if not names:
        raise ValueError(f"no masters in {root / 'solutions'}")
    if exercise is not None and exercise not in names:
        raise ValueError(f"unknown exercise {exercise!r}; expected one of {', '.join(map(repr, names))}")
    units, problems = find_submissions(paths, names, exercise)
    reference, index = _library(_package(library))
    infos = {name: _exercise(root, name, index) for name in sorted({u.exercise for u in units})}
    functions, short, unwritten, read = [], Counter(), Counter(), 0
    for unit in sorted(units, key=lambda u: (u.exercise, u.student)):
        path = next((str(Path(unit.notebook).relative_to(p)) for p in map(Path, paths)
                     if p.is_dir() and Path(unit.notebook).is_relative_to(p)), str(unit.notebook))
        try:
            found, missing, bad = _submission(unit, infos[unit.exercise], path, index)
        except ValueError as error:  # not a readable notebook
            problems.append(str(error))
            continue
        read += 1
        problems += [f"{unit.notebook}: {label} has a syntax error; its functions are not compared" for label in bad]
        unwritten.update(f"{unit.exercise} {n}" for n in missing)
        for f in found:
            if f.size < min_nodes:
                short[f"{f.exercise} {f.name}"] += 1
            else:
                functions.append(f)
    compared = len(functions)
    references = [f for f in [*reference, *(m for i in infos.values() for m in i.masters)]
                  if f.size >= max(min_nodes, 1)]
    stats = {"read_seconds": time.perf_counter() - start}
    clusters = _clusters(functions + references, threshold, stats) if functions else []
    counts = Counter(f.kind for f in references)
    return SimilarityReport(clusters, read, compared, counts, short, unwritten, problems,
                            threshold, min_nodes, time.perf_counter() - start, stats)


# -- output --------------------------------------------------------------------------------------------

def _plural(n, word):
    return f"{n} {word}{'' if n == 1 else 's'}"


def _summary(report):
    lines = [f"{_plural(report.submissions, 'submission')}: {_plural(report.compared, 'function')} compared "
             f"with each other, with {_plural(report.references['library'], 'library function')} and "
             f"{_plural(report.references['master'], 'master solution')} (threshold {report.threshold:.2f}, "
             f"{report.seconds:.1f} s): {_plural(len(report.clusters), 'cluster')}"]
    for title, counts in (("ignored as trivially short (< %d normalized nodes)" % report.min_nodes, report.short),
                          ("not written (the released stub)", report.unwritten)):
        if counts:
            lines.append(f"{title}: " + ", ".join(f"{k} x{n}" for k, n in sorted(counts.items())))
    return lines


def format_table(report, per_cluster=None):
    """The report as text: a summary, then one row per pair (and one line of places), cluster by cluster.

    Parameters
    ----------
    report : SimilarityReport
    per_cluster : int, optional
        Rows shown per cluster (default all); the others are counted.

    Returns
    -------
    str
    """
    lines, indent = _summary(report), " " * 42
    if report.clusters:
        lines += ["", f"{'cluster':>7}  {'score':>5}  {'match':<25} {'function':<50} matches"]
    for cluster in report.clusters:
        for p in cluster.pairs[:per_cluster]:
            lines.append(f"{cluster.number:>7}  {p.score:>5.2f}  {p.match:<25} {p.a.label:<50} {p.b.label}")
            lines.append(f"{indent}{p.a.where:<50} {p.b.where}")
        if per_cluster is not None and len(cluster.pairs) > per_cluster:
            lines.append(f"{indent}... and {_plural(len(cluster.pairs) - per_cluster, 'more pair')} "
                         f"({_plural(len(cluster.students), 'student')} in this cluster)")
    return "\n".join(lines)


_COLUMNS = ["cluster", "score", "match", "students_in_cluster"] + [
    f"{field}_{side}" for side in "ab" for field in ("owner", "kind", "exercise", "function", "role", "path",
                                                         "cell", "line", "nodes")]


def write_report(report, out):
    """Write ``similarity.csv`` (one row per pair) and ``similarity.md`` (cluster by cluster) into `out`.

    Parameters
    ----------
    report : SimilarityReport
    out : path
        Folder, created when missing.

    Returns
    -------
    list of Path
        The two files written.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "similarity.csv", "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(_COLUMNS)
        for cluster in report.clusters:
            for p in cluster.pairs:
                row = [cluster.number, f"{p.score:.3f}", p.match, len(cluster.students)]
                for f in (p.a, p.b):
                    row += [f.owner, f.kind, f.exercise, f.name, f.role, f.path, f.cell, f.line, f.size]
                writer.writerow(row)
    lines = ["# Similarity report", "", *(f"{line}  " for line in _summary(report)), "",
             "Scores compare normalized syntax trees (local names, constants and docstrings removed; "
             "see `particles.course.similarity`). A large cluster holding the master is usually the "
             "expected answer; a small one, or one holding a library function, deserves a look.", ""]
    for cluster in report.clusters:
        lines += [f"## Cluster {cluster.number}: score {cluster.score:.2f}, "
                  f"{_plural(len(cluster.students), 'student')}", "",
                  "| score | match | function | where | matches | where |", "| --- | --- | --- | --- | --- | --- |"]
        lines += [f"| {p.score:.2f} | {p.match} | {p.a.label} | {p.a.where} | {p.b.label} | {p.b.where} |"
                  for p in cluster.pairs]
        lines.append("")
    if report.problems:
        lines += ["## Not compared", "", *(f"* {p}" for p in report.problems), ""]
    (out / "similarity.md").write_text("\n".join(lines), encoding="utf-8")
    return [out / "similarity.csv", out / "similarity.md"]
