"""The Gradescope bundle: unpacked into a fake /autograder tree, run_autograder writes results.json."""

import json
import os
import shutil
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from particles.course.walls import isolation

from particles.cli import main

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    out = tmp_path_factory.mktemp("bundle") / "autograder.zip"
    assert main(["gradescope-bundle", "--out", str(out), "--root", str(ROOT), "--exercise", "00_warmup"]) == 0
    return out


def _autograder_tree(bundle, root, notebook_text):
    """A fake /autograder: source/ from the zip, submission/ with one notebook, results/."""
    with zipfile.ZipFile(bundle) as archive:
        archive.extractall(root / "source")
        for info in archive.infolist():  # zipfile does not restore permissions; Gradescope's unzip does
            if (info.external_attr >> 16) & stat.S_IXUSR:
                os.chmod(root / "source" / info.filename, 0o755)
    (root / "submission").mkdir()
    (root / "submission" / "my_warmup.ipynb").write_text(notebook_text)
    return root


def _run_autograder(root):
    env = dict(os.environ, AUTOGRADER_ROOT=str(root), PARTICLES_PYTHON=sys.executable)
    env.pop("PYTHONPATH", None)
    done = subprocess.run([str(root / "source" / "run_autograder")], env=env, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads((root / "results" / "results.json").read_text())


def test_bundle_contents(bundle):
    """The zip holds the two scripts (executable), the library, all exercise tests and the released exercise
    (its written questions), and GRADESCOPE.md listing the manual questions; no masters, no corpus."""
    with zipfile.ZipFile(bundle) as archive:
        names = archive.namelist()
        modes = {i.filename: (i.external_attr >> 16) & 0o777 for i in archive.infolist()}
    assert names[:2] == ["setup.sh", "run_autograder"] and modes["run_autograder"] == 0o755
    assert "tests/exercises/test_00_warmup.py" in names and "particles/course/worker/main.py" in names
    assert not [n for n in names if n.startswith(("solutions", "tests/grader"))]
    assert [n for n in names if n.startswith("exercises")] == ["exercises/00_warmup.ipynb"]
    note = zipfile.ZipFile(bundle).read("GRADESCOPE.md").decode()
    assert "| 00_warmup | 1 | 2 |" in note and "manual question" in note
    assert "--metadata" in zipfile.ZipFile(bundle).read("run_autograder").decode()
    setup = zipfile.ZipFile(bundle).read("setup.sh").decode()
    assert "pip install" in setup
    assert subprocess.run(["bash", "-n", "-c", setup]).returncode == 0


def test_run_autograder_grades_the_master(bundle, tmp_path):
    """run_autograder against a fake /autograder grades a correct notebook to full marks, hidden tests included."""
    root = _autograder_tree(bundle, tmp_path / "autograder", (ROOT / "solutions" / "00_warmup.ipynb").read_text())
    results = _run_autograder(root)
    assert results["score"] == results["extra_data"]["max_score"] == 11
    tests = [t for t in results["tests"] if not t["extra_data"].get("written")]
    assert len(tests) == 8 and {t["status"] for t in tests} == {"passed"}
    # the written question: 0 of 0 here, graded by hand on Gradescope for its 2 points
    (written,) = [t for t in results["tests"] if t["extra_data"].get("written")]
    assert written["score"] == written["max_score"] == 0 and written["extra_data"]["answered"] is True
    assert "graded by hand on Gradescope (2 points)" in written["output"]
    assert "Written answers: 1 of 1 filled in" in results["output"]
    assert {"name", "score", "max_score", "status", "output", "visibility"} <= set(results["tests"][0])
    visible = sum(t["max_score"] for t in results["tests"] if t["visibility"] == "visible")
    assert visible < 11 and results["execution_time"] > 0  # hidden tests are hidden until grades are published
    assert f"00_warmup: {visible:g} / {visible:g} points on the tests you can see" in results["output"]
    # the same sandbox as `particles grade`, and the output says which layers were active
    expected = "namespaces (bubblewrap)" if isolation.probe()["namespaces"] else "no namespaces"
    assert f"Sandbox of your code: {expected}" in results["output"]
    assert results["extra_data"]["sandbox"]["00_warmup"]["audit_hook"] is True


def test_run_autograder_survives_a_broken_submission(bundle, tmp_path):
    """A submission that is not a notebook still yields a results.json with score 0 and reasons.

    With a course file in the source and Gradescope's submission metadata, the submission's time is
    Gradescope's created_at, and an extension may name the submitter's e-mail.
    """
    root = _autograder_tree(bundle, tmp_path / "autograder", "this is not JSON")
    (root / "source" / "course.toml").write_text(
        "[exercises.00_warmup]\ndeadline = 2026-10-01T23:59:00-07:00\n[late]\npenalty_per_day = 0.25\n"
        "[extensions.\"student@example.com\"]\n00_warmup = 1\n")
    (root / "submission_metadata.json").write_text(json.dumps({
        "id": 1, "created_at": "2026-10-04T08:00:00.365935-07:00",
        "users": [{"email": "student@example.com", "id": 1234, "name": "Student User"}]}))
    results = _run_autograder(root)
    assert results["score"] == 0 and results["extra_data"]["max_score"] == 11
    tests = [t for t in results["tests"] if not t["extra_data"].get("written")]
    assert all(t["output"].startswith("not run: your notebook was not graded") for t in tests)
    assert results["output"].count("could not be read") == 1  # the reason, once
    late = results["extra_data"]["late"]["00_warmup"]
    assert (late["days_late"], late["penalty"]) == (2, 5.5) and late["source"] == "Gradescope's submission metadata"
    assert "(extension of 1 day(s) for student@example.com)" in late["reason"]
    assert "Late: submitted" in results["output"] and "-5.5" not in results["output"]  # hidden tests: no points


def test_run_autograder_writes_a_result_even_when_grading_cannot_start(bundle, tmp_path):
    """If the grader cannot even start, run_autograder still leaves a results.json that says so."""
    root = _autograder_tree(bundle, tmp_path / "autograder", "{}")
    shutil.rmtree(root / "source" / "particles")
    env = dict(os.environ, AUTOGRADER_ROOT=str(root), PARTICLES_PYTHON="/nonexistent/python")
    subprocess.run([str(root / "source" / "run_autograder")], env=env, capture_output=True, timeout=60)
    results = json.loads((root / "results" / "results.json").read_text())
    assert results["score"] == 0 and "could not grade" in results["output"]


def test_run_autograder_with_no_notebook(bundle, tmp_path):
    """An empty submission scores 0 of 11 with a reason on every test."""
    root = _autograder_tree(bundle, tmp_path / "autograder", "{}")
    (root / "submission" / "my_warmup.ipynb").unlink()
    (root / "submission" / "notes.txt").write_text("I forgot the notebook")
    results = _run_autograder(root)
    assert results["score"] == 0 and results["extra_data"]["max_score"] == 11
    assert results["output"].count("no notebook") == 1
    assert all(t["output"].startswith("not run") for t in results["tests"] if not t["extra_data"].get("written"))
    assert [t["max_score"] for t in results["tests"] if t["extra_data"].get("written")] == [0]
