"""The library's layout: its layers, no import circles, each concept in its home, one formula in one place.

The import graph of ``particles/`` is built from the syntax trees of its
modules (not by importing them): module-level imports, and imports inside
functions (lazy ones) counted separately. :data:`LAYERS` writes down which
package may import which; :data:`KERNEL_LAWS` which law of the NumPy code
each compiled kernel inlines.
"""

import ast
import functools
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "particles"

# Lazy imports that close a circle, each kept on purpose: none (the test requires this to stay empty).
KNOWN_LAZY_CIRCLES = {}

# Private names imported from another (non-private) module: none (the test requires this to stay empty).
KNOWN_PRIVATE_IMPORTS = set()

# The modules that may draw (import Matplotlib at module level) and those that belong to the grader.
DRAWING = {"particles.render", "particles.explore.figures"}
GRADER_USERS = {"particles", "particles.cli"}  # particles.check(), and the console command (its verbs' modules)


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
    """With the imports inside functions too, no two modules import each other."""
    circles = {frozenset(c) for c in _cycles(_edges(lazy=True))}
    assert KNOWN_LAZY_CIRCLES == {}
    assert sorted(sorted(c) for c in circles) == []


# The layers of the library, lowest first: a module may import its own layer's modules and those of the layers
# below, never one above (lazy imports included). A module belongs to the longest prefix that names it.
LAYERS = [
    ("what every module shares", ["particles._checks", "particles._vectors", "particles.errors"]),
    ("the backends' switch, compile wrapper and threads", ["particles.backends"]),
    ("steppers, the time loop, births and deaths, test problems",
     ["particles.integrators", "particles.population", "particles.problems"]),
    ("periodic boxes and thermostats", ["particles.md"]),
    ("the bucket grid and Verlet lists", ["particles.neighbors"]),
    ("forces, springs among them", ["particles.forces"]),
    ("the particle system", ["particles.system"]),
    ("constraints of mass-spring models, and the colouring", ["particles.constraints"]),
    ("mass-spring models and their compiled step", ["particles.massspring"]),
    ("solvers: implicit and position-based", ["particles.implicit", "particles.xpbd"]),
    ("collisions", ["particles.collisions"]),
    ("effects and flocks", ["particles.effects"]),
    ("drawing", ["particles.render"]),
    ("studies", ["particles.studies"]),
    ("explorations", ["particles.explore"]),
    ("demos", ["particles.demos"]),
    ("the tools: the tour, warm, the course, the command line",
     ["particles.tour", "particles.warm", "particles.course", "particles.cli", "particles.__main__", "particles"]),
]


def _layer(module):
    """The index in LAYERS of `module`'s layer (the longest prefix that names it), or None."""
    best, found = "", None
    for k, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > len(best):
                best, found = prefix, k
    return found


def _imported_modules(name):
    """The modules of the package that `name` imports (module-level and lazy): ``from pkg import sub`` is sub."""
    out = set()
    for target, names, _, line in IMPORTS[name]:
        subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES]
        if subs and len(subs) == len(names):
            out.update((s, line) for s in subs)
        elif target in MODULES:
            out.update([(target, line)] + [(s, line) for s in subs])
        elif target.startswith("particles."):
            out.add((target.rpartition(".")[0], line))
    return out


def test_every_module_has_a_layer():
    """Each module of the package (the course's too) belongs to a layer of LAYERS."""
    assert sorted(name for name in MODULES if _layer(name) is None) == []


def test_no_import_runs_upward_across_the_layers():
    """No module imports a module of a higher layer, at load or inside a function (the backends import no concept)."""
    upward = [f"{name}:{line} imports {target} ({LAYERS[_layer(target)][0]})" for name in sorted(MODULES)
              for target, line in sorted(_imported_modules(name)) if _layer(target) > _layer(name)]
    assert upward == []


def test_demos_and_effects_import_no_circle():
    """The demo registry is explicit (no module registers itself by importing it), effects and emitters are one-way."""
    graph = _edges(lazy=True)
    assert "particles.effects.effect" not in graph["particles.effects.emitters"]
    assert not any(target == "particles.demos" for target in graph["particles.demos.massspring"])
    assert {f"particles.demos.{m}" for m in ("effects", "collisions", "flocks", "massspring")} <= graph[
        "particles.demos"]


@pytest.mark.parametrize("name", sorted(LIBRARY - DRAWING))
def test_physics_modules_do_not_import_matplotlib_when_loaded(name):
    """Only particles.render and the explorations' figures import Matplotlib at module level."""
    loaded = [(target, line) for target, _, lazy, line in IMPORTS[name]
              if not lazy and target.split(".")[0] in ("matplotlib", "mpl_toolkits")]
    assert loaded == []


def test_the_library_imports_nothing_of_the_grader():
    """Outside particles/course/, only the console command and particles.check() import the grader."""
    users = {name.removesuffix("." + name.split(".")[-1]) if name.startswith("particles.cli.") else name
             for name in LIBRARY for target, names, _, _ in IMPORTS[name]
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
    assert KNOWN_PRIVATE_IMPORTS == set()
    assert sorted(found) == []


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
                  if re.search(r"for \w+ in range\(1, len\(times\)\)|while \w+ < len\(times\)", line)]
        grids += [name for target, names, _, _ in IMPORTS[name]
                  if "step_times" in names and name != "particles.integrators"]  # the package re-exports it
    assert loops == ["particles.integrators.loop: while k < len(times):"]
    assert grids == []


# --- one formula, one place -----------------------------------------------------------------------------------

# Every compiled kernel (a function decorated with ``@jit`` in a kernels module, one that imports
# particles.backends.compile) with the law it computes: a per-item function of its concept's NumPy code, which
# the kernel inlines (directly, or through the kernel modules' helpers).
KERNEL_LAWS = {
    "particles.forces.kernels.spring_scatter": "particles.forces.springs.damped_spring_force",
    "particles.forces.kernels.springs_in_parallel": "particles.forces.springs.damped_spring_force",
    "particles.forces.kernels.bending_in_parallel": "particles.forces.springs.joint_factor",
    "particles.forces.kernels.lennard_jones_blocks": "particles.forces.pairs.lennard_jones_virial",
    "particles.forces.kernels.nbody_pulls": "particles.forces.pairs.gravitational_pull",
    "particles.massspring.step_kernels.symplectic_euler_steps": "particles.forces.springs.damped_spring_force",
    "particles.massspring.step_kernels._block_springs": "particles.forces.springs.damped_spring_force",
    "particles.massspring.step_kernels._block_joints": "particles.forces.springs.joint_factor",
    "particles.massspring.step_kernels._block_update": "particles.forces.fields.gust_factor",
    "particles.massspring.step_kernels.clamp_pass": "particles.forces.springs.joint_factor",
    "particles.constraints.kernels.provot_passes": "particles.constraints.provot.provot_excess",
    "particles.xpbd.kernels.distance_group": "particles.xpbd.distance.multiplier_step",
    "particles.xpbd.kernels.distance_jacobi": "particles.xpbd.distance.multiplier_step",
    "particles.xpbd.kernels.substep": "particles.xpbd.distance.multiplier_step",
    "particles.xpbd.kernels.distance_violation": "particles.xpbd.distance.distance_constraint",
    "particles.implicit.kernels.local_step": "particles.implicit.sparse.projection_weight",
    "particles.collisions.collider_kernels.collider_candidates": "particles.collisions.surfaces.round_height",
    "particles.collisions.collider_kernels.collider_resolve": "particles.collisions.response.normal_change",
    "particles.collisions.body_kernels.body_vertices": "particles.collisions.response.friction_change",
    "particles.collisions.body_kernels.low_edge_samples": "particles.collisions.surfaces.box_height",
    "particles.collisions.impulse_kernels.proximity_impulses": "particles.collisions.response.proximity_impulse",
    "particles.collisions.contact_kernels.closest_pairs": "particles.collisions.proximity.triangle_contact",
    "particles.collisions.contact_kernels.proximity_rows": "particles.collisions.proximity.approaching_within",
    "particles.collisions.contact_kernels.first_contact_pairs": "particles.collisions.ccd.cubic_of",
    "particles.collisions.broad_kernels.box_candidates": "particles.collisions.triangle_crossing.intervals_overlap",
    "particles.collisions.broad_kernels.subset_pairs": "particles.collisions.triangle_crossing.intervals_overlap",
    "particles.collisions.broad_kernels.kept_pairs": "particles.collisions.triangle_crossing.intervals_overlap",
}

# The kernels that compute no per-item formula (a gather of indices, a triangular solve), with the NumPy function
# whose result they reproduce; each one's docstring names it.
KERNEL_ALGEBRA = {
    "particles.collisions.broad_kernels.corner_bounds": "particles.collisions.candidates.candidates_in_boxes",
    "particles.collisions.broad_kernels.key_rows": "particles.collisions.candidates.pair_rows",
    "particles.implicit.kernels.global_step": "particles.implicit.prefactored.Prefactored._global",
    "particles.implicit.kernels.gradient_norm": "particles.implicit.prefactored.Prefactored._gradient_norm",
}

KERNEL_MODULES = sorted(name for name in LIBRARY if name != "particles.backends.compile"
                        and any(target == "particles.backends.compile" for target, _, _, _ in IMPORTS[name]))


@functools.lru_cache(maxsize=None)
def _functions(module):
    """The module-level functions of `module`: name -> node."""
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    return {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}


def _bindings(module):
    """What the module's ``from ... import`` statements bind: name -> qualified name of the object."""
    out = {}
    for target, names, lazy, _ in IMPORTS[module]:
        if not lazy:
            out.update({n: f"{target}.{n}" for n in names})
    return out


def _compiled_kernels():
    """The qualified names of the functions decorated with ``jit(...)`` in the kernels modules."""
    found = []
    for module in KERNEL_MODULES:
        for name, node in _functions(module).items():
            for decorator in node.decorator_list:
                func = decorator.func if isinstance(decorator, ast.Call) else decorator
                if isinstance(func, ast.Name) and func.id == "jit":
                    found.append(f"{module}.{name}")
    return found


def _reached(kernel):
    """The qualified names of the functions a kernel calls, through the functions of the kernel modules it calls."""
    todo, seen, reached = [kernel], set(), set()
    while todo:  # a walk over the call graph of the kernel modules' functions
        qualified = todo.pop()
        module, _, name = qualified.rpartition(".")
        if qualified in seen or module not in KERNEL_MODULES or name not in _functions(module):
            continue
        seen.add(qualified)
        local, bound = _functions(module), _bindings(module)
        for node in ast.walk(local[name]):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
                callee = f"{module}.{node.func.id}" if node.func.id in local else bound.get(node.func.id)
                if callee is not None:
                    reached.add(callee)
                    todo.append(callee)
    return reached


def test_every_compiled_kernel_is_mapped_to_what_it_computes():
    """Each compiled kernel is listed once, with the law it inlines or the NumPy function it reproduces."""
    kernels = _compiled_kernels()
    assert sorted(set(KERNEL_LAWS) & set(KERNEL_ALGEBRA)) == []
    assert sorted(kernels) == sorted({**KERNEL_LAWS, **KERNEL_ALGEBRA})


@pytest.mark.parametrize("kernel, law", sorted(KERNEL_LAWS.items()))
def test_each_kernel_inlines_the_law_of_the_numpy_code(kernel, law):
    """The kernel calls the law, a plain function of a concept's module (not a kernels module), which the NumPy code
    of the library calls too: one formula, one place."""
    module, _, name = law.rpartition(".")
    assert module not in KERNEL_MODULES and name in _functions(module), law
    assert law in _reached(kernel)
    numpy_callers = []
    for other in sorted(LIBRARY - set(KERNEL_MODULES)):  # every function and method of the NumPy code
        bound = _bindings(other)
        for node in ast.walk(ast.parse(MODULES[other].read_text(encoding="utf-8"))):
            if not isinstance(node, ast.FunctionDef) or (other == module and node.name == name):
                continue
            names = {n.func.id for n in ast.walk(node) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
            if any((other == module and n == name) or bound.get(n) == law for n in names):
                numpy_callers.append(f"{other}.{node.name}")
    assert numpy_callers, f"no NumPy code calls {law}"


@pytest.mark.parametrize("kernel, reference", sorted(KERNEL_ALGEBRA.items()))
def test_each_kernel_without_a_formula_names_the_numpy_function_it_reproduces(kernel, reference):
    """A kernel of no per-item formula (a gather, a solve) names in its docstring the NumPy function it reproduces."""
    module, _, name = kernel.rpartition(".")
    assert _resolves(reference), reference
    assert reference.rpartition(".")[2].lstrip("_") in (ast.get_docstring(_functions(module)[name]) or "")


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


# --- the layout a newcomer walks -------------------------------------------------------------------

PACKAGES = sorted(name.split(".")[1] for name, path in MODULES.items()
                  if path.name == "__init__.py" and name.count(".") == 1)
ROOT_LIMIT, LINE_LIMIT = 15, 600
# Tests of a concept that spans a package rather than one module (a file named after a whole package is not
# one: its tests belong in the files of the modules they test), each with the reason it is one.
CONCEPT_TESTS = {
    "test_architecture": "the library's layout, across every package",
    "test_bench_scripts": "the set-ups of the scripts in bench/, built without timing them",
    "test_force_contract": "the contract every Force subclass keeps (forces/), and again on each backend (backends/)",
    "test_md_nist": "NIST's Lennard-Jones liquid, reproduced with the md package's lattice, thermostats and statistics",
    "test_switch": "the backend switch of particles/backends/__init__.py (numpy, numba, auto, the global choice)",
    "test_registry": "the demo registry of particles/demos/__init__.py (DEMOS, register, run_demo), over every demo",
    "test_docstrings": "the numpydoc sections of the demos' and effects' public functions, over several packages",
    "test_solver_contract": "what both implicit solvers (BaraffWitkin, Prefactored) promise, each test over both",
    "test_steps": "steps in one compiled call: integrators/loop.py's batches through massspring/compiled_step.py's kernel",
    "test_signatures": "one compiled kernel per argument type, whatever form the callers get: the compiled step of "
                       "massspring/, Provot's projection, the collider, the searches of collisions/compiled_stages.py",
}


def test_the_root_holds_only_what_every_area_shares():
    """particles/ holds at most 15 modules; everything else lives in a package of its area."""
    root = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(root) <= ROOT_LIMIT, root


def test_no_module_is_over_600_lines():
    """No module of the package (library and course tools) is longer than 600 lines."""
    long = {name: n for name in MODULES if (n := len(MODULES[name].read_text(encoding="utf-8").splitlines())) > LINE_LIMIT}
    assert long == {}


ALL_PACKAGES = sorted(name.removeprefix("particles.") for name, path in MODULES.items()
                      if path.name == "__init__.py" and name != "particles")
COURSE_PACKAGES = sorted(p.split(".")[1] for p in ALL_PACKAGES if p.count(".") == 1 and p.startswith("course."))


@pytest.mark.parametrize("package", ALL_PACKAGES)
def test_each_package_docstring_is_its_map(package):
    """The docstring of each package's __init__ (course's packages too) names every module and subpackage in it."""
    folder = PACKAGE.joinpath(*package.split("."))
    doc = ast.get_docstring(ast.parse((folder / "__init__.py").read_text(encoding="utf-8"))) or ""
    modules = sorted(p.stem for p in folder.glob("*.py") if p.name != "__init__.py")
    modules += sorted(p.parent.name for p in folder.glob("*/__init__.py"))
    path = package.replace(".", "/")
    missing = [m for m in modules
               if not re.search(rf"particles\.{re.escape(package)}\.{m}\b|`{m}(\.py)?`|{path}/{m}(\.py|/)", doc)]
    assert missing == []


def test_library_tests_mirror_the_packages():
    """tests/library/<package>/test_<module>.py tests particles/<package>/<module>.py (or a concept test)."""
    tests = ROOT / "tests" / "library"
    wrong = []
    for path in sorted(tests.rglob("test_*.py")):
        parts = path.relative_to(tests).parts
        package = "particles" + "".join(f".{p}" for p in parts[:-1])
        stem = path.stem
        if package != "particles" and not (package in MODULES and MODULES[package].name == "__init__.py"):
            wrong.append(f"{path.relative_to(ROOT)}: no package {package}")
        elif not (f"{package}.{stem[5:]}" in MODULES or stem in CONCEPT_TESTS):
            wrong.append(f"{path.relative_to(ROOT)}: no module {package}.{stem[5:]}")
        elif not (path.parent / "__init__.py").exists():
            wrong.append(f"{path.relative_to(ROOT)}: no __init__.py beside it")
    assert wrong == []


def test_every_concept_test_exists():
    """Each name of CONCEPT_TESTS is the name of a test file of tests/library/ (no allowance outlives its file)."""
    stems = {path.stem for path in (ROOT / "tests" / "library").rglob("test_*.py")}
    assert sorted(set(CONCEPT_TESTS) - stems) == []


# Tests of the course tools at tests/course/ itself: journeys through several packages.
COURSE_JOURNEYS = {"test_check", "test_cli", "test_provided_cells", "test_student_install", "test_term"}


def test_course_tests_mirror_the_course_packages():
    """tests/course/<package>/test_<module>.py tests particles/course/<package>/<module>.py; the grader's corpora
    live in tests/course/grader/, and only journeys through several packages at tests/course/ itself."""
    tests = ROOT / "tests" / "course"
    wrong = []
    for path in sorted(tests.rglob("test_*.py")):
        parts = path.relative_to(tests).parts
        if parts[0] == "grader":
            continue
        if len(parts) == 1:
            if path.stem not in COURSE_JOURNEYS and f"particles.course.{path.stem[5:]}" not in MODULES:
                wrong.append(f"{path.relative_to(ROOT)}: no module particles.course.{path.stem[5:]}")
            continue
        module = "particles.course." + ".".join(parts[:-1]) + "." + path.stem[5:]
        if module not in MODULES:
            wrong.append(f"{path.relative_to(ROOT)}: no module {module}")
        elif not (path.parent / "__init__.py").exists():
            wrong.append(f"{path.relative_to(ROOT)}: no __init__.py beside it")
    assert wrong == []


def _section(path, heading):
    text = (ROOT / path).read_text(encoding="utf-8")
    return re.search(rf"^## {heading}\n(.*?)(?=^## |\Z)", text, flags=re.M | re.S).group(1)


@pytest.mark.parametrize("path, heading", [("README.md", "Layout"), ("CONTRIBUTING.md", "Where to make a change")])
def test_the_layout_tables_name_every_package(path, heading):
    """README's layout and CONTRIBUTING's table name exactly the packages of particles/."""
    section = _section(path, heading)
    named = sorted(set(re.findall(r"`particles/(\w+)/", section)))
    assert named == PACKAGES
    course = sorted(set(re.findall(r"`particles/course/(\w+)/", section)))
    assert course == COURSE_PACKAGES


def _top_names(module):
    """Names bound at the top of `module` (definitions, assignments, imports) -> their node."""
    names = {}
    for node in ast.parse(MODULES[module].read_text(encoding="utf-8")).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names[node.name] = node
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            for target in (node.targets if isinstance(node, ast.Assign) else [node.target]):
                for t in (target.elts if isinstance(target, ast.Tuple) else [target]):
                    if isinstance(t, ast.Name):
                        names[t.id] = node
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for a in node.names:
                names[(a.asname or a.name).split(".")[0]] = node
        elif isinstance(node, (ast.If, ast.Try)):
            for child in ast.walk(node):
                if isinstance(child, (ast.FunctionDef, ast.ClassDef)):
                    names[child.name] = child
                elif isinstance(child, (ast.Import, ast.ImportFrom)):
                    for a in child.names:
                        names[(a.asname or a.name).split(".")[0]] = child
    return names


def _resolves(dotted):
    """Whether `particles.a.b...` names a module of the package or an attribute bound in one."""
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        if ".".join(parts[:k]) in MODULES:
            break
    module, rest = ".".join(parts[:k]), parts[k:]
    if not rest or rest[0].startswith("__"):
        return True
    node = _top_names(module).get(rest[0])
    if node is None:
        return False
    if len(rest) > 1 and isinstance(node, ast.ClassDef) and not node.bases:
        members = {n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))}
        members |= {t.id for n in node.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}
        members |= {n.target.id for n in node.body if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)}
        return rest[1] in members or rest[1].startswith("__")
    return True


def test_every_dotted_library_name_in_tests_corpora_and_notebooks_exists():
    """Each `particles.x.y` named in the tests, the grader's corpora, the lectures, masters and exercises exists."""
    files = [*sorted((ROOT / "tests").rglob("*.py")), *sorted((ROOT / "lectures").glob("*.ipynb")),
             *sorted((ROOT / "solutions").glob("*.ipynb")), *sorted((ROOT / "exercises").glob("*.ipynb"))]
    missing = set()
    for path in files:
        if path == Path(__file__).resolve():
            continue  # this file's examples
        text = path.read_text(encoding="utf-8")
        for m in re.finditer(r"(?<![\w./-])particles(?:\.[A-Za-z_]\w*)+(?![\w-])", text):
            name = m.group(0)
            if not _resolves(name):
                missing.add(f"{path.relative_to(ROOT)}: {name}")
    assert sorted(missing) == []


FUNCTION_LIMIT = 80  # lines of code of one function: docstrings, comments and blank lines not counted


def _code_lines(path):
    """The numbers of the lines of `path` that hold code (not a docstring, a comment or a blank line)."""
    import io
    import tokenize

    source = path.read_text(encoding="utf-8")
    docs = set()
    for node in ast.walk(ast.parse(source)):
        body = getattr(node, "body", None)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and body \
                and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                and isinstance(body[0].value.value, str):
            docs.update(range(body[0].lineno, body[0].end_lineno + 1))
    skipped = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER}
    return {line for token in tokenize.generate_tokens(io.StringIO(source).readline) if token.type not in skipped
            for line in range(token.start[0], token.end[0] + 1) if line not in docs}


def test_no_function_of_the_package_is_over_80_lines_of_code():
    """Every function of the package, library and course tools alike (nested functions counted in their parent), is
    at most 80 lines of code: a long one is a list of steps that want names of their own (a fused kernel is made of
    its concepts' inlined laws, short by construction)."""
    long = []
    for name, path in sorted(MODULES.items()):
        code = _code_lines(path)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = sum(1 for line in range(node.lineno, node.end_lineno + 1) if line in code)
                if n > FUNCTION_LIMIT:
                    long.append(f"{name}.{node.name}: {n} lines")
    assert long == []
