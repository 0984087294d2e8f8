"""One scripted term, end to end, as an instructor runs it.

Release the student bundle; twenty students hand in exercise 00 (on time, late, late with an
extension, very late, missing, one student from two places, malformed notebooks, a wrong answer, a
stub, a classmate not on the roster); autograde with the course file's deadline; write the review
pages; fill in the rubric; merge it without running a test again; regrade one student who handed in
again; export Canvas's and Moodle's files from a roster. Every student's total is explained in their
feedback: tests + written answers - late penalty, each part shown.
"""

import csv
import json
import re
from pathlib import Path

import pytest

from particles.course.grading.driver import grade
from particles.course.release.notebooks import write_bundle
from particles.course.results import lms
from particles.course.results.review import write_review
from particles.course.results.rubric import COLUMNS

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

    # the LMS: a roster of the twenty; fox is missing, zed is reported, never dropped
    roster = tmp_path / "roster.csv"
    with open(roster, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["submission_name", "name", "canvas_id", "sis_user_id", "sis_login_id", "section", "email"])
        for k, student in enumerate(TERM):
            writer.writerow([student, f"{student.capitalize()} Student", 1000 + k, f"S{k:03d}", student, "A",
                             f"{student}@example.edu"])
    done = lms.export_grades(out, roster, canvas=tmp_path / "canvas.csv", moodle=tmp_path / "moodle.csv")
    assert [record.student for _, record in done["export"].unmatched] == [NOT_ON_ROSTER]
    with open(tmp_path / "canvas.csv", newline="", encoding="utf-8") as handle:
        canvas = list(csv.reader(handle))
    assert canvas[0] == [*lms.CANVAS_STUDENT_COLUMNS, EXERCISE, lms.CANVAS_TOTAL]
    assert canvas[1][0] == lms.CANVAS_POINTS_ROW and len(canvas) == 2 + len(TERM)
    rows = {row[3]: row for row in canvas[2:]}
    assert float(rows["fox"][5]) == 0 and float(rows["ann"][5]) == pytest.approx(float(book["ann"][EXERCISE]))
    assert float(rows["ben"][5]) < float(rows["ann"][5])
    with open(tmp_path / "moodle.csv", newline="", encoding="utf-8") as handle:
        moodle = list(csv.DictReader(handle))
    assert list(moodle[0]) == [lms.MOODLE_IDENTIFIERS["email"], lms.MOODLE_NAME, EXERCISE, f"{EXERCISE} feedback",
                               lms.MOODLE_TOTAL]
    fox = next(row for row in moodle if row["Email address"] == "fox@example.edu")
    assert float(fox[EXERCISE]) == 0 and fox[f"{EXERCISE} feedback"] == lms.MOODLE_MISSING
    assert len(moodle) == len(TERM)
