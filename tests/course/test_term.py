"""One scripted term, end to end, as an instructor runs it.

Release the student bundle; twenty students hand in exercise 00 (on time, late, late with an
extension, very late, missing, one student from two places, malformed notebooks, a wrong answer, a
stub, a classmate not on the roster); autograde with the course file's deadline; write the review
pages; fill in the rubric; merge it without running a test again; regrade one student who handed in
again; export Canvas's and Moodle's files from a roster (read back by a port of Canvas's importer and by
PHP's fgetcsv, as Moodle reads them) and both LMSs' feedback zips. Every student's total is explained in
their feedback: tests + written answers - late penalty, each part shown.
"""

import csv
import json
import re
import zipfile
from pathlib import Path

import pytest

from particles.cli import main
from particles.course.grading.driver import grade
from particles.course.release.notebooks import write_bundle
from particles.course.results import lms
from particles.course.results.review import write_review
from particles.course.results.rubric import COLUMNS

from .results.helpers import CanvasUser, canvas_import, canvas_reupload, moodle_feedback_import, moodle_import

ROOT = Path(__file__).resolve().parents[2]
EXERCISE = "00_warmup"
DEADLINE = "2026-10-01T23:59:00+01:00"
COURSE = f"""
[late]
penalty_per_day = 0.10
cap = 0.30

[exercises.{EXERCISE}]
deadline = {DEADLINE}

[extensions.cal]
{EXERCISE} = 3
"""

# student -> (what they hand in, when); None: nothing handed in
TERM = {
    "ann": ("master", "2026-10-01T20:00:00+01:00"),        # on time
    "ben": ("master", "2026-10-02T09:59:00+01:00"),        # 10 hours late: one started day
    "cal": ("master", "2026-10-03T12:00:00+01:00"),        # late, but with a 3-day extension
    "dee": ("stub", "2026-10-01T08:00:00+01:00"),          # the untouched stub, on time
    "eli": ("master", "2026-10-07T08:00:00+01:00"),        # 6 days late: capped at 30%
    "fox": None,                                           # on the roster, never handed in
    "gil": ("twice", "2026-10-01T10:00:00+01:00"),         # gil.ipynb and Gil/00_warmup.ipynb
    "han": ("not_json", "2026-10-01T10:00:00+01:00"),
    "ida": ("nbformat3", "2026-10-01T10:00:00+01:00"),
    "jay": ("wrong", "2026-10-01T10:00:00+01:00"),         # Euler's slope taken at t + h
    **{name: ("master", "2026-09-30T12:00:00+01:00")
       for name in ("kim", "lou", "max", "ned", "oli", "pam", "quin", "rex", "sue", "tom")},
}
NOT_ON_ROSTER = "zed"


def _notebooks():
    master = json.loads((ROOT / "solutions" / f"{EXERCISE}.ipynb").read_text())
    wrong = json.loads(json.dumps(master))
    for cell in wrong["cells"]:
        if "def euler_step" in "".join(cell["source"]):
            cell["source"] = "def euler_step(f, X, t, h):\n    return X + h * f(X, t + h)\n"
    return master, wrong


def _hand_in(tmp_path):
    """The release, then the submissions folder and the times file an LMS export gives."""
    bundle = tmp_path / "bundle"
    write_bundle(ROOT, bundle)
    stub = (bundle / "exercises" / f"{EXERCISE}.ipynb").read_text()
    master, wrong = _notebooks()
    subs = tmp_path / "subs"
    texts = {"master": json.dumps(master), "stub": stub, "wrong": json.dumps(wrong), "not_json": '{"cells": [',
             "nbformat3": json.dumps({"nbformat": 3, "nbformat_minor": 0, "worksheets": [], "metadata": {}})}
    times = ["student,exercise,submitted"]
    for student, handed in {**TERM, NOT_ON_ROSTER: ("master", "2026-10-01T10:00:00+01:00")}.items():
        if handed is None:
            continue
        kind, when = handed
        (subs / student).mkdir(parents=True)
        (subs / student / f"{EXERCISE}.ipynb").write_text(texts.get(kind, texts["master"]))
        if kind == "twice":
            (subs / f"{student.capitalize()}.ipynb").write_text(texts["master"])
        times.append(f"{student},{EXERCISE},{when}")
    (tmp_path / "times.csv").write_text("\n".join(times) + "\n")
    (tmp_path / "course.toml").write_text(COURSE)
    return subs


def _fill(rubric):
    """The grader's rubric: full points for an answer, 0 and "no answer" for a blank one."""
    with open(rubric, newline="") as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        row["points"] = row["points"] or (row["max_points"] if row["student"] != "dee" else "0")
        row["comment"] = row["comment"] or ("Clear and right." if row["student"] != "dee" else "")
    with open(rubric, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    return rows


def _explained(feedback):
    """(total, tests, written, penalty) read from a student's feedback.md."""
    total = float(re.search(r"\*\*Total: ([\d.]+) / ([\d.]+) points\*\*", feedback).group(1))
    parts = re.search(r"Tests ([\d.]+) / [\d.]+; written answers, graded by people, ([\d.]+) / [\d.]+", feedback)
    penalty = re.search(r"penalty -([\d.]+) of [\d.]+ points \(submitted", feedback)
    return total, float(parts.group(1)), float(parts.group(2)), float(penalty.group(1)) if penalty else 0.0


@pytest.mark.slow
def test_a_whole_term(tmp_path):
    """Release, twenty students, autograde with deadlines, review, rubric, one regrade, Canvas and Moodle."""
    subs = _hand_in(tmp_path)
    out, review = tmp_path / "out", tmp_path / "review"
    options = dict(root=ROOT, exercise=EXERCISE, course=tmp_path / "course.toml", times=tmp_path / "times.csv",
                   seed=7, jobs=2)

    # autograde: every handed-in student has a record; the malformed and the doubled score 0 with a reason
    first = grade([subs], out, **options)
    graded = set(first["students"])
    spelled = {name.casefold(): name for name in graded}  # one student from two places keeps one spelling
    assert set(spelled) == {*TERM, NOT_ON_ROSTER} - {"fox"}
    assert sorted(first["rejected"]) and len(first["rejected"]) == 3
    records = {s.casefold(): rs[0] for s, rs in first["students"].items()}
    assert records["ann"].score == records["ann"].max_score > 0 and records["dee"].score == 0
    assert 0 < records["jay"].score < records["jay"].max_score
    for student in ("gil", "han", "ida"):
        assert records[student].score == 0 and records[student].notes[0].startswith("Not graded: ")
    assert "Gil.ipynb" in records["gil"].notes[0] and "gil/00_warmup.ipynb" in records["gil"].notes[0]
    late = {s: r.late for s, r in records.items()}
    assert late["han"]["days_late"] == 0  # a malformed notebook is 0 for its content, not for lateness
    assert late["ann"]["days_late"] == 0 and late["cal"]["days_late"] == 0 and "extension" in late["cal"]["reason"]
    assert late["ben"]["days_late"] == 1 and late["eli"]["fraction"] == 0.3 and "capped" in late["eli"]["reason"]

    # review pages and the rubric; the rubric filled in and merged: no test runs again
    pages = write_review([subs], review, root=ROOT, exercise=EXERCISE)
    assert pages["pages"] and all(p.read_text().count("</html>") == 1 for p in pages["pages"])
    rubric = review / EXERCISE / "rubric.csv"
    rows = _fill(rubric)
    assert {r["student"] for r in rows} >= graded - {spelled["gil"], "han", "ida"}
    merged = grade([subs], out, rubric=[rubric], resume=True, **options)
    assert merged["resumed"] == len(graded) - 3  # the rejected ones are checked again, never kept
    ann = merged["students"]["ann"][0]
    assert ann.written_score == ann.written_max > 0 and ann.total == ann.total_max

    # dee hands in her finished notebook (the instructor allows it): only she is graded again
    (subs / "dee" / f"{EXERCISE}.ipynb").write_text(json.dumps(_notebooks()[0]))
    kept = {p.name: p.read_bytes() for p in (out / "records").glob("*.json") if not p.name.startswith("dee__")}
    again = grade([subs], out, rubric=[rubric], students=["dee"], **options)
    assert list(again["students"]) == ["dee"] and again["students"]["dee"][0].score > 0
    assert {p.name: p.read_bytes() for p in (out / "records").glob("*.json") if not p.name.startswith("dee__")} \
        == kept

    # every student's total is explained: tests + written - penalty, and the gradebook agrees
    with open(out / "gradebook.csv", newline="") as handle:
        book = {row["student"]: row for row in csv.DictReader(handle)}
    assert set(book) == graded
    for student in graded:
        feedback = (out / student / "feedback.md").read_text()
        total, tests, written, penalty = _explained(feedback)
        assert total == pytest.approx(max(0.0, tests + written - penalty)), student
        assert float(book[student][EXERCISE]) == pytest.approx(total), student
        if student in ("ben", "eli"):
            assert penalty > 0 and "Late: raw score" in feedback
    penalty = _explained((out / "eli" / "feedback.md").read_text())[3]
    assert penalty == pytest.approx(0.3 * merged["students"]["eli"][0].total_max)  # 30% of tests and written

    # the LMS: a roster of the twenty; fox is missing, zed is reported, never dropped; pam's id number is 0 (empty
    # to PHP) and oli's name holds \" (PHP's escape)
    names = {student: f"{student.capitalize()} Student" for student in TERM}
    names["oli"] = 'Oli \\", jr'
    ids = {student: "0" if student == "pam" else f"{2000 + k}" for k, student in enumerate(TERM)}
    roster = tmp_path / "roster.csv"
    with open(roster, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["submission_name", "name", "canvas_id", "sis_user_id", "sis_login_id", "section", "email",
                         "idnumber"])
        for k, student in enumerate(TERM):
            writer.writerow([student, names[student], 1000 + k, f"S{k:03d}", student, "A", f"{student}@example.edu",
                             ids[student]])
    downloads = _lms_downloads(tmp_path, subs, names)
    code = main(["export", str(out), "--roster", str(roster), "--canvas", str(tmp_path / "canvas.csv"),
                 "--moodle", str(tmp_path / "moodle.csv"), "--moodle-id", "idnumber",
                 "--canvas-feedback", str(tmp_path / "canvas-feedback.zip"),
                 "--moodle-feedback", str(tmp_path / "moodle-feedback.zip"), *downloads])
    assert code == 1  # zed is not on the roster, pam cannot be in the Moodle file
    report = list(csv.DictReader((out / "lms-report.csv").open(encoding="utf-8")))
    assert {(r["problem"], r["student"]) for r in report} == {("not on roster", NOT_ON_ROSTER), ("missing", "fox"),
                                                              ("left out", "pam")}

    # Canvas's importer (ported) matches every row with its student, each with the gradebook's total
    users = [CanvasUser(1000 + k, names[s], "", f"S{k:03d}", s) for k, s in enumerate(TERM)]
    canvas = canvas_import((tmp_path / "canvas.csv").read_text(encoding="utf-8"), users)
    assert canvas.assignments == [EXERCISE] and [user.id for user, _ in canvas.rows] == [u.id for u in users]
    for (user, grades), student in zip(canvas.rows, TERM):
        expected = float(book[spelled[student]][EXERCISE]) if student != "fox" else 0.0
        assert float(grades[EXERCISE]) == pytest.approx(expected), student

    # Moodle's reading (PHP's fgetcsv): one row per student, each with its own id number; pam left out
    moodle = moodle_import(tmp_path / "moodle.csv")
    assert moodle["error"] is None
    assert moodle["header"] == [lms.MOODLE_IDENTIFIERS["idnumber"], lms.MOODLE_NAME, EXERCISE,
                                f"{EXERCISE} feedback", lms.MOODLE_TOTAL]
    assert moodle["users"] == [row[0] for row in moodle["rows"]] == [ids[s] for s in TERM if s != "pam"]
    rows = {row[0]: row for row in moodle["rows"]}
    assert rows[ids["oli"]][1] == names["oli"] and rows[ids["fox"]][3] == lms.MOODLE_MISSING
    assert float(rows[ids["ben"]][2]) == pytest.approx(float(book["ben"][EXERCISE]))

    # the feedback back: every graded student on the roster gets a file Canvas and Moodle attach to them
    graded_roster = [s for s in TERM if s != "fox"]
    with zipfile.ZipFile(tmp_path / "canvas-feedback.zip") as archive:
        read = canvas_reupload(archive.namelist())
        assert sorted(read.values()) == sorted((str(1000 + k), str(5000 + k)) for k, s in enumerate(TERM)
                                               if s != "fox")
        texts = [archive.read(name).decode() for name in archive.namelist()]
    with zipfile.ZipFile(tmp_path / "moodle-feedback.zip") as archive:
        read = moodle_feedback_import(archive.namelist(), {3000 + k for k in range(len(TERM))})
        assert sorted(read) == [3000 + k for k, s in enumerate(TERM) if s != "fox"]
        texts += [archive.read(name).decode() for name in archive.namelist()]
    assert len(texts) == 2 * len(graded_roster)
    advice = re.compile(r"grade again|manual question|instructors,| --[a-z]")  # what is said to instructors
    assert not [t for t in texts if str(tmp_path) in t or advice.search(t)]


def _lms_downloads(tmp_path, subs, names):
    """The LMSs' submissions downloads of the term's notebooks: Canvas's zip, Moodle's folder (as --download)."""
    canvas, moodle = tmp_path / "canvas-submissions.zip", tmp_path / "moodle-submissions"
    with zipfile.ZipFile(canvas, "w") as archive:
        for k, student in enumerate(TERM):
            for notebook in sorted((subs / student).glob("*.ipynb")) if (subs / student).is_dir() else []:
                archive.writestr(f"{student}_{1000 + k}_{5000 + k}_{notebook.name}", notebook.read_bytes())
                folder = moodle / f"{names[student]}_{3000 + k}_assignsubmission_file_"
                folder.mkdir(parents=True)
                (folder / notebook.name).write_bytes(notebook.read_bytes())
    return ["--download", str(canvas), "--download", str(moodle)]
