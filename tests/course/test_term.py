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


def _current(out):
    """(student, exercise) -> current record, from the course record of `out`."""
    from particles.course.term.database import TermRecord

    with TermRecord(out) as term:
        return term.current()


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
    kept = {k: r.to_dict() for k, r in _current(out).items() if k[0] != "dee"}
    again = grade([subs], out, rubric=[rubric], students=["dee"], **options)
    assert list(again["students"]) == ["dee"] and again["students"]["dee"][0].score > 0
    assert {k: r.to_dict() for k, r in _current(out).items() if k[0] != "dee"} == kept

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


# -- a term of two exercises from two LMSs, into one course record ---------------------------------------------

SECOND = "01_integrator_order"
TERM_COURSE = f"""
roster = "roster.csv"

[late]
penalty_per_day = 0.10
cap = 0.30

[exercises.{EXERCISE}]
deadline = {DEADLINE}

[exercises.{SECOND}]
deadline = 2026-10-15T23:59:00+01:00

[extensions.{{judy}}]
{EXERCISE} = 2
"""
ROSTER_LINES = [  # submission_name, name, canvas_id, sis_login_id, email, aliases
    ("john1", "John Smith", "2000", "smithjohn", "john.smith@uni.edu", ""),
    ("john2", "John Smith", "2001", "smithjohn2", "john.smith2@uni.edu", ""),
    ("alice", "Alice Smith", "2003", "alicesmith", "alice@uni.edu", "asmith; Alice S."),
    ("judy", "Judy Kim", "2002", "judyk", "judy@uni.edu", ""),
    ("bob", "Bob Lee", "2004", "boblee", "bob@uni.edu", ""),
    ("grace", "Grace Ho", "2005", "graceho", "grace@uni.edu", ""),
    ("henry", "Henry Wu", "2006", "henrywu", "henry@uni.edu", ""),
]
CANVAS_FILES = {  # Canvas's download of exercise 00: name -> what it holds
    "smithjohn_2000_5001_00_warmup.ipynb": "master",        # two students called John Smith, two user ids
    "smithjohn_2001_5002_00_warmup.ipynb": "wrong",
    "alicesmith_LATE_2003_5003_00_warmup.ipynb": "master",  # Canvas says late; the times file says on time
    "judyk_2002_5004_00_warmup.ipynb": "stub",              # judy's first upload ...
    "judyk_2002_5009_00_warmup-1.ipynb": "master",          # ... and her re-upload: graded
    "boblee_2004_5005_00_warmup.ipynb": "master",           # bob hands in here and in a folder: a conflict
}
TERM_TIMES = {"john1": "2026-10-01T20:00:00+01:00", "john2": "2026-10-02T09:00:00+01:00",  # john2: 1 day late
              "asmith": "2026-10-01T21:00:00+01:00", "judyk": "2026-10-03T09:00:00+01:00",  # judy: extension
              "bob": "2026-10-01T22:00:00+01:00"}


def _term_files(tmp_path):
    """The roster, the course file, Canvas's zip of exercise 00 (and bob's second copy), Gradescope's export of 01."""
    lines = ["submission_name,name,canvas_id,sis_login_id,email,aliases"]
    lines += [",".join(f'"{cell}"' for cell in line) for line in ROSTER_LINES]
    (tmp_path / "roster.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / "course.toml").write_text(TERM_COURSE.replace("{judy}", "judyk"))
    master, wrong = _notebooks()
    stub = (ROOT / "exercises" / f"{EXERCISE}.ipynb").read_text()
    texts = {"master": json.dumps(master), "wrong": json.dumps(wrong), "stub": stub}
    canvas = tmp_path / "canvas-00.zip"
    with zipfile.ZipFile(canvas, "w") as archive:
        for name, kind in CANVAS_FILES.items():
            archive.writestr(name, texts[kind])
    (tmp_path / "folder" / "bob").mkdir(parents=True)
    (tmp_path / "folder" / "bob" / f"{EXERCISE}.ipynb").write_text(texts["master"])
    times = ["student,exercise,submitted"] + [f"{s},{EXERCISE},{t}" for s, t in TERM_TIMES.items()]
    (tmp_path / "times.csv").write_text("\n".join(times) + "\n")
    second = (ROOT / "solutions" / f"{SECOND}.ipynb").read_text()
    metadata = ("submission_301:\n  :submitters:\n  - :name: Alice Smith\n    :sid: '9'\n    :email: alice@uni.edu\n"
                "  :created_at: 2026-10-17 10:00:00.123456000 +01:00\n"
                "submission_302:\n  :submitters:\n  - :name: Grace Ho\n    :email: grace@uni.edu\n"
                "  - :name: Henry Wu\n    :email: Henry@Uni.edu\n  :created_at: 2026-10-15 20:00:00 +01:00\n")
    gradescope = tmp_path / "gradescope-01.zip"
    with zipfile.ZipFile(gradescope, "w") as archive:
        archive.writestr("assignment_77_export/submission_metadata.yml", metadata)
        archive.writestr(f"assignment_77_export/submission_301/{SECOND}.ipynb", second)
        archive.writestr(f"assignment_77_export/submission_302/{SECOND}.ipynb", second)
    return canvas, gradescope


def _cli(*args):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "particles", "grade", *map(str, args), "--root", str(ROOT)],
                          capture_output=True, text=True, timeout=900)


def _interrupted(submissions, common, out):
    """Start `particles grade`, send SIGINT to its process group (as Ctrl-C at a terminal does) once its session
    runs; (the finished process, seconds from the signal to its end)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from particles.course.term.database import TermRecord

    command = [sys.executable, "-m", "particles", "grade", str(submissions), *map(str, common), "--root", str(ROOT)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:  # the run has registered its notebooks: its session starts now
        term = TermRecord(out)
        running = term.db.execute("SELECT count(*) FROM runs WHERE status = 'running'").fetchone()[0]
        term.close()
        if running:
            break
        time.sleep(0.1)
    time.sleep(1.5)
    os.killpg(process.pid, signal.SIGINT)
    start = time.monotonic()
    stdout, stderr = process.communicate(timeout=60)
    return subprocess.CompletedProcess(command, process.returncode, stdout, stderr), time.monotonic() - start


def _book(out):
    with open(out / "gradebook.csv", newline="") as handle:
        return {row["student"]: row for row in csv.DictReader(handle)}


def _totals_explained(out, book):
    """Every student's gradebook total is the sum of what their feedback explains, exercise by exercise."""
    for student, row in book.items():
        feedback = (out / student / "feedback.md").read_text()
        overall = float(re.search(r"\*\*Total: ([\d.]+) / [\d.]+ points\*\*", feedback).group(1))
        assert float(row["total"]) == pytest.approx(overall), student


@pytest.mark.slow
def test_a_term_from_two_lms_into_one_course_record(tmp_path):
    """Two exercises graded in separate runs into one record: Canvas (same-name students apart, the re-upload
    graded, LATE_ checked), a conflict resolved for good, Gradescope (its times, a group graded per member), one
    student under two LMS names in one row; typos refused; a regrade keeping written points and the late decision;
    Ctrl-C, then --resume. Every total explained."""
    canvas, gradescope = _term_files(tmp_path)
    out, course = tmp_path / "out", tmp_path / "course.toml"
    common = ["--course", course, "--seed", 7, "--jobs", 2, "--out", out]

    # typos in the course file and in the times file: exit 2, naming them, nothing graded
    course.write_text(TERM_COURSE.replace("{judy}", "judykm"))
    done = _cli(canvas, *common, "--times", tmp_path / "times.csv")
    assert done.returncode == 2 and "[extensions.judykm]: 'judykm' is no student of the roster's 7 students" in \
        done.stderr and "nothing was graded" in done.stderr
    course.write_text(TERM_COURSE.replace("{judy}", "judyk"))
    bad = tmp_path / "bad-times.csv"
    bad.write_text((tmp_path / "times.csv").read_text().replace("asmith,", "asmyth,"))
    done = _cli(canvas, *common, "--times", bad)
    assert done.returncode == 2 and "line 4: student 'asmyth'" in done.stderr
    # no time at all for a deadline: exit 2, naming the students; nothing graded, nothing late
    done = _cli(canvas, *common)
    assert done.returncode == 2 and "no submission time for" in done.stderr and "john1 (00_warmup)" in done.stderr
    assert not (out / "gradebook.csv").exists() and not list(out.glob("*/feedback.md"))

    # exercise 00 from Canvas, with bob's second copy in a folder: a conflict
    done = _cli(canvas, tmp_path / "folder", *common, "--times", tmp_path / "times.csv")
    assert done.returncode == 1, done.stderr  # the conflict was scored 0 without being run
    assert "graded the latest upload" in done.stderr and "judyk_2002_5009_00_warmup-1.ipynb" in done.stderr
    assert "Canvas marked it late (LATE_)" in done.stderr
    book = _book(out)
    assert float(book["john1"][EXERCISE]) > float(book["john2"][EXERCISE]) > 0  # two John Smiths, two rows
    assert float(book["judy"][EXERCISE]) == float(book["john1"][EXERCISE])  # the re-upload, on time (extension)
    assert float(book["bob"][EXERCISE]) == 0 and "john2" in book
    # the conflict resolved: bob's folder copy removed, bob regraded; no second row, ever
    (tmp_path / "folder" / "bob" / f"{EXERCISE}.ipynb").unlink()
    done = _cli(canvas, *common, "--times", tmp_path / "times.csv", "--student", "bob")
    assert done.returncode == 0, done.stderr
    assert float(_book(out)["bob"][EXERCISE]) == float(book["john1"][EXERCISE])

    # written answers graded for john1; john2's late decision made
    rubric = tmp_path / "rubric.csv"
    rubric.write_text(f"{','.join(COLUMNS)}\n{EXERCISE},smithjohn,1,2,1.5,Good\n")
    done = _cli(canvas, *common, "--times", tmp_path / "times.csv", "--rubric", rubric, "--resume")
    assert done.returncode == 0, done.stderr
    before = _book(out)
    assert float(before["john1"][EXERCISE]) == float(book["john1"][EXERCISE]) + 1.5

    # exercise 01 from Gradescope, stopped with Ctrl-C while its session runs: one line, within 2 s, then --resume
    stopped, seconds = _interrupted(gradescope, common, out)
    assert stopped.returncode == 130 and "Traceback" not in stopped.stderr, stopped.stderr
    assert stopped.stderr.strip().splitlines()[-1].startswith("particles grade: interrupted: ")
    assert stopped.stderr.strip().endswith("graded; rerun with --resume") and seconds < 3, (seconds, stopped.stderr)
    assert "not graded yet" in (out / "gradebook.csv").read_text()
    done = _cli(gradescope, *common, "--resume")
    assert done.returncode == 0, done.stderr
    # alice (Canvas's alicesmith) in the same row, late from created_at; the group graded per member
    book = _book(out)
    assert set(book) == {"john1", "john2", "alice", "judy", "bob", "grace", "henry"}
    assert book["alice"][EXERCISE] and book["alice"][SECOND] and book["grace"][SECOND] == book["henry"][SECOND]
    alice = json.loads((out / "alice" / "results.json").read_text())
    assert alice["extra_data"]["late"][SECOND]["days_late"] == 2
    assert "Gradescope's submission_metadata.yml" in alice["extra_data"]["late"][SECOND]["source"]
    assert float(book["alice"][SECOND]) < float(book["grace"][SECOND])

    # john1 regraded alone, without the rubric or the times file: written points and late decisions kept
    done = _cli(canvas, *common, "--student", "john1")
    assert done.returncode == 0, done.stderr
    after = _book(out)
    assert after["john1"][EXERCISE] == before["john1"][EXERCISE] and after["john2"] == book["john2"]
    assert "Question 1 | 1.5 / 2 | Good" in (out / "john1" / "feedback.md").read_text()
    _totals_explained(out, after)
