r"""Grades into the LMS: the gradebook import CSVs of Canvas and Moodle, students matched through a roster.

``particles export OUT --roster ROSTER --canvas FILE --moodle FILE`` reads the term's current records from the
course record of a graded folder (``OUT/course.sqlite``, :mod:`particles.course.term.database`) and writes one
row per student of the roster, one
column per exercise (the record's :attr:`~particles.course.results.records.SubmissionRecord.total`: tests,
written answers graded by people, minus the late penalty) and a total column.

The roster is read by :mod:`particles.course.term.roster` (its columns, the students' aliases and its checks are
documented there): the export has one row per roster student, matched to their records through
:mod:`particles.course.term.identity` like everything else the course tools match.

**Canvas** (`Canvas's guide`_, `Canvas's importer`_). Columns: ``Student, ID, SIS User ID, SIS Login ID,
Section``, one column per exercise titled with the exercise's name, then ``Final Points`` (the total). The second
line is ``Points Possible``: each exercise's points, ``(read only)`` under the total. Canvas matches a student by
``ID``, else ``SIS User ID``, else ``SIS Login ID``, else by name, exactly (its ``name`` or ``sortable_name``);
``Section`` is not used. Canvas's reader also rewrites every cell that looks like a number with a decimal comma
(``1,5`` becomes ``1.5``), so an identifier such as ``12,345`` cannot match. :func:`~particles.course.results.importers.canvas_match` says how Canvas
will find each roster student in the file: a student it can find only by name is reported as ``matched by name``,
one it cannot find at all (no identifier, and no name as Canvas knows it: a name that starts with ``=``, ``+``,
``-`` or ``@`` is written with a leading ``'``, so ``-Eve`` reads as ``'-Eve``) as ``match by hand`` (Canvas lists
the row as an unknown student, to be matched by hand on upload), and the command exits with status 1: give such a
student their ``canvas_id`` (Canvas's numeric user ID, the ``ID`` column of its gradebook export), the one identifier
Canvas's importer always tries first. A column is an existing
assignment when its title is the assignment's (or ends with ``(assignment id)``), else Canvas offers to create a
new assignment of that title with the points of the ``Points Possible`` line: name the assignments after the
exercises (``01_integrator_order``) or let the import create them. Columns whose title holds ``Current Score``,
``Current Points``, ``Current Grade``, ``Final Score``, ``Final Points``, ``Final Grade``, ``Override Score``,
``Override Grade`` or ``Override Status`` are read-only for the importer: the total is ``Final Points`` so that it
is shown and never imported as an assignment (an exercise named so is refused). Canvas has no column for a
comment (a ``Notes`` column is imported only where the course made one), so a missing submission is a 0 there and
"missing" in the report; the feedback goes back as files (:mod:`particles.course.results.returned`). UTF-8,
comma-separated, no byte-order mark; cells with commas, quotes or line breaks are quoted (RFC 4180).

**Moodle** (`Moodle's guide`_, `Moodle's importer`_). Columns: the identifier (``Email address``, ``Username`` or
``ID number``: ``--moodle-id``), ``Full name``, then for each exercise its grade (titled with the exercise's name)
and ``<exercise> feedback`` (how the grade was made, or ``missing: no graded submission``), then ``Total``. On
upload choose encoding UTF-8 and separator comma (the defaults; a byte-order mark would be removed, none is
written), map from the identifier column to ``useremail``/``username``/``useridnumber``, map each exercise to its
grade item (or "new grade item") and leave ``Full name`` and ``Total`` on "ignore" (Moodle sums its own total; a
grade above ``gradepointmax``, 100 by default, fails the import). Moodle offers a feedback column only for a grade
item that already exists ("feedback for" that item): when the exercises' grade items are new, import the grades
once with the feedback columns on "ignore", then import the file again, mapping each feedback column to its item.

Moodle reads the file with PHP's ``fgetcsv``, whose escape character is the backslash: inside a quoted cell ``\"``
does not end the cell, and a quote after a backslash is not doubled. The cells are written for that reader
(:func:`~particles.course.results.importers.moodle_cell`), so that ``Gus\", jr`` stays one cell, and a cell ending in a backslash gets a trailing
space, which Moodle trims from every cell. Moodle aborts the whole import at a row whose user it cannot find,
and skips the user look-up for an identifier PHP's ``empty()`` calls empty (``""``, and ``"0"``, after trimming
white space), so that such a row's grades go to the previous row's user: a roster student whose identifier is
empty to PHP, or holds a line break, is left out of the file and reported (pick another ``--moodle-id``).

Both files: a number is written with a dot and at most 6 decimals, without exponent or trailing zeros
(``2.5``, ``10``, ``0.00001``), and a text cell starting with ``=``, ``+``, ``-``, ``@``, a tab or a carriage
return (a spreadsheet formula) gets a leading ``'`` (`OWASP`_).

Nothing is dropped: a record whose student is on no line of the roster, a roster student without a record of an
exercise (exported as 0), a student left out of a file and a student Canvas cannot match are all listed in
``OUT/lms-report.csv`` (columns :data:`REPORT_COLUMNS`), and the command exits with status 1 when a grade did not
reach a file or will not reach its student.

.. _Canvas's guide: https://community.canvaslms.com/t5/Instructor-Guide/How-do-I-import-grades-in-the-Gradebook/ta-p/807
.. _Canvas's importer: https://github.com/instructure/canvas-lms/blob/master/lib/gradebook_importer.rb
.. _Moodle's guide: https://docs.moodle.org/en/Grade_import
.. _Moodle's importer: https://github.com/moodle/moodle/blob/main/grade/import/csv/classes/load_data.php
.. _OWASP: https://owasp.org/www-community/attacks/CSV_Injection
"""

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

from ..term.database import DATABASE, TermRecord
from ..term.roster import CANVAS_POINTS_ROW, FORMULA, NAME_COLUMN, read_roster
from .importers import canvas_match, canvas_unmatched, moodle_cell, moodle_left_out

__all__ = ["CANVAS_DOC", "CANVAS_IMPORTER", "MOODLE_DOC", "MOODLE_IMPORTER", "CANVAS_STUDENT_COLUMNS",
           "CANVAS_TOTAL", "CANVAS_POINTS_ROW", "CANVAS_READ_ONLY", "CANVAS_RESERVED", "MOODLE_IDENTIFIERS",
           "MOODLE_NAME", "MOODLE_TOTAL", "MOODLE_MISSING", "REPORT_COLUMNS", "ExportError", "Export",
           "read_records", "match", "lms_number", "lms_text", "canvas_rows", "moodle_rows", "export_grades"]

CANVAS_DOC = "https://community.canvaslms.com/t5/Instructor-Guide/How-do-I-import-grades-in-the-Gradebook/ta-p/807"
CANVAS_IMPORTER = "https://github.com/instructure/canvas-lms/blob/master/lib/gradebook_importer.rb"
MOODLE_DOC = "https://docs.moodle.org/en/Grade_import"
MOODLE_IMPORTER = "https://github.com/moodle/moodle/blob/main/grade/import/csv/classes/load_data.php"

CANVAS_STUDENT_COLUMNS = ("Student", "ID", "SIS User ID", "SIS Login ID", "Section")
"""The first columns of a Canvas gradebook CSV, in Canvas's order (its importer checks the order)."""
CANVAS_TOTAL = "Final Points"
"""The total's title: a read-only column for Canvas's importer, shown, never imported as an assignment."""
CANVAS_READ_ONLY = "(read only)"
CANVAS_RESERVED = ("Current Score", "Current Points", "Current Grade", "Final Score", "Final Points", "Final Grade",
                   "Override Score", "Override Grade", "Override Status")
"""Titles Canvas's importer never reads as assignments (a column title holding one of them)."""

MOODLE_IDENTIFIERS = {"email": "Email address", "username": "Username", "idnumber": "ID number"}
"""``--moodle-id`` -> the identifier column's title (mapped to useremail, username, useridnumber on upload)."""
MOODLE_NAME = "Full name"
MOODLE_TOTAL = "Total"
MOODLE_MISSING = "missing: no graded submission"

REPORT_COLUMNS = ("problem", "student", "exercise", "points", "detail")
"""The columns of ``lms-report.csv``; ``problem`` is one of ``not on roster``, ``not graded yet``, ``missing``,
``left out``, ``matched by name``, ``match by hand``."""



class ExportError(ValueError):
    """Records that cannot be exported (no records folder, a record that cannot be read, a clash)."""


def lms_number(x):
    """A number as both LMS read it: a dot, at most 6 decimals, no exponent, no trailing zeros (``-0`` is ``0``)."""
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"a grade must be a finite number, got {x!r}")
    text = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def lms_text(text):
    """A text cell a spreadsheet will not run: ``'`` before a leading ``= + - @``, tab or carriage return."""
    text = str(text)
    return "'" + text if text.startswith(FORMULA) else text


def read_records(out):
    """The current records of a course output folder's record (:mod:`particles.course.term.database`).

    Returns
    -------
    records : dict
        ``"student/exercise"`` -> :class:`~particles.course.results.records.SubmissionRecord`, one per student and
        exercise: the term's gradebook.
    pending : list of (student, exercise, run)
        Notebooks a run meant to grade and no run has graded since (the export says the grades are partial).

    Raises
    ------
    ExportError
        When `out` holds no course record (nor a ``records/`` folder of an earlier grader to import).
    """
    out = Path(out)
    if not (out / DATABASE).exists() and not (out / "records").is_dir():
        raise ExportError(f"{out} holds no course record ({DATABASE}): expected the folder that "
                          "`particles grade SUBMISSIONS --out OUT` writes")
    try:
        term = TermRecord(out)
    except ValueError as error:
        raise ExportError(str(error)) from None
    with term:
        records = {f"{student}/{exercise}": record for (student, exercise), record in term.current().items()}
        return records, term.pending()


@dataclass
class Export:
    """What goes into the LMS files: the roster's students, their records by exercise, and what did not match.

    Attributes
    ----------
    exercises : list of str
        The columns, sorted.
    points : dict
        exercise -> the points it can give (the largest ``total_max`` of its records).
    students : list of RosterStudent
    records : dict
        student key -> {exercise: SubmissionRecord}.
    unmatched : list of (str, SubmissionRecord)
        Records whose student is on no line of the roster (nor an alias of one), with their ``student/exercise``.
    pending : list of (student, exercise, run)
        Notebooks a grading run meant to grade and no run has graded since: these grades are not final.
    """

    exercises: list
    points: dict
    students: list
    records: dict
    unmatched: list = field(default_factory=list)
    pending: list = field(default_factory=list)

    def missing(self):
        """(student, exercise) pairs of the roster without a record: exported as 0."""
        return [(s, e) for s in self.students for e in self.exercises if e not in self.records.get(s.key, {})]

    def grade(self, student, exercise):
        """The student's points for the exercise (0 when missing)."""
        record = self.records.get(student.key, {}).get(exercise)
        return record.total if record is not None else 0.0

    def total(self, student):
        """The student's total over the exercises."""
        return sum(self.grade(student, e) for e in self.exercises)


def match(roster, records):
    """Match records (``"student/exercise"`` -> record) with the students of a roster, through their names and
    aliases (:meth:`~particles.course.term.roster.Roster.identity`).

    Raises
    ------
    ExportError
        When two records of one exercise belong to one roster student (two of their aliases graded apart).
    """
    identity = roster.identity()
    keys = {s.submission_name: s.key for s in roster.students}
    by_student, unmatched, files, points = {}, [], {}, {}
    for name, record in records.items():
        points[record.exercise] = max(points.get(record.exercise, 0.0), record.total_max)
        person = identity.find(record.student)
        if person is None:
            unmatched.append((name, record))
            continue
        key = keys[person.name]
        mine = by_student.setdefault(key, {})
        if record.exercise in mine:
            raise ExportError(f"records {files[key, record.exercise]} and {name} are both {record.exercise} of "
                              f"the roster's {person.name!r}: retire the one that is not theirs")
        mine[record.exercise], files[key, record.exercise] = record, name
    return Export(sorted(points), points, list(roster.students), by_student, unmatched)


def canvas_rows(export):
    """The lines of the Canvas file: header, ``Points Possible``, one per roster student (lists of str)."""
    reserved = [e for e in export.exercises if any(r.casefold() in e.casefold() for r in CANVAS_RESERVED)]
    if reserved:
        raise ExportError(f"exercise {reserved[0]!r} holds a title Canvas's importer treats as read-only "
                          f"({', '.join(CANVAS_RESERVED)}): it would not be imported")
    rows = [[*CANVAS_STUDENT_COLUMNS, *map(lms_text, export.exercises), CANVAS_TOTAL],
            [CANVAS_POINTS_ROW, "", "", "", "", *(lms_number(export.points[e]) for e in export.exercises),
             CANVAS_READ_ONLY]]
    for s in export.students:
        rows.append([lms_text(s.display_name), s.canvas_id, s.sis_user_id, s.sis_login_id, lms_text(s.section),
                     *(lms_number(export.grade(s, e)) for e in export.exercises), lms_number(export.total(s))])
    return rows


def _feedback(record):
    """How a record's grade was made, in one line (Moodle's feedback cell)."""
    parts = [f"tests {lms_number(record.score)}/{lms_number(record.max_score)}"]
    if record.written:
        parts.append(f"written answers {lms_number(record.written_score)}/{lms_number(record.written_max)}")
    if record.penalty:
        parts.append(f"late penalty -{lms_number(record.penalty)}")
    return ", ".join(parts)


def moodle_rows(export, identifier="email"):
    """The lines of the Moodle file and the roster students left out (no `identifier`).

    Parameters
    ----------
    export : Export
    identifier : {"email", "username", "idnumber"}
        The roster column that identifies a student in Moodle (:data:`MOODLE_IDENTIFIERS`).

    Returns
    -------
    rows : list of list of str
    left_out : list of RosterStudent
        Students without a usable `identifier` (:func:`~particles.course.results.importers.moodle_left_out` says why).
    """
    if identifier not in MOODLE_IDENTIFIERS:
        raise ValueError(f"identifier must be one of {', '.join(MOODLE_IDENTIFIERS)}, got {identifier!r}")
    header = [MOODLE_IDENTIFIERS[identifier], MOODLE_NAME]
    for e in export.exercises:
        header += [lms_text(e), lms_text(f"{e} feedback")]
    rows, left_out = [header + [MOODLE_TOTAL]], []
    for s in export.students:
        if moodle_left_out(s, identifier):
            left_out.append(s)
            continue
        row = [getattr(s, identifier), lms_text(s.display_name)]
        for e in export.exercises:
            record = export.records.get(s.key, {}).get(e)
            row += [lms_number(export.grade(s, e)), lms_text(_feedback(record) if record else MOODLE_MISSING)]
        rows.append(row + [lms_number(export.total(s))])
    return rows, left_out


def _write(path, rows, cell=None):
    """Write CSV rows: RFC 4180 (Python's writer), or each cell through `cell` (:func:`~particles.course.results.importers.moodle_cell`)."""
    with open(path, "w", encoding="utf-8", newline="") as handle:
        if cell is None:
            csv.writer(handle).writerows(rows)
        else:
            handle.writelines(",".join(map(cell, row)) + "\n" for row in rows)


def _report_rows(export, problems):
    rows = [list(REPORT_COLUMNS)]
    for name, r in export.unmatched:
        rows.append(["not on roster", lms_text(r.student), lms_text(r.exercise), lms_number(r.total),
                     lms_text(f"{name}: its student is on no line of the roster (nor an alias); not exported")])
    for student, exercise, run in export.pending:
        rows.append(["not graded yet", lms_text(student), lms_text(exercise), "",
                     lms_text(f"grading run {run} was interrupted before grading it: run particles grade --resume, "
                              "then export again")])
    for s, e in export.missing():
        rows.append(["missing", lms_text(s.submission_name), lms_text(e), "0",
                     "no graded submission: exported as 0"])
    rows += [[kind, lms_text(s.submission_name), "", "", lms_text(detail)] for kind, s, detail in problems]
    return rows


def export_grades(out, roster, canvas=None, moodle=None, name_column=NAME_COLUMN, moodle_id="email"):
    """Write the LMS files of a graded folder and ``OUT/lms-report.csv``.

    Parameters
    ----------
    out : path
        The output folder of ``particles grade --out OUT``: its course record is read, ``lms-report.csv`` written.
    roster : path
        The roster CSV (:func:`read_roster`).
    canvas, moodle : path or None
        The Canvas and Moodle files to write (at least one).
    name_column : str
        The roster's column of the grader's names.
    moodle_id : {"email", "username", "idnumber"}
        The identifier of the Moodle file.

    Returns
    -------
    dict
        ``export`` (:class:`Export`), ``files`` (format -> path), ``left_out`` (format -> list of RosterStudent),
        ``name_only`` (roster students Canvas can match only by name), ``by_hand`` (roster students Canvas cannot
        match: :func:`~particles.course.results.importers.canvas_match`), ``report`` (its path).

    Raises
    ------
    RosterError, ExportError, ValueError
        A bad roster, unreadable records, no file asked for, or a file to write that is the roster itself.
    """
    out, roster_path = Path(out), Path(roster)
    targets = {fmt: Path(p) for fmt, p in (("canvas", canvas), ("moodle", moodle)) if p is not None}
    if not targets:
        raise ValueError("nothing to write: pass --canvas FILE, --moodle FILE or both")
    given = [roster_path.resolve(), *(p.resolve() for p in targets.values())]
    if len(set(given)) < len(given):
        raise ValueError("the roster, the Canvas file and the Moodle file must be three different files")
    if moodle_id not in MOODLE_IDENTIFIERS:
        raise ValueError(f"moodle_id must be one of {', '.join(MOODLE_IDENTIFIERS)}, got {moodle_id!r}")
    records, pending = read_records(out)
    export = match(read_roster(roster_path, name_column), records)
    export.pending = pending
    rows, left_out, problems = {}, {}, []
    if "canvas" in targets:
        rows["canvas"] = canvas_rows(export)
    if "moodle" in targets:
        rows["moodle"], left_out["moodle"] = moodle_rows(export, moodle_id)
        problems += [("left out", s, f"roster line {s.line} {moodle_left_out(s, moodle_id)}: not in the Moodle file")
                     for s in left_out["moodle"]]
    name_only, by_hand = [], []
    if "canvas" in targets:
        how = {id(s): canvas_match(s, lms_text(s.display_name)) for s in export.students}
        name_only = [s for s in export.students if how[id(s)] == "name"]
        by_hand = [s for s in export.students if not how[id(s)]]
        problems += [("matched by name", s, f"roster line {s.line} has no Canvas ID, SIS User ID or SIS Login "
                      f"ID Canvas can use: Canvas can match it only by its name {s.name!r}") for s in name_only]
        problems += [("match by hand", s, f"roster line {s.line}: {canvas_unmatched(s, lms_text(s.display_name))}; Canvas lists the row as an "
                      "unknown student to match by hand on upload (give it its canvas_id)") for s in by_hand]
    for fmt, path in targets.items():
        _write(path, rows[fmt], moodle_cell if fmt == "moodle" else None)
    report = out / "lms-report.csv"
    _write(report, _report_rows(export, problems))
    return {"export": export, "files": targets, "left_out": left_out, "name_only": name_only, "by_hand": by_hand,
            "report": report}

