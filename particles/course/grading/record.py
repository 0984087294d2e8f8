"""The record stage of a grading run: each result decided, saved and reported as it arrives.

Where the results are kept is one small protocol, :class:`Recorder`: the record a resumed run may keep,
save a result, bring a saved result up to date, every current result, and mark a run started and
finished (a run that never says it finished is incomplete). :class:`FolderRecorder` keeps them as the
JSON files of ``OUT/records/`` (:mod:`particles.course.results.store`); :class:`MemoryRecorder` keeps
them in memory, for a run without an output folder. A database is a third implementation.

:class:`Collector` is what the run stage hands each batch's results to: it makes each record's late
decision, saves it, writes the students' outputs so far, and tells the caller's progress callback.
"""

from pathlib import Path
from typing import Protocol

from ..results.store import RecordStore, regrade_split

__all__ = ["Recorder", "FolderRecorder", "MemoryRecorder", "Collector", "INCOMPLETE"]

INCOMPLETE = "RUN-INCOMPLETE.txt"
"""The file in the output folder of a run that has not finished (removed when it does)."""


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

    def regrade(self, units, students):
        """``(units, others)``: the units of `students`, and the current records of everyone else."""

    def start(self, count):
        """A run that will grade `count` notebooks starts: it is incomplete until :meth:`finish`."""

    def finish(self):
        """The run finished: every notebook it was to grade has its record."""


class FolderRecorder:
    """The records as JSON files in ``OUT/records/``, one per student and exercise.

    Parameters
    ----------
    out : path
        The run's output folder.
    options : dict
        The options a record keeps (:attr:`~particles.course.grading.options.GradeOptions.recorded`).
    """

    def __init__(self, out, options):
        self.out = Path(out)
        self.store = RecordStore(self.out / "records", options)

    def kept(self, unit, version):
        return self.store.load(unit, version)

    def save(self, record):
        self.store.save(record)

    def update(self, record):
        self.store.update(record)

    def current(self):
        return self.store.load_all()

    def regrade(self, units, students):
        return regrade_split(self.store.folder, units, students)

    def start(self, count):
        (self.out / INCOMPLETE).write_text(f"This grading run, of {count} notebook(s), has not finished: its "
                                           "gradebook is partial. Run the same command with --resume.\n")

    def finish(self):
        (self.out / INCOMPLETE).unlink(missing_ok=True)


class MemoryRecorder:
    """The records of one run in memory (a run without an output folder keeps nothing on disk)."""

    def __init__(self):
        self.records, self.complete = {}, None

    def kept(self, unit, version):
        return None

    def save(self, record):
        self.records[(record.student, record.exercise)] = record

    def update(self, record):
        self.save(record)

    def current(self):
        return dict(self.records)

    def regrade(self, units, students):
        raise ValueError("student needs the records of an earlier run, which a run without out does not keep")

    def start(self, count):
        self.complete = False

    def finish(self):
        self.complete = True


class Collector:
    """What a run has decided so far, as its results arrive.

    Parameters
    ----------
    recorder : Recorder
    late : callable
        Sets a record's late decision (:class:`~particles.course.grading.deadlines.LateWork`).
    report : callable, optional
        ``report(done, students)`` writes the outputs of `students` from `done` (a stopped run keeps
        usable outputs); None writes nothing.
    progress : callable, optional
        Called with each record as it is collected.
    done : dict, optional
        Records already decided (``(student, exercise) -> record``), kept as they are.

    Attributes
    ----------
    done : dict
        ``(student, exercise) -> SubmissionRecord``: every record decided so far.
    """

    def __init__(self, recorder, late, report=None, progress=None, done=None):
        self.recorder, self.late, self.report, self.progress = recorder, late, report, progress
        self.done = dict(done or {})

    def __call__(self, records):
        """Decide, save and report `records` (a batch's)."""
        for record in records:
            self.late(record)
            self.done[(record.student, record.exercise)] = record
            self.recorder.save(record)
        if self.report is not None:
            self.report(self.done, [record.student for record in records])
        if self.progress is not None:
            for record in records:
                self.progress(record)

    def keep(self, record):
        """Keep a record of an earlier run (``--resume``); a new late decision (a new deadline or extension)
        is saved, the grade is not touched."""
        decided = record.late
        self.done[(record.student, record.exercise)] = self.late(record)
        if record.late != decided:
            self.recorder.save(record)
