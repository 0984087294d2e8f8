"""Which statements of a submission run in the grader, and which library names they use."""

from particles.course.reading.submission import SubmissionCode

FORBIDDEN = ["particles.integrators.euler", "particles.integrators.INTEGRATORS", "particles.integrators.integrate"]


def _code(*sources):
    return SubmissionCode.from_cells([(f"code cell {k}", s) for k, s in enumerate(sources, start=1)])


def test_only_definitions_imports_and_constants_run():
    """Imports, defs, classes and constant assignments run; experiments, loops, plots and magics do not."""
    code = _code("%matplotlib inline\nimport numpy as np\nh = 0.1; X0 = np.array([1.0, 0.0])",
                 "t, X = simulate(X0)\nE = X[:, 0] ** 2\nfor k in range(10):\n    print(k)\nplt.plot(t, X)",
                 "@np.vectorize\ndef sq(x):\n    return x * x\nclass A:\n    pass",
                 "%%time\nslow()")
    assert [c.source for c in code.chunks] == ["import numpy as np", "h = 0.1", "X0 = np.array([1.0, 0.0])",
                                               "@np.vectorize\ndef sq(x):\n    return x * x", "class A:\n    pass"]
    reasons = {s.text.split()[0]: s.reason for s in code.skipped}
    assert "computed by a call" in reasons["t,"] and "did not compute" in reasons["E"]
    assert reasons["for"] == "a top-level loop" and "IPython magic (`%matplotlib`)" in reasons["%matplotlib"]
    assert reasons["slow()"].startswith("an expression or call") and code.skipped[-1].line == 2  # inside %%time
    assert code.chunks[3].line == 1 and code.chunks[4].line == 4


def test_syntax_errors_are_recorded_not_raised():
    """A cell with a syntax error is reported and skipped; the other cells still run."""
    code = _code("def f(:\n    pass", "def g():\n    return 1")
    assert code.syntax_errors == [("code cell 1", "line 1: invalid syntax")]
    assert "g" in code.defines() and "f" not in code.defines()


def test_forbidden_uses_through_aliases_helpers_and_getattr():
    """Forbidden names are found through import aliases, package re-exports, helpers and getattr."""
    code = _code("import particles.integrators as I\nfrom particles import INTEGRATORS as T\nimport particles",
                 "def a(f, X, t, h):\n    return I.euler(f, X, t, h)",
                 "def b(f, X, t, h):\n    return helper(f, X, t, h)\ndef helper(f, X, t, h):\n    return T['euler'](f, X, t, h)",
                 "def c(f, X0):\n    return particles.integrate(f, X0, 0, 1, 0.1)",
                 "def d(f, X, t, h):\n    return getattr(I, 'euler')(f, X, t, h)",
                 "def clean(X):\n    return X.copy()")
    assert code.forbidden_uses("a", FORBIDDEN) == [("particles.integrators.euler", ["a"])]
    assert code.forbidden_uses("b", FORBIDDEN) == [("particles.integrators.INTEGRATORS", ["b", "helper"])]
    assert code.forbidden_uses("c", FORBIDDEN) == [("particles.integrators.integrate", ["c"])]
    assert code.forbidden_uses("d", FORBIDDEN)[0][0] == "particles.integrators.euler"
    assert code.forbidden_uses("clean", FORBIDDEN) == []


def test_parameters_and_skipped_assignments():
    """Parameter names come from the last def; a name bound only by a skipped call is explained."""
    code = _code("def step(f, X, t, h):\n    return X", "stepper = make()")
    assert code.parameters("step") == ["f", "X", "t", "h"]
    assert code.skipped_assignment("stepper").text == "stepper = make()"


def test_a_cell_source_that_is_not_text_makes_the_notebook_unreadable(tmp_path):
    """A code cell whose source holds numbers, or cells that are not a list, is an unreadable notebook (ValueError)."""
    import json

    import pytest

    from particles.course.reading.submission import notebook_cells

    cases = {"numbers": {"cells": [{"cell_type": "code", "source": [1, 2]}]},
             "a_dict": {"cells": [{"cell_type": "code", "source": {"a": 1}}]},
             "cells_dict": {"cells": {"a": 1}}}
    for name, notebook in cases.items():
        (tmp_path / f"{name}.ipynb").write_text(json.dumps(notebook))
    with pytest.raises(ValueError, match=r"the source of code cell 1 holds a list with an item of type int, not text"):
        notebook_cells(tmp_path / "numbers.ipynb")
    with pytest.raises(ValueError, match=r"the source of code cell 1 holds a value of type dict, not text"):
        notebook_cells(tmp_path / "a_dict.ipynb")
    with pytest.raises(ValueError, match=r"its cells are a dict, not a list"):
        notebook_cells(tmp_path / "cells_dict.ipynb")


def test_a_null_byte_is_a_syntax_error_without_line_none():
    """A null byte in a cell is reported as that cell's syntax error, with no 'line None'."""
    code = _code("def f():\n    return 1\x00\n", "def g():\n    return 1")
    assert len(code.syntax_errors) == 1 and code.syntax_errors[0][0] == "code cell 1"
    assert "null bytes" in code.syntax_errors[0][1] and "None" not in code.syntax_errors[0][1]
    assert "g" in code.defines()


# -- cells read as Jupyter runs them -------------------------------------------------------------

def _kept(code):
    return [(c.label, c.line, c.source.split("\n")[0]) for c in code.chunks]


def _reason(code, text):
    return next(s.reason for s in code.skipped if s.text.startswith(text))


def test_cell_magics_that_wrap_code_count_as_the_code_they_wrap():
    """%%time, %%capture and %%prun cells keep their definitions at their own line numbers; %time x = ... binds x."""
    code = _code("%%time\ndef a():\n    return 1\nslow()",
                 "\n%%capture out\nimport numpy as np\ndef b():\n    return 2",
                 "%%prun -q\nclass C:\n    pass",
                 "%time EPS = np.finfo(float).eps\ndef uses_eps():\n    return EPS")
    assert _kept(code) == [("code cell 1", 2, "def a():"), ("code cell 2", 3, "import numpy as np"),
                           ("code cell 2", 4, "def b():"), ("code cell 3", 2, "class C:"),
                           ("code cell 4", 1, "EPS = np.finfo(float).eps"), ("code cell 4", 2, "def uses_eps():")]
    assert [(s.text, s.line) for s in code.skipped] == [("slow()", 4)]


def test_line_magics_and_shell_commands_parse_and_keep_the_cell():
    """`x = %timeit -o ...`, `!pip`, `%matplotlib`, `files = !ls` and a continued magic parse as in Jupyter."""
    code = _code("!pip install numpy\n%matplotlib inline\nimport numpy as np\n%load_ext autoreload\n%autoreload 2",
                 "def f():\n    return 1\ntiming = %timeit -o f()\nfiles = !ls\n%timeit \\\n    f()\ndef g():\n"
                 "    return 2")
    assert code.syntax_errors == []
    assert _kept(code) == [("code cell 1", 3, "import numpy as np"), ("code cell 2", 1, "def f():"),
                           ("code cell 2", 7, "def g():")]  # line 7 although the transformer joined lines 5-6
    assert _reason(code, "!pip") == "a shell command (`!pip install numpy`), which the grader does not run"
    assert _reason(code, "%autoreload") == "an IPython magic (`%autoreload`), which the grader does not need"
    assert _reason(code, "timing =").startswith("an IPython magic (`%timeit`) whose result `timing`")
    assert _reason(code, "files =").startswith("an IPython magic (a shell command) whose result `files`")


def test_timeit_and_other_cell_magics_are_skipped_with_the_names_they_define():
    """A %%timeit cell (its own namespace in Jupyter) and a %%bash cell are skipped, naming what they define."""
    code = _code("%%timeit -n 1\ndef timed():\n    return 1", "%%bash\necho hi", "%%writefile data.csv\n1,2\n",
                 "%%writefile ../escape.py\nx = 1")
    timeit, bash, escape = code.skipped
    assert timeit.names == ("timed",) and "namespace of its own" in timeit.reason and timeit.text == "%%timeit -n 1"
    assert bash.reason == "a %%bash cell, which the grader does not run" and bash.names == ()
    assert escape.text == "%%writefile ../escape.py"
    assert _kept(code) == [("code cell 3", 1, "get_ipython().run_cell_magic('writefile', 'data.csv', '1,2\\n')")]


def test_without_ipython_magic_lines_are_blanked_and_cell_magics_skipped(monkeypatch):
    """Without IPython the grader falls back to blanking % and ! lines, and skips cell magics whole."""
    from particles.course.reading import magics

    monkeypatch.setattr(magics, "_MANAGER", [None])
    code = _code("%matplotlib inline\n!pip install numpy\ndef f():\n    return 1", "%%time\ndef g():\n    pass")
    assert _kept(code) == [("code cell 1", 3, "def f():")]
    assert code.skipped[0].reason == "a cell magic" and code.skipped[0].names == ("g",)


# -- what runs: by what a statement does -----------------------------------------------------------

def test_assignments_computed_by_calls_run_when_a_function_needs_them():
    """EPS from np.finfo, a dict of objects and an item assignment run because functions read them; experiments do not."""
    code = _code("import numpy as np\nEPS = np.finfo(float).eps\nclass Thing:\n    def __init__(self, k):\n"
                 "        self.k = k\nCASES = dict(a=Thing(1))\nSTEPPERS = {}\nSTEPPERS['a'] = Thing(2)\nN = 2\nN += 1",
                 "def tol(x):\n    return EPS * x\ndef case(name):\n    return CASES[name].k + STEPPERS[name].k + N",
                 "problem = Thing(3)\nt, X = np.histogram(problem.k)\nY = X[0] * 2\nfig = plt.figure()")
    kept = [c.source for c in code.chunks]
    assert {"EPS = np.finfo(float).eps", "CASES = dict(a=Thing(1))", "STEPPERS['a'] = Thing(2)", "N += 1"} <= set(kept)
    assert "computed by a call, and no function of the notebook uses `problem`" in _reason(code, "problem")
    assert "`X` or `t`" in _reason(code, "t, X") and "did not compute (it skipped `t, X" in _reason(code, "Y =")


def test_what_a_needed_assignment_uses_runs_too_at_the_position_it_is_read():
    """A needed assignment pulls in what it reads (transitively), each name's binding above it, not a later one."""
    code = _code("base = load()\nscale = 2 * base\nbase = other()",
                 "def f(x):\n    return scale * x")
    assert [c.source for c in code.chunks] == ["base = load()", "scale = 2 * base", "def f(x):\n    return scale * x"]
    assert "no function of the notebook uses `base`" in _reason(code, "base = other()")


def test_callable_values_run_so_that_a_test_can_call_them():
    """A lambda, functools.partial, a factory's result, a callable object and a name called elsewhere run."""
    code = _code("import functools\nimport numpy as np",
                 "def make():\n    def step(f, X, t, h):\n        return X\n    return step",
                 "class Stepper:\n    def __call__(self, f, X, t, h):\n        return X",
                 "euler_step = lambda f, X, t, h: X + h * f(X, t)\nmid = functools.partial(np.add, 1)\n"
                 "made = make()\nobj = Stepper()\nother = somewhere()\nresult = somewhere()\nother(1)")
    kept = [c.source for c in code.chunks]
    assert {"mid = functools.partial(np.add, 1)", "made = make()", "obj = Stepper()", "other = somewhere()"} <= set(kept)
    assert "euler_step = lambda f, X, t, h: X + h * f(X, t)" in kept and "result = somewhere()" not in kept
    assert code.parameters("euler_step") == ["f", "X", "t", "h"]


def test_the_last_definition_wins():
    """A draft redefined later: the final one counts for parameters, forbidden uses and what must run."""
    code = _code("from particles.integrators import euler\ndata = expensive()",
                 "def euler_step(f, X, t, h, draft=None):\n    return euler(f, X, t, h) + 0 * data",
                 "STEPPERS = {'euler': euler_step}",
                 "def euler_step(f, X, t, h):\n    return X + h * f(X, t)\ndef via_table(f, X, t, h):\n"
                 "    return STEPPERS['euler'](f, X, t, h)")
    assert code.parameters("euler_step") == ["f", "X", "t", "h"] and code.defines()["euler_step"][0] == "code cell 4"
    assert code.forbidden_uses("euler_step", FORBIDDEN) == []
    # STEPPERS was made while the draft was in force: through it the draft (and what it reads) still counts
    assert code.forbidden_uses("via_table", FORBIDDEN) == [("particles.integrators.euler",
                                                            ["via_table", "STEPPERS", "euler_step"])]
    assert "data = expensive()" in [c.source for c in code.chunks]
    alone = _code("data = expensive()", "def g():\n    return data", "def g():\n    return 1")
    assert "no function of the notebook uses `data`" in _reason(alone, "data")


# -- forbidden names, resolved by scope -------------------------------------------------------------

def test_local_names_that_shadow_a_forbidden_name_are_the_functions_own():
    """A local variable, parameter, comprehension variable or own later def named like a library function is not it."""
    code = _code("from particles.integrators import euler, integrate, INTEGRATORS",
                 "def a(f, X, t, h):\n    euler = X + h * f(X, t)\n    return euler",
                 "def b(f, X, t, euler):\n    return euler(f, X, t)",
                 "def c(X):\n    return [integrate for integrate in X]",
                 "def integrate(f, X0, h, n):\n    return X0\ndef d(f, X0, h, n):\n    return integrate(f, X0, h, n)",
                 "def e(f, X, t, h):\n    def inner():\n        INTEGRATORS = {}\n        return INTEGRATORS\n    return inner()")
    for name in "abcde":
        assert code.forbidden_uses(name, FORBIDDEN) == [], name


def test_names_that_resolve_to_the_library_are_found_at_any_depth():
    """Globals read in nested functions, local imports, module aliases and star imports resolve to the library."""
    code = _code("import particles\nfrom particles.integrators import *\nI = particles.integrators",
                 "def a(f, X, t, h):\n    def inner():\n        return euler(f, X, t, h)\n    return inner()",
                 "def b(f, X, t, h):\n    from particles.integrators import euler as e\n    return e(f, X, t, h)",
                 "def c(f, X, t, h):\n    return I.euler(f, X, t, h)",
                 "def d(f, X0):\n    return [integrate(f, X0, 0, 1, 0.1) for _ in range(2)]",
                 "class Table:\n    steps = INTEGRATORS\ndef e():\n    return Table")
    assert code.forbidden_uses("a", FORBIDDEN) == [("particles.integrators.euler", ["a"])]
    assert code.forbidden_uses("b", FORBIDDEN) == [("particles.integrators.euler", ["b"])]
    assert code.forbidden_uses("c", FORBIDDEN) == [("particles.integrators.euler", ["c"])]
    assert code.forbidden_uses("d", FORBIDDEN) == [("particles.integrators.integrate", ["d"])]
    assert code.forbidden_uses("e", FORBIDDEN) == [("particles.integrators.INTEGRATORS", ["e", "Table"])]


# -- messages ---------------------------------------------------------------------------------------

def test_a_name_the_grader_skipped_is_explained_not_called_undefined():
    """explain_missing names the skipped statement, its cell and line, why it was skipped and what to do."""
    code = _code("%%timeit\ndef timed(f):\n    return f", "try:\n    def in_try():\n        pass\nexcept Exception:\n"
                 "    pass", "stepper = make()", "for k in range(3):\n    pass\nlimit = 2 * k\ndef f():\n    return limit")
    assert code.explain_missing("timed") == (
        "the grader skipped `%%timeit` (code cell 1, line 1) because it is a %%timeit cell, which Jupyter runs in a "
        "namespace of its own (what it defines does not stay defined); move the definition to a cell without %%timeit")
    assert code.explain_missing("in_try").startswith("the grader skipped `try:` (code cell 2, line 1) because it is "
                                                     "a top-level try statement; define it at the top level")
    assert code.explain_missing("stepper").endswith("(the grader does not run experiments); define `stepper` with `def`")
    assert "it skipped `for k in range(3):`, code cell 4, line 1" in code.explain_missing("limit")
    assert code.explain_missing("nowhere") is None and code.explain_missing("f") is None


def test_a_definition_that_failed_to_load_is_explained():
    """When the statement that binds a name raised while loading, explain_missing quotes its error."""
    code = _code("def make():\n    def step():\n        pass\n    raise ValueError('no')\n    return step",
                 "step = make()\ndef other():\n    pass")
    error = {"label": "code cell 2", "where": "code cell 1, line 2, in make", "type": "ValueError", "message": "no"}
    assert code.explain_missing("step", [error]) is None  # two statements in code cell 2: which one raised?
    error["where"] = "code cell 2, line 1"
    assert code.explain_missing("step", [error]) == ("the grader ran `step = make()` (code cell 2, line 1), which "
                                                     "raised ValueError: no")


def test_runner_messages_say_what_the_grader_skipped():
    """A test that calls a skipped name, or a function hitting a skipped global, is told what was skipped and why."""
    from particles.course.worker.runner import Submission

    code = _code("%%timeit\ndef euler_step(f, X, t, h):\n    return X", "if True:\n    SCALE = 2.0")
    sub = Submission(code)
    try:
        assert sub._not_defined("euler_step").startswith("`euler_step` is not defined: the grader skipped `%%timeit`")
        error = {"type": "NameError", "message": "name 'SCALE' is not defined", "where": "code cell 3, line 2"}
        message = sub._raised("total_force", error, 2.0)
        assert message.startswith("`total_force` raised NameError") and "the grader skipped `if True:`" in message
        assert "not defined in your notebook" not in sub._not_defined("euler_step")
    finally:
        sub.close()


# -- the worker's stand-in for get_ipython() -----------------------------------------------------------

def test_the_shell_stand_in_answers_magics_without_ipython(tmp_path, monkeypatch):
    """time returns the value, timeit -o a result with floats and no leaked names, capture binds, shell does nothing."""
    from particles.course.reading import magics
    from particles.course.reading.ipython_shim import get_ipython_for

    namespace = {"__builtins__": __builtins__}
    namespace["get_ipython"] = get_ipython_for(namespace)
    shell = namespace["get_ipython"]()
    exec(magics.to_python("v = %time 1 + 2\n%time w = 7\nresult = %timeit -o -n 10 -r 3 z = w * 2\n"
                          "%matplotlib inline\nquiet = %timeit w"), namespace)
    result = namespace["result"]
    assert isinstance(result.best, float) and result.average == result.best and result.loops == 1
    assert namespace["v"] == 3 and namespace["w"] == 7 and "z" not in namespace and namespace["quiet"] is None
    shell.run_cell_magic("capture", "out", "print('hi')\ndef f():\n    return 5\n")
    assert namespace["f"]() == 5 and namespace["out"].stdout == "hi\n"
    shell.run_cell_magic("timeit", "-n1", "def leaked():\n    pass\n")
    assert "leaked" not in namespace
    assert shell.system("rm -rf /") is None and shell.getoutput("ls") == [] and shell.getoutput("ls").n == ""
    monkeypatch.chdir(tmp_path)
    shell.run_cell_magic("writefile", "data.csv", "1,2\n")
    shell.run_cell_magic("writefile", "../outside.csv", "3,4\n")
    assert (tmp_path / "data.csv").read_text() == "1,2\n" and not (tmp_path.parent / "outside.csv").exists()


def test_the_shell_stand_in_does_not_import_ipython():
    """The worker's get_ipython() stand-in loads without IPython, as the worker starts with NumPy only."""
    import subprocess
    import sys

    from particles.course.worker.main import BOOTSTRAP

    probe = BOOTSTRAP.split("from particles.course.worker.main")[0] + (
        "import particles.course.reading.ipython_shim; print(sorted(m for m in sys.modules if m.startswith('IPython')))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_a_notebook_with_magics_loads_and_runs_in_the_worker():
    """Magics in kept statements and inside functions run through the worker's stand-in shell."""
    from particles.course.worker.runner import Submission

    code = _code("%matplotlib inline\n!pip install numpy\nimport numpy as np",
                 "%%time\ndef step(X, h):\n    return X + h",
                 "timing = %timeit -o step(1.0, 0.1)\ndef speed():\n    return timing.best >= 0.0",
                 "def timed_step(X, h):\n    value = %time step(X, h)\n    files = !ls\n    return value + len(files)")
    with Submission(code, time_limit=5.0) as sub:
        assert sub.call("step", 1.0, 0.5) == 1.5 and sub.call("speed") is True
        assert sub.call("timed_step", 1.0, 0.25) == 1.25
        assert sub.load_errors == []
