"""The roster: who is in the course, and every name each student is known by.

A roster is a CSV file (UTF-8, a header line, then one line per student; columns in any order, titles compared
case-insensitively, ``_`` and spaces alike; other columns are ignored, so Canvas's own gradebook export is a
roster once ``--name-column`` names its column of the grader's names, e.g. ``"SIS Login ID"``; a cell is read
without the white space around it). ``particles grade``, ``particles review`` and ``particles export`` read it
(``--roster FILE``, or ``roster = "FILE"`` in the course file), and then it is the course: a name that is no
roster student's is refused wherever the instructor wrote it (extensions, times files, rubrics).

=====================  ===================  ======================================================
column                 also read under      what
=====================  ===================  ======================================================
``submission_name``                         the grader's name of the student: their output folder
                                            and gradebook row, and a name their submissions may
                                            come under (required; ``--name-column`` picks another)
``name``               ``Student``          the student's name as the LMS shows it
``canvas_id``          ``ID``               Canvas's numeric user ID (in Canvas's file names)
``sis_user_id``        ``SIS User ID``      the SIS user ID (Gradescope's ``sid`` too)
``sis_login_id``       ``SIS Login ID``     the SIS login (Canvas's file names start with it)
``section``            ``Section``          Canvas's section (shown, not used to match)
``email``              ``Email address``    the e-mail address (Moodle; Gradescope's submitters)
``username``           ``Username``         Moodle's username
``idnumber``           ``ID number``        Moodle's ID number
``aliases``            ``Aliases``          any other names the student submits under, separated
                                            by ``;`` (``alice.smith; asmith@old.uni.edu``)
=====================  ===================  ======================================================

Every name of a student (the name column, the logins, e-mail, username and aliases) is one of their names
for matching (:mod:`particles.course.term.identity`); Canvas's ID, the SIS user ID and the ID number are
matched with their kind. A roster is refused, naming its file and line, when it is empty, lacks the name
column, gives one name or identifier to two students, has a Canvas ID that is not a number or a name starting
with a spreadsheet formula character. Canvas's ``Points Possible`` line, its ``Manual Posting`` line (an
assignment with a manual posting policy) and its test student are skipped.
"""

import csv
import re
from dataclasses import dataclass
from pathlib import Path

from .identity import Identity, IdentityError, Person, name_key

__all__ = ["ROSTER_COLUMNS", "NAME_COLUMN", "IDENTIFIERS", "FORMULA", "CANVAS_POINTS_ROW", "RosterError",
           "RosterStudent", "Roster", "read_roster", "column_title"]

NAME_COLUMN = "submission_name"
ROSTER_COLUMNS = {"submission_name": ("submission_name",), "name": ("name", "Student"),
                  "canvas_id": ("canvas_id", "ID"), "sis_user_id": ("sis_user_id", "SIS User ID"),
                  "sis_login_id": ("sis_login_id", "SIS Login ID"), "section": ("section", "Section"),
                  "email": ("email", "Email address"), "username": ("username", "Username"),
                  "idnumber": ("idnumber", "ID number"), "aliases": ("aliases",)}
"""A roster's columns: field -> the titles it is read under (compared case-insensitively, ``_`` as a space)."""

IDENTIFIERS = ("canvas_id", "sis_user_id", "sis_login_id", "email", "username", "idnumber")
"""The LMS identifiers of a roster line."""

FORMULA = ("=", "+", "-", "@", "\t", "\r")
"""What a spreadsheet runs as a formula when a cell starts with it."""

CANVAS_POINTS_ROW = "Points Possible"
_CANVAS_TEST_STUDENTS = ("Student, Test", "Test Student")
_CANVAS_META_ROWS = (CANVAS_POINTS_ROW, "Manual Posting")  # lines of Canvas's export that are no student


class RosterError(ValueError):
    """A roster that cannot be used: the message names the file, the line and what was expected."""


def column_title(text):
    """A column title as rosters compare them: white space and ``_`` alike, case-folded."""
    return re.sub(r"[\s_]+", " ", str(text).strip()).casefold()


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
    aliases: tuple = ()

    @property
    def key(self):
        """The key of the grader's name (:func:`~particles.course.term.identity.name_key`)."""
        return name_key(self.submission_name)

    def person(self):
        """This student as the :class:`~particles.course.term.identity.Identity` knows them."""
        kinds = [(kind, getattr(self, kind)) for kind in IDENTIFIERS if getattr(self, kind)]
        return Person(self.submission_name, kinds + [("alias", a) for a in self.aliases], self.name, True)

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

    def identity(self):
        """The course this roster defines (closed: no other student)."""
        return Identity([s.person() for s in self.students], closed=True)


def _header(path, row, name_column):
    """field -> column index of a roster's header row (the name column as ``submission_name``)."""
    aliases = {column_title(t): name for name, titles in ROSTER_COLUMNS.items() for t in titles if name != NAME_COLUMN}
    aliases[column_title(name_column)] = NAME_COLUMN
    where, twice = {}, []
    for index, title in enumerate(row):
        name = aliases.get(column_title(title))
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
    identifiers = {column_title(t) for n, ts in ROSTER_COLUMNS.items() for t in ts if n != NAME_COLUMN}
    if column_title(name_column) in identifiers:
        # --name-column "SIS Login ID": the column is both the grader's name and that identifier
        other = next(n for n, ts in ROSTER_COLUMNS.items() if n != NAME_COLUMN
                     and column_title(name_column) in map(column_title, ts))
        if other in where:
            raise RosterError(f"roster {path}, line 1: columns {where[other] + 1} and {where[NAME_COLUMN] + 1} "
                              f"are both {other}")
        where[other] = where[NAME_COLUMN]
    return where


def _student(path, line, cells, where):
    values = {name: cells[index].strip() if index < len(cells) else "" for name, index in where.items()}
    for name in IDENTIFIERS:
        value = values.get(name, "")
        if value.startswith(FORMULA):
            raise RosterError(f"roster {path}, line {line}: {name} {value!r} starts with {value[0]!r}, which "
                              "spreadsheets run as a formula; expected an identifier")
    if values.get("canvas_id") and not values["canvas_id"].isdigit():
        raise RosterError(f"roster {path}, line {line}: canvas_id {values['canvas_id']!r} is not Canvas's numeric "
                          "user ID (expected digits only)")
    if not values[NAME_COLUMN]:
        raise RosterError(f"roster {path}, line {line}: the name column is empty; expected the name the grader "
                          "files this student's submission under")
    values["aliases"] = tuple(a.strip() for a in values.get("aliases", "").split(";") if a.strip())
    for alias in values["aliases"]:
        if alias.startswith(FORMULA):
            raise RosterError(f"roster {path}, line {line}: alias {alias!r} starts with {alias[0]!r}, which "
                              "spreadsheets run as a formula; expected a name")
    return RosterStudent(line=line, **values)


def _canvas_meta(name, own, cells):
    """Whether a line of Canvas's gradebook export is no student: ``Points Possible``, ``Manual Posting`` (empty
    name cells, the words under an assignment), its test student."""
    if CANVAS_POINTS_ROW in name or (name in _CANVAS_TEST_STUDENTS and not own):
        return True
    return not name and not own and any(cell.strip() in _CANVAS_META_ROWS for cell in cells)


def _check_unique(path, students):
    """Refuse two lines with one grader name (as the grader compares them) or one non-empty identifier."""
    for name in ("key", *IDENTIFIERS):
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
    identity = Identity()
    for student in students:  # a name of one student (an alias, a login) that is another's
        try:
            identity.add(student.person())
        except IdentityError as error:
            raise RosterError(f"roster {path}, line {student.line}: {error}; expected each name and identifier "
                              "to be one student's") from None


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
            if _canvas_meta(name, own, cells):
                continue
            students.append(_student(path, line, cells, where))
    except csv.Error as error:
        raise RosterError(f"roster {path}, line {reader.line_num}: not CSV ({error})") from None
    if not students:
        raise RosterError(f"roster {path} has a header but no student: expected one line per student")
    _check_unique(path, students)
    return Roster(path, students, tuple(name for name in ROSTER_COLUMNS if name in where))
