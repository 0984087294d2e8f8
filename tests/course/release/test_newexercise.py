"""``particles new-exercise NN_topic``: a template exercise that releases, grades and runs, and the refusals."""

import re
import shutil

import nbformat
import pytest
from nbclient import NotebookClient

from particles.cli import main
from particles.course.grading.driver import LibraryChanged, grade
from particles.course.release.notebooks import BEGIN, END, INSTRUCTOR

NAME = "05_energy"


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    """A course folder holding only what new-exercise writes and what release makes of it."""
    root = tmp_path_factory.mktemp("course")
    assert main(["new-exercise", NAME, "--root", str(root)]) == 0
    assert main(["release", "--root", str(root)]) == 0
    return root


def test_writes_a_master_and_a_test_module_in_the_course_layout(course):
    """The master has a title, a solved function, a written answer and a public check; the tests have points."""
    master = nbformat.read(course / "solutions" / f"{NAME}.ipynb", as_version=4)
    nbformat.validate(master)
    sources = [c.source for c in master.cells]
    assert sources[0].startswith("# Exercise 05 — Energy")
    assert [s for s in sources if "def kinetic_energy" in s and BEGIN in s and END in s]
    assert [c for c in master.cells if c.cell_type == "markdown" and BEGIN in c.source]
    assert sources[-1] == f'particles.check("{NAME}")'
    text = (course / "tests" / "exercises" / f"test_{NAME}.py").read_text()
    assert f'EXERCISE = "{NAME}"' in text and "FORBIDDEN = {" in text and "@pytest.mark.hidden" in text
    assert text.count("@pytest.mark.points(") == 2 and "student.call(" in text and "rng" in text
    released = (course / "exercises" / f"{NAME}.ipynb").read_text()
    assert "NotImplementedError" in released and "0.5 * float" not in released and INSTRUCTOR not in released
    assert main(["release", "--check", "--root", str(course)]) == 0


def test_master_scores_full_marks_and_the_stub_zero(course, tmp_path):
    """Graded by `particles grade`, the master gets every point, hidden test included, and the released stub none."""
    for student, folder in (("master", "solutions"), ("stub", "exercises")):
        (tmp_path / "subs" / student).mkdir(parents=True)
        shutil.copy(course / folder / f"{NAME}.ipynb", tmp_path / "subs" / student)
    try:
        summary = grade([tmp_path / "subs"], tmp_path / "out", root=course, seed=7)
    except LibraryChanged as error:  # someone edited the library meanwhile: these grades say nothing
        pytest.skip(f"re-run: {error}")
    (master,), (stub,) = summary["students"]["master"], summary["students"]["stub"]
    assert [t["passed"] for t in master["tests"]] == [True, True] and any(t["hidden"] for t in master["tests"])
    assert sum(t["points"] for t in master["tests"]) == 3
    assert not any(t["passed"] for t in stub["tests"]) and "not implemented yet" in stub["tests"][0]["reason"]
    assert (tmp_path / "out" / "stub" / "feedback.html").exists()


def test_master_and_stub_run_in_a_kernel(course):
    """The master runs clean and its check reports all public tests passed; the stub stops at its NotImplementedError."""
    outputs = {}
    for folder in ("solutions", "exercises"):
        path = course / folder / f"{NAME}.ipynb"
        nb = nbformat.read(path, as_version=4)
        NotebookClient(nb, timeout=120, kernel_name="python3", allow_errors=folder == "exercises",
                       resources={"metadata": {"path": str(path.parent)}}).execute()
        errors = [o["ename"] for c in nb.cells if c.cell_type == "code" for o in c.outputs
                  if o.get("output_type") == "error"]
        last = "".join(o.get("data", {}).get("text/plain", "") for o in nb.cells[-1].outputs)
        outputs[folder] = errors, last
    assert outputs["solutions"][0] == [] and "All public tests pass" in outputs["solutions"][1]
    errors, last = outputs["exercises"]
    assert errors == ["NotImplementedError"] and re.search(r"\b0 / 1 points on the public tests", last)


@pytest.mark.parametrize("name", ["5_energy", "05-energy", "05_Energy", "05_", "005_energy", "05_energy.py"])
def test_malformed_names_are_refused(tmp_path, name, capsys):
    """A name that is not NN_topic (two digits, lower-case topic) is refused with exit status 2, nothing written."""
    assert main(["new-exercise", name, "--root", str(tmp_path)]) == 2
    assert "malformed" in capsys.readouterr().err and not list(tmp_path.rglob("*.*"))


def test_existing_files_and_taken_numbers_are_refused(course, capsys):
    """Existing files are named and kept; another topic under a number in use is refused too (exit status 2)."""
    master = course / "solutions" / f"{NAME}.ipynb"
    before = master.read_text()
    assert main(["new-exercise", NAME, "--root", str(course)]) == 2
    err = capsys.readouterr().err
    assert f"solutions/{NAME}.ipynb" in err and f"tests/exercises/test_{NAME}.py" in err
    assert master.read_text() == before
    assert main(["new-exercise", "05_other", "--root", str(course)]) == 2
    assert "taken by 05_energy" in capsys.readouterr().err and not (course / "solutions" / "05_other.ipynb").exists()
