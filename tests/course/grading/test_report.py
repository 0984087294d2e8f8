"""The report stage: the summary of a run, the final outputs with the records brought up to date, Gradescope's file."""

import json
from pathlib import Path

from particles.course.grading.discovery import Unit
from particles.course.grading.options import GradeOptions
from particles.course.grading.record import MemoryRecorder
from particles.course.grading.report import LIBRARY_CHANGED, summarize, write_gradescope, write_reports
from particles.course.grading.session import NOT_RUN
from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.results.rubric import WrittenGrades
from particles.course.walls.isolation import Plan

ROOT = Path(__file__).resolve().parents[3]


def _record(student, exercise="00_warmup", points=2):
    return SubmissionRecord(student=student, exercise=exercise, complete=True, grader_status=0,
                            tests=[TestRecord(test="t", name="t", points=points, passed=True)])


def test_the_summary_lists_students_exercises_in_course_order_and_what_was_kept():
    """Students map to their records, exercises follow the course's order, rejected notebooks are named."""
    units = [Unit("ann", "01_integrator_order", Path("a1.ipynb")), Unit("ann", "00_warmup", Path("a0.ipynb")),
             Unit("bob", "00_warmup", Path("b0.ipynb"), rejected="not JSON")]
    done = {(u.student, u.exercise): _record(u.student, u.exercise) for u in units}
    tests = {"00_warmup": None, "01_integrator_order": None, "02_stiffness": None}
    summary = summarize(tests, units, done, ["b0.ipynb: not JSON"], Plan(), kept=1, others={"x": 1})
    assert summary["exercises"] == ["00_warmup", "01_integrator_order"]
    assert [r.exercise for r in summary["students"]["ann"]] == ["01_integrator_order", "00_warmup"]
    assert summary["rejected"] == ["b0.ipynb"] and summary["resumed"] == 1 and summary["kept"] == 1
    assert summarize(tests, [], {}, [], Plan(), 0, {})["isolation"] == "planned: no-namespaces,no-uid,landlock"


def test_final_reports_bring_the_records_up_to_date_and_say_when_the_library_changed(tmp_path):
    """write_reports writes every student's files and the gradebook, hands each record to the recorder, and a
    changed library is written down beside them."""
    options = GradeOptions(paths=(), out=tmp_path, root=ROOT)
    recorder = MemoryRecorder()
    done = {("ann", "00_warmup"): _record("ann"), ("bob", "00_warmup"): _record("bob", points=3)}
    write_reports(options, done, recorder, WrittenGrades(), changed=[])
    assert set(recorder.current()) == set(done) and not (tmp_path / LIBRARY_CHANGED).exists()
    assert "bob,3,3,3" in (tmp_path / "gradebook.csv").read_text()
    assert json.loads((tmp_path / "ann" / "results.json").read_text())["score"] == 2
    write_reports(options, done, recorder, WrittenGrades(), changed=["course/grading/expect.py"])
    assert "course/grading/expect.py" in (tmp_path / LIBRARY_CHANGED).read_text()


def test_gradescope_gets_every_test_failed_with_the_reason_when_no_notebook_was_found(tmp_path):
    """One Gradescope submission without a notebook of its exercise fails every test of it, saying why once; with
    the grader's files changed it scores nothing at all."""
    target = tmp_path / "results" / "results.json"
    options = GradeOptions(paths=(), root=ROOT, exercise="00_warmup", gradescope=target, public_only=True)
    write_gradescope(options, [], ["upload.zip: not a zip"], "walls", WrittenGrades(), changed=[])
    data = json.loads(target.read_text())
    assert data["score"] == 0 and data["tests"] and all(t["output"] == NOT_RUN for t in data["tests"])
    assert data["output"].count("upload.zip: not a zip") == 1 and "Not graded: upload.zip: not a zip" in data["output"]
    write_gradescope(options, [_record("submission")], [], "walls", WrittenGrades(), changed=["x.py"])
    changed = json.loads(target.read_text())
    assert changed["score"] == 0 and changed["tests"] == [] and "files changed" in changed["output"]


def test_the_gradebook_status_says_what_each_row_still_waits_for():
    """A notebook a run did not finish, one of an interrupted run, one no machine could grade: each is named with
    what to do; a row with nothing pending has no status."""
    from particles.course.grading.report import statuses

    lost = _record("cy")
    lost.complete, lost.notes = False, ["Not graded yet: worker tcp://10.0.0.7 died"]
    done = {("ann", "00_warmup"): _record("ann"), ("cy", "00_warmup"): lost}
    pending = [("bo", "00_warmup", None), ("di", "01_integrator_order", 3), ("cy", "00_warmup", 4)]
    said = statuses(done, pending, run=4)
    assert said == {"bo": "00_warmup not graded yet (this run has not finished; rerun with --resume)",
                    "di": "01_integrator_order not graded yet (run 3 was interrupted; rerun with --resume)",
                    "cy": "00_warmup not graded yet (worker tcp://10.0.0.7 died; rerun with --resume)"}
