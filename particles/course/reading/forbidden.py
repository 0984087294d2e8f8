"""Forbidden calls: which library names a submission's function uses.

An exercise that asks for the midpoint step forbids ``particles.integrators.midpoint``.
The check reads the submission's syntax trees (nothing is run). Every name a
function uses is resolved by scope, as Python does (:mod:`particles.course.reading.scopes`):
a parameter, a local variable, a comprehension variable or a local import is
the function's own; a global is the notebook's binding of that name that is
in force (the last one for a name read when the function is called, the last
one above for a name read when a statement runs), so the student's own
``def integrate`` or a draft redefined further down is not the library's.
Names that resolve to an import (``import particles.integrators as I`` then
``I.euler``, ``from particles import INTEGRATORS``, ``getattr(module, "name")``
with a constant string, ``from particles.integrators import *``) are compared
with the forbidden names by identity of the library objects, so a re-export
(``particles.integrate`` is ``particles.integrators.integrate``) counts too.
Uses are followed through the submission's own functions, classes and
constants (``STEPPERS = {"euler": euler}``). Dynamic tricks (``importlib``
with computed strings) are caught at run time by the worker's tripwires
(:mod:`particles.course.walls.audit`).

A submission that runs the library's *source* (read from its files and
``exec``-ed) defines functions of its own that no name check sees; those are
recognised by their compiled code (:mod:`particles.course.worker.codeprints`),
against the code of the forbidden objects that :func:`forbidden_code` lists.
"""

import ast
import importlib

from .scopes import dotted

__all__ = ["forbidden_uses", "forbidden_code"]


def _resolve_object(name):
    """The library object a dotted name refers to, or None (only for the course library)."""
    if not name.startswith("particles"):
        return None
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        try:
            for attr in parts[k:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def _star_path(code, name, before, after):
    """``module.name`` when a kept ``from module import *`` of the library, between statements `after` and
    `before`, binds `name`; else None."""
    for s in reversed(code._statements):
        node = s.node
        if (before is not None and s.index >= before) or not isinstance(node, ast.ImportFrom):
            continue
        if s.index <= after:
            return None
        if node.module and not node.level and any(a.name == "*" for a in node.names):
            module = _resolve_object(node.module)
            if module is None:
                continue
            exported = getattr(module, "__all__", None) or [n for n in dir(module) if not n.startswith("_")]
            if name in exported:
                return f"{node.module}.{name}"
    return None


def forbidden_uses(code, name, forbidden):
    """Forbidden library names that function `name` uses, directly or through helpers.

    Parameters
    ----------
    code : SubmissionCode
        The analysed submission.
    name : str
        A top-level name of the submission (a function a test calls).
    forbidden : iterable of str
        Dotted names, e.g. ``"particles.integrators.euler"``. A use is
        recognised through any import alias, attribute chain or
        ``getattr(module, "name")`` that refers to the same library object.

    Returns
    -------
    list of tuple
        ``(forbidden name, via)`` where `via` is the chain of submission
        names that leads to the use, e.g. ``["run", "euler_step"]``.
    """
    from .selection import import_path

    targets = {f: _resolve_object(f) for f in forbidden}
    found, seen, queue = [], set(), []

    def hit(path, via):
        match = _match(path, targets)
        if match and match not in {h for h, _ in found}:
            found.append((match, via or [name]))

    def resolve(root, rest, before, via, depth=0, course=False):
        """Follow the notebook's binding of `root` in force before statement `before`."""
        providers = code._in_force(root, before)
        star = _star_path(code, root, before, providers[0].index if providers else -1)
        if star:
            if not course:
                hit(star + rest, via)
            return
        for p in providers:
            node = p.node
            if p.kind == "import":
                if not course:  # the course's own cells may use the library's names
                    hit((import_path(node, root) or root) + rest, via)
            elif (isinstance(node, ast.Assign) and p.binds == {root} and len(node.targets) == 1
                  and isinstance(node.targets[0], ast.Name) and dotted(node.value) and depth < 20):
                alias = dotted(node.value)  # `I = particles.integrators`, `step = euler`
                head, _, tail = alias.partition(".")
                resolve(head, ("." + tail if tail else "") + rest, p.index, via, depth + 1,
                        course or p.label in code.provided_labels)
            elif p not in seen:
                seen.add(p)
                queue.append((p, via + [root]))

    resolve(name, "", None, [])
    while queue:
        s, via = queue.pop(0)
        course = s.label in code.provided_labels  # followed for the student's functions it names only
        for ref in s.refs:
            if ref.imported is not None:
                if not course:
                    hit(ref.imported, via)
            else:
                resolve(ref.name, ref.chain[len(ref.name):], None if ref.deferred else s.index, via, 0, course)
    return found


def _match(used, targets):
    for f, obj in targets.items():
        if used == f or used.startswith(f + "."):
            return f
    if used.startswith("particles"):
        parts = used.split(".")
        for k in range(len(parts), 1, -1):  # the longest prefix that is the same object as a target
            obj = _resolve_object(".".join(parts[:k]))
            if obj is None or isinstance(obj, (int, float, str, bool)):
                continue
            for f, target in targets.items():
                if target is not None and obj is target:
                    return f
    return None


def forbidden_code(forbidden):
    """The compiled code of the forbidden library objects, as installed: what a copy of them would run.

    Parameters
    ----------
    forbidden : iterable of str
        Dotted names: a function (``"particles.integrators.euler"``), a class
        (each of its methods), or a module (each function and class defined
        in it). Other objects (constants, dicts) have no code and are left out.

    Returns
    -------
    list of tuple
        ``(label, forbidden name, code)``, e.g.
        ``("particles.forces.Gravity.add_to", "particles.forces.Gravity", <code>)``.
    """
    import inspect
    import types

    out, seen = [], set()

    def add(label, name, obj, depth=0):
        if isinstance(obj, (staticmethod, classmethod)):
            obj = obj.__func__
        elif isinstance(obj, property):
            for part, fn in (("fget", obj.fget), ("fset", obj.fset)):
                if fn is not None:
                    add(f"{label}.{part}", name, fn, depth)
            return
        if isinstance(obj, types.FunctionType):
            obj = inspect.unwrap(obj)
            if id(obj.__code__) not in seen:
                seen.add(id(obj.__code__))
                out.append((label, name, obj.__code__))
        elif isinstance(obj, type) and depth < 2:
            for key, value in vars(obj).items():
                add(f"{label}.{key}", name, value, depth + 1)
        elif isinstance(obj, types.ModuleType) and depth == 0:
            for key, value in vars(obj).items():
                if getattr(value, "__module__", None) == obj.__name__ and isinstance(value, (type, types.FunctionType)):
                    add(f"{label}.{key}", name, value, depth + 1)

    for name in forbidden:
        obj = _resolve_object(name)
        if obj is not None:
            add(name, name, obj)
    return out
