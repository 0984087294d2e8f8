"""The worker side of a grading cluster: a Dask worker that checks itself before it joins, and the task it runs.

:class:`GraderWorker` is the Dask worker of a grading machine: ``particles grade-worker ADDRESS`` starts them
(:mod:`particles.cli.grade_worker`), ``dask worker ADDRESS --worker-class
particles.course.grading.cluster_worker.GraderWorker --nthreads 1`` too, and the embedded cluster of
``particles grade --scheduler local:N`` is made of them. Before it joins the scheduler it checks itself
(:func:`check_in`): its course folder (``$PARTICLES_COURSE_ROOT``) has exercise tests, its walls are what
``$PARTICLES_GRADER_ISOLATION`` asks (``strict``: a machine without the namespace sandbox refuses to join,
naming what it lacks), and it takes the digests of its library and of every exercise's tests. It turns
off its own ``PR_SET_DUMPABLE`` as the driver does (it holds its sessions' signing keys and reads their
records), and offers the resource :data:`~particles.course.grading.cluster_tasks.RESOURCE` once: every
grading task asks for it, so only a worker that passed its check gets one, and one batch at a time.

:func:`grade_task` is what runs there: the task's versions checked against this machine's (refused, not
retried, when they differ), the walls it asks for checked, the notebooks written to a private folder and
their digests checked, the batch graded by :func:`~particles.course.grading.run.run_batch` (the same code
as a local run: the sessions' keys never leave this machine), the folder deleted, the library checked
unchanged, and the records returned as JSON text naming this machine and its walls.
"""

import dataclasses
import hashlib
import logging
import os
import shutil
import signal
import socket
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

from distributed import Worker, get_worker

from ..paths import exercise_tests, project_root
from ..walls import isolation as isolation_module
from .cluster_tasks import RESOURCE, ClusterError, TaskRefused, course_digest, make_result, read_task
from .discovery import Unit
from .plan import Batch
from .run import SessionSettings, run_batch
from .versions import library_digest, tests_version

__all__ = ["GraderWorker", "Grader", "check_in", "grade_task", "check_versions", "task_walls", "write_notebooks",
           "lacking",
           "ISOLATION_VARIABLE"]

ISOLATION_VARIABLE = "PARTICLES_GRADER_ISOLATION"
"""The environment variable of a grading worker's walls: ``auto`` (default) or ``strict``."""

logger = logging.getLogger("distributed.worker.particles")  # shown with the worker's own log


@dataclass(frozen=True)
class Grader:
    """What a grading worker found about itself when it joined (:func:`check_in`).

    Attributes
    ----------
    root : Path
        Its course folder.
    mode : str
        ``auto`` or ``strict``.
    plan : particles.course.walls.isolation.Plan
        The strongest walls it allows (``strict``: with namespaces).
    library : str
        Its library's digest (:func:`~particles.course.grading.versions.library_digest`).
    tests : dict
        Exercise -> its tests version here.
    host : str
        The machine's name.
    """

    root: Path
    mode: str
    plan: object
    library: str
    tests: dict
    host: str

    def describe(self, worker):
        """The machine in words, as records name it: ``host (worker NAME, ADDRESS)``."""
        name = "" if str(worker.name) == worker.address else f"{worker.name}, "
        return f"{self.host} (worker {name}{worker.address})"


def lacking(found):
    """The walls a machine lacks, in words, from :func:`~particles.course.walls.isolation.probe`'s findings."""
    missing = []
    if not found["namespaces"]:
        missing.append(f"namespaces ({found['namespaces_why']})")
    if not found["root"] or found["uid_why"]:
        missing.append(f"a uid of its own per worker ({found['uid_why']})")
    if not found["landlock"]:
        missing.append("Landlock (this kernel has none)")
    return "; ".join(missing) or "nothing"


def check_in(root=None, mode=None):
    """The checks a grading worker makes before it joins; returns what it found (a :class:`Grader`).

    Parameters
    ----------
    root : path, optional
        The course folder (default: ``$PARTICLES_COURSE_ROOT``, else found from the current directory).
    mode : {"auto", "strict"}, optional
        The walls required (default: ``$PARTICLES_GRADER_ISOLATION``, else ``auto``).

    Raises
    ------
    ValueError
        On an unknown mode, or a course folder without exercise tests.
    particles.course.walls.isolation.IsolationUnavailable
        Under ``strict`` on a machine without the namespace sandbox: the message names what it lacks.
    """
    root = Path(root).resolve() if root is not None else project_root()
    mode = mode or os.environ.get(ISOLATION_VARIABLE) or "auto"
    if mode not in isolation_module.MODES:
        raise ValueError(f"{ISOLATION_VARIABLE} must be one of {', '.join(isolation_module.MODES)}, got {mode!r}")
    exercises = exercise_tests(root)
    if not exercises:
        raise ValueError(f"no exercise tests in {root / 'tests' / 'exercises'}: give the grading worker its "
                         "course folder (--root, or PARTICLES_COURSE_ROOT)")
    found = isolation_module.probe()
    if mode == "strict" and not found["namespaces"]:
        raise isolation_module.IsolationUnavailable(
            f"this machine's walls are weaker than --isolation strict requires: it lacks {lacking(found)}")
    library = library_digest()
    return Grader(root=root, mode=mode, plan=isolation_module.plan(mode), library=library,
                  tests={name: tests_version(root, name, library) for name in exercises},
                  host=socket.gethostname())


class GraderWorker(Worker):
    """A Dask worker that grades: one thread, the grading resource, and its checks made before it joins.

    A worker whose checks fail does not start (``dask worker`` exits, an embedded cluster does not
    start), with the reason in its error.
    """

    def __init__(self, *args, **kwargs):
        kwargs["resources"] = dict(kwargs.get("resources") or {}, **{RESOURCE: 1})
        kwargs["nthreads"] = 1  # one batch at a time: a session and its worker take a core
        super().__init__(*args, **kwargs)

    async def start_unsafe(self):
        self.grader = check_in()
        isolation_module.protect_this_process()
        if threading.current_thread() is threading.main_thread():
            # a terminal's Ctrl-C reaches the whole process group: the driver (or ``dask worker``'s nanny) stops
            # its workers, and their sessions die with them; neither stops half-way on its own
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        logger.info("particles grader on %s: course %s, walls %s (%s), library %s", self.grader.host,
                    self.grader.root, self.grader.plan.to_option(), self.grader.mode, self.grader.library)
        return await super().start_unsafe()


def check_versions(grader, task, name):
    """Refuse `task` when this machine would grade its exercise with other tests, library or course files."""
    exercise = task["exercise"]
    if exercise not in exercise_tests(grader.root):
        raise TaskRefused(f"{name} refuses batch {task['batch']}: it has no tests of exercise {exercise!r} in "
                          f"{grader.root}")
    library = library_digest()
    if library != task["versions"]["library"]:
        raise TaskRefused(f"{name} refuses batch {task['batch']} of {exercise}: its library is particles {library}, "
                          f"the driver's particles {task['versions']['library']}; install the driver's particles "
                          "on that machine, or stop it, then grade again with --resume")
    mine, theirs = tests_version(grader.root, exercise, library), task["versions"]["tests"]
    if mine != theirs:
        raise TaskRefused(f"{name} refuses batch {task['batch']} of {exercise}: it would grade with tests version "
                          f"{mine}, the driver grades with {theirs}; give that machine the driver's course "
                          "folder and particles, or stop it, then grade again with --resume")
    if course_digest(grader.root, exercise) != task["versions"]["course"]:
        raise TaskRefused(f"{name} refuses batch {task['batch']} of {exercise}: its master or released notebook "
                          f"of {exercise} (in {grader.root}) differs from the driver's; give that machine the "
                          "driver's course folder, then grade again with --resume")


def task_walls(grader, task, name):
    """The walls of this task's sessions: those it asks for, as far as this machine allows (strict: refused
    without namespaces)."""
    options = task["options"]
    plan = dataclasses.replace(isolation_module.Plan.from_option(options["walls"]), mode=options["mode"])
    if "strict" in (options["mode"], grader.mode) and not plan.namespaces:
        raise TaskRefused(f"{name} refuses batch {task['batch']}: the run requires --isolation strict and this "
                          f"machine lacks {lacking(isolation_module.probe())}")
    return plan


def write_notebooks(task, folder, name):
    """The task's notebooks written to `folder`, each checked against its digest; their units."""
    units = []
    for k, notebook in enumerate(task["notebooks"]):
        path = folder / f"{k:03d}.ipynb"
        path.write_bytes(notebook["data"])
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        if digest != notebook["sha256"]:
            raise TaskRefused(f"{name} refuses batch {task['batch']}: {notebook['where']} arrived with SHA-256 "
                              f"{digest}, not {notebook['sha256']}")
        units.append(Unit(notebook["student"], task["exercise"], path, origin=notebook["where"]))
    return units


def grade_task(task):
    """Grade a task (:func:`~particles.course.grading.cluster_tasks.make_task`) on this worker; run by Dask.

    Returns
    -------
    str
        The result's JSON text (:func:`~particles.course.grading.cluster_tasks.make_result`).

    Raises
    ------
    TaskRefused
        This worker is not a grader, its versions differ from the task's, its walls are weaker than
        required, or a notebook's bytes do not match their digest.
    ClusterError
        Its library changed while it graded (the records are dropped).
    """
    worker = get_worker()
    grader = getattr(worker, "grader", None)
    name = f"worker {worker.name} ({worker.address})"
    if grader is None:
        raise TaskRefused(f"{name} is not a grading worker (start it with particles grade-worker)")
    task = read_task(task)
    check_versions(grader, task, name)
    plan = task_walls(grader, task, name)
    before = isolation_module.library_checksum()
    folder = Path(tempfile.mkdtemp(prefix="particles-task-"))  # mode 0700: this uid's alone
    try:
        units = write_notebooks(task, folder, name)
        options = task["options"]
        settings = SessionSettings(root=grader.root, plan=plan, private=(str(folder),),
                                   logs=folder / "logs" if task["logs"] else None,
                                   public_only=options["public_only"], time_limit=options["time_limit"],
                                   memory_mb=options["memory_mb"], audit_hook=options["audit_hook"])
        if settings.logs is not None:
            settings.logs.mkdir()
        records = run_batch(Batch(task["batch"], tuple(units), tuple(task["seeds"])), settings)
        logs = ({p.name: p.read_text(errors="replace") for p in sorted(settings.logs.glob("*.log"))}
                if settings.logs is not None else {})
    finally:
        shutil.rmtree(folder, ignore_errors=True)  # the notebooks leave this machine's disk with the task
    changed = isolation_module.library_changes(before)
    if changed:
        raise ClusterError(f"the installed library of {name} changed while it graded batch {task['batch']} "
                           f"({', '.join(changed[:5])}): its records were dropped; do not use that machine")
    return make_result(task, records, logs, grader.describe(worker))
