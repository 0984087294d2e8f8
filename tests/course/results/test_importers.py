"""The LMS files through the importers' own reading: Moodle's by PHP's fgetcsv itself, Canvas's by a port of its rules.

(particles.course.results.importers, and the writers of particles.course.results.lms.) The readers are in
``helpers.py`` beside this file, with the lines of Moodle's and Canvas's source they follow.
"""

import csv
import random

import pytest

from particles.cli import main
from particles.course.results.importers import canvas_match, canvas_read, moodle_cell, moodle_empty
from particles.course.results.lms import REPORT_COLUMNS, export_grades, lms_text, read_roster
from particles.course.results.records import SubmissionRecord, TestRecord

from .helpers import CanvasUser, canvas_import, graded_folder, moodle_import

EXERCISE = "01_integrator_order"


def graded(tmp_path, students):
    records = []
    for k, student in enumerate(students):
        tests = [TestRecord("test_a", "a", points=2.0, passed=True), TestRecord("test_b", "b", points=1.0,
                                                                               passed=k % 2 == 0)]
        records.append(SubmissionRecord(student=student, exercise=EXERCISE, tests=tests, complete=True))
    return graded_folder(tmp_path / "out", records)


def write_roster(tmp_path, header, rows):
    path = tmp_path / "roster.csv"
    with open(path, "w", encoding="utf-8", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)
    return path


def report(out):
    return list(csv.DictReader((out / "lms-report.csv").open(encoding="utf-8")))


# --- Moodle: PHP's fgetcsv ---------------------------------------------------------------------------------------

NAMES = {"ann": "Ann Lee", "gus": 'Gus\\", jr', "hal": "Hal \\", "ida": 'Ida "the" Great, PhD', "joe": "Zoë Ñúñez-李",
         "kai": "C:\\\\", "lou": "two\nlines", "max": "=1+1", "ned": "tab\there\\"}


def test_python_csv_is_not_what_moodle_reads(tmp_path):
    """The reader is PHP's: a name with \\" written by Python's csv splits a cell and Moodle refuses the file."""
    path = tmp_path / "python.csv"
    with open(path, "w", encoding="utf-8", newline="") as handle:
        csv.writer(handle).writerows([["Email address", "Full name", "x"], ["g@x", 'Gus\\", jr', "1"]])
    assert moodle_import(path)["error"] == "csvweirdcolumns"
    path.write_text("Email address,Full name,x\na@x,Ann,1\n0,Zero,2\n", encoding="utf-8")
    read = moodle_import(path)
    assert read["error"] is None and read["users"] == ["a@x", "a@x"]  # "0" takes the previous row's user


def test_moodle_file_reads_one_row_per_student_with_their_identifier(tmp_path):
    """Every written row reads back in PHP as one row, with its own identifier and the name as written."""
    students = list(NAMES)
    out = graded(tmp_path, students)
    roster = write_roster(tmp_path, ["submission_name", "name", "idnumber"],
                          [[s, NAMES[s], f"10{k}"] for k, s in enumerate(students)])
    done = export_grades(out, roster, moodle=tmp_path / "moodle.csv", moodle_id="idnumber")
    assert done["left_out"]["moodle"] == []
    read = moodle_import(tmp_path / "moodle.csv")
    assert read["error"] is None
    assert read["header"] == ["ID number", "Full name", EXERCISE, f"{EXERCISE} feedback", "Total"]
    assert read["users"] == [row[0] for row in read["rows"]] == [f"10{k}" for k in range(len(students))]
    assert [row[1] for row in read["rows"]] == [lms_text(NAMES[s]).strip(" \t\n") for s in students]
    assert [row[2] for row in read["rows"]] == ["3" if k % 2 == 0 else "2" for k in range(len(students))]


@pytest.mark.parametrize("empty", ["0", " 0", "0 ", "\t0"])
def test_an_identifier_php_calls_empty_is_left_out_and_reported(tmp_path, capsys, empty):
    """An id number that PHP's empty() calls empty is never written: its grades would go to the row before it."""
    out = graded(tmp_path, ["ann", "bob", "cy"])
    roster = write_roster(tmp_path, ["submission_name", "idnumber", "email"],
                          [["ann", "7", "a@x"], ["bob", empty, "b@x"], ["cy", "00", "c@x"]])
    assert read_roster(roster).students[1].idnumber.strip() == "0"
    code = main(["export", str(out), "--roster", str(roster), "--moodle", str(tmp_path / "m.csv"),
                 "--moodle-id", "idnumber"])
    assert code == 1
    assert "left out of the moodle file: bob (roster line 3)" in capsys.readouterr().err
    read = moodle_import(tmp_path / "m.csv")
    assert read["error"] is None and read["users"] == ["7", "00"]  # "00" is not empty to PHP
    left = [r for r in report(out) if r["problem"] == "left out"]
    assert [r["student"] for r in left] == ["bob"] and "PHP's empty()" in left[0]["detail"]
    assert main(["export", str(out), "--roster", str(roster), "--moodle", str(tmp_path / "m.csv")]) == 0


def test_any_text_reads_back_in_php(tmp_path):
    """Random cells of quotes, backslashes, commas, spaces and line breaks read back in PHP as written (trimmed)."""
    rng = random.Random(44)
    alphabet = ['"', "\\", ",", " ", "\n", "\t", "a", "é", "0", "'"]
    cells = ["".join(rng.choice(alphabet) for _ in range(rng.randrange(1, 9))) for _ in range(400)]
    path = tmp_path / "fuzz.csv"
    path.write_text("id,text\n" + "".join(f"u{k},{moodle_cell(c)}\n" for k, c in enumerate(cells)),
                    encoding="utf-8")
    read = moodle_import(path)
    assert read["error"] is None and len(read["rows"]) == len(cells)
    trim = " \t\n\r\0\x0b"
    assert [row[1] for row in read["rows"]] == [c.strip(trim) for c in cells]


def test_moodle_empty_is_phps():
    """moodle_empty says what PHP's empty(trim(...)) says."""
    assert [moodle_empty(v) for v in ("", " ", "0", "\n0\n", "00", "0.0", "o")] == [True] * 4 + [False] * 3


# --- Canvas: its importer's rules -------------------------------------------------------------------------------


def test_canvas_file_matches_every_student_by_the_ported_rules(tmp_path, capsys):
    """Each row of the Canvas file matches its own user by ID, SIS User ID, SIS Login ID or name, as Canvas does."""
    rows = [["ann", "Ann Lee", "101", "S-1", "alee"], ["bob", "Bob Ray", "", "S-2", "bray"],
            ["cy", "Cy Ho", "", "", "cho"], ["dee", "Dee Fu", "", "", ""], ["eli", "Eli, Jr", "", "1,234", "eli"]]
    out = graded(tmp_path, [r[0] for r in rows])
    roster = write_roster(tmp_path, ["submission_name", "name", "canvas_id", "sis_user_id", "sis_login_id"], rows)
    users = [CanvasUser(101, "Ann Lee", "Lee, Ann", "S-1", "alee"), CanvasUser(102, "Bob Ray", "Ray, Bob", "S-2"),
             CanvasUser(103, "Cy Ho", "Ho, Cy", "", "cho"), CanvasUser(104, "Dee Fu", "Fu, Dee"),
             CanvasUser(105, "Eli, Jr", "Jr, Eli", "1,234", "eli"), CanvasUser(106, "Ann Lee", "Lee, Ann")]
    assert main(["export", str(out), "--roster", str(roster), "--canvas", str(tmp_path / "c.csv")]) == 0
    read = canvas_import((tmp_path / "c.csv").read_text(encoding="utf-8"), users)
    assert read.assignments == [EXERCISE] and read.points == {EXERCISE: "3"}
    assert [(user.id, grades[EXERCISE]) for user, grades in read.rows] == [(101, "3"), (102, "2"), (103, "3"),
                                                                          (104, "2"), (105, "3")]
    by = {r["student"]: r["problem"] for r in report(out)}
    assert by == {"dee": "matched by name"}  # eli's SIS User ID reads 1.234 in Canvas: matched by login
    assert "dee (roster line 5) has no Canvas ID" in capsys.readouterr().err


def test_a_name_canvas_cannot_match_is_never_said_to_match_by_name(tmp_path, capsys):
    """-Eve is written '-Eve: the ported importer matches no one, and the report says to match it by hand (exit 1)."""
    out = graded(tmp_path, ["eve", "fay"])
    roster = write_roster(tmp_path, ["submission_name", "name", "sis_user_id"], [["eve", "-Eve", ""],
                                                                                 ["fay", "Fay", "7,5"]])
    users = [CanvasUser(1, "-Eve", "-Eve"), CanvasUser(2, "Fay", "Fay", "7,5")]
    assert main(["export", str(out), "--roster", str(roster), "--canvas", str(tmp_path / "c.csv")]) == 1
    err = capsys.readouterr().err
    read = canvas_import((tmp_path / "c.csv").read_text(encoding="utf-8"), users)
    assert [user for user, _ in read.rows] == [None, users[1]]  # fay by name: her SIS id reads 7.5
    problems = {r["student"]: (r["problem"], r["detail"]) for r in report(out)}
    assert problems["eve"][0] == "match by hand" and "'-Eve" in problems["eve"][1]
    assert problems["fay"][0] == "matched by name" and "eve" in err and "by hand" in err
    assert list(report(out)[0]) == list(REPORT_COLUMNS)


def test_canvas_read_is_the_ported_converter():
    """canvas_read and the port agree on numbers with commas and dots, and leave other text alone."""
    from .helpers import _decimal_comma_to_period
    for cell in ("1,234", "1.234,5", "12,", "-3.5%", "S-1", "abc", "0012", "a\n1,5"):
        assert canvas_read(cell) == _decimal_comma_to_period(cell), cell
    assert canvas_read("1,5") == "1.5" and canvas_read("a\n1,5") == "a\n1.5"


def test_canvas_match_order():
    """ID first, then SIS User ID, SIS Login ID, then the name as written; nothing when none of them will do."""
    from particles.course.term.roster import RosterStudent
    s = RosterStudent("x", 2, name="X", canvas_id="5", sis_user_id="S", sis_login_id="L")
    assert canvas_match(s, "X") == "ID"
    assert canvas_match(RosterStudent("x", 2, name="X", sis_user_id="S", sis_login_id="L"), "X") == "SIS User ID"
    assert canvas_match(RosterStudent("x", 2, name="X", sis_user_id="1,5", sis_login_id="L"), "X") == "SIS Login ID"
    assert canvas_match(RosterStudent("x", 2, name="X"), "X") == "name"
    assert canvas_match(RosterStudent("x", 2, name="+X"), "'+X") == ""
    assert canvas_match(RosterStudent("x", 2), "x") == ""
