"""One grading session: a batch's verdicts equal each notebook's alone, one worker per notebook, no stray plugin."""

import json
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent.parent / "grader"))
import corpus  # noqa: E402

from particles.course.grading.discovery import Unit  # noqa: E402
from particles.course.grading.session import grade_batch  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]

HOSTILE = '''
import os, signal, glob

def euler_step(f, X, t, h):
    """A correct step that first tries every way out it knows (each refused), then answers."""
    for attempt in (lambda: os.kill(-1, signal.SIGKILL), lambda: os.kill(os.getppid(), signal.SIGKILL),
                    lambda: [open(p).read() for p in glob.glob("/tmp/particles-grade-*/grader/*.json")],
                    lambda: open(os.path.expanduser("~/../records.json"), "w").write("{}")):
        try:
            attempt()
        except BaseException:
            pass
    return X + h * f(X, t)
'''

KILLER = '''
import os

def total_force(x, v, m, g, d):
    """Ends its own worker."""
    os._exit(3)
'''


def _write(folder, name, notebook):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{name}_00_warmup.ipynb").write_text(json.dumps(notebook) if isinstance(notebook, dict) else notebook)


def test_honest_grade_is_the_same_alone_and_beside_hostile_ones(tmp_path):
    """The master's verdicts in one batch with two hostile notebooks equal its verdicts alone."""
    subs = tmp_path / "subs"
    _write(subs, "honest", corpus.MASTER.read_text())
    _write(subs, "hostile", corpus.build({"replace": {"euler_step": HOSTILE}}))
    _write(subs, "killer", corpus.build({"replace": {"total_force": KILLER}}))
    units = [Unit(name, "00_warmup", subs / f"{name}_00_warmup.ipynb") for name in ("hostile", "honest", "killer")]
    together = grade_batch(units, ROOT, seeds=[7, 7, 7], time_limit=5.0)
    alone = grade_batch([units[1]], ROOT, seeds=[7], time_limit=5.0)[0]
    verdicts = {t["test"]: (t["passed"], t["reason"]) for t in alone["tests"]}
    assert all(passed for passed, _ in verdicts.values()), verdicts
    assert {t["test"]: (t["passed"], t["reason"]) for t in together[1]["tests"]} == verdicts
    assert all(r["complete"] for r in together)
    hostile = {t["test"]: t for t in together[0]["tests"]}
    assert hostile["test_euler_step_circle"]["passed"]  # its attempts all failed, and it answered
    killer = {t["test"]: t for t in together[2]["tests"]}
    assert not killer["test_total_force_three_particles"]["passed"]
    assert "exit status 3" in killer["test_total_force_three_particles"]["reason"]
    assert together[1]["isolation"]["audit_hook"] is True and together[1]["sandbox"]


def test_each_notebook_of_a_batch_keeps_one_worker_through_tests_with_parameters(tmp_path):
    """A batch runs each notebook's tests together: one worker per notebook, even where tests have parameters.

    ``test_provot_pass_one_spring`` of exercise 03 has parameters of its own; pytest's ordering alone
    made the notebooks take turns there, and every turn started a new worker and loaded the notebook
    again.
    """
    master = ROOT / "solutions" / "03_provot.ipynb"
    units = []
    for name in ("ada", "bo"):
        (tmp_path / f"{name}.ipynb").write_bytes(master.read_bytes())
        units.append(Unit(name, "03_provot", tmp_path / f"{name}.ipynb"))
    records = grade_batch(units, ROOT, seeds=[5, 5])
    assert not [note for r in records for note in r["notes"] if "restarted" in note]
    assert all(r.complete and r.score == r.max_score for r in records), [r.score for r in records]
    parametrized = [t["test"] for t in records[1]["tests"] if t["test"].startswith("test_provot_pass_one_spring[")]
    assert len(parametrized) == 4, parametrized


def test_plugins_installed_beside_pytest_do_not_join_the_grading_sessions(tmp_path, monkeypatch):
    """A pytest plugin installed in the grader's environment (here one that fails every session it joins, found
    through its distribution's ``pytest11`` entry point, as pytest-randomly would be) is not loaded by the
    grading sessions: the master still gets full marks."""
    site = tmp_path / "site"
    (site / "evil_plugin-1.0.dist-info").mkdir(parents=True)
    (site / "evil_plugin-1.0.dist-info" / "METADATA").write_text("Metadata-Version: 2.1\nName: evil-plugin\nVersion: 1.0\n")
    (site / "evil_plugin-1.0.dist-info" / "entry_points.txt").write_text("[pytest11]\nevil = evil_plugin\n")
    (site / "evil_plugin.py").write_text(
        "import pathlib\n"
        f"def pytest_configure(config):\n    pathlib.Path({str(tmp_path / 'joined')!r}).write_text('x')\n"
        "def pytest_collection_modifyitems(items):\n    items.reverse()\n    raise SystemExit(4)\n")
    monkeypatch.setenv("PYTHONPATH", str(site))
    probe = subprocess.run([sys.executable, "-m", "pytest", "--co", "-q", "-p", "no:cacheprovider", str(tmp_path)],
                           capture_output=True, text=True, cwd=tmp_path)
    assert (tmp_path / "joined").exists(), probe.stdout + probe.stderr  # an ordinary pytest loads it
    (tmp_path / "joined").unlink()
    _write(tmp_path / "subs", "honest", corpus.MASTER.read_text())
    (record,) = grade_batch([Unit("honest", "00_warmup", tmp_path / "subs" / "honest_00_warmup.ipynb")], ROOT, seeds=[7])
    assert record["complete"] and all(t["passed"] for t in record["tests"]), record["tests"]
    assert not (tmp_path / "joined").exists()
