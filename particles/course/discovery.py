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

from .release import ANSWER_PROMPT

__all__ = ["Unit", "find_submissions", "written_answers", "notebook_digest"]


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


def _answer_prompts(notebook):
    """Markdown cells of a notebook that still hold the release's answer prompt (0 if unreadable)."""
    try:
        cells = json.loads(Path(notebook).read_text(encoding="utf-8")).get("cells", [])
        sources = ["".join(c.get("source", "")) if isinstance(c.get("source"), list) else str(c.get("source", ""))
                   for c in cells if isinstance(c, dict) and c.get("cell_type") == "markdown"]
    except (OSError, UnicodeDecodeError, ValueError, AttributeError, TypeError):
        return 0
    return sum(source.count(ANSWER_PROMPT) for source in sources)


def written_answers(notebook, root, exercise):
    """The written (hand-graded) answers of a submission: ``{"asked": M, "answered": k}``.

    ``asked`` counts the answer prompts of the released ``exercises/NN_topic.ipynb``;
    a prompt still present in the submission is unanswered. The autograder does
    not score these answers: the count tells the instructor what is left to read.
    """
    asked = _answer_prompts(Path(root) / "exercises" / f"{exercise}.ipynb")
    return {"asked": asked, "answered": max(asked - _answer_prompts(notebook), 0)}


def notebook_digest(path):
    """SHA-256 of a notebook file's bytes (hex), or "" when it cannot be read: what a resumed run compares."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return ""
