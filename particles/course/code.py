"""Which parts of a submitted notebook run in the grader, and what they use.

The grader runs the *definitions* of a notebook, not its experiments. From
every code cell it keeps the top-level statements that are

* imports (``import numpy as np``, ``from math import pi``),
* function and class definitions (``def``, ``class``, with their decorators),
* assignments of constants to plain names (``g = 9.81``,
  ``X0 = np.array([[1.0], [0.0]])``, ``k, L0 = 10.0, 0.5``), where the value
  uses only literals, names, arithmetic, indexing and a few cheap
  constructors (``np.array``, ``np.zeros``, ``np.linspace``, ``float``, ...),

and skips everything else: expression statements (plots, prints, calls that
run an experiment), loops, ``with``/``if``/``try`` blocks at top level,
assignments from other calls (``t, X = simulate(...)``), and IPython magics
(``%matplotlib inline``, ``!pip``, ``%%time`` cells). Each kept statement runs
separately with a time limit, so one failing statement does not hide the
definitions after it. A function that a test needs is therefore defined even
when the plotting cell below it is slow or broken.

The same syntax trees give each function's parameter names (for messages)
and the library names it uses, directly or through the submission's other
functions, which is how forbidden calls are found (:meth:`SubmissionCode.forbidden_uses`).
"""

import ast
import json
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Chunk", "Skipped", "SubmissionCode", "notebook_cells", "read_submission"]

_CHEAP_CALLS = {
    "array", "asarray", "zeros", "ones", "full", "eye", "identity", "linspace", "arange", "sqrt",
    "radians", "deg2rad", "float64", "int64", "default_rng", "exp", "log", "sin", "cos", "tan", "pi",
    "diag", "reshape",
}
_CHEAP_BUILTINS = {"float", "int", "complex", "bool", "str", "tuple", "list", "dict", "set", "frozenset",
                   "range", "len", "abs", "min", "max", "round", "sum"}
_MODULES_FOR_CHEAP_CALLS = {"numpy", "math"}
_EXPRESSION_NODES = (
    ast.Constant, ast.Name, ast.Load, ast.Attribute, ast.Tuple, ast.List, ast.Set, ast.Dict, ast.UnaryOp,
    ast.BinOp, ast.BoolOp, ast.Compare, ast.IfExp, ast.Subscript, ast.Slice, ast.Starred, ast.keyword,
    ast.operator, ast.unaryop, ast.boolop, ast.cmpop, ast.expr_context, ast.Call,
)


@dataclass
class Chunk:
    """One statement that runs in the worker: where it is, and its source."""

    label: str
    line: int
    source: str


@dataclass
class Skipped:
    """One top-level statement the grader does not run, and why."""

    label: str
    line: int
    text: str
    reason: str
    names: tuple = ()


def notebook_cells(path):
    """The code cells of notebook `path` as ``(label, source)``, e.g. ``("code cell 3", "def f...")``.

    Raises
    ------
    ValueError
        When the file is not a readable notebook: not JSON, no list of
        ``cells``, or a code cell whose ``source`` is neither a string nor a
        list of strings.
    """
    try:
        notebook = json.loads(Path(path).read_text(encoding="utf-8"))
        cells = notebook["cells"]
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError) as error:
        raise ValueError(f"{path} is not a readable Jupyter notebook ({type(error).__name__}: {error})") from None
    if not isinstance(cells, list):
        raise ValueError(f"{path} is not a readable Jupyter notebook (its cells are a {type(cells).__name__}, "
                         "not a list)")
    out, k = [], 0
    for cell in cells:
        if not isinstance(cell, dict) or cell.get("cell_type") != "code":
            continue
        k += 1
        source = cell.get("source", "")
        if isinstance(source, list) and all(isinstance(line, str) for line in source):
            source = "".join(source)
        elif not isinstance(source, str):
            raise ValueError(f"{path} is not a readable Jupyter notebook (the source of code cell {k} holds "
                             f"{_kind_of(source)}, not text)")
        out.append((f"code cell {k}", source))
    return out


def _kind_of(source):
    """What a cell's source holds when it is not text, e.g. "a list with an item of type int"."""
    if isinstance(source, list):
        bad = next(line for line in source if not isinstance(line, str))
        return f"a list with an item of type {type(bad).__name__}"
    return f"a value of type {type(source).__name__}"


def _strip_magics(source):
    """Blank out IPython line magics and shell escapes, keeping line numbers."""
    return "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in source.split("\n"))


def _dotted(node):
    """'np.linalg.norm' for a Name/Attribute chain, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
        return ".".join(reversed(parts))
    return None


class _Aliases(ast.NodeVisitor):
    """Local name -> full module or object path, from every import statement."""

    def __init__(self):
        self.map, self.star = {}, []

    def visit_Import(self, node):
        for alias in node.names:
            if alias.asname:
                self.map[alias.asname] = alias.name
            else:
                root = alias.name.split(".")[0]
                self.map[root] = root

    def visit_ImportFrom(self, node):
        if node.level or not node.module:
            return
        for alias in node.names:
            if alias.name == "*":
                self.star.append(node.module)
            else:
                self.map[alias.asname or alias.name] = f"{node.module}.{alias.name}"


def _is_cheap(node, aliases):
    for sub in ast.walk(node):
        if not isinstance(sub, _EXPRESSION_NODES):
            return False
        if isinstance(sub, ast.Call):
            name = _dotted(sub.func)
            if name is None:
                return False
            parts = name.split(".")
            if len(parts) == 1:
                if parts[0] not in _CHEAP_BUILTINS:
                    return False
            else:
                module = aliases.get(parts[0], parts[0]).split(".")[0]
                if module not in _MODULES_FOR_CHEAP_CALLS or parts[-1] not in _CHEAP_CALLS:
                    return False
    return True


def _target_names(target):
    if isinstance(target, ast.Name):
        return [target.id]
    if isinstance(target, (ast.Tuple, ast.List)):
        names = [_target_names(t) for t in target.elts]
        return None if any(n is None for n in names) else [x for n in names for x in n]
    return None


def _defined_names(stmt):
    if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return [stmt.name]
    if isinstance(stmt, (ast.Import, ast.ImportFrom)):
        return [a.asname or a.name.split(".")[0] for a in stmt.names if a.name != "*"]
    if isinstance(stmt, ast.Assign):
        return [n for t in stmt.targets for n in (_target_names(t) or [])]
    if isinstance(stmt, ast.AnnAssign):
        return _target_names(stmt.target) or []
    return []


def _classify(stmt, aliases):
    """None when `stmt` runs in the grader, else the reason it is skipped."""
    if isinstance(stmt, (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return None
    if isinstance(stmt, (ast.Assign, ast.AnnAssign)):
        targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
        if any(_target_names(t) is None for t in targets):
            return "an assignment to an attribute or an item"
        if stmt.value is None:
            return None
        if _is_cheap(stmt.value, aliases):
            return None
        return "an assignment computed by a call (only constants are assigned in the grader)"
    if isinstance(stmt, ast.Expr):
        if isinstance(stmt.value, ast.Constant):
            return "a bare value"
        return "an expression or call (plots, prints and experiments are not run)"
    if isinstance(stmt, (ast.For, ast.While, ast.AsyncFor)):
        return "a top-level loop"
    return f"a top-level {type(stmt).__name__.lower()} statement"


@dataclass
class SubmissionCode:
    """The statements of a submission that run in the grader, and an analysis of them.

    Build it with :func:`read_submission` (a notebook) or :meth:`from_cells`.
    """

    chunks: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    syntax_errors: list = field(default_factory=list)
    _statements: list = field(default_factory=list, repr=False)
    _aliases: dict = field(default_factory=dict, repr=False)
    _star: list = field(default_factory=list, repr=False)

    @classmethod
    def from_cells(cls, cells):
        """Analyse ``(label, source)`` pairs, in notebook order."""
        code = cls()
        parsed = []
        for label, source in cells:
            if source.lstrip().startswith("%%"):
                first = source.strip().splitlines()[0]
                code.skipped.append(Skipped(label, 1, first[:60], "a cell magic"))
                continue
            source = _strip_magics(source)
            try:
                tree = ast.parse(source)
            except (SyntaxError, ValueError) as error:  # ValueError: a null byte, before Python 3.12
                where = f"line {error.lineno}: " if getattr(error, "lineno", None) else ""
                code.syntax_errors.append((label, f"{where}{getattr(error, 'msg', None) or error}"))
                continue
            parsed.append((label, source, tree))
        aliases = _Aliases()
        for _, _, tree in parsed:
            aliases.visit(tree)  # imports at any depth, inside functions too
        code._aliases, code._star = aliases.map, aliases.star
        unavailable = set()  # names last bound by a statement the grader skips
        for label, source, tree in parsed:
            lines = source.split("\n")
            spans = [(min([d.lineno for d in getattr(s, "decorator_list", [])] + [s.lineno]), s.end_lineno)
                     for s in tree.body]
            for k, stmt in enumerate(tree.body):
                start, end = spans[k]
                reason = _classify(stmt, aliases.map)
                if reason is None and isinstance(stmt, (ast.Assign, ast.AnnAssign)) and stmt.value is not None:
                    used = sorted({n.id for n in ast.walk(stmt.value) if isinstance(n, ast.Name)} & unavailable)
                    if used:
                        reason = f"an assignment that uses `{used[0]}`, which the grader did not compute"
                names = set(_defined_names(stmt))
                if reason is not None and isinstance(stmt, (ast.Assign, ast.AnnAssign)):
                    unavailable |= names
                elif reason is None:
                    unavailable -= names
                if reason is not None:
                    text = lines[start - 1].strip()[:60]
                    code.skipped.append(Skipped(label, start, text, reason, tuple(_defined_names(stmt))))
                    continue
                shared = any(k != j and not (e < start or s > end) for j, (s, e) in enumerate(spans))
                if shared:
                    text = ast.get_source_segment(source, stmt) or ast.unparse(stmt)
                    start = stmt.lineno
                else:
                    text = "\n".join(lines[start - 1:end])
                code.chunks.append(Chunk(label, start, text))
                code._statements.append((label, stmt))
        return code

    def defines(self):
        """Top-level names the kept statements define, mapped to (label, line)."""
        out = {}
        for label, stmt in self._statements:
            for name in _defined_names(stmt):
                out[name] = (label, stmt.lineno)
        return out

    def skipped_assignment(self, name):
        """The skipped statement that would have defined `name`, or None."""
        return next((skip for skip in reversed(self.skipped) if name in skip.names), None)

    def parameters(self, name):
        """Parameter names of the last top-level ``def name(...)``, or None."""
        found = None
        for _, stmt in self._statements:
            if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef)) and stmt.name == name:
                a = stmt.args
                found = [p.arg for p in a.posonlyargs + a.args]
        return found

    def forbidden_uses(self, name, forbidden):
        """Forbidden library names that function `name` uses (see :func:`particles.course.forbidden.forbidden_uses`)."""
        from .forbidden import forbidden_uses

        return forbidden_uses(self, name, forbidden)


def read_submission(path):
    """:class:`SubmissionCode` of the notebook at `path`."""
    return SubmissionCode.from_cells(notebook_cells(path))

