"""The worker seen from the grader: limits, refusals, restarts, and a new exercise end to end."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import nbformat
import numpy as np
import pytest

from particles.course.reading.submission import SubmissionCode
from particles.course.grading.driver import grade
from particles.course.worker.registry import remote
from particles.course.release.notebooks import release
from particles.course.worker.runner import GradingFailure, Submission

ROOT = Path(__file__).resolve().parents[3]

SOURCE = """
import os, socket, subprocess, time
import numpy as np

def sleepy(seconds):
    time.sleep(seconds)
    return seconds

def spawn():
    return subprocess.run(["true"]).returncode

def connect():
    socket.create_connection(("127.0.0.1", 9))

def kill_parent():
    os.kill(os.getppid(), 9)

def big_file():
    with open("big.bin", "wb") as f:
        f.write(b"0" * (64 * 2**20))

def state():
    global counter
    counter = counter + 1 if "counter" in globals() else 1
    return counter

def three_evaluations_claiming_one(f, X, t):
    # evaluates f three times and tries every way to make the count say one
    for _ in range(3):
        f(X, t)
    for attempt in (lambda: setattr(f, "calls", 1), lambda: object.__setattr__(f, "calls", 1),
                    lambda: setattr(type(f), "calls", 1)):
        try:
            attempt()
        except Exception:
            pass
    return f(X, t) * 0 + len(str(f))

def two_evaluations(f, X, t, forge):
    # evaluates f twice and forges the count in one way or another (see test_forged_counts_change_nothing)
    import sys, threading
    registry = sys.modules["particles.course.worker.registry"]
    if forge == "wrapper":
        inner, f = f, lambda X, t: inner(X, t)
    elif forge == "class_call":
        original = type(f).__call__
        type(f).__call__ = lambda self, *a: original(self, *a)
    elif forge == "evaluate":
        real = registry.EVALUATE
        registry.EVALUATE = lambda token, args, kwargs: real(token, args, kwargs)
    if forge == "threads":
        out = []
        threads = [threading.Thread(target=lambda: out.append(f(X, t))) for _ in range(2)]
        [th.start() for th in threads]
        [th.join() for th in threads]
        value = out[0]
    else:
        value = f(X, t)
        value = 0.5 * (value + f(X, t))
    count = [0]
    def forget():                # a closure rebinding a counter of its own
        count[0] -= 1
    forget()
    for attempt in {"minus": lambda: setattr(f, "calls", f.calls - 1),
                    "assign": lambda: setattr(f, "calls", 1),
                    "dict": lambda: f.__dict__.update(calls=1),
                    "object": lambda: object.__setattr__(f, "calls", 1),
                    "class": lambda: setattr(type(f), "calls", 1)}.values():
        try:
            attempt()
        except Exception:
            pass
    if forge == "class_call":
        type(f).__call__ = original
    if forge == "evaluate":
        registry.EVALUATE = real
    return value
"""


@pytest.fixture(scope="module")
def submission():
    sub = Submission(SubmissionCode.from_cells([("code cell 1", SOURCE)]), time_limit=3.0)
    yield sub
    sub.close()


def test_per_call_time_limit(submission):
    """A call gets the limit it is given; a faster call in the same worker still works."""
    with pytest.raises(GradingFailure, match="did not finish within 0.5 s"):
        submission.call("sleepy", 2.0, timeout=0.5)
    assert submission.call("sleepy", 0.01) == 0.01


@pytest.mark.parametrize("name, reason", [
    ("spawn", "start other programs"),
    ("connect", "use the network"),
    ("kill_parent", "send signals to processes"),
    ("big_file", "larger than 16 MiB"),
])
def test_refused_operations(submission, name, reason):
    """Starting programs, networking, signalling the grader and huge files are refused with a reason."""
    with pytest.raises(GradingFailure, match=reason):
        submission.call(name)


def test_worker_is_reused_until_it_dies(submission):
    """Calls share one worker (state persists) until a crash forces a fresh one."""
    first = submission.call("state")
    assert submission.call("state") == first + 1
    submission.worker.kill()
    assert submission.call("state") == 1 and submission.restarts >= 2


def test_a_new_exercise_end_to_end(tmp_path):
    """A course folder with a new master and test module: release, grade, time_limit marker, forbidden call."""
    root = tmp_path / "course"
    (root / "solutions").mkdir(parents=True)
    (root / "tests" / "exercises").mkdir(parents=True)
    master = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_markdown_cell("# Exercise 99: the norm of a vector"),
        nbformat.v4.new_code_cell("import numpy as np\n\ndef norm(x):\n    \"\"\"Euclidean norm.\"\"\"\n"
                                  "    ### BEGIN SOLUTION\n    return float(np.sqrt(np.sum(np.square(x))))\n"
                                  "    ### END SOLUTION"),
    ])
    nbformat.write(master, str(root / "solutions" / "99_norm.ipynb"))
    (root / "tests" / "exercises" / "test_99_norm.py").write_text(textwrap.dedent('''
        import numpy as np
        import pytest
        from particles.course.grading.expect import expect_float

        EXERCISE = "99_norm"
        FORBIDDEN = {"numpy.linalg.norm": "write the sum of squares yourself"}

        @pytest.mark.points(2)
        @pytest.mark.time_limit(1.5)
        def test_norm(student):
            """norm of (3, 4) is 5."""
            expect_float(student.call("norm", np.array([3.0, 4.0])), 5.0, "norm([3, 4])")

        @pytest.mark.hidden
        def test_norm_random(student, rng):
            """norm matches the reference on a random vector."""
            x = rng.normal(size=7)
            expect_float(student.call("norm", x), np.sqrt(x @ x), "norm(x)")
        '''))
    assert release(root) == ["exercises/99_norm.ipynb"]
    subs = tmp_path / "subs"
    for name, body in {"good": "return float(np.sqrt(x @ x))", "slow": "import time; time.sleep(3)",
                       "lib": "return float(np.linalg.norm(x))"}.items():
        nb = json.loads((root / "exercises" / "99_norm.ipynb").read_text())
        nb["cells"][1]["source"] = f"import numpy as np\n\ndef norm(x):\n    {body}"
        (subs / name).mkdir(parents=True)
        (subs / name / "99_norm.ipynb").write_text(json.dumps(nb))
    (subs / "stub").mkdir()
    (subs / "stub" / "99_norm.ipynb").write_text((root / "exercises" / "99_norm.ipynb").read_text())
    summary = grade([subs], tmp_path / "out", root=root, seed=5, jobs=2)
    tests = {s: {t["test"]: t for t in r[0]["tests"]} for s, r in summary["students"].items()}
    assert all(t["passed"] for t in tests["good"].values())
    assert tests["good"]["test_norm"]["points"] == 2 and tests["good"]["test_norm_random"]["hidden"]
    assert "did not finish within 1.5 s" in tests["slow"]["test_norm"]["reason"]
    assert "returned None" in tests["slow"]["test_norm_random"]["reason"]  # 5 s default: the sleep ends
    assert "uses `numpy.linalg.norm`" in tests["lib"]["test_norm"]["reason"]
    assert "not implemented yet" in tests["stub"]["test_norm"]["reason"]
    assert np.isclose(tests["good"]["test_norm_random"]["seed"], 5)


def test_a_forbidden_class_keeps_its_library_subclasses_working():
    """Forbidding ParticleSystem still lets the library import and use MassSpringSystem (its subclass),
    while calling ParticleSystem itself raises PermissionError naming the reason."""
    script = textwrap.dedent('''
        import sys
        from particles.course.walls import audit as sandbox
        wires = sandbox.Tripwires({"particles.system.ParticleSystem": "write the loop yourself"})
        sys.meta_path.insert(0, wires)
        wires.wire()  # as the worker does
        from particles.massspring import MassSpringSystem, string
        s = string(5)
        assert isinstance(s, MassSpringSystem) and s.run(0.01, 0.005)[1].shape[0] == 3
        import particles.system
        assert isinstance(s, particles.system.ParticleSystem)
        try:
            particles.system.ParticleSystem([[0.0, 0.0]])
        except PermissionError as error:
            print("refused:", error)
        else:
            print("ParticleSystem was not refused")
    ''')
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr[-2000:]
    assert "refused: particles.system.ParticleSystem is not allowed in this exercise: write the loop yourself" \
        in result.stdout


ECHO_TESTS = '''
import json, os, signal
import pytest

EXERCISE = "98_echo"


@pytest.mark.points(2)
def test_echo(student, request):
    """echo returns its argument."""
    value = student.call("echo", 3)
    if value in ("kill", "forge"):  # stands for a submission that got out of its worker's walls
        forged = {"submissions": [{"id": str(k), "seed": 0, "seconds": 0.1, "tests": [
            {"test": name, "name": name, "points": 2.0, "hidden": False, "passed": True, "reason": "",
             "grader_error": False, "seconds": 0.0, "seed": None}
            for name in ("test_echo", "test_nap_marked", "test_nap_default")]} for k in range(10)]}
        with open(request.config.getoption("--grading-results"), "w") as f:
            f.write(json.dumps(forged))
        if value == "kill":  # forge the records, then kill the session before it writes its own
            os.kill(os.getpid(), signal.SIGKILL)
        request.config.option.grading_results = os.devnull  # forge them, and keep the session's own away
    assert value == 3, f"echo(3) returned {value!r}"


@pytest.mark.time_limit(3.0)
def test_nap_marked(student):
    """A test with its own time limit: nap(1.0) has 3 s, whatever --time-limit says."""
    assert student.call("nap", 1.0) == 1.0


def test_nap_default(student):
    """A test without one: --time-limit is its limit."""
    assert student.call("nap", 1.0) == 1.0


def test_the_worker_gets_no_key(student):
    """The worker's environment and open files hold neither the session's signing key nor its pipe."""
    names, fds = student.call("environment")
    assert [n for n in names if "PARTICLES" in n or "TOKEN" in n] == [], names
    assert fds == [0, 1, 2, 3, 4, 5], fds  # /dev/null, its output file twice, the two protocol pipes, listdir's
'''


def _echo_course(tmp_path, students):
    """A course folder with exercise 98_echo (see ECHO_TESTS) and a notebook per student: name -> echo's body."""
    root = tmp_path / "course"
    (root / "tests" / "exercises").mkdir(parents=True)
    (root / "tests" / "exercises" / "test_98_echo.py").write_text(ECHO_TESTS)
    subs = tmp_path / "subs"
    for name, body in students.items():
        source = (f"import os, time\n\ndef echo(x):\n    {body}\n\ndef nap(s):\n    time.sleep(s)\n    return s\n\n"
                  "def environment():\n    return sorted(os.environ), sorted(int(fd) for fd in os.listdir('/proc/self/fd'))")
        nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(source)])
        (subs / name).mkdir(parents=True)
        nbformat.write(nb, str(subs / name / "98_echo.ipynb"))
    return root, subs


def test_records_of_a_killed_or_forged_session_are_discarded(tmp_path, monkeypatch):
    """Records of a session killed after forging them, or forged while the session's own went elsewhere, do
    not count: the batch is graded again notebook by notebook, and the forger gets every test 'not run'."""
    import particles.course.grading.plan as grading

    root, subs = _echo_course(tmp_path, {"good": "return x", "killer": "return 'kill'", "forger": "return 'forge'"})
    monkeypatch.setattr(grading, "batches", lambda units, jobs: [sorted(units, key=lambda u: u.student)])
    summary = grade([subs], tmp_path / "out", root=root, seed=1, jobs=1)
    tests = {s: {t["test"]: t for t in r[0]["tests"]} for s, r in summary["students"].items()}
    assert all(t["passed"] for t in tests["good"].values()), tests["good"]
    for student, why in (("killer", "pytest exit status -9"),
                         ("forger", "the session's records were missing or not the ones it signed")):
        assert len(tests[student]) == 4 and not any(t["passed"] for t in tests[student].values()), tests[student]
        assert all(t["reason"].startswith(f"not run: grading stopped early ({why})")
                   for t in tests[student].values()), tests[student]
    logs = sorted(p.name for p in (tmp_path / "out" / "logs").iterdir())
    assert "killer-98_echo.log" in logs and "forger-98_echo.log" in logs  # each graded again, alone


def test_a_records_file_without_the_sessions_signature_is_refused(tmp_path):
    """read_records accepts the file signed with the session's key only: not unsigned, altered or re-signed."""
    from particles.course.results.signing import read_records, sign_records

    key = b"k" * 32
    body = json.dumps({"submissions": [{"id": "0", "tests": []}]})
    path = tmp_path / "records.json"
    path.write_text(json.dumps({"body": body, "signature": sign_records(body, key)}))
    assert read_records(path, key) == {"0": {"id": "0", "tests": []}}
    assert read_records(path, b"x" * 32) is None
    forged = body.replace('"tests": []', '"tests": [{"passed": true}]')
    for text in (body, json.dumps({"body": forged, "signature": sign_records(body, key)}),
                 json.dumps({"body": forged, "signature": sign_records(forged, b"guess")}), "{", ""):
        path.write_text(text)
        assert read_records(path, key) is None
    assert read_records(tmp_path / "missing.json", key) is None


def test_a_time_limit_marker_wins_over_the_default(tmp_path):
    """--time-limit is the limit of tests without a marker; a test's time_limit marker keeps its own."""
    root, subs = _echo_course(tmp_path, {"good": "return x"})
    summary = grade([subs], None, root=root, seed=1, time_limit=0.5)
    tests = {t["test"]: t for t in summary["students"]["good"][0]["tests"]}
    assert tests["test_nap_marked"]["passed"], tests["test_nap_marked"]["reason"]
    assert "did not finish within 0.5 s" in tests["test_nap_default"]["reason"]
    assert tests["test_the_worker_gets_no_key"]["passed"], tests["test_the_worker_gets_no_key"]["reason"]


def test_a_submission_cannot_read_a_classmates_notebook_or_the_grades(tmp_path):
    """The submissions folder and the output folder are private: a worker may not read or list them."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    (subs / "alice").mkdir(parents=True)
    (subs / "alice" / "00_warmup.ipynb").write_text((ROOT / "solutions" / "00_warmup.ipynb").read_text())
    peek = f'''
import json, os

def euler_step(f, X, t, h):
    cells = json.load(open({str(subs / "alice" / "00_warmup.ipynb")!r}))["cells"]
    namespace = {{"np": np}}
    exec(next("".join(c["source"]) for c in cells if "".join(c["source"]).startswith("def euler_step")), namespace)
    return namespace["euler_step"](f, X, t, h)

def total_force(x, v, m, g, d):
    os.listdir({str(out)!r})
    return m[:, None] * g - d * v
'''
    nb = json.loads((ROOT / "exercises" / "00_warmup.ipynb").read_text())
    for name in ("total_force", "euler_step"):  # total_force first: the new euler_step cell defines both
        cell = next(c for c in nb["cells"] if c["cell_type"] == "code" and f"def {name}(" in "".join(c["source"]))
        cell["source"] = peek if name == "euler_step" else "# total_force is defined with euler_step"
    (subs / "mallory").mkdir()
    (subs / "mallory" / "00_warmup.ipynb").write_text(json.dumps(nb))
    summary = grade([subs], out, root=ROOT, seed=1, public_only=True)
    alice = summary["students"]["alice"][0]["tests"]
    assert all(t["passed"] for t in alice)
    mallory = {t["test"]: t for t in summary["students"]["mallory"][0]["tests"]}
    assert "read its private files" in mallory["test_euler_step_circle"]["reason"]
    assert "alice" in mallory["test_euler_step_circle"]["reason"]
    assert "list its private folders" in mallory["test_total_force_three_particles"]["reason"]


@pytest.mark.parametrize("limits, name", [
    ({"time_limit": -1.0}, "time_limit"), ({"time_limit": 0}, "time_limit"),
    ({"time_limit": float("nan")}, "time_limit"), ({"time_limit": float("inf")}, "time_limit"),
    ({"memory_mb": 0}, "memory_mb"), ({"memory_mb": -5}, "memory_mb"), ({"memory_mb": True}, "memory_mb"),
    ({"load_time_limit": "5"}, "load_time_limit"),
])
def test_bad_limits_are_rejected(tmp_path, limits, name):
    """A limit that is not a finite number > 0 raises ValueError naming it, in Submission and in grade."""
    code = SubmissionCode.from_cells([("code cell 1", "def f():\n    return 1.0")])
    with pytest.raises(ValueError, match=f"{name} must be a finite number > 0"):
        Submission(code, **limits)
    if name in ("time_limit", "memory_mb"):
        with pytest.raises(ValueError, match=f"{name} must be a finite number > 0"):
            grade([ROOT / "solutions" / "00_warmup.ipynb"], tmp_path / "out", root=ROOT, **limits)
        assert not (tmp_path / "out").exists()


def test_counted_functions_are_counted_by_the_grader(submission):
    """A counted registry function is evaluated in the grader, which counts every call; the worker cannot lie."""
    X = np.array([1.0, 0.0])
    value = submission.call("three_evaluations_claiming_one", remote("circle", counted=True), X, 0.0)
    assert submission.calls_of(0) == 4 and value.shape == (2,)
    submission.call("three_evaluations_claiming_one", remote("circle"), X, 0.0)  # evaluated in the worker
    with pytest.raises(ValueError, match="no function counted by the grader at position 0"):
        submission.calls_of(0)  # the worker's own count is never read


@pytest.mark.parametrize("forge", ["plain", "wrapper", "class_call", "evaluate", "threads"])
def test_forged_counts_change_nothing(submission, forge):
    """Two evaluations count two, whatever the code does to `f`, its class, its count or the worker's hook."""
    X = np.array([1.0, 0.0])
    f = remote("circle", counted=True)
    value = submission.call("two_evaluations", f, X, 0.0, forge)
    assert submission.calls_of(0) == 2
    np.testing.assert_allclose(value, f(X, 0.0))


def test_a_counted_function_is_an_opaque_token_in_the_worker(tmp_path):
    """The worker gets neither the problem's name nor its parameters, so it cannot evaluate f by itself."""
    code = SubmissionCode.from_cells([("code cell 1", "def show(f):\n    return repr(f) + repr(vars(f))")])
    with Submission(code, scratch=tmp_path) as sub:
        text = sub.call("show", remote("harmonic_oscillator", counted=True, omega=2.75))
        assert "evaluated by the grader" in text
        assert "harmonic" not in text and "2.75" not in text and "omega" not in text
        with pytest.raises(ValueError, match="counted by the grader"):
            sub.calls_of(1)