"""Feedback back to students through the LMS's own bulk uploads: Canvas's and Moodle's feedback zips.

``particles export OUT --canvas-feedback FILE.zip --moodle-feedback FILE.zip`` reads the records of a graded folder
(its course record, ``OUT/course.sqlite``) and writes, per exercise (one LMS assignment each; with several exercises the zips are named
``FILE-<exercise>.zip``), the zip each LMS reads back as feedback:

* **Canvas**, the assignment's "Re-Upload Submissions" (`Canvas's guide`_): Canvas reads each file's name as
  underscore-separated parts, takes the first two all-digit parts as the student's user id and the id of a file
  of their submission, and attaches the file to that submission as a comment, under the name of the submitted
  file (``Assignment#infer_comment_context_from_filename``). The ids come from the names of Canvas's
  submissions download (``login_[LATE_]userid_fileid_name.ipynb``), which the grader reads as it is: a student
  graded from another layout is left out and reported. Since Canvas shows the comment under the student's own
  file name, the file is a notebook (``feedback_<userid>_<fileid>_<exercise>.ipynb``): the feedback in Markdown
  cells, the figures as cell attachments.
* **Moodle**, the assignment's "Upload multiple feedback files in a zip" (`Moodle's guide`_): Moodle reads each
  folder name as ``fullname_participantid_assignfeedback_file`` (``assignfeedback_file_zip_importer::
  is_valid_filename_for_import``), so each student's ``feedback.html`` is in a folder named so, with the
  participant id of the folders of Moodle's submissions download (``Full Name_123_assignsubmission_file_``); a
  student graded from another layout is left out and reported. The "Feedback files" feedback type must be on.

Graded from another layout (a folder per login, say), a student's ids come from the LMS's submissions download
itself (``--download FILE.zip``, as downloaded; a folder too), through the roster (``--roster``,
:mod:`particles.course.results.lms`): Canvas's files whose user id is the student's ``canvas_id``, Moodle's
folders whose full name is the student's ``name``; among several, the file with the graded notebook's bytes, else
the one named for the exercise.

What students read there is what :mod:`particles.course.results.reports` writes for them (no folder of the
instructor's, :mod:`particles.course.results.shown`; nothing addressed to instructors).

.. _Canvas's guide: https://community.canvaslms.com/t5/Instructor-Guide/How-do-I-upload-a-file-to-every-student-in-an-assignment/ta-p/812
.. _Moodle's guide: https://docs.moodle.org/en/Assignment_settings#Feedback_types
"""

import base64
import json
import os
import re
import tempfile
import zipfile
from pathlib import Path

from ..grading import figures
from ..grading.discovery import CANVAS, notebook_digest, student_key
from ..grading.intake import ZipRefused, extract_zip
from .reports import feedback_html, feedback_markdown
from .shown import posix as _posix, submitted_name

__all__ = ["MOODLE_FOLDER", "canvas_ids", "moodle_participant", "feedback_notebook", "read_downloads",
           "write_feedback_zips"]

MOODLE_FOLDER = re.compile(r"^(?P<fullname>.+)_(?P<participant>\d+)_assign(?:submission|feedback)_[a-z]+_?$")
"""A folder of Moodle's submissions download: the student's full name and their participant id."""

_FIGURES_NOTE = "Figures of your curves beside the reference's are in `feedback.html`, beside this file."
_DATE = (2020, 1, 1, 0, 0, 0)


def canvas_ids(notebook):
    """(user id, file id) of a notebook graded from Canvas's submissions download, else None."""
    match = CANVAS.match(submitted_name(notebook))
    return (match.group("user"), match.group("submission")) if match else None


def moodle_participant(notebook):
    """(full name, participant id) of a notebook graded from Moodle's submissions download, else None."""
    tail = _posix(notebook).rsplit(".zip:", 1)[-1]
    for part in reversed(tail.split("/")[:-1]):
        match = MOODLE_FOLDER.match(part)
        if match:
            return match.group("fullname"), match.group("participant")
    return None


def read_downloads(paths):
    """The notebooks of LMS submissions downloads (zips, opened safely, or folders), with what their names say.

    Returns
    -------
    list of dict
        One per notebook: ``name`` (its path in the download), ``sha256``, ``canvas`` ((user, file) or None),
        ``moodle`` ((full name, participant) or None).

    Raises
    ------
    ValueError
        A download that does not exist or a zip that is refused (naming it).
    """
    found = []
    with tempfile.TemporaryDirectory(prefix="particles-download-") as work:
        for k, given in enumerate(map(Path, paths)):
            if given.is_file() and given.suffix.lower() == ".zip":
                top = Path(work) / f"zip{k:03d}"
                try:
                    extract_zip(given, top)
                except ZipRefused as error:
                    raise ValueError(f"download {given}: {error}") from None
            elif given.is_dir():
                top = given
            else:
                raise ValueError(f"download {given}: no such zip or folder (expected the LMS's submissions download)")
            for folder, _, files in os.walk(top):  # links to folders are not followed
                for name in sorted(f for f in files if f.lower().endswith(".ipynb")):
                    path = Path(folder) / name
                    inside = path.relative_to(top).as_posix()
                    found.append({"name": inside, "sha256": notebook_digest(path), "canvas": canvas_ids(inside),
                                  "moodle": moodle_participant(inside)})
    return found


def _from_download(fmt, record, student, entries):
    """The ids of `record` found in the downloads' `entries` through its roster `student`, else None."""
    if student is None:
        return None
    if fmt == "canvas":
        mine = [e for e in entries if e["canvas"] and student.canvas_id and e["canvas"][0] == student.canvas_id]
    else:
        name = student_key(student.name) if student.name else None
        mine = [e for e in entries if e["moodle"] and name and student_key(e["moodle"][0]) == name]
    pick = ([e for e in mine if e["sha256"] == record.notebook_sha256 != ""]
            or [e for e in mine if record.exercise in e["name"]] or (mine if len(mine) == 1 else []))
    return pick[0][fmt] if pick else None


def feedback_notebook(record):
    """A record's feedback as a Jupyter notebook (nbformat 4): Markdown cells, the figures as attachments."""
    text = feedback_markdown(record.student, [record]).replace(_FIGURES_NOTE, "").replace("\n\n\n", "\n\n")
    cells = [{"cell_type": "markdown", "id": "feedback", "metadata": {}, "source": text}]
    for test in record.tests:
        shown = [(f"figure-{len(cells)}-{k}.png", png) for k, png in
                 enumerate(filter(None, map(figures.png, test.figures)), start=1)]
        if shown:
            cells.append({"cell_type": "markdown", "id": f"figures-{len(cells)}", "metadata": {},
                          "attachments": {name: {"image/png": base64.b64encode(png).decode()} for name, png in shown},
                          "source": f"**{test.title}**: your curve beside the reference's\n\n"
                                    + "\n".join(f"![figure {k}](attachment:{name})"
                                                for k, (name, _) in enumerate(shown, start=1))})
    return {"cells": cells, "metadata": {"language_info": {"name": "python"}}, "nbformat": 4, "nbformat_minor": 5}


def _add(archive, name, data):
    info = zipfile.ZipInfo(name, date_time=_DATE)
    info.compress_type = zipfile.ZIP_DEFLATED
    archive.writestr(info, data)


def _path(given, exercise, several):
    given = Path(given)
    return given.with_name(f"{given.stem}-{exercise}{given.suffix}") if several else given


def write_feedback_zips(records, canvas=None, moodle=None, roster=None, downloads=()):
    """Write Canvas's and Moodle's feedback zips of `records`, one per exercise.

    Parameters
    ----------
    records : iterable of SubmissionRecord
        The graded records (:func:`particles.course.results.lms.read_records`).
    canvas, moodle : path or None
        The zips to write (``name-<exercise>.zip`` beside them when the records hold several exercises).
    roster : Roster, optional
        The roster (:func:`particles.course.results.lms.read_roster`): with `downloads`, where the ids of a
        student graded from another layout are found.
    downloads : sequence of path
        The LMS's submissions downloads (zips or folders, :func:`read_downloads`).

    Returns
    -------
    dict
        ``files``: format -> {exercise: path}; ``written``: format -> [(student, exercise, name in the zip)];
        ``left_out``: format -> [(student, exercise, why)].
    """
    records = sorted(records, key=lambda r: (r.exercise, r.student))
    exercises = sorted({r.exercise for r in records})
    entries = read_downloads(downloads) if downloads else []
    identity = roster.identity() if roster is not None else None
    by_name = {s.submission_name: s for s in roster.students} if roster is not None else {}

    def student_of(record):  # the roster's line of a record's student, through their names and aliases
        person = identity.find(record.student) if identity is not None else None
        return by_name.get(person.name) if person is not None else None

    done = {"files": {}, "written": {}, "left_out": {}}
    for fmt, given in (("canvas", canvas), ("moodle", moodle)):
        if given is None:
            continue
        done["files"][fmt], done["written"][fmt], done["left_out"][fmt] = {}, [], []
        for exercise in exercises:
            path = _path(given, exercise, len(exercises) > 1)
            path.parent.mkdir(parents=True, exist_ok=True)
            with zipfile.ZipFile(path, "w") as archive:
                for record in (r for r in records if r.exercise == exercise):
                    placed = _place(fmt, record, _from_download(fmt, record, student_of(record), entries))
                    if isinstance(placed, str):
                        done["left_out"][fmt].append((record.student, exercise, placed))
                        continue
                    name, data = placed
                    _add(archive, name, data)
                    done["written"][fmt].append((record.student, exercise, name))
            done["files"][fmt][exercise] = path
    return done


def _place(fmt, record, downloaded=None):
    """(name in the zip, bytes) of a record's feedback for `fmt`, or why it cannot be returned there.

    `downloaded`: the ids found for it in the LMS's download (:func:`_from_download`), used when its own
    notebook's name does not carry them.
    """
    where = submitted_name(record.notebook) or "(no notebook)"
    if fmt == "canvas":
        ids = canvas_ids(record.notebook) or downloaded
        if ids is None:
            return (f"its notebook {where} is not named as in Canvas's submissions download "
                    "(login_userid_fileid_name.ipynb), and no file of the download given is theirs (by the "
                    "roster's canvas_id): Canvas could not tell whose submission it is")
        notebook = json.dumps(feedback_notebook(record), indent=1, ensure_ascii=False)
        return f"feedback_{ids[0]}_{ids[1]}_{record.exercise}.ipynb", notebook.encode()
    found = moodle_participant(record.notebook) or downloaded
    if found is None:
        return (f"its notebook {where} is not in a folder of Moodle's submissions download "
                "(Full Name_123_assignsubmission_file_), and no folder of the download given is theirs (by the "
                "roster's name): Moodle could not tell whose it is")
    fullname = re.sub(r"[_/\\]+", " ", found[0]).strip() or "student"
    html = feedback_html(record.student, [record])
    return f"{fullname}_{found[1]}_assignfeedback_file/feedback.html", html.encode()
