"""What the cluster tests share: a small corpus, records compared without what differs between runs, and real
Dask schedulers and grading workers started as processes on loopback."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "tests" / "course" / "grader"))
import corpus  # noqa: E402

SEED = 20261207

# what differs between two runs of the same grading: timings, the uid a worker ran as, the machine
VOLATILE = {"seconds", "sandbox", "isolation", "worker", "run", "resumed"}


def write_corpus(folder):
    """Four notebooks of 00_warmup: the master, the stub, a wrong Euler step and a result of the wrong shape."""
    folder.mkdir(parents=True, exist_ok=True)
    notebooks = {"alice": corpus.MASTER.read_text(), "bob": corpus.STUB.read_text(),
                 "carl": json.dumps(corpus.build(corpus.REJECTED["euler_as_midpoint"])),
                 "dana": json.dumps(corpus.build(corpus.REJECTED["wrong_shape"]))}
    for student, text in notebooks.items():
        (folder / f"{student}_00_warmup.ipynb").write_text(text)
    return folder


def normal(record):
    """A record's JSON data without what differs between two runs of the same grading."""
    data = record.to_dict() if hasattr(record, "to_dict") else dict(record)
    for name in VOLATILE:
        data.pop(name, None)
    data["tests"] = [{k: v for k, v in t.items() if k != "seconds"} for t in data["tests"]]
    return data


def folder_records(out):
    """``(student, exercise) -> normal record`` of the current results of an output folder's course record."""
    from particles.course.term.database import DATABASE, TermRecord

    if not (Path(out) / DATABASE).exists():
        return {}
    with TermRecord(out) as term:
        return {key: normal(record) for key, record in term.current().items()}


def run_statuses(out):
    """How each run of an output folder's course record ended, oldest first."""
    from particles.course.term.database import TermRecord

    with TermRecord(out) as term:
        return [run["status"] for run in term.runs()]


def wait_for(condition, seconds, what):
    """Poll `condition` until it is true (returned), at most `seconds`."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        found = condition()
        if found:
            return found
        time.sleep(0.05)
    raise AssertionError(f"{what} did not happen within {seconds} s")


def start(command, log, env=None):
    """A process of its own session (so that its whole group can be stopped), its output in `log`."""
    return subprocess.Popen(command, stdout=open(log, "w"), stderr=subprocess.STDOUT, start_new_session=True,
                            env=dict(os.environ, **(env or {})), cwd=ROOT)


def stop(process):
    """End a process started by :func:`start` and everything in its group."""
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    process.wait(timeout=30)


def scheduler(folder):
    """``dask scheduler`` on loopback that lets Dask try a task once (a loss reaches the grading run); its
    process and scheduler file."""
    file = folder / "scheduler.json"
    process = start([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                     "--no-dashboard", "--scheduler-file", str(file)], folder / "scheduler.log",
                    env={"DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "0"})
    wait_for(lambda: file.exists() and file.stat().st_size, 60, "the scheduler's start")
    return process, file


def grade_workers(file, log, n=2):
    """``particles grade-worker`` with `n` worker processes joining the scheduler of `file`."""
    return start([sys.executable, "-m", "particles", "grade-worker", "--scheduler-file", str(file), "--nworkers",
                  str(n), "--root", str(ROOT)], log)


def dask_worker(file, log, root=ROOT):
    """Dask's own ``dask worker`` with the documented flags of a grading worker (the route of dask-jobqueue)."""
    return start([sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(file), "--nthreads", "1",
                  "--no-dashboard", "--host", "127.0.0.1", "--worker-class",
                  "particles.course.grading.cluster_worker.GraderWorker"], log, env={"PARTICLES_COURSE_ROOT": str(root)})


def graders(client):
    """The addresses of the scheduler's grading workers."""
    from particles.course.grading.cluster_tasks import RESOURCE

    workers = client.scheduler_info()["workers"]
    return sorted(a for a, w in workers.items() if RESOURCE in (w.get("resources") or {}))


def worker_processes(process):
    """The worker processes `dask worker` (started by :func:`grade_workers`) runs, as :mod:`psutil` processes.

    Found from the operating system, never by asking the workers (``Client.run``): on Python 3.11.7 a call that
    makes a worker's event loop parse code while its task parses too can fail that task (CPython gh-106905).
    """
    import psutil

    return [child for child in psutil.Process(process.pid).children()
            if any("spawn_main" in part for part in child.cmdline())]
