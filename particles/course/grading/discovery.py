"""Which notebooks a grading run grades: submissions, students, exercises, written answers.

Layouts read (:func:`find_submissions`):

* a notebook given on the command line is one submission; the student is its
  file name without ``.ipynb``;
* a folder: notebooks directly inside it are graded the same way; notebooks
  in sub-folders belong to the student named by the first sub-folder (the
  layout of an export with one folder per student). Canvas's file names
  ``login_[late_]userid_submissionid_name.ipynb`` belong to ``login``;
  Moodle's folders ``Full Name_12345_assignsubmission_file_`` to
  ``Full_Name_12345``; Gradescope's ``submission_NNN/`` folders to the first
  submitter's e-mail address found for them in ``submission_metadata.yml``
  beside them;
* a ``.zip`` (an LMS export, or one student's upload) is opened safely into a
  private folder (:func:`particles.course.grading.intake.extract_zip`: a zip
  with links, paths out of it or the shape of a bomb is refused, saying why)
  and read as a folder; a single folder at its top holding the students'
  folders (``export/alice/...``) is looked into. A zip inside a folder is
  not opened (it is reported).

Inside a folder, links are not followed out of it: a link to a file or a
folder outside the folder, and any link to a folder, is reported and not
read; ``__MACOSX``, ``._*`` and ``.ipynb_checkpoints`` are skipped.

The exercise of a notebook is read from its metadata (written by
``particles release``), else from its file name (``..._00_warmup...``), else
from ``--exercise``, which also overrides both.

Students are compared case-insensitively, after Unicode normalization (``Alice/`` and ``alice.ipynb`` are
one student, spelled as the first of the spellings in sorted order). A student
with several notebooks of one exercise in one place (their own folder, or one
Canvas submission) gets one graded: the one named exactly ``NN_topic.ipynb``,
else the newest; the others are reported. Notebooks of one student and
exercise from *different* places (a file and a folder, ``Alice/`` and
``alice/``, two folders given) are a conflict: none of them is graded, the
student gets a :class:`Unit` rejected with a reason naming all of them, and the
problem is reported.

A notebook that is not one the grader reads (:func:`particles.course.grading.intake.read_notebook`:
not UTF-8 JSON, not nbformat 4, duplicate cell ids, too large...) is a
:class:`Unit` rejected with the one-line reason, and is reported: the driver
records 0 for it, saying why, and grades the others.
"""

import hashlib
import json
import os
import re
import unicodedata
from dataclasses import dataclass
from pathlib import Path

from ..release.answers import count_answers
from .intake import DEFAULT_LIMITS, NotebookRejected, ZipRefused, extract_zip, read_notebook, skipped_name

__all__ = ["Unit", "find_submissions", "written_answers", "released_exercise", "notebook_digest", "student_key"]

CANVAS = re.compile(r"^(?P<login>[^_]+)_(?:late_|LATE_)?(?P<user>\d+)_(?P<submission>\d+)_(?P<name>.+)$")
"""Canvas's names of the files of a submissions download."""

MOODLE = re.compile(r"^(?P<name>.+_\d+)_assign(?:submission|feedback)_[a-z]+_?$")
"""Moodle's names of the folders of a submissions download."""


@dataclass
class Unit:
    """One notebook to grade: who submitted it, which exercise it is.

    Attributes
    ----------
    student, exercise : str
    notebook : Path
        The file graded (inside a private folder when it came out of a zip).
    rejected : str
        Why it is not graded, in one line ("" to grade it): the driver records 0 with this reason.
    origin : str
        Where it came from as the instructor named it (``export.zip:alice/00_warmup.ipynb``; "" when it is
        `notebook` itself).
    handed_in : str
        The notebook as the student handed it in: its path inside the zip or folder given (``alice/00_warmup.ipynb``),
        or its name; what the student reads of it, with none of the instructor's folders.
    """

    student: str
    exercise: str
    notebook: Path
    rejected: str = ""
    origin: str = ""
    handed_in: str = ""

    @property
    def where(self):
        """Where the notebook came from, in words."""
        return self.origin or str(self.notebook)


def _exercise_of(notebook, content, exercises, override=None):
    if override:
        return override
    if isinstance(content, dict) and isinstance(content.get("metadata"), dict):
        meta = content["metadata"].get("particles")
        name = meta.get("exercise") if isinstance(meta, dict) else None
        if name in exercises:
            return name
    for name in sorted(exercises, key=len, reverse=True):
        if name in Path(notebook).stem:
            return name
    return None


def _student_name(text):
    text = unicodedata.normalize("NFC", text)  # macOS writes names decomposed (NFD), Windows composed
    return re.sub(r"[^\w.@+-]+", "_", text).strip("_") or "submission"


def student_key(text):
    """The key two names of one student compare equal by: the grader's name for `text`, case-folded.

    The grader files a submission under its folder's (or notebook's) name with every run of characters
    other than letters, digits and ``. @ + -`` replaced by ``_``; a roster compares its names with the
    records' the same way, whatever their case (``"Ann Lee"``, ``"ann_lee"`` and ``"ANN_LEE"`` are one key).
    """
    return _identity(_student_name(str(text)))
def _identity(student):
    """What two students' names are compared by: compatibility-normalized and case-folded."""
    return unicodedata.normalize("NFKC", student).casefold()


def _preference(unit):
    """Which of two notebooks of one student and exercise to grade: the exact name (after Canvas's prefix), then
    the newest (then the last in sorted order, so that the choice never depends on the order of discovery)."""
    path = Path(unit.notebook)
    match = CANVAS.match(path.name)
    name = match.group("name") if match else path.name
    try:
        mtime = path.stat().st_mtime
    except OSError:
        mtime = float("-inf")
    return (name == f"{unit.exercise}.ipynb", mtime, str(path))


def _gradescope_names(folder):
    """``submission_NNN`` -> the first submitter's e-mail (else sid, else name) from Gradescope's metadata."""
    try:
        lines = (Path(folder) / "submission_metadata.yml").read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    names, current, found = {}, None, {}
    for line in lines + ["end:"]:
        top = re.match(r"^:?(submission_\d+|\w+):\s*$", line)
        if top:
            if current and found:
                names[current] = found.get("email") or found.get("sid") or found.get("name")
            current, found = (top.group(1) if top.group(1).startswith("submission_") else None), {}
            continue
        field = re.match(r"^\s*-?\s*:(email|sid|name):\s*['\"]?(.*?)['\"]?\s*$", line)
        if current and field and field.group(2) and field.group(1) not in found:
            found[field.group(1)] = field.group(2)
    return names


def _walk(root, problems):
    """The notebooks under folder `root`, never through a link out of it: a list of (path, relative parts)."""
    root = Path(root)
    real_root = os.path.realpath(root)
    out, stack = [], [(root, ())]
    while stack:
        folder, rel = stack.pop()
        try:
            entries = sorted(os.scandir(folder), key=lambda e: e.name, reverse=True)
        except OSError as error:
            problems.append(f"{folder}: cannot be read ({error.strerror or error})")
            continue
        for entry in entries:
            if skipped_name(entry.name):
                continue
            path, parts = Path(entry.path), rel + (entry.name,)
            notebook = entry.name.lower().endswith(".ipynb")
            if entry.is_symlink():
                target = os.path.realpath(path)
                inside = os.path.commonpath([real_root, target]) == real_root
                if os.path.isdir(target) or not inside:
                    if notebook or os.path.isdir(target):
                        where = "outside the folder" if not inside else "a folder"
                        problems.append(f"{path}: a link to {target} ({where}); not followed")
                    continue
                if notebook:
                    out.append((path, parts))
            elif entry.is_dir(follow_symlinks=False) and not notebook:
                stack.append((path, parts))
            elif notebook:
                out.append((path, parts))
            elif entry.name.lower().endswith(".zip"):
                problems.append(f"{path}: a zip in a folder is not opened; give it as a SUBMISSION of its own")
    return sorted(out)


def _unwrap(folder):
    """Into a zip's single top folder while it holds students' folders (``export/alice/..., export/bob/...``,
    or Gradescope's ``submission_metadata.yml`` beside them) and no notebook."""
    folder = Path(folder)
    while True:
        entries = [e for e in folder.iterdir() if not skipped_name(e.name)]
        if len(entries) != 1 or not entries[0].is_dir():
            return folder
        inner = [e for e in entries[0].iterdir() if not skipped_name(e.name)]
        folders = sum(e.is_dir() for e in inner)
        if any(e.name.lower().endswith(".ipynb") for e in inner) or not (
                folders >= 2 or folders and any(e.name == "submission_metadata.yml" for e in inner)):
            return folder
        folder = entries[0]


def _candidates(given, problems, workdir, limits):
    """(notebook, student, source, origin) of one path given on the command line."""
    if given.suffix.lower() == ".zip" and given.exists() and not given.is_dir():
        if workdir is None:
            problems.append(f"{given}: zips are opened by particles grade only; unzip it first")
            return []
        folder = Path(workdir) / f"zip{len(list(Path(workdir).iterdir())):03d}"
        try:
            problems += extract_zip(given, folder, limits)
        except ZipRefused as error:
            problems.append(str(error))
            return []
        top = _unwrap(folder)
        return [(nb, *_who(top, parts, ("zip", str(given))), f"{given}:{Path(*parts)}", Path(*parts).as_posix())
                for nb, parts in _walk(top, problems)]
    if given.is_dir():
        return [(nb, *_who(given, parts, ("folder", str(given))), "", Path(*parts).as_posix())
                for nb, parts in _walk(given, problems)]
    if given.exists() or given.is_symlink():
        return [(given, _student_name(given.stem), ("file", str(given.resolve())), "", given.name)]
    problems.append(f"{given} does not exist")
    return []


def _who(root, parts, place):
    """The student of the notebook at `parts` under `root`, and the place it came from."""
    if len(parts) > 1:
        folder = parts[0]
        match = MOODLE.match(folder)
        if re.fullmatch(r"submission_\d+", folder):
            folder = _gradescope_names(root).get(folder, folder)
        elif match:
            folder = match.group("name")
        return _student_name(folder), (*place, "folder", parts[0])
    match = CANVAS.match(parts[0])
    if match:
        return _student_name(match.group("login")), (*place, "canvas", match.group("login"), match.group("user"))
    return _student_name(Path(parts[0]).stem), (*place, "file", parts[0])


def find_submissions(paths, exercises, exercise=None, *, workdir=None, limits=DEFAULT_LIMITS):
    """Expand notebooks, folders and zips into :class:`Unit` s and a list of problems.

    Parameters
    ----------
    paths : sequence of path
        Notebooks, folders of them, zips of them (see the module's notes).
    exercises : sequence of str
        The exercises' names (``NN_topic``).
    exercise : str, optional
        Every notebook is this exercise.
    workdir : path, optional
        A private folder (mode 0700) to open zips into, kept while their
        notebooks are graded; without it a zip is a problem.
    limits : particles.course.grading.intake.Limits
        What a notebook and a zip may hold.

    Returns
    -------
    units : list of Unit
        One per student and exercise; a unit with ``rejected`` set is not to
        be graded (a notebook the grader does not read, or a conflict).
    problems : list of str
        One line each: notebooks whose exercise could not be told, paths that
        do not exist, zips refused, links not followed, notebooks not graded
        and why.
    """
    problems, found, seen = [], [], set()
    for given in map(Path, paths):
        for nb, student, source, origin, handed_in in _candidates(given, problems, workdir, limits):
            key = (os.path.realpath(nb), _identity(student))
            if key in seen:  # the same file given twice: one submission
                continue
            seen.add(key)
            where = origin or str(nb)
            try:
                content, rejected = read_notebook(nb, limits), ""
            except NotebookRejected as error:
                content, rejected = None, f"your notebook {Path(origin or nb).name} could not be read: it {error}"
            except (ValueError, MemoryError) as error:  # never a run stopped by one file
                content, rejected = None, (f"your notebook {Path(origin or nb).name} could not be read "
                                           f"({type(error).__name__}: {' '.join(str(error).split())[:200]})")
            name = _exercise_of(nb, content, exercises, exercise)
            if name is None:
                problems.append(f"{where}: cannot tell which exercise this is; pass --exercise"
                                + (f" ({rejected})" if rejected else ""))
                continue
            if rejected:
                problems.append(f"{where}: 0 points: {rejected}")
            found.append((Unit(student, name, nb, rejected, origin, handed_in), source))
    spelling = {}
    for unit, _ in sorted(found, key=lambda f: f[0].student):
        spelling.setdefault(_identity(unit.student), unit.student)
    groups = {}
    for unit, source in found:
        unit.student = spelling[_identity(unit.student)]
        groups.setdefault((unit.student, unit.exercise), {}).setdefault(source, []).append(unit)
    units = []
    for (student, name), sources in groups.items():
        picks = []
        for own in sources.values():  # one place: the exact name, else the newest
            keep = max(own, key=_preference)
            picks.append(keep)
            problems += [f"{drop.where}: {student} has several notebooks for {name}; graded {keep.where}"
                         for drop in own if drop is not keep]
        if len(picks) == 1:
            units.append(picks[0])
            continue
        both = " and ".join(p.where for p in picks)
        yours = " and ".join(p.handed_in or Path(p.notebook).name for p in picks)  # without our folders
        reason = f"{len(picks)} notebooks from different places are yours for {name} ({yours}); none was graded"
        problems.append(f"{student}: 0 points: {len(picks)} notebooks from different places map to student "
                        f"{student} for {name} ({both}); none was graded: keep one and grade again")
        units.append(Unit(student, name, picks[0].notebook, reason, both))
    return units, problems


def released_exercise(root, exercise):
    """The released notebook of `exercise` as a dict: generated from its master when there is one.

    Returns None when neither ``solutions/NN_topic.ipynb`` nor
    ``exercises/NN_topic.ipynb`` can be read.
    """
    from ..release.notebooks import ReleaseError, read_master, release_notebook

    root = Path(root)
    master = root / "solutions" / f"{exercise}.ipynb"
    try:
        if master.exists():
            return json.loads(json.dumps(release_notebook(read_master(master), exercise)))
        return json.loads((root / "exercises" / f"{exercise}.ipynb").read_text(encoding="utf-8"))
    except (ReleaseError, OSError, UnicodeDecodeError, ValueError):
        return None


def written_answers(notebook, root, exercise):
    """The written (hand-graded) answers of a submission: ``{"asked": N, "answered": k, "blank": [...]}``.

    One answer slot per question of the released exercise
    (:func:`particles.course.release.answers.count_answers`): a slot left with its
    prompt, white space or nothing is blank. The autograder does not score
    these answers: the count tells the student and the instructor what is
    left to write and to read.
    """
    released = released_exercise(root, exercise)
    if released is None:
        return {"asked": 0, "answered": 0, "blank": []}
    return count_answers(notebook, released)


def notebook_digest(path):
    """SHA-256 of a notebook file's bytes (hex), or "" when it cannot be read: what a resumed run compares."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return ""
