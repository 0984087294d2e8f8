"""The course record: one current result per student and exercise, history kept, every change a transaction,
one run at a time, a run that died marked interrupted."""

import multiprocessing
import sqlite3

import pytest

from particles.course.grading.discovery import Unit
from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.results.rubric import Grade
from particles.course.term.database import RecordBusy, TermRecord


def _record(student, points=2, passed=True, sha="a" * 64, seed=1):
    return SubmissionRecord(student=student, exercise="00_warmup", complete=True, grader_status=0, seed=seed,
                            notebook_sha256=sha, tests_version="v1",
                            tests=[TestRecord(test="t", name="t", points=points, passed=passed)])


def test_a_new_result_replaces_the_current_one_which_stays_as_history(tmp_path):
    """Saving a result of a student's exercise makes it current; the one before is history saying why."""
    term = TermRecord(tmp_path)
    one = term.start_run("first", {})
    term.save(one, _record("ann", passed=False), {})
    two = term.start_run("second", {})
    term.save(two, _record("ann", sha="b" * 64), {})
    assert term.current()[("ann", "00_warmup")].score == 2
    history = term.history("ann", "00_warmup")
    assert [(h["run"], h["current"]) for h in history] == [(one, None), (two, 1)]
    assert history[0]["ended_why"] == f"replaced by a result of run {two}"
    assert term.db.execute("SELECT count(*) FROM tests").fetchone() == (2,)


def test_the_schema_allows_one_current_result_per_student_and_exercise(tmp_path):
    """Two current results of one student's exercise are refused by the database itself."""
    term = TermRecord(tmp_path)
    run = term.start_run("x", {})
    term.save(run, _record("ann"), {})
    row = term.db.execute("SELECT student, exercise, run, record, score, max_score, total, total_max, complete, "
                          "created FROM results").fetchone()
    with pytest.raises(sqlite3.IntegrityError, match="UNIQUE"):
        term.db.execute("INSERT INTO results (student, exercise, run, record, score, max_score, total, total_max, "
                        "complete, created, current) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, 1)", row)


def test_a_result_delivered_twice_is_written_once(tmp_path):
    """The same notebook, seed and run saved again (a task delivered twice) adds no history."""
    term = TermRecord(tmp_path)
    run = term.start_run("x", {})
    first = term.save(run, _record("ann"), {})
    assert term.save(run, _record("ann"), {}) == first and len(term.history("ann", "00_warmup")) == 1


def test_a_change_that_fails_half_way_leaves_nothing_of_itself(tmp_path, monkeypatch):
    """A result whose tests cannot be written is not saved at all: the earlier result stays current."""
    term = TermRecord(tmp_path)
    run = term.start_run("x", {})
    term.save(run, _record("ann", points=3), {})
    broken = _record("ann", sha="c" * 64)
    broken.tests.append(TestRecord(test="t", name="again", points=1, passed=True))  # the same test twice
    with pytest.raises(sqlite3.IntegrityError):
        term.save(run, broken, {})
    assert term.current()[("ann", "00_warmup")].max_score == 3 and len(term.history("ann", "00_warmup")) == 1


def _hold(path, ready, release):
    term = TermRecord(path)
    term.lock()
    ready.set()
    release.wait(30)
    term.close()


def test_a_second_run_on_one_record_is_refused_and_a_dead_run_is_marked_interrupted(tmp_path):
    """While a run holds the record another is refused, naming the holder; the lock goes with its process, and the
    next run marks a run left 'running' as interrupted."""
    context = multiprocessing.get_context("fork")
    ready, release = context.Event(), context.Event()
    holder = context.Process(target=_hold, args=(tmp_path, ready, release))
    holder.start()
    assert ready.wait(30)
    other = TermRecord(tmp_path)
    with pytest.raises(RecordBusy, match=r"another grading run \(pid \d+ on .*\) is writing the course record"):
        other.lock()
    release.set()
    holder.join(30)
    other.lock()
    run = other.start_run("dies", {})
    other.close()
    again = TermRecord(tmp_path)
    again.start_run("next", {})
    assert again.run_info(run)["status"] == "interrupted"


def test_written_grades_change_only_when_they_change_and_submission_times_are_kept(tmp_path):
    """A rubric row equal to the current grade adds nothing; a changed one replaces it; the latest real submission
    time of a student's exercise is what a regrade without a times file uses."""
    from datetime import datetime, timezone

    term = TermRecord(tmp_path)
    run = term.start_run("x", {})
    grade = Grade("00_warmup", "ann", 1, 2.0, 1.5, "ok", "rubric.csv sha256:1", "rubric.csv, line 2")
    term.save_written(run, [grade, grade])
    term.save_written(run, [grade])
    assert term.db.execute("SELECT count(*) FROM written").fetchone() == (1,)
    term.save_written(run, [Grade("00_warmup", "ann", 1, 2.0, 2.0, "good", "rubric.csv sha256:2", "")])
    assert term.written() == [("ann", "00_warmup", 1, 2.0, 2.0, "good", "rubric.csv sha256:2")]
    assert term.db.execute("SELECT count(*) FROM written").fetchone() == (2,)
    when = datetime(2026, 10, 1, 12, tzinfo=timezone.utc)
    term.add_submissions(run, [("ann", "00_warmup", "a.ipynb", "d" * 64, "canvas", when, "the times file", "planned"),
                               ("bob", "00_warmup", "b.ipynb", "e" * 64, "canvas", None, "", "planned")])
    assert term.submission_time("ann", "00_warmup") == (when, f"the times file, as recorded in run {run}")
    assert term.submission_time("bob", "00_warmup") == (None, "")
    assert [(s, e) for s, e, _ in term.pending()] == [("ann", "00_warmup"), ("bob", "00_warmup")]


def test_a_resumed_run_keeps_only_a_complete_result_of_the_same_notebook_options_and_tests(tmp_path):
    """kept() needs the same bytes, options and tests version, a complete result and a normal session end."""
    notebook = tmp_path / "ann.ipynb"
    notebook.write_text("{}")
    unit = Unit("ann", "00_warmup", notebook)
    term = TermRecord(tmp_path / "out")
    run = term.start_run("x", {})
    term.save(run, _record("ann", sha=unit.digest()), {"seed": 1})
    assert term.kept(unit, "v1", {"seed": 1}).resumed is True
    assert term.kept(unit, "v2", {"seed": 1}) is None and term.kept(unit, "v1", {"seed": 2}) is None
    notebook.write_text('{"changed": 1}')
    assert term.kept(Unit("ann", "00_warmup", notebook), "v1", {"seed": 1}) is None


def test_a_record_used_as_a_context_closes_and_releases_its_lock_even_when_the_block_fails(tmp_path):
    """``with TermRecord(out) as term``: on leaving, also by an exception, the lock is free for the next run
    and the connection is closed."""
    with pytest.raises(RuntimeError, match="stop"):
        with TermRecord(tmp_path) as term:
            term.lock()
            raise RuntimeError("stop")
    with pytest.raises(sqlite3.ProgrammingError):
        term.db.execute("SELECT 1")
    with TermRecord(tmp_path) as other:
        other.lock()  # not refused: the first one let go
