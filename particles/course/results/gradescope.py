"""``particles gradescope-bundle``: the autograder zip that Gradescope runs.

Gradescope unpacks the zip into ``/autograder/source``, runs ``setup.sh`` once
when the image is built, then ``run_autograder`` for every submission, with
the student's files in ``/autograder/submission`` and the results expected in
``/autograder/results/results.json``. The bundle holds the library, the
exercise tests (public *and* hidden: the students never see this zip), the
released exercises (what the students have: the grader reads their written
questions from them), ``GRADESCOPE.md`` and the two scripts; never the
masters or the grader's own test corpus.

Written questions are graded by people. On Gradescope, each is an entry of
``results.json`` worth 0 points that says so (:func:`particles.course.results.reports.gradescope_results`),
and ``GRADESCOPE.md`` lists them with their points: add each as a manual
question in the assignment's outline (with manual grading turned on), so
that Gradescope adds its points to the autograder's score.

``run_autograder`` honours two variables, for testing it outside Gradescope:
``AUTOGRADER_ROOT`` (default ``/autograder``) and ``PARTICLES_PYTHON`` (default
the virtual environment ``setup.sh`` made). Whatever happens, it leaves a
``results.json``: if grading fails outright, one that scores 0 and says so.

Late work: the bundle holds the course file (``course.toml``, deadlines and the
late policy, :mod:`particles.course.grading.deadlines`) when the course has one,
and ``run_autograder`` passes Gradescope's ``submission_metadata.json`` (whose
``created_at`` is the submission's time) to ``particles grade --metadata``.
"""

import shutil
import stat
import tempfile
import zipfile
from pathlib import Path

from ..paths import exercise_tests
from .rubric import exercise_questions

__all__ = ["SETUP_SH", "run_autograder_script", "write_bundle", "manual_questions", "manual_note"]

SETUP_SH = """#!/usr/bin/env bash
# Gradescope runs this once, as root, when it builds the autograder image.
set -euo pipefail
SOURCE="$(cd "$(dirname "$0")" && pwd)"
PY=""
for candidate in python3.13 python3.12 python3.11 python3; do
    if command -v "$candidate" >/dev/null 2>&1 &&
        "$candidate" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
        PY="$candidate"
        break
    fi
done
if [ -z "$PY" ]; then
    apt-get update
    DEBIAN_FRONTEND=noninteractive apt-get install -y python3.11 python3.11-venv
    PY=python3.11
fi
"$PY" -m venv "$SOURCE/.venv"
"$SOURCE/.venv/bin/python" -m pip install --quiet --upgrade pip
"$SOURCE/.venv/bin/python" -m pip install --quiet "$SOURCE"
"$SOURCE/.venv/bin/python" -c "import particles.course.grading.driver"
"""


def run_autograder_script(exercise=None):
    """The text of ``run_autograder`` (grading every notebook as `exercise` when given)."""
    exercise_arg = f" --exercise {exercise}" if exercise else ""
    return f"""#!/usr/bin/env bash
# Gradescope runs this for every submission: grade /autograder/submission into
# /autograder/results/results.json. Student code runs in a separate worker process inside
# the operating system's walls (see particles.course.walls.isolation) and may not read anything
# under /autograder but the library.
set -u
ROOT="${{AUTOGRADER_ROOT:-/autograder}}"
SOURCE="$ROOT/source"
PYTHON="${{PARTICLES_PYTHON:-$SOURCE/.venv/bin/python}}"
RESULTS="$ROOT/results/results.json"
mkdir -p "$ROOT/results"
rm -f "$RESULTS"
export PYTHONPATH="$SOURCE${{PYTHONPATH:+:$PYTHONPATH}}"
# the submission's time, for the deadlines of course.toml (when the bundle has one)
METADATA=()
if [ -f "$ROOT/submission_metadata.json" ]; then
    METADATA=(--metadata "$ROOT/submission_metadata.json")
fi
# --isolation auto: the namespace sandbox where the container allows it, else a uid of its own,
# Landlock and limits; results.json's output says which layers were active
"$PYTHON" -m particles grade "$ROOT/submission" --root "$SOURCE" --gradescope "$RESULTS" \\
    --private "$ROOT" --jobs 1 --isolation auto{exercise_arg} ${{METADATA[@]+"${{METADATA[@]}}"}}
status=$?
if [ ! -s "$RESULTS" ]; then
    printf '{{"score": 0, "output": "The autograder could not grade this submission (status %s). Please tell the instructors.", "tests": []}}\\n' "$status" > "$RESULTS"
fi
exit 0
"""


def manual_questions(root, exercises):
    """The written questions of `exercises` and their points: ``{exercise: {k: points}}`` (those with some)."""
    found = {name: exercise_questions(root, name) for name in exercises}
    return {name: questions for name, questions in found.items() if questions}


def manual_note(manual):
    """``GRADESCOPE.md``: what to set up on Gradescope, the manual questions and their points."""
    lines = ["# Setting up this autograder on Gradescope", "",
             "Upload this zip as the autograder of a programming assignment. The autograder scores the tests; "
             "the written answers are graded by people.", ""]
    if not manual:
        return "\n".join(lines + ["This assignment has no written question.", ""])
    lines += ["Turn on manual grading in the assignment's settings and add one manual question per written "
              "question to its outline, with these points (results.json lists each as a 0-point entry saying "
              "\"graded by hand on Gradescope\"):", "", "| exercise | question | points |", "| --- | ---: | ---: |"]
    lines += [f"| {name} | {k} | {points:g} |" for name, questions in manual.items()
              for k, points in sorted(questions.items())]
    total = sum(p for questions in manual.values() for p in questions.values())
    return "\n".join(lines + ["", f"Manual questions in all: {total:g} points.", ""])


def _add(archive, path, arcname, executable=False):
    info = zipfile.ZipInfo(arcname, date_time=(2020, 1, 1, 0, 0, 0))
    mode = 0o755 if executable else 0o644
    info.external_attr = (stat.S_IFREG | mode) << 16
    info.compress_type = zipfile.ZIP_DEFLATED
    data = path.read_bytes() if isinstance(path, Path) else path.encode()
    archive.writestr(info, data)


def write_bundle(root, out, exercise=None):
    """Write the Gradescope autograder zip.

    Parameters
    ----------
    root : path
        The course folder.
    out : path
        The zip file to write.
    exercise : str, optional
        Grade every submitted notebook as this exercise (one Gradescope
        assignment per exercise, the usual set-up); without it the exercise
        is read from each notebook.

    Returns
    -------
    list of str
        The names in the zip, in order (``GRADESCOPE.md`` third: the manual questions to add).
    """
    root, out = Path(root), Path(out)
    tests = exercise_tests(root)
    if exercise is not None and exercise not in tests:
        raise ValueError(f"unknown exercise {exercise!r}; expected one of {', '.join(map(repr, tests))}")
    files = []
    for name in ("pyproject.toml", "README.md", "LICENSE", "course.toml"):
        if (root / name).exists():
            files.append((root / name, name))
    for path in sorted((root / "particles").rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
            files.append((path, str(path.relative_to(root))))
    if (root / "tests" / "conftest.py").exists():
        files.append((root / "tests" / "conftest.py", "tests/conftest.py"))
    for name, path in tests.items():
        files.append((path, f"tests/exercises/{path.name}"))
    for name in tests if exercise is None else [exercise]:  # the written questions, read as the students see them
        if (root / "exercises" / f"{name}.ipynb").exists():
            files.append((root / "exercises" / f"{name}.ipynb", f"exercises/{name}.ipynb"))
    note = manual_note(manual_questions(root, list(tests) if exercise is None else [exercise]))
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=out.parent, suffix=".zip", delete=False) as tmp:
        with zipfile.ZipFile(tmp, "w") as archive:
            _add(archive, SETUP_SH, "setup.sh", executable=True)
            _add(archive, run_autograder_script(exercise), "run_autograder", executable=True)
            _add(archive, note, "GRADESCOPE.md")
            for path, arcname in files:
                _add(archive, path, arcname)
    shutil.move(tmp.name, out)
    with zipfile.ZipFile(out) as archive:
        return archive.namelist()
