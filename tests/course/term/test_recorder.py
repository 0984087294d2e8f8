"""The course record as a run's record stage: notebooks registered with their times, results saved with their run,
written grades kept across runs, the run's end said."""

from datetime import datetime, timezone
from pathlib import Path

from particles.course.grading.discovery import Unit
from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.results.rubric import Grade, WrittenGrades
from particles.course.term.database import TermRecord
from particles.course.term.recorder import DatabaseRecorder


def test_a_run_registers_its_notebooks_saves_its_results_and_says_how_it_ended(tmp_path):
    """start() records each notebook (file, digest, origin, time and its source); save() stamps the run; finish()
    says complete, and the record is free for the next run."""
    notebook = tmp_path / "ann.ipynb"
    notebook.write_text("{}")
    when = datetime(2026, 10, 1, tzinfo=timezone.utc)
    units = [Unit("ann", "00_warmup", notebook, place=("zip", "c.zip", "canvas", "7")),
             Unit("bob", "00_warmup", notebook, rejected="not JSON")]
    recorder = DatabaseRecorder.open(tmp_path / "out", {"seed": 3})
    recorder.start(units, lambda unit: (when, "the times file") if unit.student == "ann" else (None, ""))
    rows = recorder.term.db.execute("SELECT file, sha256, origin, submitted, time_source, state FROM submissions "
                                    "ORDER BY id").fetchall()
    assert rows[0][2:] == ("canvas", when.isoformat(), "the times file", "planned") and rows[0][1] == units[0].digest()
    assert rows[1][5] == "rejected"
    record = SubmissionRecord(student="ann", exercise="00_warmup", complete=True, grader_status=0,
                              notebook_sha256=units[0].digest(), tests=[TestRecord("t", "t", 2.0, passed=True)])
    recorder.save(record)
    assert record.run["id"] == recorder.run and recorder.pending() == []
    recorder.finish()
    term = TermRecord(tmp_path / "out")
    term.lock()  # free again
    assert term.run_info(1)["status"] == "complete" and term.current()[("ann", "00_warmup")].run["id"] == 1
    term.close()


def test_written_grades_persist_across_runs_and_come_back_term_wide(tmp_path):
    """A run without a rubric still gets the written grades an earlier run's rubric gave (regrades keep them)."""
    first = DatabaseRecorder.open(tmp_path, {})
    first.start([], lambda unit: (None, ""))
    grade = Grade("01_integrator_order", "ann", 1, 3.0, 2.5, "good", "r.csv sha256:1", "r.csv, line 2")
    kept = first.keep_written(WrittenGrades([grade], None, {"01_integrator_order": {1: 3.0, 2: 2.0}}))
    assert kept.grades[("01_integrator_order", "ann", 1)].points == 2.5
    first.finish()
    second = DatabaseRecorder.open(tmp_path, {})
    second.start([], lambda unit: (None, ""))
    again = second.keep_written(WrittenGrades([], None, {"01_integrator_order": {1: 3.0, 2: 2.0}}))
    assert again.covers("01_integrator_order") and again.grades[("01_integrator_order", "ann", 1)].comment == "good"
    second.finish(complete=False)
    term = TermRecord(tmp_path)
    assert term.run_info(2)["status"] == "interrupted"
    term.close()
    assert Path(tmp_path / "course.sqlite").exists()
