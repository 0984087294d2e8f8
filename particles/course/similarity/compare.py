"""Similarity report: submitted functions structurally equal to the library, a master or a classmate.

Forbidden-use checks (:mod:`~particles.course.reading.forbidden`) catch calls to the
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
    ``particles/course/``) but those that only return a call (their shape is
    any one-line call's), and the masters' solutions.

Normalization and scoring
    :mod:`particles.course.similarity.fingerprint`: each function's body becomes a
    stream of node tokens with its own names renamed, hashed with and without
    its constants; two functions score 1 for equal structure, else the
    difflib ratio of their token streams. Only candidate pairs are scored
    (MinHash bands of token 3-grams, below).

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
import numbers
import time
import zlib
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..reading.submission import notebook_cells
from ..grading.discovery import find_submissions
from .fingerprint import (Function, fingerprint, make_function, module_context, normalize, score,
                          stub_part)
from ..paths import project_root
from ..release.notebooks import BEGIN, release_notebook

__all__ = ["Function", "Pair", "Cluster", "SimilarityReport", "fingerprint", "score", "library_functions",
           "similarity", "format_table", "write_report"]

_K, _BANDS, _ROWS = 3, 24, 2
_PRIME = np.uint64((1 << 61) - 1)
_RNG = np.random.default_rng(20261201)
_A = _RNG.integers(1, 1 << 31, size=_BANDS * _ROWS, dtype=np.uint64)
_B = _RNG.integers(0, 1 << 31, size=_BANDS * _ROWS, dtype=np.uint64)



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
    stub_context, stub_defs = module_context([s for _, s in stub_statements], library=library), _defs(stub_statements)
    shared = {n: stub_part(stub_defs[n][1], stub_context) for n in asked if n in stub_defs}
    given = {normalize(node, stub_context)[1] for n, (_, node) in stub_defs.items() if n not in asked}
    context, defs = module_context([s for _, s in statements], library=library), _defs(statements)
    masters = [make_function(defs[n][1], context, shared.get(n), owner="master", kind="master", exercise=name,
                         name=n, path=f"solutions/{name}.ipynb", cell=defs[n][0], role="reference")[0]
               for n in asked]
    return _Exercise(name, asked, shared, given, masters)


def _submission(unit, info, path, library):
    """A submission's functions (asked ones and the helpers they use), and the asked names not written."""
    statements, bad = _parse_cells(notebook_cells(unit.notebook))
    context, defs = module_context([s for _, s in statements], library=library), _defs(statements)
    out, unwritten, queue, seen = [], [], [n for n in info.asked if n in defs], set()
    while queue:  # the asked functions, then the notebook's functions they use
        name = queue.pop(0)
        if name in seen:
            continue
        seen.add(name)
        label, node = defs[name]
        asked = name in info.asked
        f, used = make_function(node, context, info.shared.get(name), owner=unit.student, kind="student",
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
def _delegates(func):
    """Whether `func` only returns a call (its docstring aside): a library function that hands its work on.

    Its shape, ``return g(args)``, is that of any one-line student function
    that calls something; what it delegates to is compared in its place.
    """
    body = func.body[1:] if func.body and isinstance(func.body[0], ast.Expr) and \
        isinstance(func.body[0].value, ast.Constant) and isinstance(func.body[0].value.value, str) else func.body
    return len(body) == 1 and isinstance(body[0], ast.Return) and isinstance(body[0].value, ast.Call)


def _sources(folder):
    """The library's source files (``particles/`` except ``particles/course/``), sorted."""
    folder = Path(folder)
    return [path for path in sorted(folder.rglob("*.py"))
            if not ({"course", "__pycache__"} & set(path.relative_to(folder.parent).parts[1:-1]))]


def _library(folder):
    """The library's functions, and (its top-level defs and classes, its re-exports) for :class:`Context`.

    Parsed once per process for each state of the sources (about 2 s): a file that changes (its size or
    modification time) parses them again.
    """
    stamps = tuple((str(p), s.st_mtime_ns, s.st_size) for p, s in ((p, p.stat()) for p in _sources(folder)))
    return _parsed_library(str(folder), stamps)


@lru_cache(maxsize=2)
def _parsed_library(folder, stamps):
    """:func:`_library` for the sources whose ``(path, mtime, size)`` are `stamps` (the cache's key)."""
    folder, modules, defs, reexports = Path(folder), [], set(), {}
    for path in (Path(p) for p, _, _ in stamps):  # a loop over the library's files
        rel = path.relative_to(folder.parent)
        module = ".".join(rel.with_suffix("").parts).removesuffix(".__init__")
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        tree = ast.parse(path.read_text(encoding="utf-8"))
        modules.append((rel, module, tree, module_context(tree.body, package)))
        defs |= {f"{module}.{name}" for name in modules[-1][3].defs}
        reexports.update((f"{module}.{name}", target) for name, target in modules[-1][3].aliases.items())
    index, out = (frozenset(defs), reexports), []
    for rel, module, tree, context in modules:
        context.library = index
        stack = [(module, tree.body)]
        while stack:  # functions and methods at any depth: a loop over scopes
            prefix, body = stack.pop()
            for node in body:
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and not _delegates(node):
                    out.append(make_function(node, context, owner="library", kind="library", exercise="",
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
    return str(Path(folder or Path(__file__).resolve().parents[2]).resolve())


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
             "see `particles.course.similarity.compare`). A large cluster holding the master is usually the "
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
