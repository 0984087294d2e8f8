"""Corpora of wrong and alternative submissions for the exercises 01 onwards.

Each exercise ``NN_topic`` has a module ``tests/course/grader/cases_NN_topic.py`` that
defines

* ``EXERCISE = "NN_topic"``;
* ``REJECTED``: case name -> ``{"replace": {function: code}, "append": [code],
  "fails": {test: piece of its reason}, "passes": [tests], "culprit": function}``,
  at least eight per exercise (the typical mistakes, written as a student
  would), each losing the points it should with a message that says what is
  wrong; ``culprit`` is the function that holds the mistake, which every
  failing test's message must name (downstream of it too: the grader blames
  a helper that fails its own tests, see :mod:`particles.course.grading.blame`);
* ``CORRECT`` (optional): case name -> a case that must score full marks;
  ``"optional_fail": {test: piece}`` lists stretch-goal tests it leaves
  failing (a stub left alone), which are labelled and not scored.

Every wrong submission must be told its mistake in words: at least one piece
of ``fails`` names it (:func:`names_a_mistake`: more than the "is off by" of a
wrong number, and more than the call the reason starts with), e.g. "your
result matches a midpoint step", "your first record is not X0", "did not
finish within 2 s". A case may add ``"diagnosis": {test: phrase}`` for that
when its ``fails`` pieces only locate the failure.

A case starts from the master notebook ``solutions/NN_topic.ipynb`` without
its instructor-only cells (as students get it) and replaces the code cell that
defines each named function (``replace``), or appends code cells (``append``). The 00_warmup corpus (``corpus.py``) is the
larger one that tests the grader's defences; these test the exercises.
"""

import contextlib
import importlib
import json
import math
import os
import re
from pathlib import Path

from particles.course.release.notebooks import INSTRUCTOR, INSTRUCTOR_TAG

ROOT = Path(__file__).resolve().parents[3]
HERE = Path(__file__).resolve().parent


def case_modules():
    """The ``cases_NN_topic`` modules of this folder, in exercise order."""
    names = sorted(p.stem for p in HERE.glob("cases_*.py"))
    return [importlib.import_module(name) for name in names]


def _source(cell):
    source = cell["source"]
    return "".join(source) if isinstance(source, list) else source


def _instructor_only(cell):
    """Whether a master's cell is dropped from the students' notebooks (release's rule)."""
    return _source(cell).lstrip().startswith(INSTRUCTOR) or INSTRUCTOR_TAG in cell.get("metadata", {}).get("tags", [])


def build(exercise, case):
    """The notebook (a dict) of `case` for `exercise`, made from its master.

    The master's instructor-only cells are left out, as in what students get: they check the master against the
    library (and would run their assignments, the library's solvers and the case's own functions, in every
    worker, a second or more per notebook of some exercises).
    """
    notebook = json.loads((ROOT / "solutions" / f"{exercise}.ipynb").read_text())
    notebook["cells"] = [cell for cell in notebook["cells"] if not _instructor_only(cell)]
    for name, code in case.get("replace", {}).items():
        for cell in notebook["cells"]:
            if cell["cell_type"] == "code" and f"def {name}(" in _source(cell):
                cell["source"] = code.strip("\n")
                break
        else:
            raise KeyError(f"no code cell of {exercise} defines {name}")
    for code in case.get("append", []):
        notebook["cells"].append({"cell_type": "code", "metadata": {}, "source": code, "outputs": [],
                                  "execution_count": None, "id": f"extra-{len(notebook['cells'])}"})
    notebook["metadata"]["particles"] = {"exercise": exercise}
    return notebook


def master_code(exercise):
    """The code cells of the master of `exercise`, joined (to check that a case's culprit is one of its functions)."""
    notebook = json.loads((ROOT / "solutions" / f"{exercise}.ipynb").read_text())
    return "\n".join(_source(c) for c in notebook["cells"] if c["cell_type"] == "code")


def write_corpora(folder, modules=None):
    """Write every case as ``folder/<exercise>__<case>/<exercise>.ipynb``, plus each master and stub.

    Returns
    -------
    dict
        student name -> (exercise, case name), with case names ``"master"``
        and ``"released_stub"`` for the two reference notebooks.
    """
    folder = Path(folder)
    students = {}
    for module in modules or case_modules():
        exercise = module.EXERCISE
        cases = dict(module.REJECTED, **getattr(module, "CORRECT", {}))
        texts = {name: json.dumps(build(exercise, case), indent=1) for name, case in cases.items()}
        texts["master"] = (ROOT / "solutions" / f"{exercise}.ipynb").read_text()
        texts["released_stub"] = (ROOT / "exercises" / f"{exercise}.ipynb").read_text()
        for name, text in texts.items():
            student = f"{exercise}__{name}"
            (folder / student).mkdir(parents=True, exist_ok=True)
            (folder / student / f"{exercise}.ipynb").write_text(text)
            students[student] = (exercise, name)
    return students


# -- feedback that names the mistake --------------------------------------------------------------


def names_a_mistake(piece, reason):
    """Whether `piece` of a failing test's `reason` says what is wrong, not only where a number is off.

    It must appear in the reason, hold three words or more, contain neither "off by" nor "is off" (the
    message of any wrong number), and, when it starts the reason, go past the call being described (to
    a ": " or "; " that explains, as in "`run` is not defined: the grader skipped `try:` ...").
    """
    text = piece.lower()
    return (piece in reason and len(piece.split()) >= 3 and "off by" not in text and "is off" not in text
            and (not reason.startswith(piece) or ": " in piece or "; " in piece))


def diagnoses(case):
    """(test, phrase) pairs a case declares: its ``fails`` pieces, then its ``diagnosis`` ones."""
    return list(case.get("fails", {}).items()) + list(case.get("diagnosis", {}).items())


# -- hidden parameters never shown -----------------------------------------------------------------

DRAWS_VARIABLE = "PARTICLES_RECORD_DRAWS"
"""Set to a folder, the exercise tests' ``rng`` records its draws there (``tests/exercises/conftest.py``)."""

_FORMATS = ("g", ".3g", ".4g", ".6g", ".2f", ".3f", ".4f")
_LONG_FORMATS = ("g", ".6g")


@contextlib.contextmanager
def recording_draws(folder):
    """Within the block, grading sessions record every hidden test's draws in `folder` (see :func:`read_draws`)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    saved = os.environ.get(DRAWS_VARIABLE)
    os.environ[DRAWS_VARIABLE] = str(folder)
    try:
        yield folder
    finally:
        if saved is None:
            os.environ.pop(DRAWS_VARIABLE, None)
        else:
            os.environ[DRAWS_VARIABLE] = saved


def read_draws(folder):
    """(student, test) -> the record of what the test's ``rng`` drew; the student is the notebook's folder."""
    draws = {}
    for path in sorted(Path(folder).glob("draws-*.jsonl")):
        for line in path.read_text().splitlines():
            record = json.loads(line)
            draws[(Path(record["notebook"]).parent.name, record["test"])] = record
    return draws


def _forms(value, formats):
    out = set()
    for v in {value, abs(value)}:
        for spec in formats:
            text = format(v, spec)
            digits = re.sub(r"[^0-9]", "", text.split("e")[0]).strip("0")
            if len(digits) >= 3:  # "1.5", "0.50" or "19": too few digits to tell a draw from any other number
                out.add(text)
    return out


def number_forms(record):
    """The strings a message would show a drawn number as: each draw in the usual formats.

    Scalar draws (and arrays of up to 4 numbers) in ``%g``, ``.3g``, ``.4g``, ``.6g`` and 2, 3 and 4
    decimals, with ``10 ** v``, ``exp(v)`` and ``100 v`` for scalars (a stiffness drawn as ``10 **
    rng.uniform(...)``, a percentage); the elements of larger arrays (random states, positions) in the
    6-digit formats only, where a coincidence with another number is unlikely. Forms of fewer than three
    significant digits (``1.5``, ``0.50``, ``19``) are left out: they would match any number of the message
    (a relative error, a line number), and say little about the draw.
    """
    forms = set()
    for v in record["scalars"]:
        for derived in (v, 100 * v, 10 ** v if abs(v) < 12 else v, math.exp(v) if abs(v) < 30 else v):
            forms |= _forms(derived, _FORMATS)
    for array in record["arrays"]:
        for v in array:
            forms |= _forms(v, _FORMATS if len(array) <= 4 else _LONG_FORMATS)
    return forms


def shown_numbers(reason, record):
    """The drawn numbers of `record` (as formatted) that `reason` shows as whole numbers, sorted.

    A number is shown when it stands on its own: not inside a longer number, a word or a path (a
    checkout in ``/tmp/ci102/`` named in a message is no draw of 102).
    """
    found = []
    for text in number_forms(record):
        if re.search(rf"(?<![\w./]){re.escape(text)}(?![\d/]|\.\d)", reason):
            found.append(text)
    return sorted(found)
