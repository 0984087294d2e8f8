"""Release: exercises generated from masters, deterministic, checked; the student bundle."""

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

from particles.course.release.notebooks import ReleaseError, public_tests, release, release_notebook, write_bundle

ROOT = Path(__file__).resolve().parents[3]


def _master(*cells):
    nb = nbformat.v4.new_notebook(cells=list(cells))
    return nb


def test_committed_exercises_are_up_to_date():
    """`particles release --check` passes on the repository: exercises/ matches solutions/."""
    result = subprocess.run([sys.executable, "-m", "particles", "release", "--check", "--root", str(ROOT)],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "up to date" in result.stdout


def test_release_is_deterministic(tmp_path):
    """Releasing twice writes the same bytes, and the second run changes nothing."""
    shutil.copytree(ROOT / "solutions", tmp_path / "solutions")
    names = sorted(f"exercises/{p.name}" for p in (ROOT / "solutions").glob("*.ipynb"))
    assert sorted(release(tmp_path)) == names
    first = {name: (tmp_path / name).read_bytes() for name in names}
    assert release(tmp_path) == []
    assert {name: (tmp_path / name).read_bytes() for name in names} == first
    assert first == {name: (ROOT / name).read_bytes() for name in names}


def test_check_reports_stale_orphan_and_unclean(tmp_path):
    """--check names an out-of-date exercise, one without master, and a master with outputs."""
    shutil.copytree(ROOT / "solutions", tmp_path / "solutions")
    release(tmp_path)
    master = tmp_path / "solutions" / "00_warmup.ipynb"
    nb = json.loads(master.read_text())
    nb["cells"][1]["execution_count"] = 3
    nb["cells"][0]["source"] = "# A new title\n"
    master.write_text(json.dumps(nb))
    (tmp_path / "exercises" / "99_old.ipynb").write_text("{}")
    problems = release(tmp_path, check=True)
    assert any("00_warmup.ipynb is out of date" in p for p in problems)
    assert any("99_old.ipynb has no master" in p for p in problems)
    assert any("has outputs" in p for p in problems)
    result = subprocess.run([sys.executable, "-m", "particles", "release", "--check", "--root", str(tmp_path)],
                            capture_output=True, text=True)
    assert result.returncode == 1 and "particles release" in result.stderr


def test_solutions_become_stubs_and_prompts():
    """Solution code becomes NotImplementedError (signature and docstring kept), answers become prompts,
    instructor cells and outputs disappear."""
    code = nbformat.v4.new_code_cell('def f(x):\n    """Doc."""\n    ### BEGIN SOLUTION\n    return 2 * x\n    ### END SOLUTION')
    code.outputs = [nbformat.v4.new_output("stream", text="4")]
    code.execution_count = 1
    answer = nbformat.v4.new_markdown_cell("Why?\n\n### BEGIN SOLUTION\nBecause.\n### END SOLUTION")
    secret = nbformat.v4.new_code_cell("### INSTRUCTOR ONLY\nassert f(2) == 4")
    tagged = nbformat.v4.new_code_cell("x = 1", metadata={"tags": ["instructor-only"]})
    out = release_notebook(_master(code, answer, secret, tagged), "07_test")
    assert len(out.cells) == 3
    assert out.cells[0].source == ('def f(x):\n    """Doc."""\n    # YOUR CODE HERE\n'
                                   '    raise NotImplementedError("f is not written yet")')
    assert out.cells[0].outputs == [] and out.cells[0].execution_count is None
    assert out.cells[1].source == "Why?"  # the question, then its answer slot
    assert out.cells[2].source == "*Your answer here.*" and out.cells[2].metadata == {"particles": {"answer": 1}}
    assert out.metadata["particles"]["exercise"] == "07_test"


@pytest.mark.parametrize("source, message", [
    ("### BEGIN SOLUTION\nx = 1", "without ### END SOLUTION"),
    ("x = 1\n### END SOLUTION", "without ### BEGIN SOLUTION"),
    ("### BEGIN SOLUTION\n### BEGIN SOLUTION\n### END SOLUTION", "inside another"),
])
def test_unbalanced_markers_are_errors(source, message):
    """Unbalanced solution markers stop the release with the cell and line."""
    with pytest.raises(ReleaseError, match=message):
        release_notebook(_master(nbformat.v4.new_code_cell(source)), "07_test")


def test_released_warmup_leaks_no_solution():
    """No solution line of the master appears in the student's notebook."""
    master = nbformat.read(ROOT / "solutions" / "00_warmup.ipynb", as_version=4)
    exercise = (ROOT / "exercises" / "00_warmup.ipynb").read_text()
    for cell in master.cells:
        lines = cell.source.split("\n")
        inside = False
        for line in lines:
            if line.strip() == "### BEGIN SOLUTION":
                inside = True
            elif line.strip() == "### END SOLUTION":
                inside = False
            elif inside and len(line.strip()) > 12:
                assert json.dumps(line)[1:-1] not in exercise, line
    assert "INSTRUCTOR ONLY" not in exercise and "master agrees" not in exercise
    assert exercise.count("NotImplementedError") == 3


def test_public_tests_drop_hidden_ones():
    """public_tests removes @pytest.mark.hidden tests with their decorators, and nothing else."""
    source = (ROOT / "tests" / "exercises" / "test_00_warmup.py").read_text()
    public = public_tests(source)
    assert "hidden" not in public.replace("hidden tests", "")
    assert "def test_euler_step_circle" in public and "def test_euler_step_random" not in public
    compile(public, "public", "exec")


def test_student_bundle_holds_only_what_students_get(tmp_path):
    """The bundle has library, lectures, exercises, public tests; no solutions, hidden tests or corpus."""
    files = write_bundle(ROOT, tmp_path / "bundle")
    assert "exercises/00_warmup.ipynb" in files and "tests/exercises/test_00_warmup.py" in files
    assert "particles/course/grading/driver.py" in files and "pyproject.toml" in files
    assert not [f for f in files if f.startswith(("solutions", "tests/grader", "bench", ".git"))]
    assert not [f for f in files if "__pycache__" in f]
    text = (tmp_path / "bundle" / "tests" / "exercises" / "test_00_warmup.py").read_text()
    assert "mark.hidden" not in text and "def test_euler_step_random" not in text
    with pytest.raises(ValueError, match="not empty"):
        write_bundle(ROOT, tmp_path / "bundle")


def test_bundle_public_tests_run_against_the_student_copy(tmp_path):
    """In the bundle, pytest on the public tests grades the student's exercises/ copy: all fail on the stub."""
    write_bundle(ROOT, tmp_path / "bundle")
    result = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/exercises"],
                            cwd=tmp_path / "bundle", capture_output=True, text=True, timeout=300,
                            env={**__import__("os").environ, "PARTICLES_COURSE_ROOT": str(tmp_path / "bundle")})
    summary = result.stdout.strip().splitlines()[-1]
    assert re.fullmatch(r"\d+ failed in .*", summary), result.stdout[-2000:]
    assert "is not implemented yet" in result.stdout
