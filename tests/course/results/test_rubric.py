"""Rubrics of the written answers: every bad row refused by file and line, the merge into records and reports."""

import json
from pathlib import Path

import jsonschema
import pytest

from particles.course.grading.discovery import Unit
from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.results.reports import feedback_html, feedback_markdown, gradescope_results, write_gradebook
from particles.course.results.rubric import COLUMNS, NO_ANSWER, RubricError, WrittenGrades, exercise_questions

from .test_reports import GRADESCOPE_SCHEMA

ROOT = Path(__file__).resolve().parents[3]
EXERCISE = "01_integrator_order"  # three questions: 3, 2 and 2 points
UNITS = [Unit("ada", EXERCISE, Path("ada.ipynb")), Unit("bob", EXERCISE, Path("bob.ipynb"))]
HEADER = ",".join(COLUMNS)


def _rubric(tmp_path, *rows, name="rubric.csv"):
    path = tmp_path / name
    path.write_text("\n".join([HEADER, *rows]) + "\n")
    return path


def _record(student, blank=()):
    tests = [TestRecord(test="test_a", name="a", points=4, passed=True),
             TestRecord(test="test_b", name="b", points=6, passed=False, reason="wrong")]
    return SubmissionRecord(student=student, exercise=EXERCISE, tests=tests,
                            written_answers={"asked": 3, "answered": 3 - len(blank), "blank": list(blank)})


def test_the_masters_points_are_the_rubrics_maxima():
    """The rubric's maxima are the master's points of each question."""
    assert exercise_questions(ROOT, EXERCISE) == {1: 3.0, 2: 2.0, 3: 2.0}


@pytest.mark.parametrize("row, expected", [
    (f"{EXERCISE},eve,1,3,2,", r"line 2: unknown student 'eve'; expected one of the 2 students .*ada, bob"),
    (f"{EXERCISE},ada,4,3,2,", r"line 2: unknown question '4' of 01_integrator_order; expected one of 1, 2, 3"),
    (f"{EXERCISE},ada,one,3,2,", r"line 2: unknown question 'one'"),
    ("09_nothing,ada,1,3,2,", r"line 2: unknown exercise '09_nothing'; expected one of 01_integrator_order"),
    (f"{EXERCISE},ada,1,3,4,", r"line 2: points 4 outside \[0, 3\]"),
    (f"{EXERCISE},ada,1,3,-1,", r"line 2: points -1 outside \[0, 3\]"),
    (f"{EXERCISE},ada,1,3,two,", r"line 2: points 'two' is not a number; expected a number in \[0, 3\]"),
    (f"{EXERCISE},ada,1,3,nan,", r"line 2: points 'nan' is not a number"),
    (f"{EXERCISE},ada,1,5,2,", r"line 2: max_points '5' disagrees with the master: question 1 .* worth 3 points"),
    (f"{EXERCISE},ada,1,3", r"line 2: 4 fields; expected 6"),
])
def test_each_kind_of_bad_row_is_an_error_naming_file_line_and_expectation(tmp_path, row, expected):
    """An unknown student, question or exercise, bad points or maxima: RubricError with file and line."""
    path = _rubric(tmp_path, row)
    with pytest.raises(RubricError, match=expected) as caught:
        WrittenGrades.load([path], UNITS, ROOT)
    assert str(path) in str(caught.value) and len(caught.value.problems) == 1
    assert isinstance(caught.value, ValueError)  # the CLI's exit status 2


def test_a_duplicated_row_is_an_error_in_one_file_or_across_two(tmp_path):
    """The same student and question twice is refused, naming both places."""
    row = f"{EXERCISE},ada,1,3,2,good"
    one = _rubric(tmp_path, row, row)
    with pytest.raises(RubricError, match=r"line 3: ada's question 1 .* graded twice \(also .*line 2\)"):
        WrittenGrades.load([one], UNITS, ROOT)
    two = _rubric(tmp_path, row, name="other.csv")
    (tmp_path / "rubric.csv").write_text(f"{HEADER}\n{row}\n")
    with pytest.raises(RubricError, match=r"rubric.csv, line 2: .* graded twice \(also .*other.csv, line 2\)"):
        WrittenGrades.load([tmp_path], UNITS, ROOT)  # a folder: every CSV file under it
    assert two.exists()


@pytest.mark.parametrize("header, expected", [
    ("exercise,student,question,points,comment", r"line 1: .*missing max_points"),
    (HEADER + ",grader", r"line 1: .*unknown grader"),
    ("", r"line 1: empty file"),
])
def test_a_bad_header_is_an_error(tmp_path, header, expected):
    """A missing, unknown or absent column is refused: no column is silently dropped."""
    path = tmp_path / "rubric.csv"
    path.write_text(header)
    with pytest.raises(RubricError, match=expected):
        WrittenGrades.load([path], UNITS, ROOT)


def test_missing_paths_are_errors(tmp_path):
    """A rubric path that does not exist, or a folder without CSV files, is refused."""
    with pytest.raises(RubricError, match="no such rubric file or folder"):
        WrittenGrades.load([tmp_path / "nope.csv"], UNITS, ROOT)
    with pytest.raises(RubricError, match=r"a folder without any rubric \(\*.csv\) file"):
        WrittenGrades.load([tmp_path], UNITS, ROOT)


def _graded(tmp_path):
    path = _rubric(tmp_path, f"{EXERCISE},ada,1,3,2.5,Right idea; the order is 1.", f"{EXERCISE},ada,2,2,2,",
                   f"{EXERCISE},ada,3,2,,", "", f"{EXERCISE},bob,2,2,1,\"Half, see <the> norm\"")
    return path, WrittenGrades.load([path], UNITS, ROOT)


def test_the_merge_fills_every_question_and_the_totals(tmp_path):
    """Rows give points and comments; a missing row is "not graded yet", a blank answer without one scores 0."""
    path, written = _graded(tmp_path)
    ada, bob = _record("ada"), _record("bob", blank=[1])
    assert written.apply([ada, bob]) == 2
    assert [(w["question"], w["points"], w["max_points"], w["comment"]) for w in ada.written] == [
        ("1", 2.5, 3.0, "Right idea; the order is 1."), ("2", 2.0, 2.0, ""), ("3", None, 2.0, "")]
    assert [(w["question"], w["points"], w["comment"]) for w in bob.written] == [
        ("1", 0.0, NO_ANSWER), ("2", 1.0, "Half, see <the> norm"), ("3", None, "")]
    assert ada.written_score == 4.5 and ada.written_max == 7 and ada.total == 8.5 and ada.total_max == 17
    assert bob.total == 5 and bob.total_max == 17
    version = ada.written[0]["rubric"]
    assert version.startswith(f"{path} sha256:") and all(w["rubric"] == version for w in ada.written + bob.written)
    assert written.apply([ada, bob]) == 0  # the same rubric changes nothing
    # a changed rubric changes the records it covers, with its new version; another exercise is untouched
    path.write_text(f"{HEADER}\n{EXERCISE},ada,1,3,3,\n")
    other = SubmissionRecord(student="ada", exercise="00_warmup")
    again = WrittenGrades.load([path], UNITS + [Unit("ada", "00_warmup", Path("a.ipynb"))], ROOT)
    assert again.apply([ada, bob, other]) == 2 and other.written == []
    assert ada.written[0]["points"] == 3 and ada.written[0]["rubric"] != version and ada.written[1]["points"] is None


def test_no_rubric_changes_nothing():
    """Without a rubric the records keep no written grades and their totals are the tests' scores."""
    written = WrittenGrades.load([], UNITS, ROOT)
    ada = _record("ada")
    assert written.apply([ada]) == 0 and ada.written == [] and ada.total == ada.score == 4
    assert written.manual() == {EXERCISE: {1: 3.0, 2: 2.0, 3: 2.0}}


def test_feedback_gradebook_and_results_show_the_written_grades(tmp_path):
    """feedback.md/html list points and comments per question; the gradebook and results.json include them."""
    _, written = _graded(tmp_path)
    ada, bob = _record("ada"), _record("bob", blank=[1])
    written.apply([ada, bob])
    text = feedback_markdown("ada", [ada])
    assert "**Total: 8.5 / 17 points**" in text and f"## {EXERCISE}: 8.5 / 17" in text
    assert "| Question 1 | 2.5 / 3 | Right idea; the order is 1. |" in text
    assert "| Question 3 | not graded yet / 2 |  |" in text
    assert "written answers, graded by people, 4.5 / 7" in text
    page = feedback_html("bob", [bob])
    assert "Half, see &lt;the&gt; norm" in page and "<the>" not in page and "no answer" in page
    write_gradebook(tmp_path / "gradebook.csv", {"ada": [ada], "bob": [bob]}, [EXERCISE])
    lines = (tmp_path / "gradebook.csv").read_text().splitlines()
    assert lines[1:] == ["ada,8.5,8.5,17,complete", "bob,5,5,17,complete"]
    data = gradescope_results("ada", [ada], manual=written.manual())
    jsonschema.validate(data, GRADESCOPE_SCHEMA)
    assert data["score"] == 8.5 and data["extra_data"]["max_score"] == 17
    assert f"{EXERCISE}: Tests 4 / 10; written answers, graded by people, 4.5 / 7" in data["output"]
    entries = [t for t in data["tests"] if t["extra_data"].get("written")]
    assert [(t["score"], t["max_score"]) for t in entries] == [(2.5, 3), (2, 2), (0, 2)]
    assert entries[0]["output"] == "Graded by hand: Right idea; the order is 1."
    assert data["extra_data"]["written"][EXERCISE] == json.loads(json.dumps(ada.written))


def test_gradescope_marks_ungraded_written_questions_for_manual_grading():
    """Without a rubric each written question is a 0-point entry saying its points, and nothing meant for instructors."""
    ada = _record("ada", blank=[2])
    data = gradescope_results("ada", [ada], manual=WrittenGrades.load([], UNITS, ROOT).manual())
    jsonschema.validate(data, GRADESCOPE_SCHEMA)
    assert data["score"] == 4 and data["extra_data"]["max_score"] == 10  # the autograder's part only
    names = [t["name"] for t in data["tests"]]
    assert names[2:] == [f"{EXERCISE}: Question {k} (written answer, {p} points)" for k, p in ((1, 3), (2, 2), (3, 2))]
    manual = data["tests"][2:]
    assert all(t["score"] == t["max_score"] == 0 and "manual grading" in t["tags"] for t in manual)
    assert "graded by hand on Gradescope (3 points)" in manual[0]["output"]
    assert "instructor" not in manual[0]["output"] and "manual question" not in manual[0]["output"]
    assert [t["extra_data"]["answered"] for t in manual] == [True, False, True]
