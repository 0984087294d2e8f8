"""The record stage of a grading run: each result decided, saved and reported as it arrives.

Where the results are kept is one small protocol, :class:`Recorder`: the record a resumed run may keep, save
a result, bring a saved result up to date, every current result, the notebooks still to grade, and a run's
start (the notebooks it is to grade) and end (finished or not). The course record of an output folder
(:class:`particles.course.term.recorder.DatabaseRecorder`, a SQLite database) is the one a run with ``--out``
uses; :class:`MemoryRecorder` keeps one run's results in memory (a run without an output folder, the
Gradescope bundle's one submission).

:class:`Collector` is what the run stage hands each batch's results to: it makes each record's late
decision, saves it, writes the students' outputs so far, and tells the caller's progress callback.
"""

from typing import Protocol

__all__ = ["Recorder", "MemoryRecorder", "Collector"]


class Recorder(Protocol):
    """Where the results of grading runs are kept."""

    def kept(self, unit, version):
        """The saved record a resumed run keeps for `unit` (graded by tests of `version`), or None."""

    def save(self, record):
        """Keep `record` (a :class:`~particles.course.results.records.SubmissionRecord`) as the current one."""

    def update(self, record):
        """Bring the saved copy of `record` up to date (written grades, the late decision)."""

    def current(self):
        """Every current record: ``(student, exercise) -> SubmissionRecord``."""

    def start(self, units, times):
        """A run that is to grade `units` starts (``times(unit) -> (submitted, source)``): it is incomplete until
        :meth:`finish`."""

    def finish(self, complete=True):
        """The run ended: `complete` when every notebook it was to grade has its record."""

    def pending(self):
        """``(student, exercise, run)`` of notebooks a run meant to grade and no run graded since."""

    def keep_written(self, written):
        """Keep the written grades of this run's rubrics (a :class:`~particles.course.results.rubric.WrittenGrades`);
        returns every written grade the record holds, theirs included."""

    def keep_course(self, course):
        """Keep what the course file said this run (its extensions, as the late decisions used them)."""


class MemoryRecorder:
    """The records of one run in memory: nothing is kept for a later run."""

    def __init__(self):
        self.records, self.complete, self.run, self.planned = {}, None, None, []

    def kept(self, unit, version):
        return None

    def save(self, record):
        self.records[(record.student, record.exercise)] = record

    def update(self, record):
        self.save(record)

    def current(self):
        return dict(self.records)

    def start(self, units, times):
        self.complete, self.planned = False, [(u.student, u.exercise) for u in units if not u.rejected]

    def finish(self, complete=True):
        self.complete = complete

    def pending(self):
        return [] if self.complete else [(s, e, None) for s, e in self.planned if (s, e) not in self.records]

    def keep_written(self, written):
        return written

    def keep_course(self, course):
        pass


class Collector:
    """What a run has decided so far, as its results arrive.

    Parameters
    ----------
    recorder : Recorder
    late : callable
        Sets a record's late decision (:class:`~particles.course.grading.deadlines.LateWork`).
    report : callable, optional
        ``report(done, students, pending)`` writes the outputs of `students` from `done` (a stopped run keeps
        usable outputs, its gradebook saying what is still to grade); None writes nothing.
    progress : callable, optional
        Called with each record as it is collected.
    done : dict, optional
        Records already decided (``(student, exercise) -> record``), kept as they are.

    Attributes
    ----------
    done : dict
        ``(student, exercise) -> SubmissionRecord``: every record decided so far.
    todo : set
        ``(student, exercise)`` of the notebooks this run is to grade and has not yet.
    collected : int
        Records collected so far (kept ones too).
    """

    def __init__(self, recorder, late, report=None, progress=None, done=None):
        self.recorder, self.late, self.report, self.progress = recorder, late, report, progress
        self.done, self.todo, self.collected = dict(done or {}), set(), 0

    def __call__(self, records):
        """Decide, save and report `records` (a batch's)."""
        self.collected += len(records)
        for record in records:
            self.late(record)
            self.done[(record.student, record.exercise)] = record
            self.todo.discard((record.student, record.exercise))
            self.recorder.save(record)
        if self.report is not None:
            self.report(self.done, [record.student for record in records], sorted(self.todo))
        if self.progress is not None:
            for record in records:
                self.progress(record)

    def keep(self, record):
        """Keep a record of an earlier run (``--resume``); a new late decision (a new deadline or extension)
        is saved, the grade is not touched."""
        decided = record.late
        self.collected += 1
        self.done[(record.student, record.exercise)] = self.late(record)
        self.todo.discard((record.student, record.exercise))
        if record.late != decided:
            self.recorder.update(record)
