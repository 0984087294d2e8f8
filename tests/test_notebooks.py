"""The notebooks run top to bottom in a fresh Jupyter kernel (nbclient).

* lectures and masters (``solutions/``) must run without any error;
* a released exercise is run too, with errors allowed: its solution cells
  raise ``NotImplementedError`` by design, so the test asserts that the first
  error of the notebook is a ``NotImplementedError`` (nothing breaks before
  the student's work starts, e.g. an import that release dropped) and that
  every cell that fails after it fails because of that missing work or its
  consequences. Structure (stubs, no leaked solution) is checked in
  ``tests/test_release.py``.
"""

import re
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[1]
CLEAN = sorted((ROOT / "lectures").glob("*.ipynb")) + sorted((ROOT / "solutions").glob("*.ipynb"))
EXERCISES = sorted((ROOT / "exercises").glob("*.ipynb"))


def _run(path, allow_errors=False):
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(nb, timeout=120, kernel_name="python3", allow_errors=allow_errors,
                            resources={"metadata": {"path": str(path.parent)}})
    client.execute()
    return nb


def _errors(nb):
    return [(k, o["ename"]) for k, c in enumerate(nb.cells) if c.cell_type == "code"
            for o in c.get("outputs", []) if o.get("output_type") == "error"]


@pytest.mark.parametrize("path", CLEAN, ids=[f"{p.parent.name}/{p.name}" for p in CLEAN])
def test_notebook_runs_clean(path):
    """A lecture or master notebook runs top to bottom in a fresh kernel without errors."""
    nb = _run(path)
    assert _errors(nb) == []
    if path.parent.name == "solutions":
        last = "".join(o.get("data", {}).get("text/plain", "") + o.get("text", "")
                       for o in nb.cells[-1].get("outputs", []))
        assert "points on the public tests" in last and "All public tests pass" in last, last


@pytest.mark.parametrize("path", EXERCISES, ids=[p.name for p in EXERCISES])
def test_released_exercise_runs_up_to_the_stubs(path):
    """A released exercise runs; its first error is the NotImplementedError of a stub."""
    nb = _run(path, allow_errors=True)
    errors = _errors(nb)
    assert errors and errors[0][1] == "NotImplementedError", errors
    first_code = [k for k, c in enumerate(nb.cells) if c.cell_type == "code"][0]
    assert all(k > first_code for k, _ in errors)
    check = "".join(o.get("data", {}).get("text/plain", "") for o in nb.cells[-1].get("outputs", []))
    assert re.search(r"\b0 / \d+ points on the public tests", check) and "not implemented yet" in check, check
