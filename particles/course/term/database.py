"""The term's record: one SQLite database per course output folder, ``OUT/course.sqlite``.

Everything a term decides is kept here, and everything the course tools write for people (the gradebook,
each student's feedback and ``results.json``, the LMS files) is made from it:

* ``students`` and their ``aliases`` (the roster's, and the names their submissions came under);
* ``runs``: each grading run, its command, options and how it ended (``running``, ``complete``,
  ``interrupted``);
* ``submissions``: each notebook a run meant to grade: its file, SHA-256, origin, submission time and where
  that time came from, and its state (``planned``, ``graded``, ``rejected``, ``kept``);
* ``results``: each grade, the whole record as JSON and its totals; ``tests``: every test of it;
* ``written``: the people's grades of the written answers; ``extensions``: the course file's, as applied;
* ``overrides``: every change an instructor made by hand, who made it, when and why.

Uniqueness is the schema's: a student has one current result per exercise (a partial unique index), one
current written grade per question, an alias names one student. A result stops being current only when a
newer one of the same student and exercise replaces it, or an instructor retires it, and it stays as history
(``ended``, ``ended_why``). Every change is a transaction. A grading run holds the record's lock for its whole
length (:meth:`TermRecord.lock`): a second run on the same folder is refused, never interleaved; a run that
died (its lock is gone with its process) is marked ``interrupted`` by the next. A folder of ``records/`` from a
grader before this record is imported once when the record is made.
"""

import fcntl
import json
import os
import socket
import sqlite3
from contextlib import contextmanager
from datetime import datetime, timezone
from pathlib import Path

from ..results.records import SubmissionRecord
from .identity import Identity, Person

__all__ = ["DATABASE", "TermRecord", "RecordBusy", "SCHEMA"]

DATABASE = "course.sqlite"
"""The record's file name in a course output folder."""

SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS students (
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE,
    display TEXT NOT NULL DEFAULT '',
    on_roster INTEGER NOT NULL DEFAULT 0 CHECK (on_roster IN (0, 1)));
CREATE TABLE IF NOT EXISTS aliases (
    kind TEXT NOT NULL,
    value TEXT NOT NULL,
    student INTEGER NOT NULL REFERENCES students(id),
    PRIMARY KEY (kind, value));
CREATE TABLE IF NOT EXISTS runs (
    id INTEGER PRIMARY KEY,
    started TEXT NOT NULL,
    finished TEXT,
    status TEXT NOT NULL CHECK (status IN ('running', 'complete', 'interrupted')),
    command TEXT NOT NULL,
    options TEXT NOT NULL,
    host TEXT NOT NULL DEFAULT '',
    pid INTEGER,
    planned INTEGER NOT NULL DEFAULT 0);
CREATE TABLE IF NOT EXISTS submissions (
    id INTEGER PRIMARY KEY,
    run INTEGER NOT NULL REFERENCES runs(id),
    student INTEGER NOT NULL REFERENCES students(id),
    exercise TEXT NOT NULL,
    file TEXT NOT NULL,
    sha256 TEXT NOT NULL,
    origin TEXT NOT NULL DEFAULT '',
    submitted TEXT,
    time_source TEXT NOT NULL DEFAULT '',
    state TEXT NOT NULL CHECK (state IN ('planned', 'graded', 'rejected', 'kept')),
    UNIQUE (run, student, exercise));
CREATE TABLE IF NOT EXISTS results (
    id INTEGER PRIMARY KEY,
    student INTEGER NOT NULL REFERENCES students(id),
    exercise TEXT NOT NULL,
    run INTEGER NOT NULL REFERENCES runs(id),
    submission INTEGER REFERENCES submissions(id),
    record TEXT NOT NULL,
    score REAL NOT NULL,
    max_score REAL NOT NULL,
    total REAL NOT NULL,
    total_max REAL NOT NULL,
    late TEXT,
    seed INTEGER,
    tests_version TEXT NOT NULL DEFAULT '',
    options TEXT NOT NULL DEFAULT '{}',
    notebook_sha256 TEXT NOT NULL DEFAULT '',
    complete INTEGER NOT NULL CHECK (complete IN (0, 1)),
    current INTEGER CHECK (current IS NULL OR current = 1),
    created TEXT NOT NULL,
    ended TEXT,
    ended_why TEXT);
CREATE UNIQUE INDEX IF NOT EXISTS one_current_result ON results (student, exercise) WHERE current = 1;
CREATE TABLE IF NOT EXISTS tests (
    result INTEGER NOT NULL REFERENCES results(id),
    test TEXT NOT NULL,
    points REAL NOT NULL,
    passed INTEGER NOT NULL CHECK (passed IN (0, 1)),
    hidden INTEGER NOT NULL CHECK (hidden IN (0, 1)),
    reason TEXT NOT NULL DEFAULT '',
    PRIMARY KEY (result, test));
CREATE TABLE IF NOT EXISTS written (
    id INTEGER PRIMARY KEY,
    student INTEGER NOT NULL REFERENCES students(id),
    exercise TEXT NOT NULL,
    question INTEGER NOT NULL,
    points REAL,
    max_points REAL NOT NULL,
    comment TEXT NOT NULL DEFAULT '',
    rubric TEXT NOT NULL DEFAULT '',
    run INTEGER REFERENCES runs(id),
    current INTEGER CHECK (current IS NULL OR current = 1));
CREATE UNIQUE INDEX IF NOT EXISTS one_current_written ON written (student, exercise, question) WHERE current = 1;
CREATE TABLE IF NOT EXISTS extensions (
    student INTEGER NOT NULL REFERENCES students(id),
    exercise TEXT NOT NULL,
    value TEXT NOT NULL,
    course_file TEXT NOT NULL,
    run INTEGER REFERENCES runs(id),
    PRIMARY KEY (student, exercise));
CREATE TABLE IF NOT EXISTS overrides (
    id INTEGER PRIMARY KEY,
    student INTEGER NOT NULL REFERENCES students(id),
    exercise TEXT NOT NULL,
    what TEXT NOT NULL,
    old TEXT,
    new TEXT,
    who TEXT NOT NULL,
    at TEXT NOT NULL,
    why TEXT NOT NULL);
"""

SCHEMA_VERSION = "1"


class RecordBusy(ValueError):
    """Another grading run holds the course record: the message names it."""


def now():
    """The time of a change, as the record writes it (UTC, ISO 8601, seconds)."""
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def _json(value):
    return json.dumps(value, sort_keys=True, default=str)


class TermRecord:
    """The course record of an output folder (made, with its tables, when missing).

    Parameters
    ----------
    out : path
        The course output folder; the record is ``out/course.sqlite``.

    Attributes
    ----------
    path : Path
    imported : int
        Records imported from an earlier ``records/`` folder when this record was made (0 otherwise).
    """

    def __init__(self, out):
        self.out = Path(out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.path = self.out / DATABASE
        fresh = not self.path.exists()
        self.db = sqlite3.connect(self.path, isolation_level=None, timeout=30)
        self.db.execute("PRAGMA foreign_keys = ON")
        self.db.execute("PRAGMA journal_mode = WAL")
        self.db.executescript(SCHEMA)
        self._lock = None
        self.imported = 0
        with self.transaction():
            self.db.execute("INSERT OR IGNORE INTO meta VALUES ('schema', ?)", (SCHEMA_VERSION,))
        if fresh and (self.out / "records").is_dir():
            from .legacy import import_records

            self.imported = import_records(self, self.out / "records")

    def close(self):
        """Release the lock (if held) and the connection."""
        self.unlock()
        self.db.close()

    def __enter__(self):
        """``with TermRecord(out) as term:`` closes the record (and releases its lock) on leaving."""
        return self

    def __exit__(self, *exc):
        self.close()

    @contextmanager
    def transaction(self):
        """One change, all or nothing (``BEGIN IMMEDIATE``: no other writer in between)."""
        self.db.execute("BEGIN IMMEDIATE")
        try:
            yield self.db
        except BaseException:
            self.db.execute("ROLLBACK")
            raise
        self.db.execute("COMMIT")

    # -- the run's lock ------------------------------------------------------------------------------

    def lock(self):
        """Hold the record for one grading run; :class:`RecordBusy` when another run holds it.

        The lock is the operating system's (``flock`` on ``course.sqlite.lock``): it goes with its process,
        so a run killed outright never leaves the record locked.
        """
        handle = open(self.path.with_name(DATABASE + ".lock"), "a+")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            holder = handle.read().strip() or "another process"
            handle.close()
            raise RecordBusy(f"another grading run ({holder}) is writing the course record {self.path}: wait for "
                             "it to end (or stop it), then run again; two runs never write one record at once")
        handle.seek(0)
        handle.truncate()
        handle.write(f"pid {os.getpid()} on {socket.gethostname()}, started {now()}")
        handle.flush()
        self._lock = handle

    def unlock(self):
        """Let the next run have the record."""
        if self._lock is not None:
            fcntl.flock(self._lock, fcntl.LOCK_UN)
            self._lock.close()
            self._lock = None

    # -- students --------------------------------------------------------------------------------------

    def identity(self, roster=None):
        """Who is in the course: the roster's students (a closed course, remembered here with their aliases),
        else every student this record knows (a course that admits the students a run discovers)."""
        if roster is not None:
            identity = roster.identity()
            self.remember(identity)
            return identity
        people = {}
        for sid, name, display, on_roster in self.db.execute("SELECT id, name, display, on_roster FROM students"):
            people[sid] = Person(name, [], display, bool(on_roster))
        for kind, value, sid in self.db.execute("SELECT kind, value, student FROM aliases ORDER BY kind, value"):
            people[sid].aliases.append((kind, value))
        return Identity(people.values())

    def remember(self, identity):
        """Keep every student of `identity` and their aliases (a known alias of another student is an error)."""
        with self.transaction() as db:
            for person in identity.people.values():
                db.execute("INSERT INTO students (name, display, on_roster) VALUES (?, ?, ?) ON CONFLICT (name) "
                           "DO UPDATE SET display = excluded.display, on_roster = max(on_roster, excluded.on_roster)",
                           (person.name, person.display, int(person.on_roster)))
                sid = self.student_id(person.name)
                for kind, value in person.aliases:
                    db.execute("INSERT INTO aliases VALUES (?, ?, ?) ON CONFLICT DO NOTHING",
                               (kind, str(value), sid))

    def student_id(self, name):
        """The row of student `name` (made when missing)."""
        row = self.db.execute("SELECT id FROM students WHERE name = ?", (name,)).fetchone()
        if row is None:
            return self.db.execute("INSERT INTO students (name) VALUES (?)", (name,)).lastrowid
        return row[0]

    # -- runs ------------------------------------------------------------------------------------------

    def start_run(self, command, options):
        """A new run (status ``running``); a run still ``running`` whose process is gone is ``interrupted``."""
        with self.transaction() as db:
            db.execute("UPDATE runs SET status = 'interrupted', finished = ? WHERE status = 'running'", (now(),))
            return db.execute("INSERT INTO runs (started, status, command, options, host, pid) VALUES "
                              "(?, 'running', ?, ?, ?, ?)", (now(), command, _json(options),
                                                             socket.gethostname(), os.getpid())).lastrowid

    def finish_run(self, run, status="complete"):
        """How run `run` ended: ``complete`` or ``interrupted``."""
        with self.transaction() as db:
            db.execute("UPDATE runs SET status = ?, finished = ? WHERE id = ?", (status, now(), run))

    def runs(self):
        """Every run, oldest first: dicts of id, started, finished, status, command, planned."""
        rows = self.db.execute("SELECT id, started, finished, status, command, planned FROM runs ORDER BY id")
        return [dict(zip(("id", "started", "finished", "status", "command", "planned"), row)) for row in rows]

    def run_info(self, run):
        """``{id, started, status, command}`` of run `run` (None when there is no such run)."""
        row = self.db.execute("SELECT id, started, status, command FROM runs WHERE id = ?", (run,)).fetchone()
        return None if row is None else dict(zip(("id", "started", "status", "command"), row))

    # -- submissions -----------------------------------------------------------------------------------

    def add_submissions(self, run, rows):
        """Register what run `run` is to grade: `rows` of (student, exercise, file, sha256, origin, submitted,
        time_source, state). Returns (student, exercise) -> submission id."""
        ids = {}
        with self.transaction() as db:
            db.execute("UPDATE runs SET planned = ? WHERE id = ?", (sum(r[7] == "planned" for r in rows), run))
            for student, exercise, file, sha, origin, submitted, source, state in rows:
                sid = self.student_id(student)
                ids[(student, exercise)] = db.execute(
                    "INSERT INTO submissions (run, student, exercise, file, sha256, origin, submitted, time_source, "
                    "state) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                    (run, sid, exercise, str(file), sha, origin, submitted.isoformat() if submitted else None,
                     source, state)).lastrowid
        return ids

    def submission_time(self, student, exercise):
        """(time, source) of the latest submission of `student`'s `exercise` with a real time, else (None, "")."""
        row = self.db.execute(
            "SELECT sub.submitted, sub.time_source, runs.id FROM submissions sub JOIN students s ON s.id = "
            "sub.student JOIN runs ON runs.id = sub.run WHERE s.name = ? AND sub.exercise = ? AND sub.submitted "
            "IS NOT NULL ORDER BY sub.id DESC LIMIT 1", (student, exercise)).fetchone()
        if row is None:
            return None, ""
        return datetime.fromisoformat(row[0]), f"{row[1]}, as recorded in run {row[2]}"

    def pending(self):
        """(student, exercise, run) of notebooks a run meant to grade and that have no complete current result:
        of each student's exercise, the latest notebook registered, when the current result is not of its bytes."""
        return self.db.execute(
            "SELECT s.name, sub.exercise, sub.run FROM submissions sub JOIN students s ON s.id = sub.student "
            "WHERE sub.state = 'planned' AND sub.id = (SELECT max(id) FROM submissions WHERE student = sub.student "
            "AND exercise = sub.exercise) AND NOT EXISTS (SELECT 1 FROM results r WHERE r.student = sub.student "
            "AND r.exercise = sub.exercise AND r.current = 1 AND r.complete = 1 AND r.notebook_sha256 = sub.sha256) "
            "ORDER BY s.name, sub.exercise").fetchall()

    # -- results ---------------------------------------------------------------------------------------

    def save(self, run, record, options, submission=None):
        """Make `record` the current result of its student and exercise; the one it replaces becomes history.

        A record already current with the same notebook, seed and run (a result delivered twice) is not written
        again. Returns the result's id.
        """
        with self.transaction() as db:
            sid = self.student_id(record.student)
            current = db.execute("SELECT id, notebook_sha256, seed, run, complete FROM results WHERE student = ? "
                                 "AND exercise = ? AND current = 1", (sid, record.exercise)).fetchone()
            if current is not None and record.notebook_sha256 and current[1:4] == (
                    record.notebook_sha256, record.seed, run) and current[4] == int(record.complete):
                return current[0]
            if current is not None:
                db.execute("UPDATE results SET current = NULL, ended = ?, ended_why = ? WHERE id = ?",
                           (now(), f"replaced by a result of run {run}", current[0]))
            result = db.execute(
                "INSERT INTO results (student, exercise, run, submission, record, score, max_score, total, "
                "total_max, late, seed, tests_version, options, notebook_sha256, complete, current, created) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, 1, ?)",
                (sid, record.exercise, run, submission, _json(record.to_dict()), record.score, record.max_score,
                 record.total, record.total_max, _json(record.late) if record.late else None, record.seed,
                 record.tests_version, _json(options), record.notebook_sha256, int(record.complete),
                 now())).lastrowid
            db.executemany("INSERT INTO tests VALUES (?, ?, ?, ?, ?, ?)",
                           [(result, t.test, t.points, int(t.passed), int(t.hidden), t.reason or "")
                            for t in record.tests])
            if record.complete:
                db.execute("UPDATE submissions SET state = 'graded' WHERE student = ? AND exercise = ? AND "
                           "state = 'planned'", (sid, record.exercise))
            return result

    def update(self, record):
        """Bring the current result of `record`'s student and exercise up to date (written grades, late work,
        totals); True when it changed. The grade itself is not touched."""
        row = self.db.execute("SELECT r.id, r.record FROM results r JOIN students s ON s.id = r.student WHERE "
                              "s.name = ? AND r.exercise = ? AND r.current = 1",
                              (record.student, record.exercise)).fetchone()
        if row is None:
            return False
        kept = json.loads(row[1])
        new = dict(kept, written=record.written, late=record.late, run=record.run)
        if new == kept:
            return False
        with self.transaction() as db:
            db.execute("UPDATE results SET record = ?, total = ?, total_max = ?, late = ? WHERE id = ?",
                       (_json(new), record.total, record.total_max, _json(record.late) if record.late else None,
                        row[0]))
        return True

    def current(self):
        """Every current result: (student, exercise) -> :class:`~particles.course.results.records.SubmissionRecord`."""
        out = {}
        for name, exercise, data, run, started in self.db.execute(
                "SELECT s.name, r.exercise, r.record, r.run, runs.started FROM results r JOIN students s ON "
                "s.id = r.student JOIN runs ON runs.id = r.run WHERE r.current = 1 ORDER BY s.name, r.exercise"):
            record = SubmissionRecord.from_dict(json.loads(data))
            record.run = record.run or {"id": run, "started": started}
            out[(name, exercise)] = record
        return out

    def history(self, student, exercise=None):
        """Every result of `student` (of `exercise` only, when given), oldest first: dicts of id, exercise, run,
        total, total_max, current, ended_why."""
        rows = self.db.execute(
            "SELECT r.id, r.exercise, r.run, r.total, r.total_max, r.current, r.ended_why FROM results r JOIN "
            "students s ON s.id = r.student WHERE s.name = ? AND (? IS NULL OR r.exercise = ?) ORDER BY r.id",
            (student, exercise, exercise)).fetchall()
        return [dict(zip(("id", "exercise", "run", "total", "total_max", "current", "ended_why"), row))
                for row in rows]

    def kept(self, unit, version, options):
        """The current record a resumed run keeps for `unit`: complete, of the same notebook (SHA-256), graded
        with the same `options` by tests of `version`; else None."""
        row = self.db.execute(
            "SELECT r.record FROM results r JOIN students s ON s.id = r.student WHERE s.name = ? AND r.exercise = ? "
            "AND r.current = 1 AND r.complete = 1 AND r.notebook_sha256 = ? AND r.notebook_sha256 != '' AND "
            "r.tests_version = ? AND r.options = ?",
            (unit.student, unit.exercise, unit.digest(), version, _json(options))).fetchone()
        if row is None:
            return None
        record = SubmissionRecord.from_dict(json.loads(row[0]))
        if record.grader_status not in (0, 1):
            return None
        record.notebook, record.resumed = unit.where, True
        return record

    def retire(self, student, exercise, why, who):
        """Make the current result of `student`'s `exercise` history, by hand (an override says who and why)."""
        with self.transaction() as db:
            sid = self.student_id(student)
            row = db.execute("SELECT id, total FROM results WHERE student = ? AND exercise = ? AND current = 1",
                             (sid, exercise)).fetchone()
            if row is None:
                raise ValueError(f"{student} has no current result of {exercise} to retire")
            db.execute("UPDATE results SET current = NULL, ended = ?, ended_why = ? WHERE id = ?",
                       (now(), f"retired by {who}: {why}", row[0]))
            db.execute("INSERT INTO overrides (student, exercise, what, old, new, who, at, why) VALUES "
                       "(?, ?, 'retired', ?, NULL, ?, ?, ?)", (sid, exercise, str(row[1]), who, now(), why))

    # -- written grades and extensions -----------------------------------------------------------------

    def save_written(self, run, grades):
        """Make `grades` (:class:`~particles.course.results.rubric.Grade`) the current written grades of their
        questions; a grade that differs from the current one replaces it, which stays as history."""
        with self.transaction() as db:
            for g in grades:
                sid = self.student_id(g.student)
                old = db.execute("SELECT id, points, comment, max_points, rubric FROM written WHERE student = ? AND "
                                 "exercise = ? AND question = ? AND current = 1",
                                 (sid, g.exercise, g.question)).fetchone()
                if old is not None and old[1:] == (g.points, g.comment, g.max_points, g.rubric):
                    continue
                if old is not None:
                    db.execute("UPDATE written SET current = NULL WHERE id = ?", (old[0],))
                db.execute("INSERT INTO written (student, exercise, question, points, max_points, comment, rubric, "
                           "run, current) VALUES (?, ?, ?, ?, ?, ?, ?, ?, 1)",
                           (sid, g.exercise, g.question, g.points, g.max_points, g.comment, g.rubric, run))

    def written(self):
        """The current written grades: a list of (student, exercise, question, points, max_points, comment,
        rubric)."""
        return self.db.execute(
            "SELECT s.name, w.exercise, w.question, w.points, w.max_points, w.comment, w.rubric FROM written w JOIN "
            "students s ON s.id = w.student WHERE w.current = 1 ORDER BY s.name, w.exercise, w.question").fetchall()

    def save_extensions(self, run, course):
        """The course file's extensions as this run applied them (the record of what a late decision used)."""
        with self.transaction() as db:
            db.execute("DELETE FROM extensions")
            for student, table in course.extensions.items():
                sid = self.student_id(student)
                for exercise, value in table.items():
                    db.execute("INSERT INTO extensions VALUES (?, ?, ?, ?, ?)",
                               (sid, exercise, str(value), course.path, run))
