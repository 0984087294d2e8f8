"""Cells the course provides may use what an exercise forbids; the student's code may not.

A provided cell (no solution block in the master) is recognised in a
submission by its unchanged source (:meth:`SubmissionCode.from_cells`). The
worker trusts the code objects compiled from those cells, by identity, before
anything runs (:func:`particles.course.walls.audit._trust_state`); a tripwire passes
a use on to the library only when the nearest frame outside the library is
such code. The syntax-tree check does not follow a student's call into a
provided function either, and errors of provided cells that only follow from
unwritten functions are not the student's.
"""

import numpy as np
import pytest

from particles.course.reading.submission import SubmissionCode
from particles.course.reading.provided import provided_cells
from particles.course.worker.runner import GradingFailure, Submission

FORBIDDEN = {"particles.integrators.euler": "it is the step you are asked to write"}

PROVIDED = '''
import numpy as np
from particles.integrators import euler

def given_step(x):
    """The course's helper: one Euler step of dx/dt = -x with h = 0.1."""
    return euler(lambda X, t: -X, np.asarray(x, float), 0.0, 0.1)

first = given_step([1.0, 2.0])
'''

STUDENT = '''
def mine(x):
    return given_step(x) * 2

def cheat(x):
    return euler(lambda X, t: -X, np.asarray(x, float), 0.0, 0.1)

def spoof(x):
    namespace = dict(globals(), x0=np.asarray(x, float))
    exec(compile("r = euler(lambda X, t: -X, x0, 0.0, 0.1)", "<code cell 1>", "exec"), namespace)
    return namespace["r"]

def stub(x):
    raise NotImplementedError("stub is not written yet")

def read_first():
    return first

def read_later():
    return checked, also
'''

LATER = "checked = stub(1.0)\nalso = missing_name + 1\n"


@pytest.fixture(scope="module")
def submission():
    cells = [("code cell 1", PROVIDED), ("code cell 2", STUDENT), ("code cell 3", LATER)]
    sub = Submission(SubmissionCode.from_cells(cells, provided=[PROVIDED + "\n\n", LATER]),
                     forbidden=FORBIDDEN, time_limit=5.0)
    yield sub
    sub.close()


def test_a_provided_cell_runs_with_the_forbidden_function(submission):
    """A provided cell may use the forbidden function when it loads."""
    assert np.allclose(submission.call("read_first"), [0.9, 1.8])


def test_a_student_function_may_call_a_provided_helper(submission):
    """A student's function may call a provided helper that uses the forbidden function."""
    assert np.allclose(submission.call("mine", [1.0]), [1.8])
    assert submission.code.forbidden_uses("mine", FORBIDDEN) == []


def test_the_student_code_itself_is_refused(submission):
    """The student's own use of the forbidden function is refused, statically and at run time."""
    with pytest.raises(GradingFailure, match="particles.integrators.euler`?,? (is not allowed|which this exercise forbids)"):
        submission.call("cheat", [1.0])
    assert [use for use, _ in submission.code.forbidden_uses("cheat", FORBIDDEN)] == ["particles.integrators.euler"]


def test_code_compiled_under_a_provided_cells_name_is_not_trusted(submission):
    """Code compiled at run time under a provided cell's label is not trusted."""
    with pytest.raises(GradingFailure, match="not allowed in this exercise"):
        submission.call("spoof", [1.0])


def test_errors_of_provided_cells_that_follow_from_unwritten_code_are_not_the_students(submission):
    """NotImplementedError and consequent NameErrors of provided cells are not reported as the student's."""
    submission.call("read_first")  # loaded
    errors = submission.load_errors
    assert {e["type"] for e in errors} == {"NotImplementedError", "NameError"}
    assert submission.code.student_load_errors(errors) == []


def test_a_changed_provided_cell_is_the_students():
    """A provided cell the student changed is the student's code, under the rules."""
    edited = PROVIDED.replace("h = 0.1", "h = 0.1 (mine)")
    code = SubmissionCode.from_cells([("code cell 1", edited)], provided=[PROVIDED])
    assert not any(c.provided for c in code.chunks) and code.provided_labels == set()
    sub = Submission(code, forbidden=FORBIDDEN, time_limit=5.0)
    try:
        with pytest.raises(GradingFailure, match="particles.integrators.euler"):
            sub.call("given_step", [1.0])
    finally:
        sub.close()


def test_the_provided_cells_of_an_exercise_come_from_its_master():
    """An exercise's provided cells are its master's code cells without a solution block."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    cells = provided_cells(root, "03_provot")
    assert cells and not any("YOUR CODE HERE" in c or "BEGIN SOLUTION" in c for c in cells)
    assert any("def make_curtain" in c for c in cells)
