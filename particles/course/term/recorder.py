"""The course record as the record stage of a grading run (:class:`~particles.course.grading.record.Recorder`).

A run opens the record of its output folder, holds its lock for its whole length, registers the notebooks it
is to grade (with their submission times), saves each result as it arrives, and says at the end whether it
finished; a run that stops early is ``interrupted`` and the gradebook says which notebooks are still to grade.
"""

import shlex
import sys

from ..results.rubric import Grade, WrittenGrades
from .database import TermRecord

__all__ = ["DatabaseRecorder", "run_command"]


def run_command():
    """The command line of this process, as the record keeps it."""
    return " ".join(shlex.quote(part) for part in ["particles" if sys.argv[0].endswith("particles") else
                                                   sys.argv[0], *sys.argv[1:]])


def _origin(unit):
    """Where a notebook came from in a word: canvas, gradescope, moodle, zip, folder, file."""
    place = unit.place or ()
    if "canvas" in place:
        return "canvas"
    if any(str(p).startswith("submission_") for p in place):
        return "gradescope"
    if any("_assignsubmission_" in str(p) for p in place):
        return "moodle"
    return place[0] if place else "file"


class DatabaseRecorder:
    """The record stage on a :class:`~particles.course.term.database.TermRecord`.

    Parameters
    ----------
    term : TermRecord
        The course record, locked by this run.
    options : dict
        The options a result keeps (:attr:`~particles.course.grading.options.GradeOptions.recorded`).
    command : str, optional
        The run's command line (default: this process's).
    """

    def __init__(self, term, options, command=None):
        self.term, self.options, self.command = term, options, command or run_command()
        self.run, self.started, self.submissions, self.identity = None, None, {}, None

    @classmethod
    def open(cls, out, options):
        """The record of folder `out`, locked for this run (:class:`~particles.course.term.database.RecordBusy`
        when another run holds it)."""
        term = TermRecord(out)
        try:
            term.lock()
        except Exception:
            term.close()
            raise
        return cls(term, options)

    def kept(self, unit, version):
        return self.term.kept(unit, version, self.options)

    def save(self, record):
        record.run = {"id": self.run, "started": self.started}
        self.term.save(self.run, record, self.options, self.submissions.get((record.student, record.exercise)))

    def update(self, record):
        self.term.update(record)

    def current(self):
        return self.term.current()

    def start(self, units, times):
        """The run begins: every notebook it is to grade registered, with its submission time and its source."""
        if self.identity is not None:  # the students and the names their submissions came under
            self.term.remember(self.identity)
        self.run = self.term.start_run(self.command, self.options)
        self.started = self.term.run_info(self.run)["started"]
        rows = []
        for unit in units:
            when, source = times(unit)
            rows.append((unit.student, unit.exercise, unit.where, unit.digest(), _origin(unit), when, source,
                         "rejected" if unit.rejected else "planned"))
        self.submissions = self.term.add_submissions(self.run, rows)

    def finish(self, complete=True):
        """The run ends (``complete``, else ``interrupted``) and lets the next one have the record."""
        if self.run is not None:
            self.term.finish_run(self.run, "complete" if complete else "interrupted")
        self.term.close()

    def pending(self):
        """(student, exercise, run) of notebooks a run meant to grade and no run has graded since."""
        return self.term.pending()

    def keep_written(self, written):
        """Keep this run's rubric grades; every current written grade of the term, as a ``WrittenGrades``."""
        self.term.save_written(self.run, written.grades.values())
        grades = [Grade(exercise, student, question, max_points, points, comment, rubric, "the course record")
                  for student, exercise, question, points, max_points, comment, rubric in self.term.written()]
        questions = dict(written.questions)
        for exercise in {g.exercise for g in grades} - set(questions):  # an exercise no longer in the course
            questions[exercise] = {g.question: g.max_points for g in grades if g.exercise == exercise}
        return WrittenGrades(grades, None, questions)

    def keep_course(self, course):
        """The course file's extensions, as this run applies them."""
        if course is not None:
            self.term.save_extensions(self.run, course)
