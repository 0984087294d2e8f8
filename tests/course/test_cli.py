"""`particles grade` and `particles.check` from the command line and from Python."""

import csv
import json
import shutil
from pathlib import Path

import pytest

import particles
from particles.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_grade_a_folder_of_students(tmp_path, capsys):
    """grade --jobs 2 writes a gradebook row per student folder and prints a summary table."""
    for student, source in (("ada", "solutions"), ("bob", "exercises")):
        (tmp_path / "subs" / student).mkdir(parents=True)
        shutil.copy(ROOT / source / "00_warmup.ipynb", tmp_path / "subs" / student / "00_warmup.ipynb")
    code = main(["grade", str(tmp_path / "subs"), "--out", str(tmp_path / "out"), "--jobs", "2",
                 "--seed", "3", "--root", str(ROOT)])
    assert code == 0
    out = capsys.readouterr().out
    assert "ada" in out and "11/11" in out and "0/11" in out
    rows = {r["student"]: r for r in csv.DictReader(open(tmp_path / "out" / "gradebook.csv"))}
    assert rows["ada"]["00_warmup"] == "11" and rows["bob"]["total"] == "0" and rows["bob"]["max_total"] == "11"
    assert list((tmp_path / "out" / "logs").glob("batch*-00_warmup.log"))


def test_grade_public_only(tmp_path, capsys):
    """--public runs the 5 public points only (what a student runs)."""
    assert main(["grade", str(ROOT / "solutions" / "00_warmup.ipynb"), "--public", "--root", str(ROOT)]) == 0
    assert "5/5" in capsys.readouterr().out


def test_grade_reports_bad_arguments(tmp_path, capsys):
    """An unknown exercise is a usage error (status 2); a notebook of unknown exercise is listed, not graded."""
    assert main(["grade", str(tmp_path), "--exercise", "99_none", "--root", str(ROOT)]) == 2
    assert "unknown exercise '99_none'" in capsys.readouterr().err
    (tmp_path / "mystery.ipynb").write_text("{}")
    assert main(["grade", str(tmp_path), "--root", str(ROOT)]) == 1
    assert "cannot tell which exercise" in capsys.readouterr().err


def test_check_a_saved_notebook():
    """particles.check on a saved notebook reports public tests with readable reasons."""
    good = particles.check("00_warmup", notebook=ROOT / "solutions" / "00_warmup.ipynb", root=ROOT)
    assert good.passed and good.score == good.max_score == 5
    stub = particles.check("00_warmup", notebook=ROOT / "exercises" / "00_warmup.ipynb", root=ROOT)
    assert not stub.passed and stub.score == 0
    text = str(stub)
    assert "FAIL  euler_step takes one step" in text and "not implemented yet" in text
    assert "| ❌ |" in stub._repr_markdown_()


def test_check_in_a_terminal_exits_with_what_it_found(tmp_path, monkeypatch, capsys):
    """`particles check NN_topic [PATH]`: the report printed; status 0 when every public test passes, 1 when
    one fails (the saved NN_topic.ipynb of the current folder by default), 2 when nothing was checked."""
    monkeypatch.setenv("PARTICLES_COURSE_ROOT", str(ROOT))
    assert main(["check", "00_warmup", str(ROOT / "solutions" / "00_warmup.ipynb")]) == 0
    assert "00_warmup: 5 / 5 points on the public tests" in capsys.readouterr().out
    shutil.copy(ROOT / "exercises" / "00_warmup.ipynb", tmp_path / "00_warmup.ipynb")
    monkeypatch.chdir(tmp_path)
    assert main(["check", "00_warmup"]) == 1
    out = capsys.readouterr().out
    assert "0 / 5 points" in out and "(checked the saved notebook 00_warmup.ipynb)" in out
    assert "is not implemented yet" in out
    assert main(["check", "99_none"]) == 2
    assert "unknown exercise '99_none'; expected one of 00_warmup" in capsys.readouterr().err
    assert main(["check", "00_warmup", "missing.ipynb"]) == 2
    assert "no notebook missing.ipynb" in capsys.readouterr().err


def test_check_outside_a_notebook_needs_a_path():
    """Without a kernel and without notebook=, check says what to pass."""
    with pytest.raises(ValueError, match="notebook="):
        particles.check("00_warmup", root=ROOT)
    with pytest.raises(ValueError, match="unknown exercise"):
        particles.check("99_none", root=ROOT)


def test_one_notebook_per_student_and_exercise(tmp_path, capsys):
    """Two notebooks of one exercise from one student: the exactly named one is graded, the other reported."""
    folder = tmp_path / "subs" / "cy"
    folder.mkdir(parents=True)
    shutil.copy(ROOT / "solutions" / "00_warmup.ipynb", folder / "00_warmup.ipynb")
    shutil.copy(ROOT / "exercises" / "00_warmup.ipynb", folder / "old_00_warmup.ipynb")
    assert main(["grade", str(tmp_path / "subs"), "--public", "--root", str(ROOT)]) == 0
    captured = capsys.readouterr()
    assert "5/5" in captured.out and "several notebooks for 00_warmup" in captured.err


@pytest.mark.parametrize("option, value, name", [("--time-limit", "-1", "time_limit"), ("--time-limit", "nan", "time_limit"),
                                                 ("--memory-mb", "0", "memory_mb")])
def test_grade_rejects_bad_limits(tmp_path, capsys, option, value, name):
    """A time limit or memory limit that is not a finite number > 0 is a usage error (status 2) naming it."""
    notebook = str(ROOT / "solutions" / "00_warmup.ipynb")
    assert main(["grade", notebook, "--out", str(tmp_path / "out"), option, value, "--root", str(ROOT)]) == 2
    err = capsys.readouterr().err
    assert f"particles grade: {name} must be a finite number > 0" in err
    assert not (tmp_path / "out").exists()


def _fill(rubric, grades):
    """Fill `grades` ({student: (points, comment)}) into a rubric written by `particles review`."""
    rows = list(csv.DictReader(open(rubric, newline="")))
    for row in rows:
        if row["student"] in grades:
            row["points"], row["comment"] = grades[row["student"]]
    with open(rubric, "w", newline="") as handle:
        writer = csv.DictWriter(handle, list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def test_review_then_grade_with_the_rubric_then_change_it(tmp_path, capsys):
    """review writes the rubric; a bad rubric stops grade (status 2) before grading; a filled one is merged
    into feedback, results.json and the gradebook; a changed one regrades with --resume, running no test."""
    subs, review, out = tmp_path / "subs", tmp_path / "review", tmp_path / "out"
    for student, source in (("ada", "solutions"), ("bob", "exercises")):
        (subs / student).mkdir(parents=True)
        shutil.copy(ROOT / source / "00_warmup.ipynb", subs / student / "00_warmup.ipynb")
    assert main(["review", str(subs), "--out", str(review), "--root", str(ROOT)]) == 0
    rubric = review / "00_warmup" / "rubric.csv"
    bad = tmp_path / "bad.csv"
    bad.write_text(rubric.read_text().replace(",bob,", ",eve,"))
    grade = ["grade", str(subs), "--out", str(out), "--public", "--seed", "3", "--root", str(ROOT)]
    capsys.readouterr()
    assert main(grade + ["--rubric", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}, line 3: unknown student 'eve'" in err and "nothing was graded" in err
    assert not (out / "gradebook.csv").exists() and not list(out.glob("*/feedback.md"))
    _fill(rubric, {"ada": ("1.5", "Right; say why the error halves")})
    assert main(grade + ["--rubric", str(review)]) == 0
    rows = {r["student"]: r for r in csv.DictReader(open(out / "gradebook.csv"))}
    assert (rows["ada"]["00_warmup"], rows["ada"]["max_total"]) == ("6.5", "7")  # 5 public points + 1.5 of 2
    assert (rows["bob"]["00_warmup"], rows["bob"]["max_total"]) == ("0", "7")
    assert "| Question 1 | 1.5 / 2 | Right; say why the error halves |" in (out / "ada" / "feedback.md").read_text()
    assert "| Question 1 | 0 / 2 | no answer |" in (out / "bob" / "feedback.md").read_text()
    (written,) = [t for t in json.loads((out / "ada" / "results.json").read_text())["tests"]
                  if t["extra_data"].get("written")]
    assert written["score"] == 1.5 and written["max_score"] == 2 and "sha256:" in written["extra_data"]["rubric"]
    bob_before = (out / "bob" / "feedback.html").read_bytes()
    _fill(rubric, {"ada": ("2", "Right")})
    assert main(grade + ["--rubric", str(rubric), "--resume"]) == 0
    assert "resumed: 2 record(s)" in capsys.readouterr().out
    assert next(r for r in csv.DictReader(open(out / "gradebook.csv")) if r["student"] == "ada")["00_warmup"] == "7"
    (again,) = [t for t in json.loads((out / "ada" / "results.json").read_text())["tests"]
                if t["extra_data"].get("written")]
    assert again["score"] == 2 and again["extra_data"]["rubric"] != written["extra_data"]["rubric"]
    # bob's grade is the same, graded by the rubric's new version (its file's digest)
    bob = json.loads((out / "bob" / "results.json").read_text())
    assert bob["score"] == 0 and bob["extra_data"]["written"]["00_warmup"][0]["rubric"] == again["extra_data"]["rubric"]
    assert b"0 / 2" in bob_before and "0 / 2" in (out / "bob" / "feedback.html").read_text()


def test_grade_says_which_written_answers_the_rubric_leaves_ungraded(tmp_path, capsys):
    """Rubric rows without points are said by the command (they count 0 until graded)."""
    subs = tmp_path / "subs"
    (subs / "ada").mkdir(parents=True)
    (subs / "ada" / "00_warmup.ipynb").write_text((ROOT / "solutions" / "00_warmup.ipynb").read_text())
    assert main(["review", str(subs), "--out", str(tmp_path / "review"), "--root", str(ROOT)]) == 0
    code = main(["grade", str(subs), "--out", str(tmp_path / "out"), "--root", str(ROOT), "--public",
                 "--rubric", str(tmp_path / "review")])
    err = capsys.readouterr().err
    assert code == 0 and "rubric: 1 written answer(s) not graded yet, counted 0 until they are: ada 00_warmup " \
                         "question 1" in err


def test_the_record_verb_shows_runs_and_history_and_retires_a_result_saying_who_and_why(tmp_path, capsys):
    """`particles record OUT` lists the runs and what is not graded yet; --history a student's results; --retire
    makes the current one history, refusing without a reason."""
    from particles.course.results.records import SubmissionRecord, TestRecord
    from particles.course.term.database import TermRecord

    term = TermRecord(tmp_path)
    run = term.start_run("particles grade subs/ --out grades", {})
    term.save(run, SubmissionRecord(student="ann", exercise="00_warmup", complete=True, grader_status=0,
                                    tests=[TestRecord("t", "t", 3.0, passed=True)]), {})
    term.finish_run(run)
    term.close()
    assert main(["record", str(tmp_path)]) == 0
    assert "run 1: complete" in capsys.readouterr().out
    assert main(["record", str(tmp_path), "--retire", "ann", "00_warmup"]) == 2
    assert "--retire needs --why" in capsys.readouterr().err
    assert main(["record", str(tmp_path), "--retire", "ann", "00_warmup", "--why", "copied", "--who", "prof"]) == 0
    assert main(["record", str(tmp_path), "--history", "ann"]) == 0
    assert "history: retired by prof: copied" in capsys.readouterr().out
    assert main(["record", str(tmp_path / "nothing")]) == 2
