"""Which notebooks a grading run grades: submissions, students, exercises, written answers.

* a notebook given on the command line is one submission; the student is its
  file name without ``.ipynb``;
* a folder: notebooks directly inside it are graded the same way; notebooks
  in sub-folders belong to the student named by the first sub-folder (the
  layout of an export with one folder per student).

The exercise of a notebook is read from its metadata (written by
``particles release``), else from its file name (``..._00_warmup...``), else
from ``--exercise``, which also overrides both. A student with several
notebooks of one exercise gets one graded (the one named exactly
``NN_topic.ipynb``, else the newest); the others are reported.
"""

import hashlib
import json
import re
from dataclasses import dataclass
from pathlib import Path

from ..release.answers import count_answers

__all__ = ["Unit", "find_submissions", "written_answers", "released_exercise", "notebook_digest", "student_key"]


@dataclass
class Unit:
    """One notebook to grade: who submitted it, which exercise it is."""

    student: str
    exercise: str
    notebook: Path


def _exercise_of(notebook, exercises, override=None):
    if override:
        return override
    try:
        meta = json.loads(Path(notebook).read_text(encoding="utf-8")).get("metadata", {})
        name = meta.get("particles", {}).get("exercise")
        if name in exercises:
            return name
    except (OSError, UnicodeDecodeError, ValueError, AttributeError):
        pass
    for name in sorted(exercises, key=len, reverse=True):
        if name in Path(notebook).stem:
            return name
    return None


def _student_name(text):
    return re.sub(r"[^\w.@+-]+", "_", text).strip("_") or "submission"


def student_key(text):
    """The key two names of one student compare equal by: the grader's name for `text`, case-folded.

    The grader files a submission under its folder's (or notebook's) name with every run of characters
    other than letters, digits and ``. @ + -`` replaced by ``_``; a roster compares its names with the
    records' the same way, whatever their case (``"Ann Lee"``, ``"ann_lee"`` and ``"ANN_LEE"`` are one key).
    """
    return _student_name(str(text)).casefold()


def _preference(unit):
    """Which of two notebooks of one student and exercise to grade: the exact name, then the newest."""
    path = Path(unit.notebook)
    return (path.name == f"{unit.exercise}.ipynb", path.stat().st_mtime)


def find_submissions(paths, exercises, exercise=None):
    """Expand notebooks and folders into :class:`Unit` s and a list of problems.

    Returns
    -------
    units : list of Unit
    problems : list of str
        Notebooks whose exercise could not be told, and paths that do not exist.
    """
    units, problems = [], []
    for given in map(Path, paths):
        if given.is_file():
            found = [(given, given.stem)]
        elif given.is_dir():
            found = []
            for nb in sorted(given.rglob("*.ipynb")):
                if ".ipynb_checkpoints" in nb.parts:
                    continue
                rel = nb.relative_to(given)
                found.append((nb, rel.parts[0] if len(rel.parts) > 1 else nb.stem))
        else:
            problems.append(f"{given} does not exist")
            continue
        for nb, student in found:
            name = _exercise_of(nb, exercises, exercise)
            if name is None:
                problems.append(f"{nb}: cannot tell which exercise this is; pass --exercise")
                continue
            units.append(Unit(_student_name(student), name, nb))
    chosen = {}
    for unit in units:  # one notebook per student and exercise: the exact name, else the newest
        key = (unit.student, unit.exercise)
        if key not in chosen:
            chosen[key] = unit
            continue
        keep, drop = sorted([chosen[key], unit], key=_preference, reverse=True)
        chosen[key] = keep
        problems.append(f"{drop.notebook}: {unit.student} has several notebooks for {unit.exercise}; "
                        f"graded {keep.notebook}")
    return list(chosen.values()), problems


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
