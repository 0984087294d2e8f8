r"""Grades into the LMS: the gradebook import CSVs of Canvas and Moodle, students matched through a roster.

``particles export OUT --roster ROSTER --canvas FILE --moodle FILE`` reads the records of a graded folder
(``OUT/records/``, :mod:`particles.course.results.store`) and writes one row per student of the roster, one
column per exercise (the record's :attr:`~particles.course.results.records.SubmissionRecord.total`: tests,
written answers graded by people, minus the late penalty) and a total column.

The roster (CSV, UTF-8, a header line, then one line per student; columns in any order, names compared
case-insensitively, ``_`` and spaces alike; other columns are ignored, so Canvas's own gradebook export is a
roster once ``--name-column`` names its column of the grader's names, e.g. ``"SIS Login ID"``; a
cell is read without the white space around it):

=====================  ===================  ======================================================
column                 also read under      what
=====================  ===================  ======================================================
``submission_name``                         the name the grader files the student under: the
                                            submission's folder (or notebook) name, e.g. a login
                                            (required; ``--name-column`` picks another column)
``name``               ``Student``          the student's name as the LMS shows it
``canvas_id``          ``ID``               Canvas's numeric user ID
``sis_user_id``        ``SIS User ID``      Canvas's SIS User ID
``sis_login_id``       ``SIS Login ID``     Canvas's SIS Login ID
``section``            ``Section``          Canvas's section (shown, not used to match)
``email``              ``Email address``    Moodle's email address
``username``           ``Username``         Moodle's username
``idnumber``           ``ID number``        Moodle's ID number
=====================  ===================  ======================================================

A roster is refused, naming its file and line, when it is empty, lacks the name column, repeats a name (as the
grader compares them: :func:`particles.course.grading.discovery.student_key`) or a non-empty identifier, has a
Canvas ID that is not a number or an identifier starting with a spreadsheet formula character. Canvas's
``Points Possible`` line and its test student (``Student, Test`` without the name cell) are skipped.

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
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..grading.discovery import student_key
from .importers import canvas_match, canvas_unmatched, moodle_cell, moodle_left_out
from .records import SubmissionRecord

__all__ = ["CANVAS_DOC", "CANVAS_IMPORTER", "MOODLE_DOC", "MOODLE_IMPORTER", "CANVAS_STUDENT_COLUMNS",
           "CANVAS_TOTAL", "CANVAS_POINTS_ROW", "CANVAS_READ_ONLY", "CANVAS_RESERVED", "MOODLE_IDENTIFIERS",
           "MOODLE_NAME", "MOODLE_TOTAL", "MOODLE_MISSING", "REPORT_COLUMNS", "ROSTER_COLUMNS", "NAME_COLUMN",
           "RosterError", "ExportError", "RosterStudent", "Roster", "Export", "read_roster", "read_records",
           "match", "lms_number", "lms_text", "canvas_rows", "moodle_rows", "export_grades"]

CANVAS_DOC = "https://community.canvaslms.com/t5/Instructor-Guide/How-do-I-import-grades-in-the-Gradebook/ta-p/807"
CANVAS_IMPORTER = "https://github.com/instructure/canvas-lms/blob/master/lib/gradebook_importer.rb"
MOODLE_DOC = "https://docs.moodle.org/en/Grade_import"
MOODLE_IMPORTER = "https://github.com/moodle/moodle/blob/main/grade/import/csv/classes/load_data.php"

CANVAS_STUDENT_COLUMNS = ("Student", "ID", "SIS User ID", "SIS Login ID", "Section")
"""The first columns of a Canvas gradebook CSV, in Canvas's order (its importer checks the order)."""
CANVAS_TOTAL = "Final Points"
"""The total's title: a read-only column for Canvas's importer, shown, never imported as an assignment."""
CANVAS_POINTS_ROW = "Points Possible"
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
"""The columns of ``lms-report.csv``; ``problem`` is one of ``not on roster``, ``missing``, ``left out``,
``matched by name``, ``match by hand``."""

NAME_COLUMN = "submission_name"
ROSTER_COLUMNS = {"submission_name": ("submission_name",), "name": ("name", "Student"),
                  "canvas_id": ("canvas_id", "ID"), "sis_user_id": ("sis_user_id", "SIS User ID"),
                  "sis_login_id": ("sis_login_id", "SIS Login ID"), "section": ("section", "Section"),
                  "email": ("email", "Email address"), "username": ("username", "Username"),
                  "idnumber": ("idnumber", "ID number")}
"""A roster's columns: field -> the titles it is read under (compared case-insensitively, ``_`` as a space)."""

_IDENTIFIERS = ("canvas_id", "sis_user_id", "sis_login_id", "email", "username", "idnumber")
_FORMULA = ("=", "+", "-", "@", "\t", "\r")
_CANVAS_TEST_STUDENTS = ("Student, Test", "Test Student")


class RosterError(ValueError):
    """A roster that cannot be used: the message names the file, the line and what was expected."""


class ExportError(ValueError):
    """Records that cannot be exported (no records folder, a record that cannot be read, a clash)."""


def _title(text):
    return re.sub(r"[\s_]+", " ", str(text).strip()).casefold()


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
    return "'" + text if text.startswith(_FORMULA) else text


@dataclass(frozen=True)
class RosterStudent:
    """One line of a roster: the grader's name of the student and the LMS identifiers (``""`` when not given)."""

    submission_name: str
    line: int
    name: str = ""
    canvas_id: str = ""
    sis_user_id: str = ""
    sis_login_id: str = ""
    section: str = ""
    email: str = ""
    username: str = ""
    idnumber: str = ""

    @property
    def key(self):
        """The key records are matched by (:func:`~particles.course.grading.discovery.student_key`)."""
        return student_key(self.submission_name)

    @property
    def display_name(self):
        """The name to show: ``name``, else the grader's name."""
        return self.name or self.submission_name


@dataclass
class Roster:
    """The students of a roster file, in the file's order; ``columns``: the fields its header has."""

    path: Path
    students: list
    columns: tuple


def _header(path, row, name_column):
    """field -> column index of a roster's header row (the name column as ``submission_name``)."""
    aliases = {_title(t): name for name, titles in ROSTER_COLUMNS.items() for t in titles if name != NAME_COLUMN}
    aliases[_title(name_column)] = NAME_COLUMN
    where, twice = {}, []
    for index, title in enumerate(row):
        name = aliases.get(_title(title))
        if name is None:
            continue
        if name in where:
            twice.append(f"columns {where[name] + 1} and {index + 1} are both {name}")
        where[name] = index
    if twice:
        raise RosterError(f"roster {path}, line 1: {'; '.join(twice)}")
    if NAME_COLUMN not in where:
        raise RosterError(f"roster {path}, line 1: no column {name_column!r} (the name the grader files each "
                          f"student's submission under); its columns are {', '.join(map(repr, row))}; "
                          "pass --name-column to use another")
    if _title(name_column) in {_title(t) for n, ts in ROSTER_COLUMNS.items() for t in ts if n != NAME_COLUMN}:
        # --name-column "SIS Login ID": the column is both the grader's name and that identifier
        other = next(n for n, ts in ROSTER_COLUMNS.items() if n != NAME_COLUMN
                     and _title(name_column) in map(_title, ts))
        if other in where:
            raise RosterError(f"roster {path}, line 1: columns {where[other] + 1} and {where[NAME_COLUMN] + 1} "
                              f"are both {other}")
        where[other] = where[NAME_COLUMN]
    return where


def _student(path, line, cells, where):
    values = {name: cells[index].strip() if index < len(cells) else "" for name, index in where.items()}
    for name in _IDENTIFIERS:
        value = values.get(name, "")
        if value.startswith(_FORMULA):
            raise RosterError(f"roster {path}, line {line}: {name} {value!r} starts with {value[0]!r}, which "
                              "spreadsheets run as a formula; expected an identifier")
    if values.get("canvas_id") and not values["canvas_id"].isdigit():
        raise RosterError(f"roster {path}, line {line}: canvas_id {values['canvas_id']!r} is not Canvas's numeric "
                          "user ID (expected digits only)")
    if not values[NAME_COLUMN]:
        raise RosterError(f"roster {path}, line {line}: the name column is empty; expected the name the grader "
                          "files this student's submission under")
    return RosterStudent(line=line, **values)


def _check_unique(path, students):
    """Refuse two lines with one grader name (as the grader compares them) or one non-empty identifier."""
    for name in ("key", *_IDENTIFIERS):
        seen = {}
        for student in students:
            value = getattr(student, name)
            value = value.casefold() if name in ("email", "key") else value
            if not value:
                continue
            if value in seen:
                what = (f"the name {student.submission_name!r} is the grader's {student.key!r}, as the name on "
                        f"line {seen[value].line} ({seen[value].submission_name!r}): names compare "
                        "case-insensitively after the grader's normalisation" if name == "key"
                        else f"{name} {getattr(student, name)!r} is also on line {seen[value].line}")
                raise RosterError(f"roster {path}, line {student.line}: {what}; expected one line per student")
            seen[value] = student


def read_roster(path, name_column=NAME_COLUMN):
    """Read and check a roster CSV (the columns of :data:`ROSTER_COLUMNS`).

    Parameters
    ----------
    path : path
        The roster: UTF-8 (a byte-order mark is allowed), a header line, one line per student.
    name_column : str
        The column of the grader's names of the students (default ``submission_name``; for Canvas's
        gradebook export, e.g. ``"SIS Login ID"``).

    Returns
    -------
    Roster

    Raises
    ------
    RosterError
        Naming the file, the line and what was expected: unreadable, empty, no name column, a duplicate name or
        identifier, a Canvas ID that is not a number, an identifier starting with a formula character.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except OSError as error:
        raise RosterError(f"roster {path}: cannot be read ({error.strerror or error})") from None
    except UnicodeDecodeError as error:
        raise RosterError(f"roster {path}: byte {error.start} is not UTF-8; expected a CSV saved as UTF-8") from None
    reader = csv.reader(text.splitlines(keepends=True))
    try:
        header = next((row for row in reader if any(c.strip() for c in row)), None)
        if header is None:
            raise RosterError(f"roster {path} is empty: expected a header line ({NAME_COLUMN}, then LMS "
                              "identifiers such as canvas_id or email) and one line per student")
        where = _header(path, header, name_column)
        students = []
        for cells in reader:
            if not any(c.strip() for c in cells):
                continue
            line = reader.line_num
            if len(cells) > len(header):
                raise RosterError(f"roster {path}, line {line}: {len(cells)} cells; expected at most "
                                  f"{len(header)}, as in the header")
            name = cells[where["name"]].strip() if "name" in where and where["name"] < len(cells) else ""
            own = cells[where[NAME_COLUMN]].strip() if where[NAME_COLUMN] < len(cells) else ""
            if CANVAS_POINTS_ROW in name or (name in _CANVAS_TEST_STUDENTS and not own):
                continue  # lines of Canvas's own export that are no student
            students.append(_student(path, line, cells, where))
    except csv.Error as error:
        raise RosterError(f"roster {path}, line {reader.line_num}: not CSV ({error})") from None
    if not students:
        raise RosterError(f"roster {path} has a header but no student: expected one line per student")
    _check_unique(path, students)
    return Roster(path, students, tuple(name for name in ROSTER_COLUMNS if name in where))


def read_records(folder):
    """The :class:`~particles.course.results.records.SubmissionRecord` s of a ``records/`` folder, by file.

    Returns
    -------
    dict
        file name -> record.

    Raises
    ------
    ExportError
        When the folder does not exist or a record file cannot be read as a record (naming it).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise ExportError(f"{folder} is not a folder of records: expected the records/ folder that "
                          "`particles grade SUBMISSIONS --out OUT` writes")
    records = {}
    for path in sorted(folder.glob("*.json")):
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            if isinstance(data, dict):
                data.pop("options", None)
            records[path.name] = SubmissionRecord.from_dict(data)
        except (OSError, UnicodeDecodeError, ValueError, TypeError) as error:
            raise ExportError(f"record {path} cannot be read ({error}); grade it again or remove it") from None
    return records


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
        Records whose student is on no line of the roster, with their file names.
    """

    exercises: list
    points: dict
    students: list
    records: dict
    unmatched: list = field(default_factory=list)

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
    """Match records (file name -> record) with the students of a roster.

    Raises
    ------
    ExportError
        When two records of one exercise belong to one roster student (names differing only in case).
    """
    keys = {s.key for s in roster.students}
    by_student, unmatched, files, points = {}, [], {}, {}
    for name, record in records.items():
        points[record.exercise] = max(points.get(record.exercise, 0.0), record.total_max)
        key = student_key(record.student)
        if key not in keys:
            unmatched.append((name, record))
            continue
        mine = by_student.setdefault(key, {})
        if record.exercise in mine:
            raise ExportError(f"records {files[key, record.exercise]} and {name} are both {record.exercise} of "
                              f"the roster's {key!r}: remove the one that is not theirs")
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
                     lms_text(f"records/{name}: its student is on no line of the roster; not exported")])
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
        The output folder of ``particles grade --out OUT``: its ``records/`` are read, ``lms-report.csv`` written.
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
    export = match(read_roster(roster_path, name_column), read_records(out / "records"))
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

