"""Grades into the LMS: Canvas's and Moodle's import CSVs against their documented columns; rosters, hostile names."""

import csv
import io
import re

import pytest

from particles.cli import main
from particles.course.grading.discovery import student_key
from particles.course.results import lms
from particles.course.results.lms import (ExportError, canvas_rows, export_grades, lms_number, lms_text, match,
                                          moodle_rows, read_records)
from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.term.database import TermRecord
from particles.course.term.roster import RosterError, read_roster

# Canvas, "How do I import grades in the Gradebook?"
# https://community.canvaslms.com/t5/Instructor-Guide/How-do-I-import-grades-in-the-Gradebook/ta-p/807
# and its importer, https://github.com/instructure/canvas-lms/blob/master/lib/gradebook_importer.rb
CANVAS_STUDENT_COLUMNS = ["Student", "ID", "SIS User ID", "SIS Login ID", "Section"]
CANVAS_NOT_ASSIGNMENTS = ["Current Score", "Current Points", "Current Grade", "Final Score", "Final Points",
                          "Final Grade", "Override Score", "Override Grade", "Override Status"]
# Moodle, "Grade import" (CSV: map from an identifier column to a user field; a grade item or its feedback per column)
# https://docs.moodle.org/en/Grade_import and
# https://github.com/moodle/moodle/blob/main/grade/import/csv/classes/load_data.php
MOODLE_USER_FIELDS = {"Email address": "useremail", "Username": "username", "ID number": "useridnumber"}


def canvas_import(text):
    """What Canvas's importer reads from a file (its header rules, as in gradebook_importer.rb)."""
    rows = list(csv.reader(io.StringIO(text)))
    header = rows[0]
    assert "Student" in header[0] and "ID" in header[1], "Canvas: Student, then ID"
    assert re.search(r"SIS\s+User\s+ID", header[2]) and re.search(r"SIS\s+Login\s+ID", header[3])
    assert "Section" in header[4], "Canvas: Section is the last student column"
    assignments = [(i, h) for i, h in enumerate(header) if i >= 5
                   and not re.search("|".join(CANVAS_NOT_ASSIGNMENTS), h)]
    points, students = {}, []
    for row in rows[1:]:
        assert len(row) == len(header)
        if "Points Possible" in row[0]:
            points = {h: row[i] for i, h in assignments}
            continue
        students.append({"id": row[1], "sis_user_id": row[2], "sis_login_id": row[3], "name": row[0],
                         "grades": {h: float(row[i]) for i, h in assignments}})
    return [h for _, h in assignments], points, students


def moodle_import(text, identifier="Email address"):
    """Moodle's preview of a file: identifier -> {column: value}; every line must name its user."""
    rows = list(csv.reader(io.StringIO(text)))
    header = rows[0]
    assert header[0] == identifier
    users = {}
    for row in rows[1:]:
        assert len(row) == len(header) and row[0].strip(), "a line without its user takes the previous user's"
        users[row[0]] = dict(zip(header[1:], row[1:]))
    return header, users


def record(student, exercise, passed=(True, True), written=None, penalty=None):
    tests = [TestRecord(f"test_{k}", f"check {k}", points=p, passed=ok)
             for k, (p, ok) in enumerate(zip((2.5, 1.0), passed))]
    return SubmissionRecord(student=student, exercise=exercise, tests=tests, written=written or [],
                            late={"penalty": penalty, "reason": "late"} if penalty else None, complete=True)


def graded(tmp_path, records):
    """A graded folder: its course record holding `records`, as `particles grade --out` leaves it."""
    out = tmp_path / "out"
    term = TermRecord(out)
    run = term.start_run("particles grade (a test)", {})
    for r in records:
        term.save(run, r, {"public_only": False})
    term.finish_run(run)
    term.close()
    return out


def roster_file(tmp_path, text, name="roster.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


ROSTER = ("submission_name,name,canvas_id,sis_user_id,sis_login_id,section,email,username,idnumber\n"
          "ann,\"Lee, Ann\",101,S-1,alee,A,ann@uni.org,alee,1001\n"
          "Bob Smith,\"Smith, Bob\",102,S-2,bsmith,B,bob@uni.org,bsmith,1002\n"
          "carl,Carl Ito,103,S-3,cito,A,carl@uni.org,cito,1003\n")


@pytest.fixture
def course(tmp_path):
    out = graded(tmp_path, [record("ann", "01_integrator_order"),
                            record("ann", "02_stiffness", passed=(False, True),
                                   written=[{"question": "q1", "points": 1.5, "max_points": 2.0}], penalty=0.5),
                            record("Bob_Smith", "01_integrator_order", passed=(True, False))])
    return out, roster_file(tmp_path, ROSTER)


def test_canvas_file_reads_as_canvas_importer_reads_it(course, tmp_path):
    """The Canvas file has Canvas's documented columns in order: students by ID, one assignment per exercise."""
    out, roster = course
    export_grades(out, roster, canvas=tmp_path / "canvas.csv")
    text = (tmp_path / "canvas.csv").read_text(encoding="utf-8")
    header = text.splitlines()[0].split(",")
    assert header == CANVAS_STUDENT_COLUMNS + ["01_integrator_order", "02_stiffness", "Final Points"]
    assignments, points, students = canvas_import(text)
    assert assignments == ["01_integrator_order", "02_stiffness"]  # the total is never read as an assignment
    assert points == {"01_integrator_order": "3.5", "02_stiffness": "5.5"}  # tests (+ written questions)
    assert [(s["id"], s["sis_login_id"]) for s in students] == [("101", "alee"), ("102", "bsmith"), ("103", "cito")]
    assert [s["grades"] for s in students] == [{"01_integrator_order": 3.5, "02_stiffness": 1.0 + 1.5 - 0.5},
                                               {"01_integrator_order": 2.5, "02_stiffness": 0.0},
                                               {"01_integrator_order": 0.0, "02_stiffness": 0.0}]
    assert text.splitlines()[1].endswith(",(read only)") and not text.startswith("\ufeff")


def test_moodle_file_has_documented_columns(course, tmp_path):
    """The Moodle file: an identifier Moodle maps to a user field, a grade and a feedback per exercise, a total."""
    out, roster = course
    for identifier, title in [("email", "Email address"), ("username", "Username"), ("idnumber", "ID number")]:
        export_grades(out, roster, moodle=tmp_path / "moodle.csv", moodle_id=identifier)
        header, users = moodle_import((tmp_path / "moodle.csv").read_text(encoding="utf-8"), title)
        assert title in MOODLE_USER_FIELDS
        assert header == [title, "Full name", "01_integrator_order", "01_integrator_order feedback",
                          "02_stiffness", "02_stiffness feedback", "Total"]
    assert list(users) == ["1001", "1002", "1003"]
    assert users["1001"]["02_stiffness"] == "2"
    assert users["1001"]["02_stiffness feedback"] == "tests 1/3.5, written answers 1.5/2, late penalty -0.5"
    assert users["1001"]["Total"] == "5.5" and users["1002"]["Total"] == "2.5"


def test_missing_submission_is_zero_and_missing(course, tmp_path):
    """A roster student without a record gets 0 in both files, "missing" in Moodle's feedback and in the report."""
    out, roster = course
    done = export_grades(out, roster, canvas=tmp_path / "c.csv", moodle=tmp_path / "m.csv")
    _, _, students = canvas_import((tmp_path / "c.csv").read_text(encoding="utf-8"))
    carl = next(s for s in students if s["id"] == "103")
    assert carl["grades"] == {"01_integrator_order": 0.0, "02_stiffness": 0.0}
    _, users = moodle_import((tmp_path / "m.csv").read_text(encoding="utf-8"))
    assert users["carl@uni.org"]["01_integrator_order feedback"] == lms.MOODLE_MISSING
    assert users["carl@uni.org"]["Total"] == "0"
    report = list(csv.DictReader(done["report"].open(encoding="utf-8")))
    missing = {(r["student"], r["exercise"]) for r in report if r["problem"] == "missing"}
    assert missing == {("carl", "01_integrator_order"), ("carl", "02_stiffness"), ("Bob Smith", "02_stiffness")}
    assert list(report[0]) == list(lms.REPORT_COLUMNS)


def test_record_not_on_roster_is_reported_never_dropped(tmp_path, capsys):
    """A record whose student is not on the roster is in the report and on stderr, and the command exits with 1."""
    out = graded(tmp_path, [record("ann", "01_integrator_order"), record("zoe", "01_integrator_order")])
    roster = roster_file(tmp_path, ROSTER)
    code = main(["export", str(out), "--roster", str(roster), "--canvas", str(tmp_path / "c.csv")])
    assert code == 1
    err = capsys.readouterr().err
    assert "not on the roster: zoe (01_integrator_order, 3.5/3.5 points, zoe/01_integrator_order)" in err
    report = list(csv.DictReader((out / "lms-report.csv").open(encoding="utf-8")))
    assert [(r["problem"], r["student"], r["points"]) for r in report if r["problem"] == "not on roster"] == [
        ("not on roster", "zoe", "3.5")]
    assert "zoe" not in (tmp_path / "c.csv").read_text(encoding="utf-8")


def test_names_match_as_the_grader_files_them():
    """Roster names match records case-insensitively after the grader's normalisation (spaces and punctuation)."""
    assert student_key("Bob Smith") == student_key("bob_smith") == student_key("BOB_SMITH") == "bob_smith"
    assert student_key("ann.lee@uni.org") == "ann.lee@uni.org" and student_key("ann") != student_key("anne")


def test_cli_export_writes_both_files(course, tmp_path, capsys):
    """`particles export` writes both files and the report; exit 0 when every record and student is in them."""
    out, roster = course
    code = main(["export", str(out), "--roster", str(roster), "--canvas", str(tmp_path / "c.csv"),
                 "--moodle", str(tmp_path / "m.csv"), "--moodle-id", "username"])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "missing: carl has no graded 01_integrator_order: exported as 0" in printed.out
    assert (tmp_path / "c.csv").exists() and (tmp_path / "m.csv").exists() and (out / "lms-report.csv").exists()
    assert main(["export", str(out), "--roster", str(roster)]) == 2  # nothing asked for
    assert "nothing to write" in capsys.readouterr().err


def test_cli_refuses_to_overwrite_the_roster(course, capsys):
    """A --canvas FILE that is the roster is refused (exit 2) and the roster is kept."""
    out, roster = course
    assert main(["export", str(out), "--roster", str(roster), "--canvas", str(roster)]) == 2
    assert "three different files" in capsys.readouterr().err
    assert roster.read_text(encoding="utf-8") == ROSTER


def test_student_without_moodle_identifier_is_left_out_and_reported(tmp_path, capsys):
    """A roster student without the chosen Moodle identifier is not written (Moodle would take the previous user)."""
    out = graded(tmp_path, [record("ann", "01_integrator_order"), record("bob", "01_integrator_order")])
    roster = roster_file(tmp_path, "submission_name,email,canvas_id\nann,ann@uni.org,1\nbob,,2\n")
    code = main(["export", str(out), "--roster", str(roster), "--moodle", str(tmp_path / "m.csv")])
    assert code == 1
    assert "left out of the moodle file: bob (roster line 3) has no email" in capsys.readouterr().err
    _, users = moodle_import((tmp_path / "m.csv").read_text(encoding="utf-8"))
    assert list(users) == ["ann@uni.org"]
    report = (out / "lms-report.csv").read_text(encoding="utf-8")
    assert "left out,bob,,,roster line 3 has no email: not in the Moodle file" in report


HOSTILE = ["=HYPERLINK(\"http://evil\",\"x\")", "+1+2", "-3", "@SUM(A1)", "O'Brien, \"Dan\"", "Zoë Ñúñez-李",
           "two\nlines", "tab\tinside"]


def test_hostile_names_round_trip_quoted_and_neutralised(tmp_path):
    """Names with commas, quotes, line breaks and non-ASCII survive csv reading; formula starts get a leading '."""
    lines = ["submission_name,name,canvas_id,section,email"]
    for k, name in enumerate(HOSTILE):
        quoted = '"' + name.replace('"', '""') + '"'
        lines.append(f"s{k},{quoted},{k + 1},{quoted},s{k}@uni.org")
    roster = roster_file(tmp_path, "\n".join(lines) + "\n")
    out = graded(tmp_path, [record(f"s{k}", "01_integrator_order") for k in range(len(HOSTILE))])
    export_grades(out, roster, canvas=tmp_path / "c.csv", moodle=tmp_path / "m.csv")
    canvas = list(csv.reader((tmp_path / "c.csv").open(encoding="utf-8", newline="")))[2:]
    moodle = list(csv.reader((tmp_path / "m.csv").open(encoding="utf-8", newline="")))[1:]
    for name, c_row, m_row in zip(HOSTILE, canvas, moodle):
        expected = "'" + name if name[0] in "=+-@\t" else name
        assert c_row[0] == c_row[4] == m_row[1] == expected
        assert c_row[5] == m_row[2] == "3.5"
    assert all(not cell.startswith(("=", "+", "-", "@", "\t")) for row in canvas + moodle for cell in row)


@pytest.mark.parametrize("x, text", [(1e-05, "0.00001"), (2.0, "2"), (2.5, "2.5"), (1 / 3, "0.333333"),
                                     (1e7, "10000000"), (-0.0, "0"), (0.1 + 0.2, "0.3"), (3, "3")])
def test_numbers_as_the_lms_reads_them(x, text):
    """Numbers: a dot, no exponent, no trailing zeros, at most 6 decimals."""
    assert lms_number(x) == text
    assert float(text) == pytest.approx(x, abs=5e-7)


def test_numbers_refuse_nan():
    """A grade that is not a finite number is refused, not written as nan."""
    with pytest.raises(ValueError, match="finite"):
        lms_number(float("nan"))


def test_text_cells_neutralised():
    """Only a leading formula character is neutralised; other text is unchanged."""
    assert lms_text("=1+1") == "'=1+1" and lms_text("a=b") == "a=b" and lms_text("") == ""


def test_roster_not_utf8_or_missing(tmp_path, capsys):
    """A roster in another encoding, or none, is refused with its name (exit 2 from the command)."""
    path = tmp_path / "latin1.csv"
    path.write_bytes("submission_name,name\nzoe,Zoë\n".encode("latin-1"))
    with pytest.raises(RosterError, match="is not UTF-8; expected a CSV saved as UTF-8"):
        read_roster(path)
    out = graded(tmp_path, [record("zoe", "01_integrator_order")])
    assert main(["export", str(out), "--roster", str(tmp_path / "none.csv"), "--canvas", str(tmp_path / "c")]) == 2
    assert "none.csv: cannot be read" in capsys.readouterr().err


def test_canvas_gradebook_export_is_a_roster(tmp_path):
    """Canvas's own export is a roster with --name-column: its Points Possible line and test student are skipped."""
    text = ("\ufeffStudent,ID,SIS User ID,SIS Login ID,Section,Quiz 1 (55),Current Score,Final Score\n"
            "    Points Possible,,,,,10,(read only),(read only)\n"
            "\"Lee, Ann\",101,S-1,alee,A,9,90,90\n"
            "\"Student, Test\",999,,,A,,,\n")
    roster = read_roster(roster_file(tmp_path, text), name_column="SIS Login ID")
    assert [(s.submission_name, s.name, s.canvas_id, s.sis_login_id, s.line) for s in roster.students] == [
        ("alee", "Lee, Ann", "101", "alee", 3)]
    out = graded(tmp_path, [record("ALee", "01_integrator_order")])
    export_grades(out, roster.path, canvas=tmp_path / "c.csv", name_column="SIS Login ID")
    _, _, students = canvas_import((tmp_path / "c.csv").read_text(encoding="utf-8"))
    assert students[0]["grades"] == {"01_integrator_order": 3.5} and students[0]["id"] == "101"


def test_records_of_one_student_twice_are_refused(tmp_path):
    """Two records of one exercise for one roster student (names differing in case) stop the export, naming both."""
    out = graded(tmp_path, [record("ann", "01_integrator_order"), record("Ann", "01_integrator_order")])
    roster = read_roster(roster_file(tmp_path, ROSTER))
    with pytest.raises(ExportError, match=r"records Ann/01_integrator_order and ann/01_integrator_order"):
        match(roster, read_records(out)[0])


def test_no_course_record_and_an_unreadable_old_record(tmp_path):
    """A folder without a course record, or an old records/ folder with a file that is not a record, is an error
    naming it (never a silent 'missing')."""
    with pytest.raises(ExportError, match="holds no course record"):
        read_records(tmp_path / "nothing")
    old = tmp_path / "old"
    (old / "records").mkdir(parents=True)
    (old / "records" / "bob__01_integrator_order.json").write_text('{"student": "bob"}')
    with pytest.raises(ExportError, match=r"bob__01_integrator_order.json into the course record: .*'exercise'"):
        read_records(old)


def test_canvas_refuses_an_exercise_titled_as_a_read_only_column(tmp_path):
    """An exercise whose title Canvas would read as its own read-only column is refused, not silently lost."""
    roster = read_roster(roster_file(tmp_path, ROSTER))
    export = match(roster, {"a.json": record("ann", "Final Score quiz")})
    with pytest.raises(ExportError, match="read-only"):
        canvas_rows(export)
    rows, left_out = moodle_rows(export)
    assert rows[0][2] == "Final Score quiz" and left_out == []
