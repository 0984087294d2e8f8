"""Where the names of a notebook statement resolve: to a local of some function, or to the notebook.

A name inside a function is the notebook's global only when Python would
look it up there: not when it is a parameter, a local variable, a
comprehension variable or a local import of that function or of an
enclosing one (class bodies are not enclosing scopes for the functions
inside them, as in Python). :func:`references` lists, for one top-level
statement, every name that resolves to the notebook's namespace, with the
attribute chain written after it (``I.euler``) and whether it is read when
the statement runs or only when a function it defines is called; names bound
to a local ``import`` carry the imported path instead. The grader uses this
to decide which assignments the functions need (:mod:`particles.course.reading.submission`)
and which library objects they use (:mod:`particles.course.reading.forbidden`).
"""

import ast
from dataclasses import dataclass

__all__ = ["Reference", "references", "bound_names", "dotted"]


@dataclass(frozen=True)
class Reference:
    """One use of a name in a statement.

    Attributes
    ----------
    name : str
        The name as written, e.g. ``"I"`` in ``I.euler(f, X, t, h)``.
    chain : str
        The name and the attributes after it, e.g. ``"I.euler"``.
    deferred : bool
        True inside a function or lambda body: read when it is called, after the
        whole notebook ran, not when the statement runs.
    call : bool
        The chain is called, ``name(...)``.
    imported : str or None
        For a local name bound by an ``import`` in its function: the imported
        path and the attributes, e.g. ``"particles.integrators.euler"``. None for
        a name of the notebook.
    """

    name: str
    chain: str
    deferred: bool
    call: bool = False
    imported: str = None


def dotted(node):
    """``"np.linalg.norm"`` for a chain of Name and Attribute nodes, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
        return ".".join(reversed(parts))
    return None


def _import_bindings(node):
    """``{bound name: imported path}`` of an Import or ImportFrom node (relative imports: path None)."""
    out = {}
    for alias in node.names:
        if alias.name == "*":
            continue
        if isinstance(node, ast.Import):
            if alias.asname:
                out[alias.asname] = alias.name
            else:
                root = alias.name.split(".")[0]
                out[root] = root
        else:
            absolute = node.module and not node.level
            out[alias.asname or alias.name] = f"{node.module}.{alias.name}" if absolute else None
    return out


_COMPREHENSIONS = (ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp)


def _scope_bindings(nodes):
    """Names local to one scope's code, the local imports among them, and the names it declares ``global``."""
    bound, imports, declared, outer = set(), {}, set(), set()
    stack = list(nodes)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            bound.add(node.name)
            continue
        if isinstance(node, ast.Lambda):
            continue
        if isinstance(node, _COMPREHENSIONS):  # only `:=` inside binds in the enclosing scope
            bound.update(n.target.id for n in ast.walk(node) if isinstance(n, ast.NamedExpr))
            continue
        if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            bound.add(node.id)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for name, path in _import_bindings(node).items():
                bound.add(name)
                if path is not None:
                    imports[name] = path
        elif isinstance(node, ast.Global):
            declared.update(node.names)
        elif isinstance(node, ast.Nonlocal):
            outer.update(node.names)
        elif isinstance(node, ast.ExceptHandler) and node.name:
            bound.add(node.name)
        elif isinstance(node, (ast.MatchAs, ast.MatchStar)) and node.name:
            bound.add(node.name)
        elif isinstance(node, ast.MatchMapping) and node.rest:
            bound.add(node.rest)
        stack.extend(ast.iter_child_nodes(node))
    local = bound - declared - outer  # `global` and `nonlocal` names are not this scope's
    return local, {k: v for k, v in imports.items() if k in local}, declared


def bound_names(stmt):
    """Names a top-level statement binds in the notebook (inside ``if``, ``for``, ``with``, ``try`` too)."""
    bound, _, _ = _scope_bindings([stmt])
    return bound


def _arguments(args):
    return [a.arg for a in args.posonlyargs + args.args + args.kwonlyargs + [args.vararg, args.kwarg] if a]


class _Scope:
    def __init__(self, kind, bound=(), imports=None, declared=()):
        self.kind, self.bound, self.imports, self.declared = kind, set(bound), dict(imports or {}), set(declared)


class _Visitor(ast.NodeVisitor):
    """Walks one top-level statement with a stack of scopes, collecting :class:`Reference` objects."""

    def __init__(self):
        self.scopes = [_Scope("module")]
        self.found = []

    def _resolve(self, name):
        """None when `name` is the notebook's, else the local import path or ``""`` for another local."""
        for depth, scope in enumerate(reversed(self.scopes)):
            if scope.kind == "module":
                return None
            if scope.kind == "class" and depth > 0:
                continue  # a class body is not an enclosing scope of the functions in it
            if name in scope.declared:
                return None  # `global name`
            if name in scope.bound:
                return scope.imports.get(name, "")
        return None

    def _record(self, chain, call=False):
        name, _, rest = chain.partition(".")
        local = self._resolve(name)
        deferred = any(s.kind in ("function", "lambda") for s in self.scopes)
        if local is None:
            self.found.append(Reference(name, chain, deferred, call))
        elif local:
            self.found.append(Reference(name, chain, deferred, call, local + ("." + rest if rest else "")))

    def visit_Name(self, node):
        if isinstance(node.ctx, ast.Load):
            self._record(node.id)

    def visit_Attribute(self, node):
        chain = dotted(node)
        if chain is None or not isinstance(node.ctx, ast.Load):
            self.visit(node.value)
        else:
            self._record(chain)

    def visit_AugAssign(self, node):
        if isinstance(node.target, ast.Name):  # `x += 1` reads x
            self._record(node.target.id)
        self.generic_visit(node)

    def visit_Call(self, node):
        chain = dotted(node.func)
        if chain is None:
            self.visit(node.func)
        else:
            self._record(chain, call=True)
        if (chain == "getattr" and self._resolve("getattr") is None and len(node.args) >= 2
                and dotted(node.args[0]) and isinstance(node.args[1], ast.Constant)
                and isinstance(node.args[1].value, str)):
            self._record(f"{dotted(node.args[0])}.{node.args[1].value}")
        for child in node.args + [k.value for k in node.keywords]:
            self.visit(child)

    def _visit_signature(self, node):
        args = node.args
        for default in args.defaults + [d for d in args.kw_defaults if d is not None]:
            self.visit(default)
        if not isinstance(node, ast.Lambda):
            for a in args.posonlyargs + args.args + args.kwonlyargs + [args.vararg, args.kwarg]:
                if a is not None and a.annotation is not None:
                    self.visit(a.annotation)
            if node.returns is not None:
                self.visit(node.returns)

    def visit_FunctionDef(self, node):
        for decorator in node.decorator_list:
            self.visit(decorator)
        self._visit_signature(node)
        bound, imports, declared = _scope_bindings(node.body)
        self.scopes.append(_Scope("function", bound | set(_arguments(node.args)), imports, declared))
        for stmt in node.body:
            self.visit(stmt)
        self.scopes.pop()

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_Lambda(self, node):
        self._visit_signature(node)
        self.scopes.append(_Scope("lambda", _arguments(node.args)))
        self.visit(node.body)
        self.scopes.pop()

    def visit_ClassDef(self, node):
        for child in node.decorator_list + node.bases + [k.value for k in node.keywords]:
            self.visit(child)
        bound, imports, declared = _scope_bindings(node.body)
        self.scopes.append(_Scope("class", bound, imports, declared))
        for stmt in node.body:
            self.visit(stmt)
        self.scopes.pop()

    def _visit_comprehension(self, node, parts):
        first, *others = node.generators
        self.visit(first.iter)  # evaluated in the enclosing scope
        targets = {n.id for g in node.generators for n in ast.walk(g.target) if isinstance(n, ast.Name)}
        self.scopes.append(_Scope("comprehension", targets))
        for condition in first.ifs:
            self.visit(condition)
        for generator in others:
            self.visit(generator.iter)
            for condition in generator.ifs:
                self.visit(condition)
        for part in parts:
            self.visit(part)
        self.scopes.pop()

    def visit_ListComp(self, node):
        self._visit_comprehension(node, [node.elt])

    visit_SetComp = visit_GeneratorExp = visit_ListComp

    def visit_DictComp(self, node):
        self._visit_comprehension(node, [node.key, node.value])


def references(stmt):
    """The names of the notebook that a top-level statement uses, in source order (a list of :class:`Reference`).

    Examples
    --------
    >>> import ast
    >>> stmt = ast.parse("def f(X, h):\\n    midpoint = X + h\\n    return np.add(midpoint, EPS)").body[0]
    >>> [(r.chain, r.deferred) for r in references(stmt)]
    [('np.add', True), ('EPS', True)]
    """
    visitor = _Visitor()
    visitor.visit(stmt)
    return visitor.found
