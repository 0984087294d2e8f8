"""Forbidden calls: which library names a submission's function uses.

An exercise that asks for the midpoint step forbids ``particles.integrators.midpoint``.
The check reads the submission's syntax trees (nothing is run): every name
and attribute chain is resolved through the submission's imports
(``import particles.integrators as I`` then ``I.midpoint``, ``from particles
import INTEGRATORS``, ``getattr(module, "name")`` with a constant string) and
compared with the forbidden names by identity of the library objects, so a
re-export (``particles.integrate`` is ``particles.integrators.integrate``)
counts too. Uses are followed through the submission's own helper functions.
Dynamic tricks (``importlib`` with computed strings) are caught at run time by
the worker's tripwires (:mod:`particles.course.sandbox`).
"""

import ast
import importlib

from .code import _defined_names, _dotted

__all__ = ["forbidden_uses"]


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


def _uses(code, stmt):
    """Dotted names (resolved through imports) and top-level names used by one statement."""
    dotted, names = set(), set()
    for node in ast.walk(stmt):
        if isinstance(node, (ast.Attribute, ast.Name)):
            name = _dotted(node)
            if name:
                root, _, rest = name.partition(".")
                full = code._aliases.get(root, root if not code._star else None)
                if full is None:  # a star import may have brought the name in
                    full = next((f"{m}.{root}" for m in code._star), root)
                dotted.add(full + ("." + rest if rest else ""))
                names.add(root)
        if isinstance(node, ast.Call) and _dotted(node.func) == "getattr" and len(node.args) >= 2:
            base, attr = _dotted(node.args[0]), node.args[1]
            if base and isinstance(attr, ast.Constant) and isinstance(attr.value, str):
                root, _, rest = base.partition(".")
                full = code._aliases.get(root, root)
                dotted.add(f"{full}{'.' + rest if rest else ''}.{attr.value}")
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for alias in node.names:
                if alias.name != "*":
                    dotted.add(f"{node.module}.{alias.name}")
    return dotted, names

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
        functions that leads to the use, e.g. ``["run", "euler_step"]``.
    """
    targets = {}
    for f in forbidden:
        obj = _resolve_object(f)
        targets[f] = obj
    by_name = {}
    for label, stmt in code._statements:
        for defined in _defined_names(stmt):
            by_name.setdefault(defined, []).append(stmt)
    found, seen, queue = [], set(), [(name, [name])]
    while queue:
        current, via = queue.pop(0)
        if current in seen:
            continue
        seen.add(current)
        for stmt in by_name.get(current, []):
            dotted, names = _uses(code, stmt)
            for used in sorted(dotted):
                hit = _match(used, targets)
                if hit and hit not in {h for h, _ in found}:
                    found.append((hit, via))
            for other in sorted(names):
                if other in by_name and other not in seen and other != current:
                    queue.append((other, via + [other]))
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
