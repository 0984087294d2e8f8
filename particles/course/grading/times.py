"""When each notebook was submitted: never guessed, always said where it came from.

The time of a submission is, in this order (:class:`SubmissionTimes`): Gradescope's
``submission_metadata.json`` of a one-submission run (``created_at``; ``particles grade --metadata FILE``, which
the bundle's ``run_autograder`` passes), Gradescope's export's ``submission_metadata.yml`` (each submission's
``created_at``, read in :mod:`particles.course.grading.discovery`), a times file (``--times FILE``: a CSV
``student,exercise,submitted``, ``submitted`` in ISO 8601 with a zone, ``student`` any name or alias of the
student), the time the course's record kept from an earlier run, and the notebook file's modification time
only with ``--times-from mtime`` (Canvas's and Moodle's downloads carry no time: a file's time is when it was
unzipped). When an exercise has a deadline and one of its notebooks has no time, the run stops before grading,
naming the students (:func:`check_times`); Canvas's ``LATE_`` flag is checked against the time.
"""

import csv
import json
import os
from datetime import datetime, timezone
from pathlib import Path

from .deadlines import parse_time, shown_time

__all__ = ["SubmissionTimes", "read_times", "read_gradescope_metadata", "check_times"]


def read_gradescope_metadata(path):
    """(created_at, aliases) of Gradescope's ``submission_metadata.json``.

    Gradescope writes the file to ``/autograder/submission_metadata.json``
    (https://gradescope-autograders.readthedocs.io/en/latest/submission_metadata/): ``created_at``
    is the submission's time (ISO 8601 with its zone), ``users`` the submitters (``email``, ``id``,
    ``name``, sometimes ``sid``), whose e-mails and ids an extension may name.

    Raises
    ------
    ValueError
        When the file cannot be read, is not JSON, or has no valid ``created_at``.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise ValueError(f"cannot read Gradescope's submission metadata {path}: {error}") from None
    if not isinstance(data, dict) or "created_at" not in data:
        raise ValueError(f"{path}: Gradescope's submission metadata has no created_at")
    submitted = parse_time(data["created_at"], f"{path}: created_at")
    aliases = []
    for user in data.get("users") or []:
        if isinstance(user, dict):
            aliases += [str(user[k]) for k in ("email", "sid", "id") if user.get(k) not in (None, "")]
    return submitted, aliases


def read_times(path, identity=None, exercises=None):
    """The times file: a CSV with the columns ``student``, ``exercise``, ``submitted`` (others ignored).

    Parameters
    ----------
    path : path
    identity : particles.course.term.identity.Identity, optional
        Who is in the course: every ``student`` cell must be one of its students' names or aliases (it is
        read as that student's grader name). Without it the cells are taken as they are.
    exercises : sequence of str, optional
        The course's exercises: any other ``exercise`` cell is an error.

    Returns
    -------
    dict
        (student, exercise) -> aware datetime. An empty ``exercise`` cell stands for every exercise
        (key ``(student, "")``).

    Raises
    ------
    ValueError
        When the file cannot be read, lacks a column, a row's time is not ISO 8601 with a zone, names an unknown
        student or exercise (every such row named), or a student and exercise are given twice.
    """
    path = Path(path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:
            rows = list(csv.DictReader(handle))
            columns = rows and list(rows[0]) or []
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ValueError(f"cannot read the times file {path}: {error}") from None
    missing = [c for c in ("student", "exercise", "submitted") if c not in columns]
    if rows and missing:
        raise ValueError(f"{path}: no column {', '.join(missing)}; expected a header student,exercise,submitted")
    times, unknown = {}, []
    for line, row in enumerate(rows, start=2):
        key = ((row["student"] or "").strip(), (row["exercise"] or "").strip())
        if not key[0]:
            raise ValueError(f"{path}, line {line}: no student")
        if exercises is not None and key[1] and key[1] not in exercises:
            unknown.append(f"line {line}: exercise {key[1]!r} (expected one of {', '.join(exercises)})")
            continue
        if identity is not None:
            person = identity.find(key[0])
            if person is None:
                unknown.append(f"line {line}: student {key[0]!r}")
                continue
            key = (person.name, key[1])
        if key in times:
            raise ValueError(f"{path}, line {line}: {key[0]} {key[1] or '(every exercise)'} is given twice")
        times[key] = parse_time(row["submitted"] or "", f"{path}, line {line}, submitted")
    if unknown:
        who = identity.describe() if identity is not None else "the course"
        raise ValueError(f"{path}: {len(unknown)} row(s) name no student or exercise of {who}: "
                         f"{'; '.join(unknown)}; correct them (or add the name to the roster's aliases)")
    return times


class SubmissionTimes:
    """When each notebook was submitted, from what the instructor gave; never guessed.

    In this order: Gradescope's ``submission_metadata.json`` of a one-submission run (`metadata`), the
    download's own time (Gradescope's ``submission_metadata.yml``:
    :attr:`~particles.course.grading.discovery.Unit.submitted`), a times file (`times`), the time the course's
    record kept for the student's exercise from an earlier run (`earlier`), and the notebook file's modification
    time only when the instructor accepts it (`from_mtime`, ``--times-from mtime``): a file's time is when it
    was downloaded or unzipped, not when it was submitted.

    Parameters
    ----------
    metadata : path, optional
        Gradescope's ``submission_metadata.json`` (every notebook graded is of that one submission).
    times : path, optional
        A times file (:func:`read_times`).
    identity : particles.course.term.identity.Identity, optional
        Who is in the course (the times file's names are checked against it).
    exercises : sequence of str, optional
        The course's exercises (the times file's are checked against them).
    from_mtime : bool
        Accept the notebook file's modification time when nothing else gives one.
    earlier : callable, optional
        ``earlier(student, exercise) -> (datetime or None, source)``: the course record's.
    """

    def __init__(self, metadata=None, times=None, identity=None, exercises=None, from_mtime=False, earlier=None):
        self.metadata = read_gradescope_metadata(metadata) if metadata is not None else None
        self.times = read_times(times, identity, exercises) if times is not None else {}
        self.from_mtime, self.earlier = from_mtime, earlier

    def aliases(self):
        """Other names of the submitter (Gradescope's e-mails and ids) an extension may use."""
        return tuple(self.metadata[1]) if self.metadata else ()

    def of(self, unit):
        """(submitted, source) of a :class:`~particles.course.grading.discovery.Unit`; (None, "") if unknown."""
        if self.metadata is not None:
            return self.metadata[0], "Gradescope's submission metadata"
        if unit.submitted is not None:
            return unit.submitted, unit.time_source
        for key in ((unit.student, unit.exercise), (unit.student, "")):
            if key in self.times:
                return self.times[key], "the times file"
        if self.earlier is not None:
            when, source = self.earlier(unit.student, unit.exercise)
            if when is not None:
                return when, source
        if not self.from_mtime:
            return None, ""
        try:
            mtime = os.stat(unit.notebook).st_mtime
        except OSError:
            return None, ""
        return datetime.fromtimestamp(mtime, tz=timezone.utc), "the notebook file's modification time"


def check_times(units, course, times):
    """Every notebook of an exercise with a deadline has a real submission time; Canvas's ``LATE_`` flags agree.

    Returns
    -------
    list of str
        Problems to report (a ``LATE_`` file that its time says was on time).

    Raises
    ------
    ValueError
        Naming every student whose notebook of an exercise with a deadline has no submission time: a run never
        decides lateness from a guess (``--times-from mtime`` accepts the files' times).
    """
    missing, problems = [], []
    for unit in units:
        deadline, _ = course.deadline_of(unit.student, unit.exercise, times.aliases()) if course else (None, "")
        if deadline is None:
            continue
        when, source = times.of(unit)
        if when is None:
            missing.append(f"{unit.student} ({unit.exercise})")
        elif unit.late_flag and when <= deadline:
            problems.append(f"{unit.where}: Canvas marked it late (LATE_), but {source} says it was submitted "
                            f"{shown_time(when)}, before the deadline {shown_time(deadline)}: check the times")
    if missing:
        raise ValueError(f"no submission time for {len(missing)} notebook(s) of exercises with a deadline: "
                         f"{', '.join(missing)}; give them (--times FILE: a CSV student,exercise,submitted; "
                         "Gradescope's export carries them), or accept the notebook files' modification times "
                         "with --times-from mtime; nothing was graded")
    return problems
