"""The worker's watch: the foreign code a call can reach, and the code that starts running during it."""

import functools
import inspect
import subprocess
import sys
import textwrap
import types
from pathlib import Path

import numpy as np

import particles.integrators.steppers as steppers
from particles.course.worker.codeprints import fingerprint
from particles.course.worker.codewatch import reachable_code

ROOT = Path(__file__).resolve().parents[3]


def _steppers_copy():
    """The library's steppers module, run again from its source: a dict of new functions."""
    namespace = {"__name__": "particles.integrators.steppers", "__package__": "particles.integrators"}
    exec(compile(inspect.getsource(steppers), "<copy>", "exec"), namespace)
    return namespace


def test_reachable_code_follows_what_a_function_can_run():
    """Globals, dicts, closures, partials, classes and made-up modules are followed; installed functions are not."""
    copy = _steppers_copy()
    module = types.ModuleType("mine")
    module.rk4 = copy["rk4"]
    namespace = {"np": np, "TABLE": {"a": [copy["euler"]]}, "mod": module,
                 "PART": functools.partial(copy["midpoint"], None)}
    exec("def graded(f, X, t, h):\n    return TABLE['a'][0](f, X, t, h) + mod.x + PART(X, t, h) + np.sum(X)",
         namespace)
    codes = reachable_code(namespace["graded"], own={id(namespace["graded"].__code__)})
    found = {c.co_name for c in codes}
    assert {"euler", "rk4", "midpoint"} <= found and "graded" not in found
    assert "check_arguments" not in found  # the installed library's own helper: the tripwires' business
    closure = (lambda g: lambda *a: g(*a))(copy["trapezoid"])
    assert "trapezoid" in {c.co_name for c in reachable_code(closure)}


def test_reachable_code_reports_copies_run_in_an_installed_module():
    """A copy run with an installed module's globals is reported (not followed); an original only when made at load."""
    import particles.integrators.common as common

    copy = _steppers_copy()
    in_module = types.FunctionType(copy["euler"].__code__, vars(common))
    assert [c.co_name for c in reachable_code(in_module)] == ["euler"]
    assert reachable_code(steppers.euler) == []
    made = types.FunctionType(steppers.euler.__code__, vars(steppers))  # the original code, made anew at load
    assert [c.co_name for c in reachable_code(made, created={id(steppers.euler.__code__)})] == ["euler"]
    closure = (lambda g: lambda *a: g(*a))(copy["trapezoid"])
    assert "trapezoid" in {c.co_name for c in reachable_code(closure)}


def test_reachable_code_does_not_descend_into_trusted_code():
    """A function of the course's own cells (trusted) is neither reported nor followed."""
    copy = _steppers_copy()
    namespace = {"EULER": copy["euler"]}
    exec("def provided(f, X, t, h):\n    return EULER(f, X, t, h)", namespace)
    trusted = {id(namespace["provided"].__code__)}
    assert reachable_code(namespace["provided"], trusted=trusted) == []


def test_the_recorder_sees_code_that_starts_running_while_armed():
    """exec, FunctionType and __code__ = are recorded while armed, not before; the library's imports are not."""
    script = textwrap.dedent('''
        import sys, types
        from particles.course.worker import codewatch
        hook, arm, take = codewatch.recorder("/library/")
        sys.addaudithook(hook)
        exec("def before(): pass", {})
        arm(True)
        exec(compile("def inside(): pass", "<mine>", "exec"), {})
        made = types.FunctionType((lambda: 1).__code__, {})
        def g(): pass
        g.__code__ = (lambda: 2).__code__
        exec(compile("x = 1", "/library/module.py", "exec"), {})
        arm(False)
        exec("def after(): pass", {})
        print(sorted(c.co_name for c in take()), take())
    ''')
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
                         cwd=str(ROOT))
    assert out.stdout.strip() == "['<lambda>', '<lambda>', '<module>'] []", out.stderr


def test_the_watch_reports_foreign_code_only_once_and_never_the_notebooks():
    """The notebook's own code is left out (even shaped like the library's); a copy of the library's is reported."""
    from particles.course.worker.codewatch import CodeWatch

    taken = []
    watch = CodeWatch(lambda flag: None, lambda: taken.pop() if taken else [])
    notebook = compile("def euler_step(f, X, t, h):\n    return X + h * f(X, t)", "<code cell 2>", "exec")
    watch.own_code([({"provided": False}, notebook)])
    namespace = {}
    exec(notebook, namespace)
    copy = _steppers_copy()["euler"]
    assert watch.report(watch.reachable(namespace["euler_step"])) == []
    taken.append([copy.__code__, copy.__code__])
    report = watch.report([])
    assert [r["fp"] for r in report] == [fingerprint(steppers.euler.__code__)]


def test_the_recorder_skips_installed_modules_the_import_system_loads_and_nothing_else():
    """A standard-library module imported during a call is not recorded (its functions would be fingerprinted one
    by one); the same file's code compiled by hand, a copy loaded from another folder (also through a path that
    only looks installed), a loader subclass or a loader given a method of its own, and a module in an excluded
    folder are."""
    script = textwrap.dedent('''
        import importlib.machinery, importlib.util, os, shutil, sys, tempfile
        from particles.course.worker import codewatch
        assert "colorsys" not in sys.modules and "wave" not in sys.modules
        stdlib = os.path.dirname(os.__file__)
        source = os.path.join(stdlib, "colorsys.py")
        scratch = tempfile.mkdtemp()
        hook, arm, take = codewatch.recorder("/library/", exclude=[scratch])
        sys.addaudithook(hook)

        def load(loader, name):
            spec = importlib.util.spec_from_loader(name, loader)
            module = importlib.util.module_from_spec(spec)
            loader.exec_module(module)

        def names():
            return sorted({c.co_filename.replace(stdlib, "STDLIB").replace(scratch, "SCRATCH") for c in take()})

        arm(True)
        import colorsys
        print("import", names())
        exec(compile(open(source).read(), source, "exec"), {})
        print("compiled", names())
        copy = shutil.copy(source, os.path.join(scratch, "colorsys2.py"))
        load(importlib.machinery.SourceFileLoader("colorsys2", copy), "colorsys2")
        print("copy", names())
        disguised = os.path.join(stdlib, os.path.relpath(copy, stdlib))  # stdlib/../../tmp/...: starts like stdlib
        assert disguised.startswith(stdlib)
        load(importlib.machinery.SourceFileLoader("colorsys3", disguised), "colorsys3")
        print("disguised", len(take()))

        class Mine(importlib.machinery.SourceFileLoader):
            pass
        load(Mine("colorsys4", source), "colorsys4")
        print("subclass", names())
        loader = importlib.machinery.SourceFileLoader("colorsys5", source)
        loader.get_data = lambda path, read=loader.get_data: read(path)
        load(loader, "colorsys5")
        print("own method", names())
        arm(False)
        hook, arm, take = codewatch.recorder("/library/", exclude=[stdlib])
        sys.addaudithook(hook)
        arm(True)
        import wave
        print("excluded", [n for n in names() if n.endswith("wave.py")])
    ''')
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
                         cwd=str(ROOT))
    assert out.stdout.splitlines() == [
        "import []",
        "compiled ['STDLIB/colorsys.py']",
        "copy ['SCRATCH/colorsys2.py']",
        "disguised 1",
        "subclass ['STDLIB/colorsys.py']",
        "own method ['STDLIB/colorsys.py']",
        "excluded ['STDLIB/wave.py']",
    ], out.stdout + out.stderr
