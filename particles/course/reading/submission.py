"""Which parts of a submitted notebook run in the grader, and what they use.

Cells are read as Jupyter runs them (:mod:`particles.course.reading.magics`): IPython's
own transformer turns magics and ``!`` commands into ``get_ipython()`` calls,
which the worker answers with a stand-in shell
(:mod:`particles.course.reading.ipython_shim`). A ``%%time``, ``%%capture`` or
``%%prun`` cell counts as the code it wraps, and ``%time stmt`` as ``stmt``; a
``%%timeit`` cell does not, since Jupyter runs it in a namespace of its own
and nothing it defines stays defined.

What runs is decided by what each top-level statement does, not by its
syntax alone:

* **definitions always run**: imports, ``def`` and ``class`` (with their
  decorators), assignments of a ``lambda``, and ``%%writefile`` cells that
  write a file in the working folder;
* **constants run**: assignments whose value uses only literals, names,
  arithmetic, indexing and a few cheap constructors (``g = 9.81``,
  ``X0 = np.array([[1.0], [0.0]])``), unless they use a name the grader did
  not compute;
* **other assignments run when they are needed**: an assignment computed by a
  call (``EPS = np.finfo(float).eps``, ``CASES = dict(a=Thing(1))``,
  ``x = %timeit -o f()``), an item or attribute assignment and ``+=`` run
  when they bind a name that a function or class the tests can reach reads as
  a global, or that another statement that runs reads (transitively); and an
  assignment to a single name runs when its value is **callable**, so that a
  test may call it: a wrapper (``functools.partial``, ``np.vectorize``), a call
  of the notebook's own function that returns a function or of its own class
  with ``__call__``, or a name that the notebook calls (``name(...)``) or also
  defines with ``def``;
* **everything else is skipped**, with its reason: expression statements
  (plots, prints, experiments), top-level loops, ``if``, ``with`` and ``try``
  blocks, other magics and shell commands, and assignments nothing needs
  (``t, X = simulate(...)`` whose result no function uses).

The last definition of a name wins, as when the notebook runs from top to
bottom: a global read inside a function is the name's last binding in the
notebook, a name read by a top-level statement its last binding above it.
What the tests can reach starts from the definitions in force at the end, so a
draft redefined further down neither pulls in what it used nor counts for the
forbidden-use check or :meth:`SubmissionCode.parameters`.

This keeps grading as fast as running definitions only: the experiments of the
masters (``t, X = run(...)``, a stability study) are assignments no function
reads. Each kept statement runs separately with a time limit, so one failing
statement does not hide the definitions after it. The rule is applied by
:mod:`particles.course.reading.selection`; when a test needs a name the grader skipped,
:meth:`SubmissionCode.explain_missing` says which statement, where, and why.

The same syntax trees, with names resolved by scope
(:mod:`particles.course.reading.scopes`), give each function's parameter names (for
messages) and the library names it uses, directly or through the submission's
other functions and constants (:meth:`SubmissionCode.forbidden_uses`).
"""

import ast
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from .magics import magic_call, to_python, transformer
from .scopes import bound_names
from .selection import Statement, analyse, import_names, import_path, providers

__all__ = ["Chunk", "Skipped", "SubmissionCode", "notebook_cells", "read_submission"]

_WRAPPING_CELL_MAGICS = {"time", "capture", "prun"}  # run the body in the notebook's namespace


@dataclass
class Chunk:
    """One statement that runs in the worker: where it is, and its source."""

    label: str
    line: int
    source: str
    provided: bool = False  # from a cell the course provides, unchanged (see SubmissionCode.from_cells)


@dataclass
class Skipped:
    """One top-level statement the grader does not run, why, and the names it would have bound."""

    label: str
    line: int
    text: str
    reason: str
    names: tuple = ()
    advice: str = ""


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


# -- reading cells ----------------------------------------------------------------------------

def _names_in(source):
    """Top-level names a piece of Python would bind (for messages), () when it does not parse."""
    try:
        tree = ast.parse(to_python(source))
    except (SyntaxError, ValueError):
        return ()
    return tuple(sorted(set().union(*[bound_names(s) for s in tree.body])))


def _first_line(source):
    """1-based number of the first line of `source` that is not blank."""
    return next((k for k, line in enumerate(source.split("\n"), start=1) if line.strip()), 1)


def _skip(label, line, text, reason, names=(), advice=""):
    return Statement(label, line, line, None, "", text[:60], reason=reason, binds=frozenset(names), advice=advice)


def _read_cell(label, source, offset, out, errors):
    """Append the top-level statements of `source` (a cell, or the body of a ``%%time`` cell) to `out`.

    `offset` is the number of cell lines above `source`; syntax errors go to `errors`.
    """
    manager = transformer()
    if manager is None and source.lstrip().startswith("%%"):
        first = _first_line(source)
        body = "\n".join(source.split("\n")[first:])
        out.append(_skip(label, offset + first, source.split("\n")[first - 1].strip(), "a cell magic",
                         _names_in(body), "move the definition to a cell without a magic"))
        return
    try:
        python = source
        tree = ast.parse(python)  # plain Python: Jupyter runs it as it is
    except (SyntaxError, ValueError):
        python = to_python(source, manager)
        try:
            tree = ast.parse(python)
        except (SyntaxError, ValueError) as error:  # ValueError: a null byte, before Python 3.12
            where = f"line {error.lineno + offset}: " if getattr(error, "lineno", None) else ""
            errors.append((label, f"{where}{getattr(error, 'msg', None) or error}"))
            return
    original, lines = source.split("\n"), python.split("\n")
    spans = [(min([d.lineno for d in getattr(s, "decorator_list", [])] + [s.lineno]), s.end_lineno) for s in tree.body]
    for k, stmt in enumerate(tree.body):
        start, end = spans[k]
        text = (original[start - 1] if start <= len(original) else lines[start - 1]).strip()
        magic = magic_call(stmt.value) if isinstance(stmt, ast.Expr) else None
        if magic and magic[0] == "run_cell_magic":
            _read_cell_magic(label, source, offset, magic, stmt, out, errors)
            continue
        if magic and magic[0] == "run_line_magic" and magic[1] == "time" and magic[2].strip():
            _read_cell(label, magic[2].strip(), offset + start - 1, out, errors)  # `%time x = f()` binds x
            continue
        shared = any(k != j and not (e < start or s > end) for j, (s, e) in enumerate(spans))
        if shared:
            chunk, start = ast.get_source_segment(python, stmt) or ast.unparse(stmt), stmt.lineno
        else:
            chunk = "\n".join(lines[start - 1:end])
        out.append(Statement(label, offset + start, offset + end, stmt, chunk, text[:60]))


def _read_cell_magic(label, source, offset, magic, stmt, out, errors):
    _, name, line, body = magic
    first = offset + _first_line(source)  # the %% line; the body starts below it
    header = f"%%{name} {line}".strip()
    if name in _WRAPPING_CELL_MAGICS:
        _read_cell(label, body, first, out, errors)
    elif name == "timeit":
        out.append(_skip(label, first, header, "a %%timeit cell, which Jupyter runs in a namespace of its own "
                         "(what it defines does not stay defined)", _names_in(body),
                         "move the definition to a cell without %%timeit"))
    elif name in ("writefile", "file") and re.fullmatch(r"(-a\s+)?[\w.-]+", line.strip()) and ".." not in line:
        python = ast.unparse(stmt)
        out.append(Statement(label, first, first, stmt, python, header[:60], kind="magic"))
    else:
        out.append(_skip(label, first, header, f"a %%{name} cell, which the grader does not run", _names_in(body),
                         f"move the definition to a cell without %%{name}"))


# -- the analysis -----------------------------------------------------------------------------

@dataclass
class SubmissionCode:
    """The statements of a submission that run in the grader, and an analysis of them.

    Build it with :func:`read_submission` (a notebook) or :meth:`from_cells`.
    """

    chunks: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    syntax_errors: list = field(default_factory=list)
    _statements: list = field(default_factory=list, repr=False)
    _binders: dict = field(default_factory=dict, repr=False)
    _cache: dict = field(default_factory=dict, repr=False)
    provided_labels: set = field(default_factory=set)

    @classmethod
    def from_cells(cls, cells, provided=()):
        """Analyse ``(label, source)`` pairs, in notebook order.

        Parameters
        ----------
        cells : list of (str, str)
            Labels and sources of the code cells.
        provided : iterable of str, optional
            Sources of the cells the course provides (see
            :func:`particles.course.reading.provided.provided_cells`). A cell whose
            source is one of them, up to trailing white space, is the course's:
            its statements may use what the exercise forbids, and its errors
            are not the student's (:meth:`student_load_errors`). A cell the
            student changed is the student's.
        """
        code = cls()
        given = {normalized_source(p) for p in provided}
        statements = []
        code.provided_labels = set()
        for label, source in cells:
            if given and normalized_source(source) in given:
                code.provided_labels.add(label)
            _read_cell(label, source, 0, statements, code.syntax_errors)
        aliases = {}
        for s in statements:
            if isinstance(s.node, (ast.Import, ast.ImportFrom)):
                for name in import_names(s.node):
                    aliases[name] = import_path(s.node, name) or name
        analyse(statements, aliases)
        for s in statements:
            if s.reason is not None:
                code.skipped.append(Skipped(s.label, s.line, s.text, s.reason, tuple(sorted(s.binds | s.updates)),
                                            s.advice))
                continue
            code.chunks.append(Chunk(s.label, s.line, s.source, s.label in code.provided_labels))
            code._statements.append(s)
            for name in s.binds | s.updates:
                code._binders.setdefault(name, []).append(s)
        return code

    def _in_force(self, name, before=None):
        """The kept statements whose effect on `name` is in force before statement `before` (None: at the end)."""
        return providers(self._binders, name, before)

    def _definition(self, name):
        """The kept statement that last binds `name` as a whole, or None."""
        return next((s for s in self._in_force(name) if name in s.binds), None)

    def defines(self):
        """Top-level names the kept statements define, mapped to (label, line) of their last definition."""
        return {name: (s.label, s.line) for name in self._binders
                for s in [self._definition(name)] if s is not None}

    def skipped_assignment(self, name):
        """The last skipped statement that would have bound `name` (an assignment, a block, a cell), or None."""
        return next((skip for skip in reversed(self.skipped) if name in skip.names), None)

    def parameters(self, name):
        """Parameter names of the definition of `name` in force (a ``def`` or a ``lambda``), or None."""
        s = self._definition(name)
        node = None if s is None else s.node
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args
        elif isinstance(node, (ast.Assign, ast.AnnAssign)) and isinstance(node.value, ast.Lambda):
            args = node.value.args
        else:
            return None
        return [p.arg for p in args.posonlyargs + args.args]

    def forbidden_uses(self, name, forbidden):
        """Forbidden library names that function `name` uses (see :func:`particles.course.reading.forbidden.forbidden_uses`)."""
        from .forbidden import forbidden_uses

        key = (name, tuple(sorted(forbidden)))
        if key not in self._cache:
            self._cache[key] = forbidden_uses(self, name, forbidden)
        return list(self._cache[key])

    def student_load_errors(self, load_errors):
        """The load errors the student caused: those of the course's cells that only follow from others dropped.

        A provided cell that calls a function still unwritten raises
        ``NotImplementedError``; one that reads a name an earlier failure
        left unbound raises ``NameError``. Neither is the student's mistake
        (the unwritten functions are reported by the tests). Any other error
        of a provided cell is kept: the student's code made it fail.
        """
        bound = set(self._binders)
        kept = []
        for error in load_errors:
            if error.get("label") in self.provided_labels:
                if error.get("type") == "NotImplementedError":
                    continue
                message = str(error.get("message", ""))
                if error.get("type") == "NameError" and message.count("'") >= 2 and (
                        message.split("'")[1] in bound or any(e is not error for e in load_errors)):
                    continue
            kept.append(error)
        return kept

    def explain_missing(self, name, load_errors=()):
        """Why `name` is missing in the worker although the notebook binds it, as a clause; None if it does not.

        Parameters
        ----------
        name : str
            A top-level name.
        load_errors : list of dict
            The worker's errors from loading the notebook (``label``, ``where``, ``type``, ``message``).

        Returns
        -------
        str or None
            E.g. "the grader skipped `%%timeit` (code cell 3, line 1) because it
            is a %%timeit cell, ...; move the definition to a cell without %%timeit".
        """
        s = self._definition(name)
        if s is not None:
            same_cell = [c for c in self._statements if c.label == s.label]
            for error in load_errors:
                line = re.match(rf"{re.escape(s.label)}, line (\d+)", error.get("where", ""))
                inside = line is not None and s.line <= int(line.group(1)) <= s.end
                if error.get("label") == s.label and (inside or (line is None and len(same_cell) == 1)):
                    return (f"the grader ran `{s.text}` ({s.label}, line {s.line}), which raised "
                            f"{error.get('type')}: {error.get('message')}")
            return None
        skip = self.skipped_assignment(name)
        if skip is None:
            return None
        advice = skip.advice or f"define `{name}` with `def`"
        return (f"the grader skipped `{skip.text}` ({skip.label}, line {skip.line}) because it is {skip.reason}; "
                f"{advice}")


def normalized_source(source):
    """A cell's source without trailing white space on its lines and around it (how cells are compared)."""
    return "\n".join(line.rstrip() for line in str(source).strip().split("\n"))


def read_submission(path):
    """:class:`SubmissionCode` of the notebook at `path`."""
    return SubmissionCode.from_cells(notebook_cells(path))
