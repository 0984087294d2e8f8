"""The task a grading cluster runs, and its result: a batch and its records as plain data.

A grading cluster (:mod:`~particles.course.grading.cluster`) sends a worker machine
(:mod:`~particles.course.grading.cluster_worker`) nothing of the driver's objects. A task is a dict of plain
values (:func:`make_task`): the batch's number and exercise, each notebook's bytes with their SHA-256, its
student and where it came from, the seeds drawn before submission, the options a session grades with, and
the versions the driver grades with: the library's digest, the tests'
(:func:`~particles.course.grading.versions.tests_version`) and the exercise's course files
(:func:`course_digest`: its master and released notebook, which the sessions read). A worker whose own
versions differ refuses the task (:class:`TaskRefused`): it is not sent again, for that machine must first
be set up as the driver's is.

The result is JSON text (:func:`make_result`): one record per notebook as
:meth:`~particles.course.results.records.SubmissionRecord.to_dict` writes it, each naming the machine that
graded it and the walls it had, and the sessions' logs. :func:`read_result` turns it back into records on
the driver and checks that they are the task's: the same students, exercise, notebooks' digests and seeds.
This module imports nothing of Dask: the driver's command line reads :class:`ClusterError` without it.
"""

import hashlib
import json
from pathlib import Path

from ..results.records import SubmissionRecord

__all__ = ["FORMAT", "RESOURCE", "ClusterError", "TaskRefused", "make_task", "read_task", "make_result",
           "read_result", "course_digest", "delivery_keys"]

FORMAT = 1
"""The version of the task's and the result's layout (a worker and a driver of different layouts refuse)."""

RESOURCE = "particles_grader"
"""The Dask resource a grading worker offers (one) and every grading task asks for: only a worker that passed
its join check gets a task, and it grades one batch at a time."""

LOG_CHARACTERS = 1_000_000
"""The most of one session's log a result carries back (its end is kept)."""


class ClusterError(RuntimeError):
    """The cluster cannot grade this run: no scheduler, no grading worker, a worker that refused a task."""


class TaskRefused(ClusterError):
    """A worker refused a task: its tests, library or course files differ from the driver's, its walls are
    weaker than the run requires, or a notebook's bytes do not match their digest. Never sent again."""


def course_digest(root, exercise):
    """SHA-256 (12 hex digits) of the exercise's course files that a session reads besides its tests.

    The master ``solutions/NN_topic.ipynb`` (the cells the course provides are read from it) and the
    released ``exercises/NN_topic.ipynb`` (its answer slots are counted); a missing one counts as missing.
    """
    digest = hashlib.sha256()
    for path in (Path(root) / "solutions" / f"{exercise}.ipynb", Path(root) / "exercises" / f"{exercise}.ipynb"):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(hashlib.sha256(path.read_bytes()).digest() if path.is_file() else b"missing")
    return digest.hexdigest()[:12]


def make_task(batch, settings, versions):
    """The task of `batch` (a :class:`~particles.course.grading.plan.Batch`): plain data a worker can grade.

    Parameters
    ----------
    batch : Batch
    settings : particles.course.grading.run.SessionSettings
        The run's settings: the options and walls the task asks for (its paths stay on the driver).
    versions : dict
        ``tests`` (the exercise's tests version, with the library's digest), ``library`` (the library's digest)
        and ``course`` (:func:`course_digest`), as the driver grades.

    Returns
    -------
    dict
    """
    notebooks = []
    for unit in batch.units:
        data = Path(unit.notebook).read_bytes()
        notebooks.append({"student": unit.student, "where": unit.where, "sha256": hashlib.sha256(data).hexdigest(),
                          "data": data})
    plan = settings.plan
    options = {"public_only": bool(settings.public_only), "time_limit": settings.time_limit,
               "memory_mb": settings.memory_mb, "audit_hook": bool(settings.audit_hook),
               "walls": plan.to_option(), "mode": plan.mode}
    return {"format": FORMAT, "batch": batch.number, "exercise": batch.exercise, "versions": dict(versions),
            "notebooks": notebooks, "seeds": [int(s) for s in batch.seeds], "options": options,
            "logs": settings.logs is not None}


def read_task(task):
    """Check the layout of a task a worker received; returns it (raises :class:`TaskRefused` when it is not one)."""
    keys = {"format", "batch", "exercise", "versions", "notebooks", "seeds", "options", "logs"}
    if (not isinstance(task, dict) or not keys <= set(task) or task["format"] != FORMAT
            or not {"tests", "library", "course"} <= set(task["versions"])):
        raise TaskRefused(f"not a grading task of layout {FORMAT} (a driver of another version of particles?)")
    if len(task["notebooks"]) != len(task["seeds"]) or not task["notebooks"]:
        raise TaskRefused("a grading task needs one seed per notebook")
    return task


def make_result(task, records, logs, worker):
    """The result of `task` as JSON text: the records (each saying which machine graded it) and the logs.

    Parameters
    ----------
    task : dict
    records : list of SubmissionRecord
        One per notebook of the task, in order.
    logs : dict
        Log name -> text (each cut to its last :data:`LOG_CHARACTERS`).
    worker : str
        The machine that graded them, in words (set as each record's ``worker``).
    """
    for record in records:
        record.worker = worker
    return json.dumps({"format": FORMAT, "batch": task["batch"], "records": [r.to_dict() for r in records],
                       "logs": {name: text[-LOG_CHARACTERS:] for name, text in logs.items()}})


def read_result(task, text):
    """The records and logs of a task's result, checked against the task.

    Returns
    -------
    records : list of SubmissionRecord
        One per notebook of the task, in order.
    logs : dict
        Log name -> text.

    Raises
    ------
    ClusterError
        When the result is not JSON of the expected layout or its records are not the task's notebooks
        (student, exercise, digest and seed, in order).
    """
    try:
        data = json.loads(text)
        records = [SubmissionRecord.from_dict(r) for r in data["records"]]
        logs = {str(k): str(v) for k, v in dict(data.get("logs", {})).items()}
    except (TypeError, ValueError, KeyError) as error:
        raise ClusterError(f"a worker's result of batch {task['batch']} could not be read ({error})") from None
    expected = delivery_keys(task)
    got = [(r.student, r.exercise, r.notebook_sha256, r.seed) for r in records]
    if data.get("format") != FORMAT or data.get("batch") != task["batch"] or got != expected:
        raise ClusterError(f"a worker's result of batch {task['batch']} ({task['exercise']}) does not hold the "
                           f"records of its notebooks: got {got}, expected {expected}")
    return records, logs


def delivery_keys(task):
    """What makes each notebook of a task the same delivery: ``(student, exercise, sha256, seed)``, in order."""
    return [(n["student"], task["exercise"], n["sha256"], int(seed))
            for n, seed in zip(task["notebooks"], task["seeds"])]
