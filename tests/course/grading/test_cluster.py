"""The run stage on a Dask cluster: the same records as a local run, Ctrl-C, duplicates dropped, addresses checked."""

import os
import signal
import socket
import subprocess
import sys

import pytest

pytest.importorskip("distributed")

from particles.course.grading import cluster_tasks  # noqa: E402
from particles.course.grading.cluster import ClusterRunner, check_address, is_loopback  # noqa: E402
from particles.course.grading.cluster_tasks import ClusterError  # noqa: E402
from particles.course.grading.driver import grade  # noqa: E402
from particles.course.grading.options import GradeOptions  # noqa: E402

from .helpers import ROOT, SEED, folder_records, run_statuses, wait_for  # noqa: E402


def test_importing_the_driver_and_the_command_line_loads_no_dask():
    """Without --scheduler nothing of Dask is imported: the driver, the grade verb's options and the CLI."""
    code = ("import sys, particles.course.grading.driver, particles.cli, particles.cli.grade; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed') "
            "or m.startswith('particles.course.grading.cluster')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0 and done.stdout == "[]\n", done.stderr


@pytest.mark.parametrize("options, message", [
    ({"scheduler": "local:0"}, "scheduler must be local:N"),
    ({"scheduler": "http://127.0.0.1:8786"}, "scheduler must be local:N"),
    ({"scheduler": "tcp://127.0.0.1"}, "scheduler must be local:N"),
    ({"scheduler": "local:2", "scheduler_file": __file__}, "give scheduler or scheduler_file, not both"),
    ({"scheduler_file": "/nonexistent/scheduler.json"}, "scheduler_file /nonexistent/scheduler.json does not exist"),
    ({"scheduler": "local:2", "jobs": 2}, "jobs is this machine's pool"),
    ({"scheduler": "local:2", "python": sys.executable}, "python cannot be given with scheduler"),
])
def test_the_cluster_options_are_checked_once(options, message):
    """A malformed scheduler, two of them, or this machine's pool options beside one: a ValueError naming it."""
    with pytest.raises(ValueError, match=message):
        GradeOptions(paths=(), root=ROOT, **options)


def test_a_scheduler_off_this_machine_needs_tls_and_its_certificates():
    """Loopback may be plain TCP; any other address must be tls:// with the CA file, certificate and key."""
    none = {"CA file": None, "certificate": None, "key": None}
    for address in ("tcp://127.0.0.1:8786", "tcp://localhost:8786", "tcp://[::1]:8786", "tls://127.0.0.1:1"):
        check_address(address, none)
    assert is_loopback("127.0.0.2") and not is_loopback("192.0.2.7")
    with pytest.raises(ClusterError, match="not on this machine: .* it must use TLS with certificates"):
        check_address("tcp://192.0.2.7:8786", none)
    with pytest.raises(ClusterError, match="uses TLS but this side has no certificate, key"):
        check_address("tls://192.0.2.7:8786", dict(none, **{"CA file": "ca.pem"}))
    check_address("tls://192.0.2.7:8786", {"CA file": "ca.pem", "certificate": "c.pem", "key": "k.pem"})
    with pytest.raises(ClusterError, match="must be tcp://HOST:PORT or tls://HOST:PORT"):
        check_address("ucx://127.0.0.1:1", none)


def test_a_result_that_is_not_its_tasks_records_is_refused(subs, local_run):
    """The driver reads a worker's result as JSON and takes it only when it holds the task's notebooks, in order
    (student, exercise, digest, seed): another student's record, or another seed, is a clear error."""
    from particles.course.grading.discovery import Unit
    from particles.course.grading.plan import Batch
    from particles.course.grading.run import SessionSettings
    from particles.course.results.records import SubmissionRecord
    from particles.course.walls.isolation import Plan

    students = ("alice_00_warmup", "bob_00_warmup")
    units = tuple(Unit(s, "00_warmup", subs / f"{s}.ipynb") for s in students)
    task = cluster_tasks.make_task(Batch(3, units, (5, 6)), SessionSettings(root=ROOT, plan=Plan()),
                                   {"tests": "t", "library": "l", "course": "c"})
    kept = folder_records(local_run)
    alice, bob = (SubmissionRecord.from_dict(kept[(s, "00_warmup")]) for s in students)
    alice.seed, bob.seed = 5, 6
    text = cluster_tasks.make_result(task, [alice, bob], {"x.log": "..."}, "m (worker 0, tcp://a)")
    records, logs = cluster_tasks.read_result(task, text)
    assert [r.student for r in records] == list(students) and logs == {"x.log": "..."}
    assert {r.worker for r in records} == {"m (worker 0, tcp://a)"}
    swapped = cluster_tasks.make_result(task, [bob, alice], {}, "m")
    with pytest.raises(ClusterError, match="does not hold the records of its notebooks"):
        cluster_tasks.read_result(task, swapped)
    with pytest.raises(ClusterError, match="could not be read"):
        cluster_tasks.read_result(task, "{not json")


def test_a_scheduler_run_records_what_a_local_run_records(subs, local_run, tmp_path):
    """--scheduler local:2 (an embedded cluster of two grading processes) gives the records of --jobs 2 with the
    same seed, each saying which machine graded it and under which walls; the logs come back too."""
    out = tmp_path / "out"
    summary = grade([subs], out, scheduler="local:2", seed=SEED, root=ROOT)
    assert folder_records(out) == folder_records(local_run)
    assert (out / "gradebook.csv").read_text() == (local_run / "gradebook.csv").read_text()
    for student, (record,) in summary["students"].items():
        assert record.worker.startswith(f"{socket.gethostname()} (worker ") and "tls://127.0.0.1:" in record.worker
        local = _current(local_run)[(student, "00_warmup")]
        assert sorted(record.isolation) == sorted(local.isolation)
        assert record.sandbox.split(", ")[0] == local.sandbox.split(", ")[0]  # namespaces, or not, alike
    logs = sorted(p.name for p in (out / "logs").glob("*.log"))
    assert logs and logs == sorted(p.name for p in (local_run / "logs").glob("*.log"))
    assert run_statuses(out) == ["complete"]


def _current(out):
    from particles.course.term.database import TermRecord

    with TermRecord(out) as term:
        return term.current()


def test_ctrl_c_cancels_the_cluster_run_and_ends_as_a_local_run_does(subs, tmp_path):
    """Ctrl-C (SIGINT to the command's process group, as a terminal sends it) on `particles grade --scheduler local:2`
    ends with one line saying to --resume, status 130, no traceback, and no process of the run left behind."""
    out = tmp_path / "out"
    command = [sys.executable, "-m", "particles", "grade", str(subs), "--out", str(out), "--seed", str(SEED),
               "--scheduler", "local:2", "--root", str(ROOT)]
    driver = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              start_new_session=True)
    first = driver.stdout.readline()  # the first notebook graded: other batches are running or queued
    assert first.startswith("  graded "), driver.stderr.read()
    os.killpg(driver.pid, signal.SIGINT)
    _, err = driver.communicate(timeout=120)
    assert driver.returncode == 130, err
    (line,) = err.strip().splitlines()
    assert line.startswith("particles grade: interrupted: ") and line.endswith(" graded; rerun with --resume")
    assert run_statuses(out) == ["interrupted"] and 1 <= len(folder_records(out)) <= 4
    wait_for(lambda: not _alive(driver.pid), 20, "the end of every process of the run")


def _alive(session):
    """The processes of a session that are not zombies (a zombie is waiting for init to reap it)."""
    listed = subprocess.run(["ps", "-s", str(session), "-o", "pid=,stat="], capture_output=True, text=True).stdout
    return [line.split()[0] for line in listed.splitlines() if "Z" not in line.split()[1]]


def test_a_duplicate_delivery_is_handed_on_once(subs):
    """The same batch delivered twice (the same notebook's digest and seed: sent again after a loss, graded after
    all) reaches the run stage once; the delivery's key names the notebook, its digest and seed."""
    from particles.course.grading.discovery import Unit
    from particles.course.grading.plan import Batch
    from particles.course.grading.run import SessionSettings
    from particles.course.walls.isolation import plan

    unit = Unit("alice", "00_warmup", subs / "alice_00_warmup.ipynb")
    settings = SessionSettings(root=ROOT, plan=plan("auto"), public_only=True)
    said = []
    runner = ClusterRunner("local:2", root=ROOT, say=said.append)
    try:
        for _ in range(2):
            runner.submit(Batch(0, (unit,), (7,)), settings)
        outcomes = list(runner.completed())
    finally:
        runner.close()
    (outcome,) = outcomes
    assert outcome.lost is None and [(r.student, r.seed, r.complete) for r in outcome.results] == [("alice", 7, True)]
    assert said == ["particles grade: 1 notebook(s) of batch 0 of 00_warmup delivered again; their first records "
                    "are kept"]
    task = cluster_tasks.make_task(Batch(0, (unit,), (7,)), settings, {"tests": "t", "library": "l", "course": "c"})
    assert cluster_tasks.delivery_keys(task) == [("alice", "00_warmup", outcome.results[0].notebook_sha256, 7)]


def test_grade_refuses_a_scheduler_off_this_machine_without_tls_before_connecting(subs, monkeypatch, capsys):
    """`particles grade --scheduler tcp://<another machine>` stops with status 2 and the reason, and never connects."""
    from particles.cli import main
    from particles.course.grading import cluster

    monkeypatch.setattr(cluster, "Client", lambda *a, **k: pytest.fail("connected to a scheduler off loopback"))
    assert main(["grade", str(subs), "--scheduler", "tcp://192.0.2.7:8786", "--root", str(ROOT)]) == 2
    err = capsys.readouterr().err
    assert "particles grade: the scheduler tcp://192.0.2.7:8786 is not on this machine" in err
