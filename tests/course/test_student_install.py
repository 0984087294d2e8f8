"""The student's path, from a venv holding only what a student installs.

A student gets the release bundle (:func:`particles.course.release.notebooks.write_bundle`)
and installs it with ``pip install -e .``: the base dependencies of
``pyproject.toml``, no extras. The venv here is that install, built without
the network: a ``--without-pip`` venv whose site-packages hard-links the
distributions of the base requirements' closure (read from the test run's own
environment with ``importlib.metadata``, extras and markers as pip evaluates
them) and a ``.pth`` file naming the bundle, as an editable install does.
Nothing of ``[dev]`` (pytest-xdist, ipywidgets) or ``[fast]`` (numba) is there.

In it, ``particles.check`` on every untouched stub scores 0 and names the
functions left to write; on every exercise filled in with its master's
solutions, full marks; neither prints an error of a cell the course provides;
the written answers count 0 of N and N of N. Without pytest the check refuses
with the command that installs it.
"""

import json
import os
import re
import shutil
import subprocess
import sys
import venv
from importlib import metadata
from pathlib import Path

import nbformat
import pytest
from packaging.markers import default_environment
from packaging.requirements import Requirement

from particles.course.release.answers import SLOT_KEY, answer_slots
from particles.course.release.notebooks import BEGIN, END, _instructor_only, release_notebook, write_bundle

ROOT = Path(__file__).resolve().parents[2]
EXERCISES = sorted(p.stem for p in (ROOT / "solutions").glob("[0-9][0-9]_*.ipynb"))


def _closure(requirements):
    """Distributions that the requirement strings need, transitively (markers evaluated, no extras)."""
    env = default_environment()
    seen, queue = {}, list(requirements)
    while queue:
        req = Requirement(queue.pop())
        if req.marker is not None and not req.marker.evaluate(dict(env, extra="")):
            continue
        name = re.sub(r"[-_.]+", "-", req.name).lower()
        if name in seen:
            continue
        try:
            dist = metadata.distribution(req.name)
        except metadata.PackageNotFoundError:
            continue
        seen[name] = dist
        wanted = set(req.extras)
        for sub in dist.requires or []:
            subreq = Requirement(sub)
            if subreq.marker is None:
                queue.append(sub)
            elif any(subreq.marker.evaluate(dict(env, extra=e)) for e in wanted | {""}):
                queue.append(str(Requirement(f"{subreq.name}{subreq.specifier}")) if subreq.extras == set()
                             else sub.split(";")[0])
    return seen


def _base_requirements():
    text = (ROOT / "pyproject.toml").read_text()
    block = text.split("dependencies = [", 1)[1].split("\n]", 1)[0]
    return re.findall(r'^\s*"([^"]+)"', block, re.M)


def _link(source, target):
    try:
        os.link(source, target)
    except OSError:
        shutil.copy2(source, target)


def student_venv(folder, bundle, without=()):
    """A venv in `folder` with the base install of `bundle` (minus the distributions `without`); its python."""
    venv.EnvBuilder(with_pip=False, symlinks=True).create(folder)
    python = folder / "bin" / "python"
    site = Path(subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    dists = _closure(_base_requirements())
    for name, dist in dists.items():
        if name in without:
            continue
        tops = {Path(str(f)).parts[0] for f in dist.files or [] if not str(f).startswith("..")}
        base = Path(dist.locate_file(""))
        for top in tops:  # hard links (copies across file systems): the grader's walls hide symlinks' targets
            source, target = base / top, site / top
            if target.exists() or not source.exists():
                continue
            if source.is_dir():
                shutil.copytree(source, target, copy_function=_link, symlinks=True)
            else:
                _link(source, target)
    (site / "particles-bundle.pth").write_text(str(bundle) + "\n")
    return python


def finished(exercise):
    """The released stub of `exercise` filled in as a student would: the master's code and answers."""
    master = nbformat.read(str(ROOT / "solutions" / f"{exercise}.ipynb"), as_version=4)
    student = release_notebook(master, exercise)
    code = {c.get("id"): c.source for c in master.cells if c.cell_type == "code" and not _instructor_only(c)}
    blocks = []
    for cell in master.cells:
        if cell.cell_type == "markdown":
            blocks += re.findall(rf"{re.escape(BEGIN)}\n(.*?)\n\s*{re.escape(END)}", cell.source, re.S)
    for cell in student.cells:
        if cell.cell_type == "code" and cell.get("id") in code:
            cell.source = code[cell["id"]]
        k = cell.get("metadata", {}).get("particles", {}).get(SLOT_KEY)
        if k:
            cell.source = blocks[k - 1]
    return student


SCRIPT = r"""
import json, sys, particles
root, out = sys.argv[1], {}
for exercise, path in json.loads(sys.argv[2]).items():
    try:
        r = particles.check(exercise, notebook=path, root=root)
        out[path] = {"score": r.score, "max": r.max_score, "n": len(r.tests), "unwritten": r.unwritten,
                     "notes": r.notes, "text": str(r)}
    except Exception as error:
        out[path] = {"error": f"{type(error).__name__}: {error}"}
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(python of the student's venv, the bundle, {exercise: (stub path, finished path)})."""
    tmp = tmp_path_factory.mktemp("student")
    bundle = tmp / "course"
    write_bundle(ROOT, bundle)
    notebooks = {}
    for exercise in EXERCISES:
        done = bundle / "exercises" / f"{exercise}-done.ipynb"
        nbformat.write(finished(exercise), str(done))
        notebooks[exercise] = (bundle / "exercises" / f"{exercise}.ipynb", done)
    return student_venv(tmp / "venv", bundle), bundle, notebooks


def _student_env():
    return {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}


def _run(python, bundle, jobs):
    env = _student_env()
    proc = subprocess.run([python, "-c", SCRIPT, str(bundle), json.dumps(jobs)], capture_output=True, text=True,
                          cwd=bundle, env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_the_student_venv_holds_the_base_install_only(installed):
    """The student's venv imports the bundle's particles and pytest, and none of the extras."""
    python, bundle, _ = installed
    probe = ("import importlib.util as u, particles, pytest; "
             "print(particles.__file__, [m for m in ('xdist', 'numba', 'ipywidgets') if u.find_spec(m)])")
    out = subprocess.run([python, "-c", probe], capture_output=True, text=True, check=True, cwd=bundle.parent,
                         env=_student_env()).stdout
    assert out.startswith(str(bundle)) and out.strip().endswith("[]"), out


def test_every_stub_scores_0_and_names_what_is_left_to_write(installed):
    """Every untouched stub scores 0, names its unwritten functions, 0 of N answers, no provided-cell error."""
    python, bundle, notebooks = installed
    results = _run(python, bundle, {ex: str(stub) for ex, (stub, _) in notebooks.items()})
    for exercise, (stub, _) in notebooks.items():
        r = results[str(stub)]
        assert "error" not in r, (exercise, r)
        assert r["n"] > 0 and r["score"] == 0 and r["max"] > 0, (exercise, r["text"])
        assert r["unwritten"] and "Not implemented yet:" in r["text"], (exercise, r["text"])
        assert "All public tests pass" not in r["text"], exercise
        assert not [n for n in r["notes"] if n.startswith("While loading")], (exercise, r["notes"])
        asked = len(answer_slots(release_notebook(nbformat.read(str(ROOT / "solutions" / f"{exercise}.ipynb"),
                                                                as_version=4), exercise)))
        if asked:
            assert any(n.startswith(f"Written answers: 0 of {asked} filled in") for n in r["notes"]), r["notes"]


def test_every_finished_exercise_gets_full_marks(installed):
    """Every exercise filled in with its master's solutions scores full marks, N of N answers, no provided-cell error."""
    python, bundle, notebooks = installed
    results = _run(python, bundle, {ex: str(done) for ex, (_, done) in notebooks.items()})
    for exercise, (_, done) in notebooks.items():
        r = results[str(done)]
        assert "error" not in r, (exercise, r)
        assert r["n"] > 0 and r["score"] == r["max"] > 0, (exercise, r["text"])
        assert not r["unwritten"] and "All public tests pass" in r["text"], (exercise, r["text"])
        assert not [n for n in r["notes"] if n.startswith("While loading")], (exercise, r["notes"])
        asked = len(answer_slots(json.loads(json.dumps(finished(exercise)))))
        if asked:
            assert any(n.startswith(f"Written answers: {asked} of {asked} filled in") for n in r["notes"]), \
                r["notes"]


def test_without_pytest_the_check_refuses_with_the_command_that_fixes_it(installed, tmp_path):
    """In a student venv without pytest the check raises CheckError naming the command that installs it."""
    _, bundle, notebooks = installed
    python = student_venv(tmp_path / "venv", bundle, without={"pytest"})
    stub = str(notebooks[EXERCISES[0]][0])
    r = _run(python, bundle, {EXERCISES[0]: stub})[stub]
    assert r.get("error", "").startswith("CheckError:"), r
    assert "pip install pytest" in r["error"] and "nothing was checked" in r["error"], r["error"]
