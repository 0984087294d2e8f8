"""Which statements of a notebook run in the grader: the rule of :mod:`particles.course.reading.submission`, applied.

:func:`analyse` takes the notebook's top-level statements in order (each a
:class:`Statement`, read by :mod:`particles.course.reading.submission`), classifies them
(definition, constant, assignment computed by a call, item assignment, block,
magic, ...), follows what the definitions in force read as globals
(:mod:`particles.course.reading.scopes`) from statement to statement, and gives each
statement that does not run its reason.
"""

import ast
from dataclasses import dataclass, field

from .magics import magic_call
from .scopes import bound_names, dotted, references

__all__ = ["Statement", "analyse", "providers", "import_names", "import_path"]

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
_WRAPPERS = {  # calls that return a function made from their arguments
    "functools.partial", "functools.lru_cache", "functools.cache", "functools.wraps", "functools.singledispatch",
    "numpy.vectorize", "numpy.frompyfunc", "numba.jit", "numba.njit", "numba.vectorize", "operator.itemgetter",
    "operator.attrgetter", "operator.methodcaller",
}


@dataclass(eq=False)
class Statement:
    """A top-level statement of the notebook, in order, with what the analysis found out about it.

    ``label``, ``line`` and ``end`` say where it is (cell lines), ``node`` is its
    syntax tree (None for a cell skipped whole), ``source`` the Python that runs,
    ``text`` its first line as written; :func:`analyse` fills in the rest.
    """

    label: str
    line: int
    end: int
    node: ast.AST
    source: str
    text: str
    kind: str = "other"  # import, def, decl, magic, assign, update, other
    index: int = 0
    binds: frozenset = frozenset()
    updates: frozenset = frozenset()
    refs: list = field(default_factory=list)
    reason: str = None
    advice: str = ""
    value: str = ""  # for assignments: lambda, cheap, magic, computed
    callable: bool = False  # an assignment to one name whose value a test may call


def _target_roots(target):
    """Names whose values an assignment to `target` binds or changes: ``(bound, changed)``, None if neither."""
    if isinstance(target, ast.Name):
        return {target.id}, set()
    if isinstance(target, ast.Starred):
        return _target_roots(target.value)
    if isinstance(target, (ast.Attribute, ast.Subscript)):
        root = target.value
        while isinstance(root, (ast.Attribute, ast.Subscript)):
            root = root.value
        return (set(), {root.id}) if isinstance(root, ast.Name) else None
    if isinstance(target, (ast.Tuple, ast.List)):
        parts = [_target_roots(t) for t in target.elts]
        if any(p is None for p in parts):
            return None
        return set().union(*[p[0] for p in parts]), set().union(*[p[1] for p in parts])
    return None


def import_names(node):
    """Names an Import or ImportFrom node binds (not those of ``*``)."""
    return {a.asname or a.name.split(".")[0] for a in node.names if a.name != "*"}


def _is_cheap(node, aliases):
    for sub in ast.walk(node):
        if not isinstance(sub, _EXPRESSION_NODES):
            return False
        if isinstance(sub, ast.Call):
            name = dotted(sub.func)
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


def _classify(s, aliases):
    """Set the kind, bound names and, for statements that never run, the reason of `s`."""
    node = s.node
    if isinstance(node, (ast.Import, ast.ImportFrom)):
        s.kind, s.binds = "import", frozenset(import_names(node))
        if s.binds == {"get_ipython"}:
            s.kind, s.reason = "other", "an import of IPython's get_ipython, which the grader provides itself"
    elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        s.kind, s.binds = "def", frozenset([node.name])
    elif isinstance(node, ast.AnnAssign) and node.value is None:
        s.kind = "decl"
    elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        roots = [_target_roots(t) for t in targets]
        if any(r is None for r in roots):
            s.reason = "an assignment to an attribute or an item of something that is not a name"
            return
        s.binds = frozenset().union(*[r[0] for r in roots])
        s.updates = frozenset().union(*[r[1] for r in roots])
        if isinstance(node, ast.AugAssign):
            s.binds, s.updates = frozenset(), s.binds | s.updates
        s.kind = "update" if s.updates else "assign"
        value = node.value
        if isinstance(value, ast.Lambda):
            s.value = "lambda"
        elif magic_call(value):
            s.value = "magic"
        elif _is_cheap(value, aliases) and not isinstance(node, ast.AugAssign):
            s.value = "cheap"
        else:
            s.value = "computed"
    elif isinstance(node, ast.Expr):
        magic = magic_call(node.value)
        if magic and magic[0] in ("system", "getoutput"):
            s.reason = f"a shell command (`!{magic[2].strip()[:40]}`), which the grader does not run"
        elif magic:
            s.reason = f"an IPython magic (`%{magic[1]}`), which the grader does not need"
        elif isinstance(node.value, ast.Constant):
            s.reason = "a bare value"
        else:
            s.reason = "an expression or call (plots, prints and experiments are not run)"
    else:
        keyword = {ast.For: "for", ast.AsyncFor: "for", ast.While: "while", ast.With: "with", ast.If: "if",
                   ast.Try: "try"}.get(type(node), type(node).__name__.lower())
        s.reason = "a top-level loop" if keyword in ("for", "while") else f"a top-level {keyword} statement"
        s.binds = frozenset(bound_names(node))
        s.advice = f"define it at the top level of a cell, outside the `{keyword}` block"


def providers(binders, name, before=None):
    """The statements whose effect on `name` is in force just before statement number `before` (None: at the end).

    The last full binding of `name`, and the item or attribute assignments after it, latest first.
    """
    out = []
    for s in reversed(binders.get(name, ())):
        if before is not None and s.index >= before:
            continue
        out.append(s)
        if name in s.binds:
            break
    return out


def _returns_function(fn):
    """True when the body of function `fn` returns a lambda, a function it defines, or a wrapper call."""
    inner = {n.name for n in ast.walk(fn) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n is not fn}
    inner |= {t.id for n in ast.walk(fn) if isinstance(n, ast.Assign) and isinstance(n.value, ast.Lambda)
              for t in n.targets if isinstance(t, ast.Name)}
    for node in ast.walk(fn):
        if isinstance(node, ast.Return) and node.value is not None:
            value = node.value
            if isinstance(value, ast.Lambda) or (isinstance(value, ast.Name) and value.id in inner):
                return True
            if isinstance(value, ast.Call) and (dotted(value.func) or "").split(".")[-1] in ("partial", "vectorize"):
                return True
    return False


def import_path(node, name):
    """The dotted path that import statement `node` binds to `name`, or None."""
    for alias in node.names:
        if isinstance(node, ast.Import):
            if alias.asname == name:
                return alias.name
            if not alias.asname and alias.name.split(".")[0] == name:
                return name
        elif (alias.asname or alias.name) == name and node.module and not node.level:
            return f"{node.module}.{alias.name}"
    return None


def _is_callable_value(s, binders, called):
    """True when assignment `s` (to one name) makes something a test may call (see :mod:`particles.course.reading.submission`)."""
    if s.binds & called:
        return True
    for name in s.binds:
        if any(o is not s and (o.kind == "def" or o.value == "lambda") for o in binders.get(name, ())):
            return True
    value = s.node.value
    if not isinstance(value, ast.Call):
        return False
    func = value.func.func if isinstance(value.func, ast.Call) else value.func  # lru_cache(maxsize=8)(f)
    chain = dotted(func)
    if chain is None:
        return False
    root, _, rest = chain.partition(".")
    for p in providers(binders, root, s.index)[:1]:
        if p.kind == "import":
            path = (import_path(p.node, root) or root) + ("." + rest if rest else "")
            return path in _WRAPPERS
        if not rest and isinstance(p.node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            return _returns_function(p.node)
        if not rest and isinstance(p.node, ast.ClassDef):
            return any(isinstance(n, ast.FunctionDef) and n.name == "__call__" for n in p.node.body)
    return False


def _needed(statements, binders, called):
    """The statements that something the tests can reach needs (see :mod:`particles.course.reading.submission`).

    `statements` are those that may run, `binders` maps a name to those among
    them that bind or change it, `called` holds the names the notebook calls.
    """
    for s in statements:
        if s.kind == "assign" and s.value in ("computed", "magic") and len(s.binds) == 1:
            s.callable = _is_callable_value(s, binders, called)
    reached, work = set(), []

    def reach(s, full):
        if (s, full) not in reached:
            reached.add((s, full))
            work.append((s, full))

    for s in statements:  # what always runs: its decorators, defaults and class bodies
        if s.kind in ("import", "def", "decl", "magic") or s.value == "lambda":
            reach(s, False)
    for name in binders:  # the definitions in force at the end, and changes after them: what a test may call
        in_force = providers(binders, name)
        last = in_force[-1] if in_force else None
        if last is not None and name in last.binds and (last.kind in ("import", "def") or last.value == "lambda"
                                                        or last.callable):
            for p in in_force:
                reach(p, True)
    while work:
        s, full = work.pop()
        for ref in s.refs:
            if ref.deferred and not full:
                continue
            for p in providers(binders, ref.name, None if ref.deferred else s.index):
                reach(p, True)
    return {s for s, _ in reached}


def analyse(statements, aliases):
    """Decide what runs: set ``reason`` (and ``advice``) on every statement that is skipped.

    Parameters
    ----------
    statements : list of Statement
        The notebook's top-level statements in notebook order; those skipped
        already (a ``%%timeit`` cell) carry their reason and no syntax tree.
    aliases : dict
        Name -> module path of the notebook's imports (``{"np": "numpy"}``), to
        recognise the cheap constructors of constants.
    """
    for index, s in enumerate(statements):
        s.index = index
        if s.node is not None:
            if s.kind == "other" and s.reason is None:
                _classify(s, aliases)
            s.refs = references(s.node)
    binders = {}
    for s in statements:
        if s.reason is None:
            for name in s.binds | s.updates:
                binders.setdefault(name, []).append(s)
    called = {r.name for s in statements for r in s.refs if r.call and r.chain == r.name}
    needed = _needed([s for s in statements if s.reason is None], binders, called)
    available, unavailable = set(), {}
    for s in statements:
        if s.reason is None and s.kind in ("assign", "update"):
            if not (s in needed or (s.kind == "assign" and s.value in ("cheap", "lambda"))):
                names = " or ".join(f"`{n}`" for n in sorted(s.binds | s.updates)[:3])
                if s.kind == "update":
                    s.reason = f"a change to {names}, which no function of the notebook uses"
                elif s.value == "magic":
                    magic = magic_call(s.node.value)
                    shown = f"`%{magic[1]}`" if magic[1] else "a shell command"
                    s.reason = f"an IPython magic ({shown}) whose result {names} no function of the notebook uses"
                else:
                    what = "a call" if any(isinstance(n, ast.Call) for n in ast.walk(s.node.value)) else "code"
                    s.reason = (f"an assignment computed by {what}, and no function of the notebook uses {names} "
                                "(the grader does not run experiments)")
            else:
                missing = next((r.name for r in s.refs if not r.deferred and r.name in unavailable), None)
                if missing is not None:
                    origin = unavailable[missing]
                    s.reason = (f"an assignment that uses `{missing}`, which the grader did not compute (it skipped "
                                f"`{origin.text}`, {origin.label}, line {origin.line})")
                    s.advice = "compute it inside the function that needs it, or from constants"
        if s.reason is None:
            available |= s.binds
            for name in s.binds:
                unavailable.pop(name, None)
        else:
            for name in s.binds:
                if s.kind in ("assign", "update") or name not in available:
                    unavailable[name] = s
                    available.discard(name)

