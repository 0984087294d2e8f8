"""The worker seen from the grader: limits, refusals, restarts, and a new exercise end to end."""

import json
import subprocess
import sys
import textwrap

import nbformat
import numpy as np
import pytest

from particles.course.code import SubmissionCode
from particles.course.grading import grade
from particles.course.release import release
from particles.course.runner import GradingFailure, Submission

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
    ("big_file", "File too large"),
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
        from particles.course.expect import expect_float

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
        from particles.course import sandbox
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
