"""The grading driver keeps its records: written as they are made, resumed, kept by a killed driver, late work."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent.parent / "grader"))
import corpus  # noqa: E402

from particles.course.walls import isolation  # noqa: E402
from particles.course.grading.driver import LibraryChanged, grade  # noqa: E402
from particles.course.term.database import TermRecord  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]


def _write(folder, name, notebook):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{name}_00_warmup.ipynb").write_text(json.dumps(notebook) if isinstance(notebook, dict) else notebook)


def _current(out):
    """student -> current record (of 00_warmup) in the course record of `out`."""
    with TermRecord(out) as term:
        return {student: record for (student, _), record in term.current().items()}


def test_records_are_written_as_they_are_made_and_resumed(tmp_path):
    """Each notebook's record is in the course record after its batch; --resume keeps unchanged ones and grades the
    rest (a changed notebook, a result retired)."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    for k in range(3):
        _write(subs, f"s{k}", corpus.MASTER.read_text())
    first = grade([subs], out, seed=11, root=ROOT)
    assert sorted(_current(out)) == [f"s{k}_00_warmup" for k in range(3)]
    assert first["resumed"] == 0
    # one notebook changes, one result is retired: both are graded again
    _write(subs, "s1", corpus.STUB.read_text())
    term = TermRecord(out)
    term.retire("s2_00_warmup", "00_warmup", "graded with the wrong tests", "the instructor")
    term.close()
    again = grade([subs], out, seed=11, root=ROOT, resume=True)
    assert again["resumed"] == 1
    scores = {s: sum(t["points"] for t in r[0]["tests"] if t["passed"]) for s, r in again["students"].items()}
    assert scores == {"s0_00_warmup": 11, "s1_00_warmup": 0, "s2_00_warmup": 11}
    assert (out / "gradebook.csv").read_text().count("\n") == 4
    # other options: nothing is kept
    assert grade([subs], out, seed=12, root=ROOT, resume=True)["resumed"] == 0
    with pytest.raises(ValueError, match="resume needs out"):
        grade([subs], None, resume=True, root=ROOT)


def test_a_killed_driver_keeps_its_records(tmp_path):
    """A `particles grade` killed mid-run leaves the finished records and its run marked interrupted by the next;
    --resume grades only the rest."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    for k in range(6):
        _write(subs, f"s{k}", corpus.MASTER.read_text())
    command = [sys.executable, "-m", "particles", "grade", str(subs), "--out", str(out), "--seed", "5",
               "--root", str(ROOT)]
    driver = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and (not (out / "course.sqlite").exists() or len(_current(out)) < 2):
        time.sleep(0.1)
    os.killpg(driver.pid, signal.SIGKILL)
    driver.wait()
    kept = len(_current(out))
    assert 2 <= kept
    book = out / "gradebook.csv"  # a partial gradebook says so (when the run got to write one)
    assert not book.exists() or "not graded yet" in book.read_text() or kept == 6
    done = subprocess.run(command + ["--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert f"resumed: {kept} record(s)" in done.stdout or kept == 6
    assert len(_current(out)) == 6
    assert "sandbox: " in done.stdout
    term = TermRecord(out)
    assert [status for (status,) in term.db.execute("SELECT status FROM runs ORDER BY id")] == ["interrupted",
                                                                                                "complete"]
    term.close()
    assert "not graded yet" not in (out / "gradebook.csv").read_text()


def test_a_changed_library_fails_the_run_loudly(tmp_path, monkeypatch):
    """When the library differs at the end of a run, grade raises LibraryChanged and marks the outputs."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    _write(subs, "s0", corpus.MASTER.read_text())
    monkeypatch.setattr(isolation, "library_changes", lambda before, package=None: ["course/grading/expect.py"])
    with pytest.raises(LibraryChanged, match="expect.py") as caught:
        grade([subs], out, seed=1, root=ROOT)
    assert "s0_00_warmup" in caught.value.summary["students"]
    assert "Do not trust" in (out / "LIBRARY-CHANGED.txt").read_text()


COURSE = """
[late]
penalty_per_day = 0.1
cap = 0.5

[exercises.00_warmup]
deadline = 2026-10-01T23:59:00+01:00

[extensions.alice]
00_warmup = 3
"""


def _late_course(tmp_path, others=()):
    """alice and bob submit the master; alice has a 3-day extension, bob is 10 hours late; `others` are on time."""
    subs = tmp_path / "subs"
    for student in ("alice", "bob", *others):
        (subs / student).mkdir(parents=True)
        (subs / student / "00_warmup.ipynb").write_text(corpus.MASTER.read_text())
    (tmp_path / "course.toml").write_text(COURSE)
    (tmp_path / "times.csv").write_text("student,exercise,submitted\nalice,00_warmup,2026-10-03T10:00:00+01:00\n"
                                        "bob,00_warmup,2026-10-02T09:59:00+01:00\n"
                                        + "".join(f"{o},00_warmup,2026-10-01T09:00:00+01:00\n" for o in others))
    return subs, {"course": tmp_path / "course.toml", "times": tmp_path / "times.csv", "seed": 5, "root": ROOT}


def test_late_work_is_penalized_and_one_student_is_regraded_alone(tmp_path):
    """Records carry the late decision and the tests version; --student regrades alice, bob's record is kept."""
    from particles.course.grading import versions

    subs, options = _late_course(tmp_path)
    out = tmp_path / "out"
    grade([subs], out, **options)
    records = {student: record.to_dict() for student, record in _current(out).items()}
    assert records["alice"]["late"]["penalty"] == 0 and "(extension of 3 day(s) for alice)" in \
        records["alice"]["late"]["reason"]
    bob = records["bob"]["late"]
    assert (bob["days_late"], bob["penalty"], bob["source"]) == (1, 1.1, "the times file")
    assert bob["reason"].startswith("submitted 10 hours after the deadline 2026-10-01 23:59 +01:00: "
                                    "-10% of the exercise's points")
    assert {r["tests_version"] for r in records.values()} == {versions.tests_version(ROOT, "00_warmup")}
    assert "alice,11,11,11" in (out / "gradebook.csv").read_text()
    assert "bob,9.9,9.9,11" in (out / "gradebook.csv").read_text()
    feedback = (out / "bob" / "feedback.md").read_text()
    assert "**Total: 9.9 / 11 points**" in feedback
    assert "Late: raw score 11, penalty -1.1 of 11 points (submitted 10 hours" in feedback
    assert "Graded by tests version tests=" in feedback
    assert "Graded by tests version" in (out / "bob" / "feedback.html").read_text()
    results = json.loads((out / "bob" / "results.json").read_text())
    assert results["score"] == 9.9 and results["extra_data"]["late"]["00_warmup"]["penalty"] == 1.1
    assert "Late: submitted 10 hours after the deadline" in results["output"]  # no points: hidden tests hidden
    assert "raw score" not in results["output"]

    # bad uses of --student, refused before anything is graded
    with pytest.raises(ValueError, match="unknown student 'carol'.*the students are alice, bob"):
        grade([subs], out, students=["carol"], **options)
    with pytest.raises(ValueError, match="holds none"):
        grade([subs], tmp_path / "empty", students=["alice"], **options)
    with pytest.raises(ValueError, match="student needs out"):
        grade([subs], None, students=["alice"], **options)

    # alice hands in the stub instead: only she is graded again
    (subs / "alice" / "00_warmup.ipynb").write_text(corpus.STUB.read_text())
    bob_before = _current(out)["bob"].to_dict()
    again = grade([subs], out, students=["alice"], **options)
    assert list(again["students"]) == ["alice"] and again["students"]["alice"][0].score == 0
    assert _current(out)["bob"].to_dict() == bob_before
    gradebook = (out / "gradebook.csv").read_text()
    assert "alice,0,0,11" in gradebook and "bob,9.9,9.9,11" in gradebook
    assert "**Total: 0 / 11 points**" in (out / "alice" / "feedback.md").read_text()

    # a new extension for bob: --resume keeps both grades and only remakes bob's late decision
    options["course"].write_text(COURSE + "\n[extensions.bob]\n00_warmup = 1\n")
    resumed = grade([subs], out, resume=True, **options)
    assert resumed["resumed"] == 2 and resumed["students"]["bob"][0].penalty == 0
    assert _current(out)["bob"].late["days_late"] == 0
    assert "bob,11,11,11" in (out / "gradebook.csv").read_text()


def test_resume_grades_again_the_records_of_a_changed_test(tmp_path, monkeypatch):
    """--resume keeps a record only when its tests version is the current one of its exercise."""
    from particles.course.grading import driver, session
    from particles.course.grading.discovery import notebook_digest
    from particles.course.results.records import SubmissionRecord, TestRecord

    subs, options = _late_course(tmp_path)
    graded = []

    def fake_batch(units, root, **kwargs):  # no pytest session: complete records, as grade_batch makes them
        graded.extend(u.student for u in units)
        return [SubmissionRecord(student=u.student, exercise=u.exercise, notebook=str(u.notebook), complete=True,
                                 grader_status=0, notebook_sha256=notebook_digest(u.notebook),
                                 tests=[TestRecord(test="t", name="t", points=11, passed=True)],
                                 tests_version=driver.tests_version(root, u.exercise)) for u in units]

    monkeypatch.setattr(session, "grade_batch", fake_batch)
    out = tmp_path / "out"
    grade([subs], out, **options)
    assert sorted(graded) == ["alice", "bob"]
    graded.clear()
    assert grade([subs], out, resume=True, **options)["resumed"] == 2 and graded == []
    real = driver.tests_version
    monkeypatch.setattr(driver, "tests_version", lambda root, exercise, library=None: real(root, exercise, "new"))
    assert grade([subs], out, resume=True, **options)["resumed"] == 0 and sorted(graded) == ["alice", "bob"]
    assert _current(out)["alice"].tests_version.endswith(" library=new")


class MemoryRunner:
    """A run stage that grades nothing: each notebook passes one test of 11 points. Batches holding a notebook
    named in `lose` come back lost (a machine that died with them), every time they are submitted."""

    def __init__(self, lose=()):
        self.lose, self.queue, self.submitted, self.closed = set(lose), [], [], None

    def submit(self, batch, settings):
        self.submitted.append([u.student for u in batch.units])
        self.queue.append(batch)

    def completed(self):
        from particles.course.grading.run import Outcome
        from particles.course.results.records import SubmissionRecord, TestRecord

        while self.queue:
            batch = self.queue.pop(0)
            if self.lose & {u.student for u in batch.units}:
                yield Outcome(batch, lost="the worker machine went away")
                continue
            yield Outcome(batch, results=[
                SubmissionRecord(student=u.student, exercise=u.exercise, notebook=u.where, seed=seed, complete=True,
                                 grader_status=0, tests=[TestRecord(test="t", name="t", points=11, passed=True)])
                for u, seed in zip(batch.units, batch.seeds)])

    def close(self, cancel=False):
        self.closed = "cancelled" if cancel else "done"


class MemoryRecorder:
    """A record stage in a dict, implementing the recorder protocol with nothing on disk."""

    def __init__(self):
        self.records, self.saved, self.marks, self.times = {}, [], [], {}

    def kept(self, unit, version):
        return None

    def save(self, record):
        self.records[(record.student, record.exercise)] = record
        self.saved.append(record.student)

    def update(self, record):
        self.records[(record.student, record.exercise)] = record

    def current(self):
        return dict(self.records)

    def start(self, units, times):
        self.marks.append(("start", len(units)))
        self.times = {u.student: times(u) for u in units}

    def finish(self, complete=True):
        self.marks.append(("finish", complete))

    def pending(self):
        return []

    def keep_written(self, written):
        return written

    def keep_course(self, course):
        self.marks.append(("course", sorted(course.extensions)))


def test_a_whole_run_through_memory_run_and_record_stages(tmp_path):
    """grade() with the run and record stages swapped for in-memory fakes: every notebook gets one current record,
    late decisions are made, a lost batch is sent again, then notebook by notebook, and a notebook lost every time
    gets an incomplete record saying why (never a silent 0); the run is marked started and finished."""
    subs, options = _late_course(tmp_path, others=("carl", "dana", "eve", "malformed"))
    (subs / "malformed" / "00_warmup.ipynb").write_text('{"cells": [')
    runner, recorder, seen = MemoryRunner(lose={"dana"}), MemoryRecorder(), []
    summary = grade([subs], None, runner=runner, recorder=recorder, progress=seen.append, jobs=1, **options)
    assert sorted(s for s, _ in recorder.records) == ["alice", "bob", "carl", "dana", "eve", "malformed"]
    assert sorted(r.student for r in seen) == sorted(recorder.saved) == sorted(summary["students"])
    assert recorder.marks == [("start", 6), ("course", ["alice"]), ("finish", True)] and runner.closed == "done"
    assert recorder.times["bob"][1] == "the times file"
    # dana's batch: sent, lost, sent again, lost, then cut into single notebooks; dana alone is lost twice more
    dana_batches = [b for b in runner.submitted if "dana" in b]
    assert len(dana_batches[0]) > 1 and dana_batches[0] == dana_batches[1] and dana_batches[2:] == [["dana"]] * 2
    dana = recorder.records[("dana", "00_warmup")]
    assert not dana.complete and dana.score == 0 and dana.tests
    assert all(t.reason.startswith("not graded: the worker machine went away; the instructor can grade it again "
                                   "with --resume") for t in dana.tests)
    for student in ("alice", "bob", "carl", "eve"):
        assert recorder.records[(student, "00_warmup")].score == 11
    assert recorder.records[("bob", "00_warmup")].late["penalty"] == 1.1  # the late decision, from the times file
    malformed = recorder.records[("malformed", "00_warmup")]
    assert malformed.score == 0 and malformed.notes[0].startswith("Not graded: ")
    assert summary["rejected"] and summary["resumed"] == 0


def test_an_interrupted_run_stays_marked_incomplete_and_its_runner_drops_what_has_not_started(tmp_path):
    """A run stopped in its run stage (here Ctrl-C after the first batch) closes its runner with the batches not
    started dropped, keeps the records it collected, says in its gradebook what is not graded yet, and is marked
    interrupted in the course record; --resume finishes it."""
    from particles.course.grading.driver import GradingInterrupted

    subs, options = _late_course(tmp_path, others=("carl", "dana"))  # two batches of two

    class Interrupted(MemoryRunner):
        def completed(self):
            for k, outcome in enumerate(super().completed()):
                if k == 1:
                    raise KeyboardInterrupt
                yield outcome

    runner, out = Interrupted(), tmp_path / "out"
    with pytest.raises(GradingInterrupted, match="interrupted: 2 of 4 graded; rerun with --resume"):
        grade([subs], out, runner=runner, jobs=2, **options)
    assert runner.closed == "cancelled"
    assert len(_current(out)) == 2
    book = (out / "gradebook.csv").read_text()
    assert book.count("00_warmup not graded yet (this run has not finished; rerun with --resume)") == 2
    term = TermRecord(out)
    assert term.db.execute("SELECT status FROM runs").fetchall() == [("interrupted",)]
    assert len(term.pending()) == 2
    term.close()
    grade([subs], out, runner=MemoryRunner(), resume=True, jobs=2, **options)
    assert len(_current(out)) == 4 and "not graded yet" not in (out / "gradebook.csv").read_text()
