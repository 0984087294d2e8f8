"""Feedback back to students (particles.course.results.returned): the zips as Canvas and Moodle read them back."""

import json
import zipfile

import nbformat

from particles.cli import main
from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.results.returned import canvas_ids, moodle_participant, write_feedback_zips

from .helpers import canvas_reupload, graded_folder, moodle_feedback_import

SECRET = "/home/prof/course-2026"


def _record(student, notebook, exercise="00_warmup"):
    figure = {"title": "order", "xlabel": "h", "ylabel": "error", "loglog": True,
              "series": [{"label": "yours", "x": [0.1, 0.01], "y": [0.1, 0.01]},
                         {"label": "reference", "x": [0.1, 0.01], "y": [0.01, 0.0001]}]}
    tests = [TestRecord("test_a", "a works", points=2.0, passed=True),
             TestRecord("test_b", "b converges", points=1.0, reason=f"order 1 ({SECRET}/tests/test_00.py)",
                        figures=[figure])]
    return SubmissionRecord(student=student, exercise=exercise, notebook=notebook, tests=tests, complete=True,
                            notes=[f"Not graded: see {SECRET}/subs/x.ipynb"])


RECORDS = [_record("alee", f"{SECRET}/canvas.zip:alee_101_5551_00_warmup.ipynb"),
           _record("bray", f"{SECRET}/subs/bray_LATE_102_5552_warmup.ipynb"),
           _record("Ann_Lee_12", f"{SECRET}/moodle.zip:Ann Lee_12_assignsubmission_file_/00_warmup.ipynb"),
           _record("Bo_Yu_13", f"{SECRET}/subs/Bo Yu_13_assignsubmission_file_/sub/00_warmup.ipynb"),
           _record("cy", f"{SECRET}/subs/cy/00_warmup.ipynb")]


def test_ids_of_the_lms_downloads_are_read_from_the_graded_notebook():
    """Canvas's user and file ids, Moodle's full name and participant id, from the download's names."""
    assert [canvas_ids(r.notebook) for r in RECORDS] == [("101", "5551"), ("102", "5552"), None, None, None]
    assert [moodle_participant(r.notebook) for r in RECORDS] == [None, None, ("Ann Lee", "12"), ("Bo Yu", "13"),
                                                                None]


def test_canvas_reads_each_file_as_a_comment_on_its_students_submission(tmp_path):
    """Canvas's rule gives each file's user and submitted file; the file is a notebook (Canvas shows it under the
    student's own notebook's name) holding the feedback and its figure, with no path of the instructor's."""
    done = write_feedback_zips(RECORDS, canvas=tmp_path / "canvas.zip")
    with zipfile.ZipFile(done["files"]["canvas"]["00_warmup"]) as archive:
        names = archive.namelist()
        assert canvas_reupload(names) == {"feedback_101_5551_00_warmup.ipynb": ("101", "5551"),
                                          "feedback_102_5552_00_warmup.ipynb": ("102", "5552")}
        for name in names:
            text = archive.read(name).decode()
            notebook = nbformat.reads(text, as_version=4)
            nbformat.validate(notebook)
            assert "Feedback for" in notebook.cells[0].source and "order 1 (test_00.py)" in notebook.cells[0].source
            assert "image/png" in json.dumps(notebook.cells[1]["attachments"]) and "attachment:" in notebook.cells[1].source
            assert SECRET not in text and "feedback.html" not in text and "instructors," not in text
    assert [s for s, _, _ in done["left_out"]["canvas"]] == ["Ann_Lee_12", "Bo_Yu_13", "cy"]


def test_moodle_reads_each_folder_as_its_participants_feedback_files(tmp_path):
    """Moodle's rule gives each folder's participant and the feedback file; the page names no instructor path."""
    done = write_feedback_zips(RECORDS, moodle=tmp_path / "moodle.zip")
    with zipfile.ZipFile(done["files"]["moodle"]["00_warmup"]) as archive:
        names = archive.namelist()
        assert moodle_feedback_import(names, {12, 13, 14}) == {12: ["/feedback.html"], 13: ["/feedback.html"]}
        assert names == ["Ann Lee_12_assignfeedback_file/feedback.html", "Bo Yu_13_assignfeedback_file/feedback.html"]
        for name in names:
            page = archive.read(name).decode()
            assert "<h1>Feedback for " in page and "data:image/png;base64," in page and SECRET not in page
    assert [s for s, _, _ in done["left_out"]["moodle"]] == ["alee", "bray", "cy"]


def test_one_zip_per_exercise_and_the_command(tmp_path, capsys):
    """Records of two exercises give a zip per exercise; the command says who was left out and exits 1."""
    graded_folder(tmp_path / "out", [*RECORDS[:3], _record("alee", f"{SECRET}/c.zip:alee_101_7771_01_x.ipynb",
                                                            "01_integrator_order")])
    code = main(["export", str(tmp_path / "out"), "--canvas-feedback", str(tmp_path / "fb.zip")])
    printed = capsys.readouterr()
    assert code == 1 and "no canvas feedback for Ann_Lee_12 (00_warmup)" in printed.err
    assert sorted(p.name for p in tmp_path.glob("fb-*.zip")) == ["fb-00_warmup.zip", "fb-01_integrator_order.zip"]
    with zipfile.ZipFile(tmp_path / "fb-01_integrator_order.zip") as archive:
        assert archive.namelist() == ["feedback_101_7771_01_integrator_order.ipynb"]
    assert "fb-00_warmup.zip (canvas feedback for 00_warmup): 2 students" in printed.out


def test_ids_from_the_lms_download_through_the_roster(tmp_path, capsys):
    """Students graded from their own folders get their feedback back through the LMS's download and the roster:
    Canvas's file by canvas_id (the one with the graded bytes), Moodle's folder by name."""
    from particles.course.term.roster import read_roster
    subs = tmp_path / "subs"
    records = []
    for student in ("ann", "bo"):
        (subs / student).mkdir(parents=True)
        (subs / student / "00_warmup.ipynb").write_text(f'{{"who": "{student}"}}')
        record = _record(student, str(subs / student / "00_warmup.ipynb"))
        record.notebook_sha256 = __import__("hashlib").sha256(f'{{"who": "{student}"}}'.encode()).hexdigest()
        records.append(record)
    graded_folder(tmp_path / "out", records)
    roster = tmp_path / "roster.csv"
    roster.write_text("submission_name,name,canvas_id\nann,Ann Lee,101\nbo,Bo Yu,102\n")
    with zipfile.ZipFile(tmp_path / "canvas-download.zip", "w") as archive:
        archive.writestr("leeann_101_9001_00_warmup.ipynb", '{"who": "someone else"}')
        archive.writestr("leeann_101_9002_00_warmup.ipynb", '{"who": "ann"}')
        archive.writestr("yubo_LATE_102_9003_notebook.ipynb", '{"who": "bo"}')
    moodle = tmp_path / "moodle-download"
    (moodle / "Ann Lee_31_assignsubmission_file_").mkdir(parents=True)
    (moodle / "Ann Lee_31_assignsubmission_file_" / "00_warmup.ipynb").write_text("{}")
    code = main(["export", str(tmp_path / "out"), "--roster", str(roster), "--canvas-feedback", str(tmp_path / "c.zip"),
                 "--moodle-feedback", str(tmp_path / "m.zip"), "--download", str(tmp_path / "canvas-download.zip"),
                 "--download", str(moodle)])
    assert code == 1 and "no moodle feedback for bo (00_warmup)" in capsys.readouterr().err  # no folder of Bo Yu
    with zipfile.ZipFile(tmp_path / "c.zip") as archive:
        assert canvas_reupload(archive.namelist()) == {"feedback_101_9002_00_warmup.ipynb": ("101", "9002"),
                                                       "feedback_102_9003_00_warmup.ipynb": ("102", "9003")}
    with zipfile.ZipFile(tmp_path / "m.zip") as archive:
        assert moodle_feedback_import(archive.namelist(), {31}) == {31: ["/feedback.html"]}
    read = read_roster(roster)
    assert write_feedback_zips([], canvas=tmp_path / "x.zip", roster=read)["written"] == {"canvas": []}
