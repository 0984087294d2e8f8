"""The record stage: a result decided, saved, reported and counted as it arrives; what a run has still to grade."""

from pathlib import Path

from particles.course.grading.discovery import Unit
from particles.course.grading.record import Collector, MemoryRecorder
from particles.course.results.records import SubmissionRecord, TestRecord


def _record(student, passed=True):
    return SubmissionRecord(student=student, exercise="00_warmup", notebook=f"{student}.ipynb", complete=True,
                            grader_status=0, tests=[TestRecord(test="t", name="t", points=2, passed=passed)])


def test_the_collector_decides_saves_reports_and_counts_each_result():
    """Each record gets its late decision before it is saved; the report is told the batch's students; progress
    sees every record; the records decided are in `done`, with those it was given."""
    decided, reported, seen = [], [], []
    recorder = MemoryRecorder()

    def late(record):
        decided.append(record.student)
        record.late = {"penalty": 0.0, "student": record.student}
        return record

    earlier = _record("zoe")
    collect = Collector(recorder, late, report=lambda done, students, todo: reported.append((len(done), students,
                                                                                              todo)),
                        progress=seen.append, done={("zoe", "00_warmup"): earlier})
    collect.todo = {("ann", "00_warmup"), ("bob", "00_warmup"), ("cy", "00_warmup")}
    collect([_record("ann"), _record("bob", passed=False)])
    assert decided == ["ann", "bob"] and [r.student for r in seen] == ["ann", "bob"]
    assert reported == [(3, ["ann", "bob"], [("cy", "00_warmup")])] and collect.collected == 2
    assert set(recorder.current()) == {("ann", "00_warmup"), ("bob", "00_warmup")}
    assert recorder.current()[("ann", "00_warmup")].late == {"penalty": 0.0, "student": "ann"}
    assert collect.done[("zoe", "00_warmup")] is earlier and collect.done[("bob", "00_warmup")].score == 0


def test_a_kept_record_is_saved_again_only_when_its_late_decision_changed():
    """--resume keeps a record as it is; a new deadline or extension changes its late decision, which is saved."""
    recorder = MemoryRecorder()
    same = Collector(recorder, lambda record: record)
    same.keep(_record("ann"))
    assert recorder.current() == {} and ("ann", "00_warmup") in same.done

    def extended(record):
        record.late = {"penalty": 0.0, "reason": "extension"}
        return record

    Collector(recorder, extended).keep(_record("bob"))
    assert recorder.current()[("bob", "00_warmup")].late["reason"] == "extension"


def test_the_memory_recorder_keeps_nothing_for_a_later_run_and_knows_what_is_left():
    """A run without an output folder resumes nothing; until it finishes, what it has not graded is pending."""
    recorder = MemoryRecorder()
    units = [Unit("ann", "00_warmup", Path("ann.ipynb")), Unit("bob", "00_warmup", Path("bob.ipynb"))]
    recorder.start(units, lambda unit: (None, ""))
    assert recorder.kept(units[0], "v") is None and recorder.complete is False
    recorder.save(_record("ann"))
    assert recorder.pending() == [("bob", "00_warmup", None)]
    recorder.finish()
    assert recorder.complete is True and recorder.pending() == []
