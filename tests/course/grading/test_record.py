"""The record stage: a result decided, saved, reported and counted as it arrives; a run marked until it finishes."""

from pathlib import Path

import pytest

from particles.course.grading.discovery import Unit
from particles.course.grading.record import INCOMPLETE, Collector, FolderRecorder, MemoryRecorder
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
    collect = Collector(recorder, late, report=lambda done, students: reported.append((len(done), students)),
                        progress=seen.append, done={("zoe", "00_warmup"): earlier})
    collect([_record("ann"), _record("bob", passed=False)])
    assert decided == ["ann", "bob"] and [r.student for r in seen] == ["ann", "bob"]
    assert reported == [(3, ["ann", "bob"])]
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


def test_the_folder_recorder_marks_a_run_until_it_finishes_and_keeps_records_as_files(tmp_path):
    """start() writes the incomplete mark (the gradebook is partial), finish() removes it; save, update and
    current go through the records folder; regrade names the students it knows."""
    recorder = FolderRecorder(tmp_path, {"seed": 1})
    recorder.start(3)
    assert "of 3 notebook(s), has not finished" in (tmp_path / INCOMPLETE).read_text()
    recorder.save(_record("ann"))
    record = _record("ann")
    record.late = {"penalty": 1.0}
    recorder.update(record)
    assert recorder.current()[("ann", "00_warmup")].late == {"penalty": 1.0}
    recorder.finish()
    assert not (tmp_path / INCOMPLETE).exists()
    units, others = recorder.regrade([Unit("ann", "00_warmup", Path("ann.ipynb"))], ["ann"])
    assert [u.student for u in units] == ["ann"] and others == {}
    with pytest.raises(ValueError, match="unknown student 'bob'"):
        recorder.regrade([Unit("ann", "00_warmup", Path("ann.ipynb"))], ["bob"])


def test_the_memory_recorder_keeps_nothing_for_a_later_run():
    """A run without an output folder resumes nothing and cannot regrade one student."""
    recorder = MemoryRecorder()
    recorder.start(1)
    assert recorder.kept(Unit("ann", "00_warmup", Path("ann.ipynb")), "v") is None and recorder.complete is False
    recorder.finish()
    assert recorder.complete is True
    with pytest.raises(ValueError, match="student needs the records of an earlier run"):
        recorder.regrade([], ["ann"])
