"""The grading driver keeps its records: written as they are made, resumed, the same alone and in a batch."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent.parent / "grader"))
import corpus  # noqa: E402

from particles.course.walls import isolation  # noqa: E402
from particles.course.grading.discovery import Unit  # noqa: E402
from particles.course.grading.driver import LibraryChanged, _batches, grade, grade_batch  # noqa: E402

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


def test_records_are_written_as_they_are_made_and_resumed(tmp_path):
    """Each notebook's record is on disk after its batch; --resume keeps unchanged ones and grades the rest."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    for k in range(3):
        _write(subs, f"s{k}", corpus.MASTER.read_text())
    first = grade([subs], out, seed=11, root=ROOT)
    records = sorted(p.name for p in (out / "records").glob("*.json"))
    assert records == [f"s{k}_00_warmup__00_warmup.json" for k in range(3)]
    assert first["resumed"] == 0
    # one notebook changes, one record is lost (a run stopped before it): both are graded again
    _write(subs, "s1", corpus.STUB.read_text())
    (out / "records" / "s2_00_warmup__00_warmup.json").unlink()
    again = grade([subs], out, seed=11, root=ROOT, resume=True)
    assert again["resumed"] == 1
    scores = {s: sum(t["points"] for t in r[0]["tests"] if t["passed"]) for s, r in again["students"].items()}
    assert scores == {"s0_00_warmup": 11, "s1_00_warmup": 0, "s2_00_warmup": 11}
    assert (out / "gradebook.csv").read_text().count("\n") == 4
    # other options: nothing is kept
    assert grade([subs], out, seed=12, root=ROOT, resume=True)["resumed"] == 0
    with pytest.raises(ValueError, match="resume needs out"):
        grade([subs], None, resume=True, root=ROOT)


def test_a_killed_driver_keeps_its_records(tmp_path):
    """A `particles grade` killed mid-run leaves the finished records; --resume grades only the rest."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    for k in range(6):
        _write(subs, f"s{k}", corpus.MASTER.read_text())
    command = [sys.executable, "-m", "particles", "grade", str(subs), "--out", str(out), "--seed", "5",
               "--root", str(ROOT)]
    driver = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list((out / "records").glob("*.json"))) < 2:
        time.sleep(0.05)
    os.killpg(driver.pid, signal.SIGKILL)
    driver.wait()
    kept = len(list((out / "records").glob("*.json")))
    assert 2 <= kept
    done = subprocess.run(command + ["--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert f"resumed: {kept} record(s)" in done.stdout or kept == 6
    assert len(list((out / "records").glob("*.json"))) == 6
    assert "sandbox: " in done.stdout


def test_a_record_cut_off_before_its_rename_is_no_record(tmp_path, monkeypatch):
    """Killed between writing and renaming: the folder holds no ``*.json`` but the finished ones, nothing to load."""
    from particles.course.results.records import SubmissionRecord
    from particles.course.results.store import RecordStore

    subs, out = tmp_path / "subs", tmp_path / "out"
    _write(subs, "s0", corpus.MASTER.read_text())
    grade([subs], out, seed=3, root=ROOT)
    store = RecordStore(out / "records", {"other": "options"})
    (record,) = [json.loads(p.read_text()) for p in (out / "records").glob("*.json")]
    monkeypatch.setattr(os, "replace", lambda *args: None)  # the rename never happens
    store.path("s0_00_warmup", "00_warmup").unlink()
    record.pop("options")
    store.save(SubmissionRecord.from_dict(record))
    assert list((out / "records").glob("*.json")) == []
    assert len(list((out / "records").glob(".record-*"))) == 1


def test_a_changed_library_fails_the_run_loudly(tmp_path, monkeypatch):
    """When the library differs at the end of a run, grade raises LibraryChanged and marks the outputs."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    _write(subs, "s0", corpus.MASTER.read_text())
    monkeypatch.setattr(isolation, "library_changes", lambda before, package=None: ["course/grading/expect.py"])
    with pytest.raises(LibraryChanged, match="expect.py") as caught:
        grade([subs], out, seed=1, root=ROOT)
    assert "s0_00_warmup" in caught.value.summary["students"]
    assert "Do not trust" in (out / "LIBRARY-CHANGED.txt").read_text()


COURSE = """
[late]
penalty_per_day = 0.1
cap = 0.5

[exercises.00_warmup]
deadline = 2026-10-01T23:59:00+01:00

[extensions.alice]
00_warmup = 3
"""


def _late_course(tmp_path):
    """alice and bob submit the master; alice has a 3-day extension, bob is 10 hours late."""
    subs = tmp_path / "subs"
    for student in ("alice", "bob"):
        (subs / student).mkdir(parents=True)
        (subs / student / "00_warmup.ipynb").write_text(corpus.MASTER.read_text())
    (tmp_path / "course.toml").write_text(COURSE)
    (tmp_path / "times.csv").write_text("student,exercise,submitted\nalice,00_warmup,2026-10-03T10:00:00+01:00\n"
                                        "bob,00_warmup,2026-10-02T09:59:00+01:00\n")
    return subs, {"course": tmp_path / "course.toml", "times": tmp_path / "times.csv", "seed": 5, "root": ROOT}


def test_late_work_is_penalized_and_one_student_is_regraded_alone(tmp_path):
    """Records carry the late decision and the tests version; --student regrades alice, bob's record is kept."""
    from particles.course.grading import versions

    subs, options = _late_course(tmp_path)
    out = tmp_path / "out"
    grade([subs], out, **options)
    records = {p.name.split("__")[0]: json.loads(p.read_text()) for p in (out / "records").glob("*.json")}
    assert records["alice"]["late"]["penalty"] == 0 and "(extension of 3 day(s) for alice)" in \
        records["alice"]["late"]["reason"]
    bob = records["bob"]["late"]
    assert (bob["days_late"], bob["penalty"], bob["source"]) == (1, 1.1, "the times file")
    assert bob["reason"].startswith("submitted 10 hours after the deadline 2026-10-01 23:59 +01:00: "
                                    "-10% of the exercise's points")
    assert {r["tests_version"] for r in records.values()} == {versions.tests_version(ROOT, "00_warmup")}
    assert "alice,11,11,11" in (out / "gradebook.csv").read_text()
    assert "bob,9.9,9.9,11" in (out / "gradebook.csv").read_text()
    feedback = (out / "bob" / "feedback.md").read_text()
    assert "**Total: 9.9 / 11 points**" in feedback
    assert "Late: raw score 11, penalty -1.1 of 11 points (submitted 10 hours" in feedback
    assert "Graded by tests version tests=" in feedback
    assert "Graded by tests version" in (out / "bob" / "feedback.html").read_text()
    results = json.loads((out / "bob" / "results.json").read_text())
    assert results["score"] == 9.9 and results["extra_data"]["late"]["00_warmup"]["penalty"] == 1.1
    assert "Late: raw score 11" in results["output"]

    # bad uses of --student, refused before anything is graded
    with pytest.raises(ValueError, match="unknown student 'carol'.*the students are alice, bob"):
        grade([subs], out, students=["carol"], **options)
    with pytest.raises(ValueError, match="holds none"):
        grade([subs], tmp_path / "empty", students=["alice"], **options)
    with pytest.raises(ValueError, match="student needs out"):
        grade([subs], None, students=["alice"], **options)

    # alice hands in the stub instead: only she is graded again
    (subs / "alice" / "00_warmup.ipynb").write_text(corpus.STUB.read_text())
    bob_bytes = (out / "records" / "bob__00_warmup.json").read_bytes()
    again = grade([subs], out, students=["alice"], **options)
    assert list(again["students"]) == ["alice"] and again["students"]["alice"][0].score == 0
    assert (out / "records" / "bob__00_warmup.json").read_bytes() == bob_bytes
    gradebook = (out / "gradebook.csv").read_text()
    assert "alice,0,0,11" in gradebook and "bob,9.9,9.9,11" in gradebook
    assert "**Total: 0 / 11 points**" in (out / "alice" / "feedback.md").read_text()

    # a new extension for bob: --resume keeps both grades and only remakes bob's late decision
    options["course"].write_text(COURSE + "\n[extensions.bob]\n00_warmup = 1\n")
    resumed = grade([subs], out, resume=True, **options)
    assert resumed["resumed"] == 2 and resumed["students"]["bob"][0].penalty == 0
    assert json.loads((out / "records" / "bob__00_warmup.json").read_text())["late"]["days_late"] == 0
    assert "bob,11,11,11" in (out / "gradebook.csv").read_text()


def test_resume_grades_again_the_records_of_a_changed_test(tmp_path, monkeypatch):
    """--resume keeps a record only when its tests version is the current one of its exercise."""
    from particles.course.grading import driver
    from particles.course.grading.discovery import notebook_digest
    from particles.course.results.records import SubmissionRecord, TestRecord

    subs, options = _late_course(tmp_path)
    graded = []

    def fake_batch(units, root, **kwargs):  # no pytest session: complete records, as grade_batch makes them
        graded.extend(u.student for u in units)
        return [SubmissionRecord(student=u.student, exercise=u.exercise, notebook=str(u.notebook), complete=True,
                                 grader_status=0, notebook_sha256=notebook_digest(u.notebook),
                                 tests=[TestRecord(test="t", name="t", points=11, passed=True)],
                                 tests_version=driver.tests_version(root, u.exercise)) for u in units]

    monkeypatch.setattr(driver, "grade_batch", fake_batch)
    out = tmp_path / "out"
    grade([subs], out, **options)
    assert sorted(graded) == ["alice", "bob"]
    graded.clear()
    assert grade([subs], out, resume=True, **options)["resumed"] == 2 and graded == []
    real = driver.tests_version
    monkeypatch.setattr(driver, "tests_version", lambda root, exercise, library=None: real(root, exercise, "new"))
    assert grade([subs], out, resume=True, **options)["resumed"] == 0 and sorted(graded) == ["alice", "bob"]
    record = json.loads((out / "records" / "alice__00_warmup.json").read_text())
    assert record["tests_version"].endswith(" library=new")


@pytest.mark.parametrize("jobs", [1, 2, 4])
@pytest.mark.parametrize("sizes", [[15, 20, 17, 17, 14, 12], [17], [300], [1], [2, 1, 3], [21], [41, 3]])
def test_batches_cover_every_notebook_once_large_first_one_exercise_each(sizes, jobs):
    """Batches keep the notebooks' order, one exercise each, at most 20; none of one beside a larger one of its
    exercise; one exercise's batches never grow; and a run of many notebooks over several exercises takes
    fewer sessions than six per exercise (each session costs about 1 s to start)."""
    units = [Unit(f"s{e}_{k}", f"{e:02d}_topic", Path(f"s{e}_{k}.ipynb"))
             for e, n in enumerate(sizes) for k in range(n)]
    batches = _batches(units, jobs)
    assert [u for b in batches for u in b] == units
    assert all(0 < len(b) <= 20 and len({u.exercise for u in b}) == 1 for b in batches)
    for exercise in {u.exercise for u in units}:
        mine = [len(b) for b in batches if b[0].exercise == exercise]
        assert mine == [1] or 1 not in mine, mine
    if len(sizes) == 1:  # one exercise: sizes never grow, so the run ends on small batches
        assert all(a >= b for a, b in zip(map(len, batches), map(len, batches[1:])))
    if len(units) >= 60:
        assert len(batches) >= 2 * jobs
    if len(sizes) > 1 and len(units) >= 60:
        assert len(batches) < 6 * len(sizes)


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
