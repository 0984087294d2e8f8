"""Grading workers of a running cluster (``dask scheduler`` and ``particles grade-worker`` as processes, loopback):
a worker killed mid-batch, a driver killed and resumed, and the workers' refusals (tests' version, walls, digests)."""

import asyncio
import os
import re
import shutil
import signal
import subprocess
import sys
import threading

import pytest

pytest.importorskip("distributed")

import psutil  # noqa: E402  (a dependency of distributed)
from distributed import Client, Scheduler  # noqa: E402

from particles.course.grading import cluster_worker  # noqa: E402
from particles.course.grading.cluster import ClusterRunner  # noqa: E402
from particles.course.grading.cluster_tasks import TaskRefused, make_task  # noqa: E402
from particles.course.grading.cluster_worker import GraderWorker, check_in  # noqa: E402
from particles.course.grading.discovery import Unit  # noqa: E402
from particles.course.grading.driver import grade  # noqa: E402
from particles.course.grading.plan import Batch  # noqa: E402
from particles.course.grading.record import MemoryRecorder  # noqa: E402
from particles.course.grading.run import SessionSettings  # noqa: E402
from particles.course.walls import isolation  # noqa: E402

from .helpers import (ROOT, SEED, dask_worker, folder_records, grade_workers, graders, normal,  # noqa: E402
                      run_statuses, scheduler, stop, wait_for, worker_processes)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A scheduler and two grading workers (``particles grade-worker --nworkers 2``), each a process of its own."""
    folder = tmp_path_factory.mktemp("dask")
    process, file = scheduler(folder)
    workers = grade_workers(file, folder / "workers.log")
    client = Client(scheduler_file=str(file))
    try:
        wait_for(lambda: len(graders(client)) == 2, 120, "two grading workers joining")
        yield file, client, workers
    finally:
        client.close()
        stop(workers)
        stop(process)


class CountingRecorder(MemoryRecorder):
    """Records in memory, every save counted."""

    def __init__(self):
        super().__init__()
        self.saves = []

    def save(self, record):
        self.saves.append((record.student, record.exercise))
        super().save(record)


def _session_on_a_worker(workers):
    """``(worker pid, session pid)`` of a grading session running under one of the grading workers, or None."""
    for worker in worker_processes(workers):
        for child in worker.children(recursive=True):
            try:
                if "particles.course.grading.plugin" in child.cmdline():
                    return worker.pid, child.pid
            except psutil.NoSuchProcess:
                pass
    return None


def _ended(pid):
    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


def test_a_worker_killed_mid_batch_leaves_exactly_one_record_per_notebook(cluster, subs, local_run):
    """SIGKILL to a grading worker while its session grades a batch: the session dies with it (no orphan), the batch
    comes back lost and is graded again, and each notebook is saved exactly once, as a local run grades it."""
    file, client, workers = cluster
    killed = {}

    def kill_a_worker():
        killed["worker"], killed["session"] = wait_for(lambda: _session_on_a_worker(workers), 120,
                                                       "a grading session on a worker")
        os.kill(killed["worker"], signal.SIGKILL)

    lost, recorder = [], CountingRecorder()
    killer = threading.Thread(target=kill_a_worker)
    killer.start()
    summary = grade([subs], None, runner=ClusterRunner(scheduler_file=file, root=ROOT, say=lost.append),
                    recorder=recorder, scheduler_file=file, seed=SEED, root=ROOT)
    killer.join()
    wait_for(lambda: _ended(killed["session"]), 20, "the end of the killed worker's session")
    assert sorted(recorder.saves) == sorted(set(recorder.saves)) and len(recorder.saves) == 4
    assert {k: normal(r) for k, r in recorder.current().items()} == folder_records(local_run)
    assert len(summary["students"]) == 4
    assert len(lost) == 1 and "was lost: the worker grading it died (tcp://127.0.0.1:" in lost[0]
    wait_for(lambda: len(graders(client)) == 2, 120, "the nanny's new worker joining")


def test_a_killed_driver_resumed_against_the_same_cluster_gives_the_same_gradebook(cluster, subs, local_run, tmp_path):
    """`particles grade --scheduler-file` killed after its first records, then run again with --resume against the
    same cluster: the gradebook and records are those of an uninterrupted run."""
    file, _, _ = cluster
    out = tmp_path / "out"
    command = [sys.executable, "-m", "particles", "grade", str(subs), "--out", str(out), "--seed", str(SEED),
               "--scheduler-file", str(file), "--root", str(ROOT)]
    driver = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    wait_for(lambda: (out / "course.sqlite").exists() and folder_records(out), 180, "a first record")
    os.killpg(driver.pid, signal.SIGKILL)
    driver.wait()
    kept = len(folder_records(out))
    done = subprocess.run(command + ["--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert kept == 4 or f"resumed: {kept} record(s)" in done.stdout
    assert (out / "gradebook.csv").read_text() == (local_run / "gradebook.csv").read_text()
    assert folder_records(out) == folder_records(local_run) and run_statuses(out)[-1] == "complete"
    assert run_statuses(out)[0] == "interrupted"  # the killed run, marked so by the next


def _course_with_other_tests(folder):
    """A copy of the course folder whose tests of 00_warmup differ by one comment line."""
    for part in ("tests/exercises", "solutions", "exercises"):
        shutil.copytree(ROOT / part, folder / part, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    shutil.copy(ROOT / "tests" / "conftest.py", folder / "tests" / "conftest.py")
    test = folder / "tests" / "exercises" / "test_00_warmup.py"
    test.write_text(test.read_text() + "\n# a test changed on this machine only\n")
    return folder


def test_a_worker_with_another_tests_version_is_refused_with_a_clear_error(subs, tmp_path):
    """A grading worker (started by `dask worker` with the documented flags) whose course folder has other tests of
    the exercise refuses its batch, which is not sent again: the run stops (status 2) naming the worker and both
    versions, and no record is saved."""
    process, file = scheduler(tmp_path)
    workers = dask_worker(file, tmp_path / "worker.log", _course_with_other_tests(tmp_path / "course"))
    try:
        out = tmp_path / "out"
        done = subprocess.run([sys.executable, "-m", "particles", "grade", str(subs), "--out", str(out), "--seed",
                               str(SEED), "--scheduler-file", str(file), "--root", str(ROOT)],
                              capture_output=True, text=True, timeout=300)
    finally:
        stop(workers)
        stop(process)
    assert done.returncode == 2, done.stdout + done.stderr
    (line,) = [line for line in done.stderr.splitlines() if line.startswith("particles grade: ")]
    assert "(tcp://127.0.0.1:" in line and "refuses batch " in line and " of 00_warmup: it would grade with tests " \
        "version tests=" in line and ", the driver grades with tests=" in line and "--resume" in line
    assert folder_records(out) == {} and run_statuses(out) == ["interrupted"]


def test_a_machine_with_weaker_walls_refuses_to_join_under_strict(monkeypatch):
    """Under --isolation strict a machine without the namespace sandbox refuses to join, naming what it lacks:
    the check raises, and a grading worker with it never registers with the scheduler."""
    found = dict(isolation.probe(), namespaces=False, namespaces_why="bubblewrap cannot make namespaces here (test)")
    monkeypatch.setattr(isolation, "probe", lambda: found)
    lacks = r"it lacks namespaces \(bubblewrap cannot make namespaces here \(test\)\)"
    with pytest.raises(isolation.IsolationUnavailable, match=r"weaker than --isolation strict requires: " + lacks):
        check_in(ROOT, "strict")
    assert check_in(ROOT, "auto").plan.namespaces is False  # auto: it joins, and its records say its walls
    monkeypatch.setenv(cluster_worker.ISOLATION_VARIABLE, "strict")
    monkeypatch.setenv("PARTICLES_COURSE_ROOT", str(ROOT))

    async def join():
        async with Scheduler(host="127.0.0.1", port=0, dashboard_address="127.0.0.1:0") as scheduler:
            with pytest.raises(Exception) as refused:
                async with GraderWorker(scheduler.address, host="127.0.0.1"):
                    pass
            return refused.value, len(scheduler.workers)

    error, joined = asyncio.run(join())
    while error.__cause__ is not None:
        error = error.__cause__
    assert isinstance(error, isolation.IsolationUnavailable) and "lacks namespaces" in str(error) and joined == 0


def test_a_task_asking_for_more_than_the_worker_has_or_altered_on_the_way_is_refused(monkeypatch, tmp_path):
    """A worker refuses a task of another library, naming both; one that joined under auto without namespaces
    refuses a strict run's task, naming what it lacks; a notebook whose bytes do not match their digest is
    refused; all before grading anything."""
    notebook = tmp_path / "alice.ipynb"
    notebook.write_text((ROOT / "solutions" / "00_warmup.ipynb").read_text())
    strict = isolation.Plan(namespaces=True, separate_uid=True, landlock=True, mode="strict")
    task = make_task(Batch(4, (Unit("alice", "00_warmup", notebook),), (1,)), SessionSettings(root=ROOT, plan=strict),
                     {"tests": "t", "library": "0.0.1+000000000000", "course": "c"})
    mine = check_in(ROOT, "auto").library
    with pytest.raises(TaskRefused, match=rf"worker w refuses batch 4 of 00_warmup: its library is particles "
                                          rf"{re.escape(mine)}, the driver's particles 0.0.1\+000000000000; install"):
        cluster_worker.check_versions(check_in(ROOT, "auto"), task, "worker w")
    found = dict(isolation.probe(), namespaces=False, namespaces_why="no bwrap (test)")
    monkeypatch.setattr(isolation, "probe", lambda: found)
    grader = check_in(ROOT, "auto")
    with pytest.raises(TaskRefused, match=r"worker w refuses batch 4: the run requires --isolation strict and this "
                                          r"machine lacks namespaces \(no bwrap \(test\)\)"):
        cluster_worker.task_walls(grader, task, "worker w")
    task["notebooks"][0]["data"] += b" "
    with pytest.raises(TaskRefused, match=f"{notebook} arrived with SHA-256 [0-9a-f]{{64}}, not "
                                          f"{task['notebooks'][0]['sha256']}"):
        cluster_worker.write_notebooks(task, tmp_path, "worker w")


def test_grade_worker_refuses_to_join_before_it_starts_any_worker(tmp_path, monkeypatch, capsys):
    """`particles grade-worker` refuses, with status 2 and the reason, a scheduler off this machine without TLS, an
    unreadable scheduler file or a course folder without tests, before it becomes a Dask worker."""
    from particles.cli import main

    monkeypatch.setattr(os, "execve", lambda *a: pytest.fail("started a worker"))
    assert main(["grade-worker", "tcp://192.0.2.7:8786", "--root", str(ROOT)]) == 2
    assert "refusing to join: the scheduler tcp://192.0.2.7:8786 is not on this machine" in capsys.readouterr().err
    assert main(["grade-worker", "--scheduler-file", str(tmp_path / "none.json"), "--root", str(ROOT)]) == 2
    assert f"cannot read the scheduler's address from {tmp_path / 'none.json'}" in capsys.readouterr().err
    (tmp_path / "course" / "solutions").mkdir(parents=True)
    assert main(["grade-worker", "tcp://127.0.0.1:8786", "--root", str(tmp_path / "course")]) == 2
    assert "refusing to join: no exercise tests in" in capsys.readouterr().err
    assert main(["grade-worker"]) == 2 and "give the scheduler's ADDRESS or --scheduler-file" in capsys.readouterr().err
