"""Release: student notebooks from the instructors' masters, and the student bundle.

``solutions/NN_topic.ipynb`` is the only place an exercise is written. The
student version ``exercises/NN_topic.ipynb`` is generated from it:

* in code cells, the lines between ``### BEGIN SOLUTION`` and
  ``### END SOLUTION`` become ``raise NotImplementedError(...)`` at the same
  indentation, so the function keeps its signature and docstring;
* in markdown cells, each block between the same markers becomes a cell of
  its own, an answer slot holding the prompt "*Your answer here.*" (see
  :mod:`particles.course.release.answers`: one slot per question, so that answers
  are counted and graded one by one);
* cells whose first line is ``### INSTRUCTOR ONLY``, or that carry the tag
  ``instructor-only``, are dropped;
* outputs, execution counts and editor metadata are cleared, and the
  notebook metadata records which exercise it is (the grader reads it, so a
  renamed file is still recognised).

The output is a pure function of the master (no dates, no random ids), so
running it twice changes nothing and ``--check`` can compare byte for byte.
"""

import ast
import copy
import json
import re
import shutil
from pathlib import Path

import nbformat

from .answers import ANSWER_PROMPT, BEGIN, END, SLOT_KEY, STUB_LINE, solution_parts
from ..paths import exercise_tests

__all__ = ["BEGIN", "END", "INSTRUCTOR", "ReleaseError", "release_notebook", "render", "release",
           "stale_exercises", "public_tests", "write_bundle"]

INSTRUCTOR = "### INSTRUCTOR ONLY"
INSTRUCTOR_TAG = "instructor-only"


class ReleaseError(ValueError):
    """A master notebook cannot be released (unbalanced markers, unreadable file)."""


def _source(cell):
    source = cell.get("source", "")
    return "".join(source) if isinstance(source, list) else source


def _enclosing_function(lines, index, indent):
    """Name of the ``def`` that contains line `index` (indented by `indent`), or None."""
    for line in reversed(lines[:index]):
        match = re.match(r"(\s*)(?:async\s+)?def\s+(\w+)", line)
        if match and len(match.group(1)) < len(indent):
            return match.group(2)
    return None


def _strip_solutions(source, kind, where):
    lines = source.split("\n")
    out, inside, start = [], False, None
    for k, line in enumerate(lines):
        marker = line.strip()
        if marker == BEGIN:
            if inside:
                raise ReleaseError(f"{where}: {BEGIN} inside another solution block (line {k + 1})")
            inside, start = True, k
            indent = line[: len(line) - len(line.lstrip())]
            if kind == "code":
                name = _enclosing_function(lines, k, indent)
                what = f"{name} is not written yet" if name else "this part is not written yet"
                out.append(f"{indent}{STUB_LINE}")
                out.append(f'{indent}raise NotImplementedError("{what}")')
            else:
                out.append(ANSWER_PROMPT)
        elif marker == END:
            if not inside:
                raise ReleaseError(f"{where}: {END} without {BEGIN} (line {k + 1})")
            inside = False
        elif not inside:
            out.append(line)
    if inside:
        raise ReleaseError(f"{where}: {BEGIN} (line {start + 1}) without {END}")
    return "\n".join(out)


def _instructor_only(cell):
    first = _source(cell).lstrip().split("\n", 1)[0].strip()
    tags = cell.get("metadata", {}).get("tags", [])
    return first.startswith(INSTRUCTOR) or INSTRUCTOR_TAG in tags


def release_notebook(master, exercise, source_name=None):
    """The student version of a master notebook.

    Parameters
    ----------
    master : dict or NotebookNode
        The master, as read by ``nbformat.read(..., as_version=4)``.
    exercise : str
        Its name, ``NN_topic``.
    source_name : str, optional
        Where the master lives, for error messages and the metadata.

    Returns
    -------
    NotebookNode

    Raises
    ------
    ReleaseError
        On unbalanced solution markers.
    """
    source_name = source_name or f"solutions/{exercise}.ipynb"
    cells, slots = [], 0
    for index, cell in enumerate(master.get("cells", [])):
        if _instructor_only(cell):
            continue
        kind = cell.get("cell_type")
        where = f"{source_name}, cell {index + 1}"
        tags = [t for t in cell.get("metadata", {}).get("tags", []) if t != INSTRUCTOR_TAG]
        metadata = {"tags": tags} if tags else {}
        cell_id = cell.get("id") or f"cell-{index}"
        if kind == "markdown" and BEGIN in _source(cell):
            _strip_solutions(_source(cell), kind, where)  # the markers' checks
            for j, (part, text) in enumerate(solution_parts(_source(cell))):
                if part == "answer":
                    slots += 1
                    new = nbformat.v4.new_markdown_cell(
                        ANSWER_PROMPT, metadata={"particles": {SLOT_KEY: slots}})
                    new["id"] = f"{cell_id}-answer-{slots}"
                else:
                    new = nbformat.v4.new_markdown_cell(text, metadata=copy.deepcopy(metadata))
                    new["id"] = cell_id if j == 0 else f"{cell_id}-{j}"
                cells.append(new)
            continue
        text = _strip_solutions(_source(cell), kind, where)
        if kind == "code":
            new = nbformat.v4.new_code_cell(text, metadata=metadata)
        elif kind == "markdown":
            new = nbformat.v4.new_markdown_cell(text, metadata=metadata)
        else:
            new = nbformat.v4.new_raw_cell(text, metadata=metadata)
        new["id"] = cell_id
        cells.append(new)
    notebook = nbformat.v4.new_notebook(cells=cells)
    notebook.nbformat, notebook.nbformat_minor = 4, 5
    kernelspec = master.get("metadata", {}).get("kernelspec") or {
        "name": "python3", "display_name": "Python 3", "language": "python"}
    notebook.metadata = {
        "kernelspec": copy.deepcopy(kernelspec),
        "language_info": {"name": "python"},
        "particles": {"exercise": exercise, "generated_from": source_name,
                      "note": "generated by `particles release`: edit the master, not this file"},
    }
    return notebook


def render(notebook):
    """The notebook as the exact text that is written (nbformat's layout, final newline)."""
    text = nbformat.writes(notebook)
    return text if text.endswith("\n") else text + "\n"


def read_master(path):
    """The master notebook at `path` (nbformat 4); :class:`ReleaseError` when it is not a notebook."""
    try:
        return nbformat.read(str(path), as_version=4)
    except Exception as error:  # nbformat raises several kinds; all mean "not a notebook"
        raise ReleaseError(f"{path} is not a readable notebook: {error}") from None


def _expected(root):
    root = Path(root)
    out = {}
    for master in sorted((root / "solutions").glob("*.ipynb")):
        notebook = release_notebook(read_master(master), master.stem, f"solutions/{master.name}")
        out[root / "exercises" / master.name] = render(notebook)
    return out


def stale_exercises(root):
    """Problems that ``particles release --check`` reports, as readable lines.

    An exercise that differs from what its master generates, an exercise
    without a master, and a master committed with outputs.
    """
    root = Path(root)
    problems = []
    expected = _expected(root)
    for path, text in expected.items():
        if not path.exists():
            problems.append(f"{path.relative_to(root)} is missing")
        elif path.read_text(encoding="utf-8") != text:
            problems.append(f"{path.relative_to(root)} is out of date with solutions/{path.name}")
    for path in sorted((root / "exercises").glob("*.ipynb")):
        if path not in expected:
            problems.append(f"{path.relative_to(root)} has no master in solutions/")
    for master in sorted((root / "solutions").glob("*.ipynb")):
        cells = json.loads(master.read_text(encoding="utf-8")).get("cells", [])
        if any(c.get("outputs") or c.get("execution_count") for c in cells if c.get("cell_type") == "code"):
            problems.append(f"solutions/{master.name} has outputs; clear them before committing")
    return problems


def release(root, check=False):
    """Write ``exercises/*.ipynb`` from ``solutions/*.ipynb`` (or only check them).

    Returns
    -------
    list of str
        With ``check=False``: the files written (those that changed). With
        ``check=True``: the problems found (empty when all is up to date).
    """
    root = Path(root)
    if check:
        return stale_exercises(root)
    written = []
    (root / "exercises").mkdir(exist_ok=True)
    for path, text in _expected(root).items():
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
            written.append(str(path.relative_to(root)))
    return written


def _is_hidden(node):
    for decorator in getattr(node, "decorator_list", []):
        target = decorator.func if isinstance(decorator, ast.Call) else decorator
        if isinstance(target, ast.Attribute) and target.attr == "hidden":
            return True
        if isinstance(target, ast.Name) and target.id == "hidden":
            return True
    return False


def public_tests(source, name="tests"):
    """The source of an exercise test module without its hidden tests.

    Removes every top-level test function or class decorated with
    ``@pytest.mark.hidden``, decorators included.

    Raises
    ------
    ReleaseError
        When hidden tests remain in a form this function does not remove
        (e.g. a module-level ``pytestmark``).
    """
    tree = ast.parse(source)
    lines = source.split("\n")
    drop = set()
    for node in tree.body:
        if _is_hidden(node):
            start = min([d.lineno for d in node.decorator_list] + [node.lineno])
            drop.update(range(start - 1, node.end_lineno))
    kept = [line for k, line in enumerate(lines) if k not in drop]
    text = re.sub(r"\n{4,}", "\n\n\n", "\n".join(kept)).rstrip("\n") + "\n"
    for node in ast.walk(ast.parse(text)):
        marked = isinstance(node, ast.Attribute) and node.attr == "hidden"
        if marked or _is_hidden(node):
            raise ReleaseError(
                f"{name}, line {node.lineno}: a hidden marker remains after removing hidden tests; "
                "mark each hidden test function or class with @pytest.mark.hidden"
            )
    header = "# Public tests of this exercise. The autograder also runs hidden tests with random parameters.\n"
    return header + text


def write_bundle(root, dest):
    """Write what students receive into `dest`: and nothing else.

    The bundle holds the library (``particles/``), ``lectures/``, the
    released ``exercises/`` (regenerated from the masters, so it is never
    stale), the public tests (``tests/exercises/``, hidden tests removed),
    ``tests/conftest.py``, ``README.md``, ``pyproject.toml`` and ``Makefile``.
    No masters, no hidden tests, no grader corpus, no benchmarks.

    Returns
    -------
    list of str
        The files written, relative to `dest`.

    Raises
    ------
    ValueError
        When `dest` exists and is not empty.
    """
    root, dest = Path(root), Path(dest)
    if dest.exists() and any(dest.iterdir()):
        raise ValueError(f"dest must be a new or empty folder, but {dest} is not empty")
    dest.mkdir(parents=True, exist_ok=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".ipynb_checkpoints")
    for name in ("README.md", "pyproject.toml", "Makefile", "LICENSE"):
        if (root / name).exists():
            shutil.copy2(root / name, dest / name)
    shutil.copytree(root / "particles", dest / "particles", ignore=ignore)
    if (root / "lectures").is_dir():
        shutil.copytree(root / "lectures", dest / "lectures", ignore=ignore)
    (dest / "exercises").mkdir()
    if (root / "exercises" / "README.md").exists():
        shutil.copy2(root / "exercises" / "README.md", dest / "exercises" / "README.md")
    for path, text in _expected(root).items():
        (dest / "exercises" / path.name).write_text(text, encoding="utf-8")
    (dest / "tests" / "exercises").mkdir(parents=True)
    if (root / "tests" / "conftest.py").exists():
        shutil.copy2(root / "tests" / "conftest.py", dest / "tests" / "conftest.py")
    for name, path in exercise_tests(root).items():
        text = public_tests(path.read_text(encoding="utf-8"), str(path.relative_to(root)))
        (dest / "tests" / "exercises" / path.name).write_text(text, encoding="utf-8")
    return sorted(str(p.relative_to(dest)) for p in dest.rglob("*") if p.is_file())
