"""Which notebooks are graded, as whom: conflicts named, links not followed out, LMS layouts, bad files kept."""

import json
import os
import time
import zipfile
from pathlib import Path

import pytest

from particles.course.grading.discovery import find_submissions
from particles.course.grading.intake import Limits

EXERCISES = ["00_warmup", "01_integrator_order"]


def notebook(exercise=None):
    """A small valid notebook's text, with the exercise in its metadata when given."""
    meta = {"particles": {"exercise": exercise}} if exercise else {}
    return json.dumps({"nbformat": 4, "nbformat_minor": 5, "metadata": meta,
                       "cells": [{"cell_type": "code", "id": "a", "source": "x = 1", "metadata": {},
                                  "outputs": [], "execution_count": None}]})


def put(path, text=None):
    """Write a notebook at `path` (folders made); returns the path."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(notebook() if text is None else text)
    return path


def found(paths, exercise="00_warmup", **options):
    """{student: unit} and the problems of find_submissions."""
    units, problems = find_submissions(paths, EXERCISES, exercise, **options)
    assert len({u.student for u in units}) == len(units) or exercise is None
    return {u.student: u for u in units}, problems


# -- duplicates ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("first, second", [("alice.ipynb", "Alice/00_warmup.ipynb"),
                                           ("Alice/00_warmup.ipynb", "alice/00_warmup.ipynb"),
                                           ("ALICE.ipynb", "alice.IPYNB"),
                                           ("alice/00_warmup.ipynb", "alice_12_34_00_warmup.ipynb")])
def test_two_places_mapping_to_one_student_are_a_conflict_naming_both(tmp_path, first, second):
    """A file and a folder, or two folders or files differing by case, of one student: neither is graded, the
    student gets one rejected unit naming both, and the problem is reported."""
    a, b = put(tmp_path / first), put(tmp_path / second)
    units, problems = found([tmp_path])
    assert len(units) == 1
    unit = next(iter(units.values()))
    assert unit.student.casefold() == "alice" and unit.exercise == "00_warmup"
    assert first in unit.rejected and second in unit.rejected and "none was graded" in unit.rejected
    assert str(tmp_path) not in unit.rejected  # the student reads it: the names they handed in, not our folders
    assert any(str(a) in p and str(b) in p for p in problems)


def test_two_folders_given_with_one_student_are_a_conflict(tmp_path):
    """The same student in two folders given on the command line is a conflict, not an overwrite."""
    a, b = put(tmp_path / "one" / "bob" / "00_warmup.ipynb"), put(tmp_path / "two" / "Bob" / "x_00_warmup.ipynb")
    units, _ = found([tmp_path / "one", tmp_path / "two"])
    assert list(units) == ["Bob"] and units["Bob"].origin == f"{a} and {b}"
    assert "(bob/00_warmup.ipynb and Bob/x_00_warmup.ipynb)" in units["Bob"].rejected


def test_one_students_own_folder_keeps_the_exact_name_else_the_newest(tmp_path):
    """Several notebooks in one student's folder: the exact name wins, else the newest; the others are
    reported, and this is not a conflict."""
    exact = put(tmp_path / "carol" / "00_warmup.ipynb")
    newer = put(tmp_path / "carol" / "00_warmup-Copy1.ipynb")
    old = put(tmp_path / "dave" / "try_00_warmup.ipynb")
    new = put(tmp_path / "dave" / "final_00_warmup.ipynb")
    os.utime(old, (time.time() + 100, time.time() + 100))
    os.utime(new, (time.time() + 200, time.time() + 200))
    units, problems = found([tmp_path])
    assert units["carol"].notebook == exact and not units["carol"].rejected
    assert units["dave"].notebook == new and not units["dave"].rejected
    assert sorted(problems) == sorted([f"{newer}: carol has several notebooks for 00_warmup; graded {exact}",
                                       f"{old}: dave has several notebooks for 00_warmup; graded {new}"])


def test_the_same_file_given_twice_is_one_submission(tmp_path):
    """A notebook given alone and inside its folder is graded once, without a conflict."""
    path = put(tmp_path / "erin.ipynb")
    units, problems = found([path, tmp_path, path])
    assert list(units) == ["erin"] and not units["erin"].rejected and problems == []


def test_one_student_spelled_two_ways_in_two_exercises_is_one_student(tmp_path):
    """Frank/ and frank.ipynb of different exercises are no conflict, and one spelling names both."""
    put(tmp_path / "Frank" / "00_warmup.ipynb")
    put(tmp_path / "frank.ipynb", notebook("01_integrator_order"))
    units, problems = find_submissions([tmp_path], EXERCISES)
    assert sorted((u.student, u.exercise, u.rejected) for u in units) == [
        ("Frank", "00_warmup", ""), ("Frank", "01_integrator_order", "")] and problems == []


# -- links -----------------------------------------------------------------------------------------------------

def test_links_out_of_the_folder_are_not_followed(tmp_path):
    """A link to a notebook or a folder outside, or to any folder, is reported and not read; a link to a
    notebook inside the folder is read; the real folders are."""
    subs, outside = tmp_path / "subs", tmp_path / "outside"
    put(outside / "secret.ipynb")
    put(outside / "zed" / "00_warmup.ipynb")
    inside = put(subs / "grace" / "00_warmup.ipynb")
    (subs / "mallory.ipynb").symlink_to(outside / "secret.ipynb")
    (subs / "trudy").symlink_to(outside / "zed")
    (subs / "grace2").symlink_to(subs / "grace")
    (subs / "heidi.ipynb").symlink_to(inside)
    (subs / "loop").symlink_to(subs)
    units, problems = found([subs])
    assert sorted(units) == ["grace", "heidi"]
    assert units["heidi"].notebook == subs / "heidi.ipynb" and not units["heidi"].rejected
    for name in ("mallory.ipynb", "trudy", "grace2", "loop"):
        assert sum(p.startswith(f"{subs / name}: a link to ") and p.endswith("not followed") for p in problems) == 1
    assert f"{outside}" in " ".join(p for p in problems if "trudy" in p)


def test_a_broken_link_is_a_notebook_that_cannot_be_read(tmp_path):
    """A link to nothing inside the folder is kept as its student's notebook, rejected: 'cannot be read'."""
    (tmp_path / "ivan.ipynb").symlink_to(tmp_path / "gone.ipynb")
    units, _ = found([tmp_path])
    assert "your notebook ivan.ipynb could not be read: it cannot be read" in units["ivan"].rejected


# -- malformed notebooks ---------------------------------------------------------------------------------------

def test_a_malformed_notebook_is_a_rejected_unit_and_a_problem(tmp_path):
    """Bad files are kept as their students' units with the one-line reason (0 points), never dropped."""
    put(tmp_path / "judy.ipynb", '{"cells": [')
    put(tmp_path / "ken.ipynb", json.dumps({"nbformat": 3, "worksheets": []}))
    (tmp_path / "leo.ipynb").mkdir()
    (tmp_path / "mia.ipynb").write_bytes(b"\xff\xfe{}")
    put(tmp_path / "ok.ipynb")
    units, problems = found([tmp_path])
    assert sorted(units) == ["judy", "ken", "leo", "mia", "ok"] and not units["ok"].rejected
    assert units["judy"].rejected.startswith("your notebook judy.ipynb could not be read: it is not valid JSON")
    assert units["ken"].rejected.startswith("your notebook ken.ipynb could not be read: it is nbformat 3, expected 4")
    assert units["leo"].rejected == "your notebook leo.ipynb could not be read: it is a folder, not a notebook file"
    assert units["mia"].rejected.startswith("your notebook mia.ipynb could not be read: it is not UTF-8 text")
    assert sorted(p.split(":")[0] for p in problems) == sorted(str(tmp_path / f"{n}.ipynb")
                                                             for n in ("judy", "ken", "leo", "mia"))


def test_a_bad_notebook_of_an_unknown_exercise_is_reported_with_its_reason(tmp_path):
    """Without --exercise and no exercise in its name, a bad notebook is a problem that says both."""
    put(tmp_path / "nia.ipynb", "[]")
    units, problems = found([tmp_path], exercise=None)
    assert units == {} and problems == [f"{tmp_path / 'nia.ipynb'}: cannot tell which exercise this is; pass "
                                        "--exercise (your notebook nia.ipynb could not be read: it holds a list in "
                                        "JSON, not a notebook (an object with cells))"]


def test_the_limits_reach_discovery(tmp_path):
    """The limits given to find_submissions are the notebooks' limits."""
    put(tmp_path / "olga.ipynb")
    units, _ = found([tmp_path], limits=Limits(notebook_bytes=10))
    assert "more than the 10 bytes a notebook may have" in units["olga"].rejected


# -- zips and LMS layouts --------------------------------------------------------------------------------------

def make_zip(path, members):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


def test_an_lms_export_zip_names_its_students(tmp_path):
    """Canvas's file names, Moodle's folders, a wrapper folder and Gradescope's metadata name the students."""
    work = tmp_path / "work"
    work.mkdir(mode=0o700)
    canvas = make_zip(tmp_path / "canvas.zip", {"smithj_late_101_202_00_warmup.ipynb": notebook(),
                                                "doea_103_204_00_warmup-1.ipynb": notebook(),
                                                "doea_103_204_00_warmup.ipynb": notebook()})
    moodle = make_zip(tmp_path / "moodle.zip", {
        "Ann Lee_555_assignsubmission_file_/00_warmup.ipynb": notebook()})
    gradescope = make_zip(tmp_path / "gradescope.zip", {
        "assignment_9_export/submission_metadata.yml":
            "submission_77:\n  :submitters:\n  - :name: Bo Wu\n    :sid: '42'\n    :email: bo@example.com\n"
            "  :created_at: 2026-01-01\nsubmission_78:\n  :submitters:\n  - :name: Cy\n    :sid: '43'\n",
        "assignment_9_export/submission_77/00_warmup.ipynb": notebook(),
        "assignment_9_export/submission_78/work.ipynb": notebook(),
        "assignment_9_export/submission_79/work.ipynb": notebook()})
    single = make_zip(tmp_path / "upload.zip", {"pat/00_warmup.ipynb": notebook()})
    units, problems = found([canvas, moodle, gradescope, single], workdir=work)
    assert sorted(units) == ["43", "Ann_Lee_555", "bo@example.com", "doea", "pat", "smithj", "submission_79"]
    assert units["smithj"].origin == f"{canvas}:smithj_late_101_202_00_warmup.ipynb"
    assert units["smithj"].notebook.is_relative_to(work) and units["smithj"].notebook.is_file()
    assert units["smithj"].late_flag and units["smithj"].aliases == (("canvas_id", "101"), ("login", "smithj"))
    # Canvas's re-upload of one file name is "-1": the latest upload is graded, and the report says so
    assert units["doea"].origin.endswith(":doea_103_204_00_warmup-1.ipynb") and not units["doea"].rejected
    assert problems == [f"{canvas}:doea_103_204_00_warmup.ipynb: doea has several notebooks for 00_warmup; "
                        f"graded the latest upload, {canvas}:doea_103_204_00_warmup-1.ipynb"]
    assert units["bo@example.com"].aliases == (("email", "bo@example.com"), ("sid", "42"))
    assert units["bo@example.com"].submitted is None  # a date without a time is no submission time


def test_a_refused_zip_is_a_problem_and_a_zip_needs_a_workdir(tmp_path):
    """An unsafe zip grades nothing and says why; without a private folder, a zip is a problem too."""
    work = tmp_path / "work"
    work.mkdir(mode=0o700)
    bad = make_zip(tmp_path / "bad.zip", {"quinn/00_warmup.ipynb": notebook(), "../x.ipynb": notebook()})
    units, problems = found([bad], workdir=work)
    assert units == {} and len(problems) == 1 and "bad.zip: zip refused: member '../x.ipynb'" in problems[0]
    units, problems = found([bad])
    assert units == {} and problems == [f"{bad}: zips are opened by particles grade only; unzip it first"]
    assert list(work.iterdir()) == [] and not (tmp_path / "x.ipynb").exists()


def test_a_zip_and_a_folder_of_one_student_are_a_conflict(tmp_path):
    """A student in a zip and in a folder given beside it: a conflict naming the zip's member and the file."""
    work = tmp_path / "work"
    work.mkdir(mode=0o700)
    lms = make_zip(tmp_path / "lms.zip", {"rita/00_warmup.ipynb": notebook()})
    loose = put(tmp_path / "subs" / "Rita.ipynb")
    units, _ = found([lms, tmp_path / "subs"], workdir=work)
    assert list(units) == ["Rita"] and units["Rita"].origin == f"{lms}:rita/00_warmup.ipynb and {loose}"
    assert "(rita/00_warmup.ipynb and Rita.ipynb)" in units["Rita"].rejected


def test_a_missing_path_is_a_problem(tmp_path):
    """A path that does not exist is reported by name."""
    assert found([tmp_path / "nope"]) == ({}, [f"{tmp_path / 'nope'} does not exist"])


def test_rglob_would_have_followed_what_discovery_does_not(tmp_path):
    """The walk does not read a notebook reached through a link to a folder outside, which a glob of the
    folder lists (the reason discovery walks the folder itself)."""
    put(tmp_path / "outside" / "00_warmup.ipynb")
    (tmp_path / "subs").mkdir()
    (tmp_path / "subs" / "sam.ipynb").symlink_to(tmp_path / "outside" / "00_warmup.ipynb")
    assert [p.name for p in (tmp_path / "subs").rglob("*.ipynb")] == ["sam.ipynb"]
    assert found([tmp_path / "subs"])[0] == {}


def test_a_zip_is_looked_into_only_when_its_top_folder_holds_students(tmp_path):
    """export/{a,b}/ is unwrapped to students a and b; one student's zip (pat/...) keeps pat; a zip inside
    a folder is reported, not opened."""
    work = tmp_path / "work"
    work.mkdir(mode=0o700)
    export = make_zip(tmp_path / "export.zip", {"export/uma/00_warmup.ipynb": notebook(),
                                                "export/vic/00_warmup.ipynb": notebook(),
                                                "export/readme.txt": "hello"})
    single = make_zip(tmp_path / "single.zip", {"wes/00_warmup.ipynb": notebook(), "wes/notes/a.txt": "x"})
    (tmp_path / "subs").mkdir()
    (tmp_path / "subs" / "xia.zip").write_bytes(single.read_bytes())
    units, problems = found([export, single, tmp_path / "subs"], workdir=work)
    assert sorted(units) == ["uma", "vic", "wes"]
    assert problems == [f"{tmp_path / 'subs' / 'xia.zip'}: a zip in a folder is not opened; give it as a "
                        "SUBMISSION of its own"]


def test_names_written_composed_and_decomposed_are_one_student(tmp_path):
    """José/ as macOS writes it (decomposed) and josé.ipynb (composed) are one student: a conflict."""
    put(tmp_path / "Jose\u0301" / "00_warmup.ipynb")
    put(tmp_path / "jos\u00e9.ipynb")
    units, _ = found([tmp_path])
    assert list(units) == ["Jos\u00e9"] and "none was graded" in units["Jos\u00e9"].rejected


# -- who is who: Canvas's user ids, Gradescope's groups and times, the roster's aliases ------------------------


def test_two_canvas_students_with_one_login_stay_two_and_each_gets_their_latest_upload(tmp_path):
    """Canvas's user id, not its login, says whose a file is; of one user's files the largest attachment id wins."""
    work = tmp_path / "work"
    work.mkdir(mode=0o700)
    canvas = make_zip(tmp_path / "canvas.zip", {"smithjohn_2000_5001_00_warmup.ipynb": notebook(),
                                                "smithjohn_2001_5002_00_warmup.ipynb": notebook(),
                                                "smithjohn_2001_5007_00_warmup.ipynb": notebook()})
    units, problems = found([canvas], workdir=work)
    assert sorted(units) == ["smithjohn", "smithjohn_2001"] and not any(u.rejected for u in units.values())
    assert units["smithjohn_2001"].origin.endswith("smithjohn_2001_5007_00_warmup.ipynb")
    assert problems == [f"{canvas}:smithjohn_2001_5002_00_warmup.ipynb: smithjohn_2001 has several notebooks for "
                        f"00_warmup; graded the latest upload, {canvas}:smithjohn_2001_5007_00_warmup.ipynb"]


def test_a_gradescope_group_is_graded_once_per_member_at_its_created_at(tmp_path):
    """Every submitter of a Gradescope submission gets the notebook, with the submission's created_at."""
    from datetime import datetime, timedelta, timezone

    work = tmp_path / "work"
    work.mkdir(mode=0o700)
    export = make_zip(tmp_path / "gs.zip", {
        "export/submission_metadata.yml": "submission_5:\n  :submitters:\n  - :name: A\n    :email: a@uni.edu\n"
        "  - :name: B\n    :sid: '77'\n    :email: b@uni.edu\n  :created_at: 2026-10-02 10:00:00.5 -07:00\n",
        "export/submission_5/00_warmup.ipynb": notebook(), "export/submission_6/00_warmup.ipynb": notebook()})
    units, problems = found([export], workdir=work)
    assert sorted(units) == ["a@uni.edu", "b@uni.edu", "submission_6"] and problems == []
    when = datetime(2026, 10, 2, 10, 0, 0, 500000, tzinfo=timezone(timedelta(hours=-7)))
    assert units["a@uni.edu"].submitted == units["b@uni.edu"].submitted == when
    assert units["b@uni.edu"].aliases == (("email", "b@uni.edu"), ("sid", "77"))
    assert units["submission_6"].submitted is None


def test_the_roster_joins_one_students_names_from_two_lms_and_names_strangers(tmp_path):
    """With a roster, Canvas's login and Gradescope's e-mail of one student are that student; a name that is no
    roster student's is graded under its own name and reported."""
    from particles.course.term.identity import Identity, Person

    work = tmp_path / "work"
    work.mkdir(mode=0o700)
    course = Identity([Person("alice", [("login", "alicesmith"), ("email", "alice@uni.edu")]),
                       Person("bob", [("canvas_id", "12")])], closed=True)
    canvas = make_zip(tmp_path / "canvas.zip", {"alicesmith_10_20_00_warmup.ipynb": notebook(),
                                                "someone_12_21_00_warmup.ipynb": notebook(),
                                                "zed_13_22_00_warmup.ipynb": notebook()})
    gradescope = make_zip(tmp_path / "gs.zip", {
        "x/submission_metadata.yml": "submission_1:\n  :submitters:\n  - :email: Alice@Uni.edu\n",
        "x/submission_1/01_integrator_order.ipynb": notebook("01_integrator_order")})
    units, problems = find_submissions([canvas, gradescope], EXERCISES, workdir=work, identity=course)
    assert sorted((u.student, u.exercise) for u in units) == [("alice", "00_warmup"), ("alice", "01_integrator_order"),
                                                              ("bob", "00_warmup"), ("zed", "00_warmup")]
    assert [u.on_roster for u in units if u.student == "zed"] == [False]
    assert problems == [f"{canvas}:zed_13_22_00_warmup.ipynb: 'zed' is no student of the roster (nor an alias of "
                        "one): graded as zed; add the name to their roster line's aliases"]
