"""The run stage: batches graded by a runner, a session's unfinished notebooks again alone, lost batches retried."""

import threading
from pathlib import Path

import pytest

from particles.course.grading import run, session
from particles.course.grading.discovery import Unit
from particles.course.grading.plan import Batch
from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.walls.isolation import Plan

ROOT = Path(__file__).resolve().parents[3]
SETTINGS = run.SessionSettings(root=ROOT, plan=Plan(), public_only=True)


def _batch(number, *students):
    return Batch(number, tuple(Unit(s, "00_warmup", Path(f"{s}.ipynb")) for s in students), (7,) * len(students))


def _graded(unit, complete=True):
    return SubmissionRecord(student=unit.student, exercise=unit.exercise, complete=complete, grader_status=0,
                            tests=[TestRecord(test="t", name="t", points=1, passed=complete)])


def test_a_session_that_stopped_early_has_its_unfinished_notebooks_graded_alone(monkeypatch):
    """run_batch grades the batch in one session, then each notebook it did not finish in a session of its own,
    with the same seed, each logged under the student's name."""
    alone = []
    monkeypatch.setattr(session, "grade_batch", lambda units, root, **k: [_graded(u, u.student != "bo") for u in units])
    monkeypatch.setattr(session, "grade_unit", lambda unit, root, seed, log, **k: alone.append((unit.student, seed,
                                                                                             log)) or _graded(unit))
    logs = run.SessionSettings(root=ROOT, plan=SETTINGS.plan, logs=Path("logs"))
    results = run.run_batch(_batch(0, "al", "bo", "cy"), logs)
    assert [r.complete for r in results] == [True, True, True]
    assert alone == [("bo", 7, Path("logs") / "bo-00_warmup.log")]


def test_the_local_runner_grades_jobs_batches_at_a_time_and_raises_a_grader_fault(monkeypatch):
    """LocalRunner runs up to `jobs` batches at once and yields each outcome; an exception while grading (a fault
    of the grader, not of a submission) comes out of completed()."""
    running, most = [0], [0]
    lock = threading.Lock()
    gate = threading.Barrier(2, timeout=10)

    def grade_batch(units, root, **options):
        with lock:
            running[0] += 1
            most[0] = max(most[0], running[0])
        gate.wait()  # both batches run at the same time, or this times out
        with lock:
            running[0] -= 1
        if units[0].student == "boom":
            raise OSError("disk full")
        return [_graded(u) for u in units]

    monkeypatch.setattr(session, "grade_batch", grade_batch)
    runner = run.LocalRunner(jobs=2)
    runner.submit(_batch(0, "al"), SETTINGS)
    runner.submit(_batch(1, "bo"), SETTINGS)
    outcomes = list(runner.completed())
    runner.close()
    assert most[0] == 2 and sorted(o.results[0].student for o in outcomes) == ["al", "bo"]
    assert all(o.lost is None for o in outcomes)
    gate.reset()
    runner = run.LocalRunner(jobs=2)
    runner.submit(_batch(0, "boom"), SETTINGS)
    runner.submit(_batch(1, "al"), SETTINGS)
    with pytest.raises(OSError, match="disk full"):
        list(runner.completed())
    runner.close()


class LosingRunner:
    """Grades batches at once, except that a batch with a student of `lose` is lost `times` times (each batch;
    with `whole_only`, only batches of several notebooks are lost)."""

    def __init__(self, lose, times, whole_only=False):
        self.lose, self.left, self.queue, self.log, self.closed = set(lose), {}, [], [], None
        self.times, self.whole_only = times, whole_only

    def submit(self, batch, settings):
        self.log.append(tuple(u.student for u in batch.units))
        self.queue.append(batch)

    def completed(self):
        while self.queue:
            batch = self.queue.pop(0)
            key = tuple(u.student for u in batch.units)
            losable = self.lose & set(key) and not (self.whole_only and len(key) == 1)
            if losable and self.left.setdefault(key, self.times) > 0:
                self.left[key] -= 1
                yield run.Outcome(batch, lost="worker tcp://10.0.0.7 died")
            else:
                yield run.Outcome(batch, results=[_graded(u) for u in batch.units])

    def close(self, cancel=False):
        self.closed = cancel


@pytest.mark.parametrize("times, submissions", [
    (1, [("al", "bo"), ("cy",), ("al", "bo")]),                                 # retried whole, then graded
    (2, [("al", "bo"), ("cy",), ("al", "bo"), ("al",), ("bo",)]),                # then notebook by notebook
])
def test_a_lost_batch_is_sent_again_then_notebook_by_notebook(times, submissions):
    """Lost once: the batch is submitted again; lost twice: cut into single notebooks; every notebook gets exactly
    one record."""
    runner, collected = LosingRunner({"bo"}, times, whole_only=True), []
    run.run_all([_batch(0, "al", "bo"), _batch(1, "cy")], runner, SETTINGS, collected.extend)
    assert runner.log == submissions and runner.closed is False
    assert sorted(r.student for r in collected) == ["al", "bo", "cy"] and all(r.complete for r in collected)


def test_a_notebook_lost_every_time_gets_an_incomplete_record_naming_why():
    """A single notebook still lost after its retries is recorded as not graded yet (complete False, so --resume
    grades it again), every test of its exercise failed with the reason, never a silent 0."""
    runner, collected = LosingRunner({"bo"}, 99), []
    run.run_all([_batch(0, "al", "bo")], runner, SETTINGS, collected.extend)
    (bo,) = [r for r in collected if r.student == "bo"]
    assert not bo.complete and bo.seed == 7 and len(bo.tests) >= 3
    assert all(t.reason == "not graded: worker tcp://10.0.0.7 died; the instructor can grade it again with --resume"
               for t in bo.tests)
    assert bo.notes == ["Not graded yet: worker tcp://10.0.0.7 died"]
    assert runner.log.count(("bo",)) == 2 and [r.student for r in collected].count("al") == 1
