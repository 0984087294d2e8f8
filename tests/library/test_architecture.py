"""The library's layout: no import circles, each concept in its home, one time loop.

The import graph of ``particles/`` is built from the syntax trees of its
modules (not by importing them): module-level imports, and imports inside
functions (lazy ones) counted separately.
"""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "particles"

# Lazy imports that close a circle, each kept on purpose.
KNOWN_LAZY_CIRCLES = {
    frozenset({"particles.implicit", "particles.statics"}):
        "`from particles.implicit import relax` (relax's old home) resolves lazily to particles.statics, "
        "which uses the implicit solvers",
}

# Private names imported from another (non-private) module, in modules this layout does not own yet.
KNOWN_PRIVATE_IMPORTS = {
    ("particles.thermostats", "particles.integrators", "_arguments"),
    ("particles.thermostats", "particles.integrators", "_evaluate"),
    ("particles.thermostats", "particles.integrators", "_split"),
    ("particles.xpbd", "particles.pbdconstraints", "_ConstraintSet"),
}

# The modules that may draw (import Matplotlib at module level) and those that belong to the grader.
DRAWING = {"particles.render"}
GRADER_USERS = {"particles", "particles.cli"}  # the console command, and particles.check()


def _modules():
    """Module name -> path of every module of the package."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        name = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        out[name] = path
    return out


MODULES = _modules()
LIBRARY = {name for name in MODULES if not name.startswith("particles.course")}


def _imports(name):
    """The imports of module `name`: a list of (target module, imported names, lazy, line)."""
    path = MODULES[name]
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []

    def visit(body, lazy):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                visit(node.body, True)
                continue
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = ".".join(base[:len(base) - node.level + 1])
                    target = f"{base}.{node.module}" if node.module else base
                else:
                    target = node.module or ""
                found.append((target, [a.name for a in node.names], lazy, node.lineno))
            elif isinstance(node, ast.Import):
                found.extend((a.name, [], lazy, node.lineno) for a in node.names)
            for child in ast.iter_child_nodes(node):  # statements nested in if, try, with, class bodies
                if isinstance(child, ast.stmt):
                    visit([child], lazy)

    visit(ast.parse(path.read_text(encoding="utf-8")).body, False)
    return found


IMPORTS = {name: _imports(name) for name in MODULES}


def _edges(lazy):
    """The import graph between the package's modules: module -> set of modules it imports."""
    graph = {name: set() for name in MODULES}
    for name, imports in IMPORTS.items():
        for target, names, is_lazy, _ in imports:
            if is_lazy and not lazy:
                continue
            if target in MODULES:
                graph[name].add(target)
            graph[name].update(f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES)
            if target not in MODULES and target.startswith("particles."):
                graph[name].add(target.rpartition(".")[0])
        graph[name].discard(name)
    return graph


def _cycles(graph):
    """The cycles found by a depth-first search, each a list of module names (first == last)."""
    state, stack, found = {}, [], []

    def dfs(u):  # a recursion over modules
        state[u] = "open"
        stack.append(u)
        for v in sorted(graph[u]):
            if state.get(v) == "open":
                found.append(stack[stack.index(v):] + [v])
            elif v not in state:
                dfs(v)
        stack.pop()
        state[u] = "done"

    for u in sorted(graph):
        if u not in state:
            dfs(u)
    return found


def test_the_module_level_import_graph_is_acyclic():
    """No two modules import each other, directly or through others, when they are loaded."""
    assert _cycles(_edges(lazy=False)) == []


def test_lazy_imports_close_no_other_circle():
    """With the imports inside functions too, the only circles are the documented ones."""
    circles = {frozenset(c) for c in _cycles(_edges(lazy=True))}
    assert circles <= set(KNOWN_LAZY_CIRCLES), [sorted(c) for c in circles - set(KNOWN_LAZY_CIRCLES)]


def test_demos_and_effects_import_no_circle():
    """The demo registry is explicit (no module registers itself by importing it), effects and emitters are one-way."""
    graph = _edges(lazy=True)
    assert "particles.effects" not in graph["particles.emitters"]
    assert not any(target == "particles.demos" for target in graph["particles.demos.massspring"])
    assert {f"particles.demos.{m}" for m in ("effects", "collisions", "flocks", "massspring")} <= graph[
        "particles.demos"]


@pytest.mark.parametrize("name", sorted(LIBRARY - DRAWING))
def test_physics_modules_do_not_import_matplotlib_when_loaded(name):
    """Only particles.render imports Matplotlib at module level; the others do so, if at all, when drawing."""
    loaded = [(target, line) for target, _, lazy, line in IMPORTS[name]
              if not lazy and target.split(".")[0] in ("matplotlib", "mpl_toolkits")]
    assert loaded == []


def test_the_library_imports_nothing_of_the_grader():
    """Outside particles/course/, only the console command and particles.check() import the grader."""
    users = {name for name in LIBRARY for target, names, _, _ in IMPORTS[name]
             if target.startswith("particles.course") or (target == "particles" and "course" in names)}
    assert users <= GRADER_USERS, sorted(users - GRADER_USERS)


def test_no_private_helper_is_imported_from_another_module():
    """A name starting with '_' is imported only from a private module (particles._checks, particles._vectors)."""
    found = set()
    for name in LIBRARY:
        for target, names, _, _ in IMPORTS[name]:
            private_module = target.rpartition(".")[2].startswith("_")
            if target.startswith("particles") and not private_module:
                found |= {(name, target, n) for n in names if n.startswith("_") and not n.startswith("__")}
    found = {f for f in found if f[:2] != ("particles", "particles.course.check")}  # check's lazy import
    assert found <= KNOWN_PRIVATE_IMPORTS, sorted(found - KNOWN_PRIVATE_IMPORTS)


def test_one_unit_vector_helper():
    """Lengths and unit vectors are computed by one helper, particles._vectors.unit, not redefined elsewhere."""
    defined = [name for name in LIBRARY
               if re.search(r"^def _?unit\(", MODULES[name].read_text(encoding="utf-8"), flags=re.M)]
    assert defined == ["particles._vectors"]


def test_only_the_system_assigns_its_state():
    """Outside particles/system.py no code assigns ``something.X`` or ``something.t`` (one loop, one owner)."""
    found = []
    for name in sorted(LIBRARY - {"particles.system"}):
        for node in ast.walk(ast.parse(MODULES[name].read_text(encoding="utf-8"))):
            targets = node.targets if isinstance(node, ast.Assign) else \
                [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign)) else []
            for target in targets:
                for t in (target.elts if isinstance(target, ast.Tuple) else [target]):
                    if isinstance(t, ast.Attribute) and t.attr in ("X", "t") and not (
                            isinstance(t.value, ast.Name) and t.value.id == "self"):
                        found.append(f"{name}:{node.lineno}")
    assert found == []


def test_one_time_loop():
    """Only the generic integrator loops over time steps: nothing else builds a time grid with step_times."""
    loops, grids = [], []
    for name in sorted(LIBRARY):
        text = MODULES[name].read_text(encoding="utf-8")
        loops += [f"{name}: {line.strip()}" for line in text.splitlines()
                  if re.search(r"for \w+ in range\(1, len\(times\)\)", line)]
        grids += [name for target, names, _, _ in IMPORTS[name] if "step_times" in names]
    assert loops == ["particles.integrators: for k in range(1, len(times)):"]
    assert grids == []


def test_long_modules_are_listed_in_the_readme():
    """Every module over 400 lines (library and course tools) is named, with the reason, in the README's layout."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    layout = re.search(r"^## Layout\n(.*?)^## ", readme, flags=re.M | re.S).group(1)
    long = sorted(name for name in MODULES if len(MODULES[name].read_text(encoding="utf-8").splitlines()) > 400)
    missing = [name for name in long if f"`{MODULES[name].relative_to(ROOT).as_posix()}`" not in layout]
    assert missing == []


def test_every_test_says_what_it_checks():
    """Every test function of the suite opens with a docstring (one line saying what it checks)."""
    import ast

    missing = []
    for path in sorted((ROOT / "tests").rglob("test_*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.startswith("test"):
                if not (ast.get_docstring(node) or "").strip():
                    missing.append(f"{path.relative_to(ROOT)}::{node.name}")
    assert missing == []
