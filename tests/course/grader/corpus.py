"""A corpus of submissions to exercise 00_warmup, each with what the grader must say about it.

Each case starts from the master notebook and replaces the code cell that
defines one or more functions (``replace``), or appends cells (``append``) or
puts cells before the first one (``prepend``).
``fails`` maps the tests that must fail to a piece of their one-line reason;
``passes`` lists tests that must still pass. At least one piece of ``fails``
(or a ``diagnosis``, see ``exercise_corpus.py``) names the mistake in words,
not only the "is off by" of a wrong number. Correct variants (``CORRECT``)
must score full marks.
"""

import json
from pathlib import Path

import exercise_corpus  # this folder is on sys.path (see test_corpus.py)

ROOT = Path(__file__).resolve().parents[3]
MASTER = ROOT / "solutions" / "00_warmup.ipynb"
STUB = ROOT / "exercises" / "00_warmup.ipynb"

EULER_PUBLIC = [
    "test_euler_step_circle", "test_euler_step_oscillator", "test_euler_step_leaves_X_unchanged",
]

REJECTED = {
    "euler_as_midpoint": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    X_mid = X + 0.5 * h * f(X, t)
    return X + h * f(X_mid, t + 0.5 * h)
"""},
        "fails": {"test_euler_step_circle": "your result matches a midpoint step",
                  "test_euler_step_random": "matches a midpoint step"},
    },
    # (f evaluated at t + h, a plain wrong answer, is euler_slope_at_the_end of cases_00_warmup.py: graded once)
    "infinite_loop": {
        "replace": {"total_force": """
def total_force(x, v, m, g, d):
    while True:
        pass
"""},
        "fails": {"test_total_force_three_particles": "did not finish within 2 s"},
        "passes": EULER_PUBLIC,
    },
    # a leftover debugging print in a loop: the worker's output file reaches its limit (16 MiB), and the
    # student is told so, not "OSError: File too large"
    "prints_in_a_loop": {
        "replace": {"total_force": """
def total_force(x, v, m, g, d):
    F = np.asarray(m, dtype=float)[:, None] * np.asarray(g, dtype=float) - d * np.asarray(v, dtype=float)
    for k in range(10**6):          # checking the forces while debugging
        print(f"check {k}: total force {F.sum():.3f} N " + "-" * 80)
    return F
"""},
        "fails": {"test_total_force_three_particles": "your code printed more than 16 MiB (the limit) at code cell 4, "
                                                      "line 4, in total_force; remove the prints inside loops",
                  "test_total_force_random": "remove the prints inside loops"},
        "passes": EULER_PUBLIC,
    },
    "loop_that_catches_the_timeout": {
        "replace": {"total_force": """
import time

def total_force(x, v, m, g, d):
    while True:
        try:
            time.sleep(0.05)
        except BaseException:
            pass
"""},
        "fails": {"test_total_force_three_particles": "did not finish within 2 s",
                  "test_total_force_random": "did not finish within 2 s"},
        "passes": EULER_PUBLIC + ["test_run_circle"],
    },
    "huge_allocation": {
        "replace": {"total_force": """
def total_force(x, v, m, g, d):
    work = np.ones(400_000_000)   # 3.2 GB
    return m[:, None] * g - d * v + work[0] * 0
"""},
        "fails": {"test_total_force_three_particles": "ran out of memory"},
        "passes": EULER_PUBLIC,
    },
    "calls_sys_exit": {
        "replace": {"euler_step": """
import sys

def euler_step(f, X, t, h):
    sys.exit(0)
"""},
        "fails": {"test_euler_step_circle": "raised SystemExit at code cell 2, line 4, in euler_step (sys.exit() or "
                                            "exit() was called); a function must return its result"},
        "passes": ["test_total_force_three_particles"],
    },
    "calls_os_exit": {
        "replace": {"euler_step": """
import os

def euler_step(f, X, t, h):
    os._exit(0)
"""},
        "fails": {"test_euler_step_circle": "ended the worker process with exit status 0",
                  "test_run_circle": "ended the worker process"},
        "passes": ["test_total_force_three_particles"],
    },
    "crashes_the_interpreter": {
        "replace": {"total_force": """
import faulthandler

def total_force(x, v, m, g, d):
    faulthandler._sigsegv()        # a segmentation fault, as a bug in compiled code would cause
    return m[:, None] * g - d * v
"""},
        "fails": {"test_total_force_three_particles": "crashed the worker process with SIGSEGV"},
        "passes": EULER_PUBLIC + ["test_run_circle"],
    },
    "raises_keyboard_interrupt": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    raise KeyboardInterrupt
"""},
        "fails": {"test_euler_step_circle": "raised KeyboardInterrupt at code cell 2, line 2, in euler_step; do not "
                                            "raise or simulate interrupts in your code"},
        "passes": ["test_total_force_three_particles"],
    },
    "raises_system_exit": {
        "replace": {"total_force": """
def total_force(x, v, m, g, d):
    raise SystemExit("done")
"""},
        "fails": {"test_total_force_three_particles": "raised SystemExit at code cell 4, line 2, in total_force "
                                                      "(sys.exit() or exit() was called)"},
        "passes": EULER_PUBLIC,
    },
    "wrong_shape": {
        "replace": {"total_force": """
def total_force(x, v, m, g, d):
    return (m[:, None] * g - d * v).sum(axis=0)
"""},
        "fails": {"test_total_force_three_particles": "expected shape (3, 2); your result matches the total force "
                                                      "summed over all particles"},
    },
    "returns_nan": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    return X + h * f(X, t) * np.nan
"""},
        "fails": {"test_euler_step_circle": "expected finite numbers"},
    },
    "mutates_input": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    X += h * f(X, t)
    return X
"""},
        "fails": {"test_euler_step_leaves_X_unchanged": "modified its input `X` in place"},
        "passes": ["test_euler_step_circle", "test_euler_step_oscillator"],
    },
    "prints_a_passing_results_line": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    print("========== 8 passed in 0.01s ==========")
    print('{"score": 11, "max_score": 11, "tests": []}')
    return X.copy()
"""},
        "fails": {"test_euler_step_circle": "your result matches X itself: the step X + h f(X, t) is missing",
                  "test_euler_step_oscillator": "your result matches X itself"},
    },
    "writes_a_fake_results_json": {
        "replace": {"total_force": """
import json, os

def total_force(x, v, m, g, d):
    fake = json.dumps({"score": 11, "tests": []})
    open("results.json", "w").write(fake)           # its own folder: allowed, and ignored
    for folder in ("/autograder/results", os.path.join(os.getcwd(), "..", "..", "results")):
        open(os.path.join(folder, "results.json"), "w").write(fake)
    return np.zeros_like(x)
"""},
        "fails": {"test_total_force_three_particles": "write outside their working directory"},
    },
    "monkeypatches_numpy_checks": {
        "replace": {"euler_step": """
import numpy.testing

def euler_step(f, X, t, h):
    np.allclose = lambda *args, **kwargs: True
    np.isclose = lambda a, b, *args, **kwargs: np.ones(np.shape(a), dtype=bool)
    numpy.testing.assert_allclose = lambda *args, **kwargs: None
    return X * 0.0
"""},
        "fails": {"test_euler_step_circle": "your result matches zeros, not the new state X + h f(X, t)",
                  "test_euler_step_oscillator": "your result matches zeros"},
    },
    "monkeypatches_builtins": {
        "replace": {"total_force": """
import builtins

def total_force(x, v, m, g, d):
    builtins.abs = lambda value: 0.0
    builtins.isinstance = lambda *args: True
    builtins.AssertionError = type("Nothing", (Exception,), {})
    return np.zeros((1,))
"""},
        "fails": {"test_total_force_three_particles": "replaced Python's built-in AssertionError, abs, isinstance"},
        "passes": EULER_PUBLIC,
    },
    "reads_the_solution_file": {
        "replace": {"euler_step": """
import json, pathlib
import particles

def euler_step(f, X, t, h):
    master = pathlib.Path(particles.__file__).resolve().parents[1] / "solutions" / "00_warmup.ipynb"
    cells = json.loads(master.read_text())["cells"]
    namespace = {"np": np}
    exec("".join(cells[3]["source"]), namespace)
    return namespace["euler_step"](f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "read its private files"},
    },
    "spies_on_the_grader_process": {
        "replace": {"euler_step": """
import os

def euler_step(f, X, t, h):
    secrets = open(f"/proc/{os.getppid()}/environ", "rb").read()   # the grader's environment
    return X + h * f(X, t) + 0.0 * len(secrets)
"""},
        "fails": {"test_euler_step_circle": "read its private files (/proc/"},
    },
    "hard_codes_public_answers": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    f(X, t)
    if X.shape == (2,):
        return np.array([1.0, 0.1])
    if X.shape == (1, 2, 1):
        return np.array([[[1.025], [0.3]]])
    return X.copy()
"""},
        # the third public test now checks the result too, not only that X was left unchanged
        "fails": {"test_euler_step_random": "your result matches X itself: the step X + h f(X, t) is missing",
                  "test_euler_step_leaves_X_unchanged": "your result matches X itself",
                  "test_run_circle": "your result matches one step from X0 in every record"},
        "passes": ["test_euler_step_circle", "test_euler_step_oscillator", "test_total_force_three_particles"],
    },
    "calls_the_library_stepper": {
        "replace": {"euler_step": """
from particles.integrators import euler

def euler_step(f, X, t, h):
    return euler(f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "uses `particles.integrators.euler`",
                  "test_run_circle": "through run -> euler_step"},
    },
    "calls_the_library_stepper_dynamically": {
        "replace": {"euler_step": """
import importlib

def euler_step(f, X, t, h):
    module = importlib.import_module("particles." + "integ" + "rators")
    return getattr(module, "eu" + "ler")(f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "not allowed in this exercise"},
    },
    "calls_the_library_loop": {
        "replace": {"run": """
import particles

def run(f, X0, t0, h, n_steps):
    return particles.integrate(f, X0, t0, t0 + n_steps * h, h, method="euler")
"""},
        "fails": {"test_run_circle": "uses `particles.integrators.integrate`, which this exercise forbids: it is the "
                                     "loop you are asked to write"},
        "passes": EULER_PUBLIC,
    },
    "wrong_damping_sign": {
        "replace": {"total_force": """
def total_force(x, v, m, g, d):
    return m[:, None] * g + d * v
"""},
        "fails": {"test_total_force_three_particles": "your result matches m g + d v: the damping has the wrong sign",
                  "test_total_force_random": "the damping has the wrong sign"},
    },
    "returns_a_list": {
        "replace": {"total_force": """
def total_force(x, v, m, g, d):
    return (m[:, None] * g - d * v).tolist()
"""},
        "fails": {"test_total_force_three_particles": "returned a list"},
    },
    "integer_result": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    return (X + h * f(X, t)).astype(int)
"""},
        "fails": {"test_euler_step_circle": "returned an array of dtype int64, expected floating-point numbers"},
    },
    "run_off_by_one": {
        "replace": {"run": """
def run(f, X0, t0, h, n_steps):
    t = t0 + h * np.arange(n_steps)
    X = [X0]
    for k in range(n_steps - 1):
        X.append(euler_step(f, X[-1], t[k], h))
    return t, np.array(X)
"""},
        "fails": {"test_run_circle": "expected shape (11,); your result matches the times without the last one: "
                                     "your loop takes one step too few (n_steps steps make n_steps + 1 records"},
    },
    "run_returns_only_states": {
        "replace": {"run": """
def run(f, X0, t0, h, n_steps):
    X = [np.asarray(X0, dtype=float)]
    for k in range(n_steps):
        X.append(euler_step(f, X[-1], t0 + k * h, h))
    return np.array(X)
"""},
        "fails": {"test_run_circle": "returned an array of shape (11, 2)"},
    },
    "run_is_a_generator": {
        "replace": {"run": """
def run(f, X0, t0, h, n_steps):
    for k in range(n_steps + 1):
        yield t0 + k * h
"""},
        "fails": {"test_run_circle": "returned a generator, expected the tuple (t, X)"},
    },
    "evaluates_f_twice": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    slope = f(X, t)
    check = f(X, t)
    return X + h * 0.5 * (slope + check)
"""},
        "fails": {"test_euler_step_leaves_X_unchanged": "evaluated f 2 times"},
        "passes": ["test_euler_step_circle"],
    },
    "function_renamed": {
        "replace": {"run": """
def simulate(f, X0, t0, h, n_steps):
    return None
"""},
        "fails": {"test_run_circle": "`run` is not defined in your notebook; define a function called `run`"},
        "passes": EULER_PUBLIC,
    },
    "syntax_error": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h)
    return X + h * f(X, t)
"""},
        "fails": {"test_euler_step_circle": "has a syntax error"},
        "passes": ["test_total_force_three_particles"],
    },
    "defined_in_a_timeit_cell": {  # Jupyter runs a %%timeit cell in a namespace of its own: nothing stays defined
        "replace": {"euler_step": """
%%timeit -n 1 -r 1
def euler_step(f, X, t, h):
    return X + h * f(X, t)
"""},
        "fails": {"test_euler_step_circle": "`euler_step` is not defined: the grader skipped `%%timeit -n 1 -r 1` "
                                            "(code cell 2, line 1) because it is a %%timeit cell",
                  "test_run_circle": "`euler_step` is not defined: the grader skipped `%%timeit -n 1 -r 1`"},
        "passes": ["test_total_force_three_particles"],
    },
    "defined_inside_a_try_block": {
        "replace": {"run": """
try:
    def run(f, X0, t0, h, n_steps):
        X0 = np.asarray(X0, dtype=float)
        t = t0 + h * np.arange(n_steps + 1)
        X = np.empty((n_steps + 1,) + X0.shape)
        X[0] = X0
        for k in range(n_steps):
            X[k + 1] = euler_step(f, X[k], t[k], h)
        return t, X
except Exception as error:
    print("run is broken:", error)
"""},
        "fails": {"test_run_circle": "`run` is not defined: the grader skipped `try:` (code cell 5, line 1) because it "
                                     "is a top-level try statement; define it at the top level of a cell"},
        "passes": EULER_PUBLIC,
    },
    "constant_set_in_an_if_block": {
        "replace": {"total_force": """
if "DRAG_SIGN" not in globals():
    DRAG_SIGN = -1.0           # the drag opposes the velocity


def total_force(x, v, m, g, d):
    m = np.asarray(m, dtype=float)
    return m[:, None] * np.asarray(g, dtype=float) + DRAG_SIGN * d * np.asarray(v, dtype=float)
"""},
        "fails": {"test_total_force_three_particles": "raised NameError at code cell 4, line 7, in total_force: "
                                                      "`DRAG_SIGN` is not defined: the grader skipped `if "},
        "passes": EULER_PUBLIC,
    },
    "endless_recursion": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    return euler_step(f, X, t, h / 2)
"""},
        "fails": {"test_euler_step_circle": "raised RecursionError at code cell 2, line 2, in euler_step: maximum "
                                            "recursion depth exceeded"},
    },
    "disables_the_audit_hook_and_forges_the_records": {  # /tmp/audit_5/forge.py of the audit
        "replace": {"euler_step": """
import json, os, re, signal, sys

def euler_step(f, X, t, h):
    sys.modules["particles.course.walls.audit"].Policy.__call__ = lambda self, event, args: None
    argv = [a.decode() for a in open(f"/proc/{os.getppid()}/cmdline", "rb").read().split(b"\\0")]
    results = argv[argv.index("--grading-results") + 1]
    batch = json.load(open(argv[argv.index("--grading-batch") + 1]))
    names = re.findall(r"def (test_\\w+)\\(", open(next(a for a in argv if a.endswith(".py"))).read())
    tests = [{"test": n, "name": n, "points": 2.0, "hidden": False, "passed": True, "reason": "",
              "grader_error": False, "seconds": 0.01, "seed": None} for n in names]
    fake = {"submissions": [{"id": j["id"], "seed": j["seed"], "tests": tests, "seconds": 1.0} for j in batch]}
    open(results, "w").write(json.dumps(fake))
    os.kill(os.getppid(), signal.SIGKILL)
    return X
"""},
        # replacing Policy.__call__ does not switch the audit hook off: /proc of the grader stays private
        "fails": {"test_euler_step_circle": "read its private files (/proc/"},
        "passes": ["test_total_force_three_particles"],
    },
    "disables_the_audit_hook_and_reads_the_master": {  # /tmp/audit_5/bypass.py of the audit
        "replace": {"euler_step": """
import json, pathlib, sys
import particles

def euler_step(f, X, t, h):
    sys.modules["particles.course.walls.audit"].Policy.__call__ = lambda self, event, args: None
    master = pathlib.Path(particles.__file__).resolve().parents[1] / "solutions" / "00_warmup.ipynb"
    cells = json.loads(master.read_text())["cells"]
    namespace = {"np": np}
    exec("".join(cells[3]["source"]), namespace)
    return namespace["euler_step"](f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "read its private files"},
        "passes": ["test_total_force_three_particles"],
    },
    "finds_the_hook_with_gc": {
        "replace": {"euler_step": """
import gc

def euler_step(f, X, t, h):
    hooks = [o for o in gc.get_objects() if getattr(o, "__name__", "") == "hook"]
    return X + h * f(X, t) * len(hooks)
"""},
        "fails": {"test_euler_step_circle": "inspect the grader's objects (gc.get_objects)"},
    },
    "takes_the_original_from_the_tripwires": {  # /tmp/audit_5/wires.py of the audit
        "replace": {"euler_step": """
import importlib, sys

def euler_step(f, X, t, h):
    module = importlib.import_module("particles." + "integrators")
    wires = sys.modules["particles.course.walls.audit"].WIRES
    real = getattr(module, "eu" + "ler")._original
    return real(f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "raised AttributeError at code cell 2, line 6, in euler_step"},
    },
    "imports_the_library_past_the_tripwires": {
        "replace": {"euler_step": """
import importlib, sys

def euler_step(f, X, t, h):
    sys.meta_path[:] = [finder for finder in sys.meta_path if "Tripwires" not in type(finder).__name__]
    sys.modules.pop("particles." + "integrators", None)   # loaded (and wired) by the first cell: load it again
    module = importlib.import_module("particles." + "integrators")
    return getattr(module, "eu" + "ler")(f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "load the library past its tripwires"},
    },
    "loads_the_library_with_a_loader_of_its_own": {
        "replace": {"euler_step": """
import importlib.util
import particles

def euler_step(f, X, t, h):
    path = particles.__path__[0] + "/integrators/steppers.py"
    spec = importlib.util.spec_from_file_location("my_integrators", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.euler(f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "load the library past its tripwires"},
    },
    # -- a forged count of f scores as its honest content: f evaluated twice (issue 23) ----------------------
    "forges_the_count_by_decrementing_it": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    slope = f(X, t)
    check = f(X, t)           # evaluated twice...
    f.calls -= 1              # ...and the count made to say once
    return X + h * 0.5 * (slope + check)
"""},
        "fails": {"test_euler_step_leaves_X_unchanged": "euler_step evaluated f 2 times in one step; Euler's method "
                                                         "uses exactly one evaluation"},
        "passes": ["test_euler_step_circle", "test_euler_step_oscillator", "test_euler_step_random", "test_run_circle"],
    },
    "forges_the_count_with_setattr_and_its_dict": {
        "replace": {"euler_step": """
def euler_step(f, X, t, h):
    slope = 0.5 * (f(X, t) + f(X, t))
    f.calls = 1
    setattr(f, "calls", 1)
    vars(f)["calls"] = 1
    for cls in type(f).__mro__[:-1]:
        try:
            setattr(cls, "calls", 1)
        except TypeError:
            pass
    return X + h * slope
"""},
        "fails": {"test_euler_step_leaves_X_unchanged": "evaluated f 2 times in one step"},
        "passes": ["test_euler_step_circle", "test_euler_step_oscillator", "test_euler_step_random"],
    },
    "forges_the_count_with_a_wrapper_a_thread_and_a_new_f": {
        "replace": {"euler_step": """
import sys, threading

def euler_step(f, X, t, h):
    registry = sys.modules["particles.course.worker.registry"]
    real = registry.EVALUATE
    registry.EVALUATE = lambda *args: real(*args)       # the worker's link to the grader, wrapped
    calls = 0
    def counted(X, t):                                  # a wrapper with a counter of its own, in a closure
        nonlocal calls
        calls += 1
        return f(X, t)
    results = []
    worker = threading.Thread(target=lambda: results.append(counted(X, t)))
    worker.start()
    worker.join()
    calls -= 1
    slope = 0.5 * (results[0] + counted(X, t))
    registry.EVALUATE = real
    f = lambda X, t: slope                              # f replaced: no more evaluations
    return X + h * f(X, t)
"""},
        "fails": {"test_euler_step_leaves_X_unchanged": "evaluated f 2 times in one step"},
        "passes": ["test_euler_step_circle", "test_euler_step_oscillator", "test_euler_step_random"],
    },
    # -- the library's source, read and run: the library's code, not the student's (issue 23) ----------------
    "execs_the_library_source_read_with_open": {
        "replace": {"euler_step": """
import particles

def euler_step(f, X, t, h):
    path = particles.__path__[0] + "/integrators/steppers.py"
    namespace = {"__name__": "particles.integrators.steppers", "__package__": "particles.integrators"}
    exec(open(path).read(), namespace)
    return namespace["eu" + "ler"](f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "`euler_step` runs the library's code, not yours: this is the library's "
                                            "`particles.integrators.euler`",
                  "test_euler_step_random": "this is the library's `particles.integrators.euler`",
                  "test_run_circle": "this is the library's `particles.integrators.euler`"},
        "passes": ["test_total_force_three_particles"],
    },
    "execs_inspect_getsource_at_load_renamed": {
        "replace": {"euler_step": """
import inspect, re
import particles.integrators.steppers as steppers_module


def _my_notes():
    text = inspect.getsource(steppers_module)
    text = re.sub(r"\\beuler\\b", "forward_step", text).replace("Explicit (forward) Euler step", "My own step")
    namespace = {"__name__": "particles.integrators.steppers", "__package__": "particles.integrators"}
    exec(compile(text, "<my notes>", "exec"), namespace)
    return namespace


NOTES = _my_notes()


def euler_step(f, X, t, h):
    return NOTES["forward_step"](f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "this is the library's `particles.integrators.euler`",
                  "test_euler_step_oscillator": "runs the library's code, not yours"},
        "passes": ["test_total_force_three_particles"],
    },
    "builds_a_function_from_the_library_code": {
        "replace": {"euler_step": """
import importlib.util, types
import particles.integrators.common as common


def euler_step(f, X, t, h):
    spec = importlib.util.find_spec("particles.integrators.steppers")
    module_code = compile(spec.loader.get_source(spec.name), "<reading>", "exec")
    code = next(c for c in module_code.co_consts if getattr(c, "co_name", "") == "eu" + "ler")
    step = types.FunctionType(code, vars(common))        # the library's globals: check_arguments, evaluate
    return step(f, X, t, h)
"""},
        "fails": {"test_euler_step_circle": "this is the library's `particles.integrators.euler`",
                  "test_euler_step_leaves_X_unchanged": "this is the library's `particles.integrators.euler`"},
        "passes": ["test_total_force_three_particles"],
    },
}

CORRECT = {
    # honest code that the recognition of the library's code must leave alone (issue 23)
    # helpers named like the library's (particles.integrators.common), and a step shaped exactly like the
    # library's euler: compiled from the notebook's own cell, it is the student's code
    "own_helpers_named_like_the_library": {
        "replace": {"euler_step": """
def check_arguments(X, t, h):            # my helpers, with the library's names
    return np.asarray(X, dtype=float), float(h)


def evaluate(f, X, t):
    return np.asarray(f(X, t), dtype=float)


def euler_step(f, X, t, h):
    X, h = check_arguments(X, t, h)
    return X + h * evaluate(f, X, t)
"""},
    },
    "stepper_built_by_exec_of_its_own_source": {
        "replace": {"euler_step": """
import types

_SOURCE = "def step(f, X, t, h):\\n    'One Euler step.'\\n    return X + h * f(X, t)\\n"


def _build():
    namespace = {}
    exec(compile(_SOURCE, "<my stepper>", "exec"), namespace)
    return types.FunctionType(namespace["step"].__code__, namespace, "euler_step")


_STEP = _build()


def euler_step(f, X, t, h):
    return _STEP(f, X, t, h)
"""},
    },
    # correct notebooks in the forms that a grader reading cells naively gets wrong (issue 10)
    "time_and_capture_cell_magics": {
        "replace": {
            "euler_step": """
%%time
def euler_step(f, X, t, h):
    return X + h * f(X, t)

print(euler_step(lambda X, t: -X, np.ones(2), 0.0, 0.1))
""",
            "total_force": """
%%capture forces_output
def total_force(x, v, m, g, d):
    m = np.asarray(m, dtype=float)
    return m[:, None] * np.asarray(g, dtype=float) - d * np.asarray(v, dtype=float)

print(total_force(np.zeros((1, 2)), np.ones((1, 2)), np.ones(1), np.array([0.0, -9.81]), 0.1))
""",
        },
    },
    "timeit_result_assigned_next_to_the_definition": {
        "replace": {"total_force": """
def total_force(x, v, m, g, d):
    m = np.asarray(m, dtype=float)
    return m[:, None] * np.asarray(g, dtype=float) - d * np.asarray(v, dtype=float)


x3, v3, m3 = np.zeros((3, 2)), np.ones((3, 2)), np.ones(3)
timing = %timeit -o -n 100 total_force(x3, v3, m3, np.array([0.0, -9.81]), 0.1)
print(f"{timing.best * 1e6:.1f} microseconds per call")
"""},
    },
    "lambda_stepper": {
        "replace": {"euler_step": """
euler_step = lambda f, X, t, h: X + h * f(X, t)   # one explicit Euler step
"""},
    },
    "stepper_from_a_factory": {
        "replace": {"euler_step": """
def make_stepper():
    def step(f, X, t, h):
        return X + h * f(X, t)
    return step

euler_step = make_stepper()
"""},
    },
    "eps_from_finfo_used_in_a_function": {
        "replace": {"run": """
EPS = np.finfo(float).eps          # machine epsilon


def run(f, X0, t0, h, n_steps):
    if abs(h) <= EPS:
        raise ValueError(f"h must not be zero, got {h}")
    X0 = np.asarray(X0, dtype=float)
    t = t0 + h * np.arange(n_steps + 1)
    X = np.empty((n_steps + 1,) + X0.shape)
    X[0] = X0
    for k in range(n_steps):
        X[k + 1] = euler_step(f, X[k], t[k], h)
    return t, X
"""},
    },
    "dict_of_force_objects": {
        "replace": {"total_force": """
class Term:
    def __init__(self, kind):
        self.kind = kind

    def __call__(self, v, m, g, d):
        return m[:, None] * g if self.kind == "gravity" else -d * v


TERMS = dict(gravity=Term("gravity"), drag=Term("drag"))


def total_force(x, v, m, g, d):
    m, g, v = np.asarray(m, dtype=float), np.asarray(g, dtype=float), np.asarray(v, dtype=float)
    return TERMS["gravity"](v, m, g, d) + TERMS["drag"](v, m, g, d)
"""},
    },
    "local_variables_named_like_forbidden_names": {  # the master's last cell imports euler, Gravity and Damping
        "replace": {
            "euler_step": """
def euler_step(f, X, t, h):
    euler = X + h * f(X, t)          # my Euler step, a local variable
    return euler
""",
            "total_force": """
def total_force(x, v, m, g, d):
    Gravity = np.asarray(m, dtype=float)[:, None] * np.asarray(g, dtype=float)
    Damping = -d * np.asarray(v, dtype=float)
    return sum(term for term in (Gravity, Damping))
""",
        },
    },
    "own_integrate_shadows_the_library_import": {
        "replace": {"run": """
from particles import integrate    # the library's loop, to compare with mine below


def integrate(f, X0, t0, h, n_steps):       # my own loop, under the same name
    X0 = np.asarray(X0, dtype=float)
    t = t0 + h * np.arange(n_steps + 1)
    X = np.empty((n_steps + 1,) + X0.shape)
    X[0] = X0
    for k in range(n_steps):
        X[k + 1] = euler_step(f, X[k], t[k], h)
    return t, X


def run(f, X0, t0, h, n_steps):
    return integrate(f, X0, t0, h, n_steps)
"""},
    },
    "draft_redefined_further_down": {
        "replace": {"euler_step": """
from particles.integrators import euler


def euler_step(f, X, t, h):
    return euler(f, X, t, h)        # a first draft with the library's step; mine is at the end
"""},
        "append": ["def euler_step(f, X, t, h):\n    return X + h * f(X, t)"],
    },
    "pip_install_and_other_line_magics": {
        "prepend": ["""!pip install numpy
%pip install -q matplotlib
%matplotlib inline
%load_ext autoreload
%autoreload 2
files = !ls
try:
    import particles
except ImportError:
    !pip install particles"""],
    },
    "per_coordinate_loops_and_lists": {
        "replace": {
            "euler_step": """
def euler_step(f, X, t, h):
    slope = np.asarray(f(X, t), dtype=float)
    out = np.array(X, dtype=float, copy=True)
    out += h * slope          # on the copy, never on X
    return out
""",
            "total_force": """
def total_force(x, v, m, g, d):
    F = np.empty(np.shape(v))
    for a in range(F.shape[1]):   # a loop over the coordinates, not over particles
        F[:, a] = m * g[a] - d * v[:, a]
    return F
""",
            "run": """
def run(f, X0, t0, h, n_steps):
    states, times = [np.array(X0, dtype=float)], [t0]
    while len(states) <= n_steps:
        k = len(states) - 1
        states.append(euler_step(f, states[-1], t0 + k * h, h))
        times.append(t0 + (k + 1) * h)
    return np.array(times), np.stack(states)
""",
        },
    },
    "helpers_and_other_names": {
        "replace": {
            "euler_step": """
def _tangent(rhs, state, time):
    return np.asarray(rhs(state, time))


def euler_step(f, X, t, h):
    return np.add(X, h * _tangent(f, X, t))
""",
            "total_force": """
def _weights(masses, gravity):
    return np.outer(masses, gravity)


def total_force(x, v, m, g, d):
    drag = np.multiply(-d, v)
    return _weights(m, g) + drag
""",
            "run": """
def run(f, X0, t0, h, n_steps):
    times = np.linspace(t0, t0 + n_steps * h, n_steps + 1)
    trajectory = np.zeros((n_steps + 1,) + np.shape(X0))
    trajectory[0] = X0
    for k, tk in enumerate(times[:-1]):
        trajectory[k + 1] = euler_step(f, trajectory[k], tk, h)
    return times, trajectory
""",
        },
    },
    "slow_and_broken_experiments_around_correct_code": {
        "replace": {
            "total_force": """
from typing import Callable

GRAVITY = np.array([0.0, -9.81])


class ForceSum:
    def __call__(self, m, g, d, v):
        return np.einsum("i,j->ij", m, g) - d * v


def total_force(x, v, m, g, d):
    return ForceSum()(np.asarray(m, float), np.asarray(g, float), float(d), np.asarray(v, float))
""",
        },
        "append": [
            "import time\nfor _ in range(1000):\n    time.sleep(1)   # an experiment the grader must not run",
            "plt.plot(undefined_name)",
            "%timeit euler_step(circle_field, X, 0.0, 0.1)",
        ],
    },
}


def build(case):
    """The notebook (a dict) of corpus case `case` (a dict with replace/append/prepend)."""
    notebook = exercise_corpus.build("00_warmup", case)
    for k, code in enumerate(case.get("prepend", [])):
        notebook["cells"].insert(k, {"cell_type": "code", "metadata": {}, "source": code, "outputs": [],
                                     "execution_count": None, "id": f"prepended-{k}"})
    return notebook


def write_corpus(folder):
    """Write every case as ``folder/<case>/00_warmup.ipynb`` (one student per case); return the names."""
    folder = Path(folder)
    names = []
    cases = dict(REJECTED, **CORRECT)
    for name, case in cases.items():
        (folder / name).mkdir(parents=True, exist_ok=True)
        (folder / name / "00_warmup.ipynb").write_text(json.dumps(build(case), indent=1))
        names.append(name)
    for name, path in (("master", MASTER), ("released_stub", STUB)):
        (folder / name).mkdir(parents=True, exist_ok=True)
        (folder / name / "00_warmup.ipynb").write_text(path.read_text())
        names.append(name)
    return names
