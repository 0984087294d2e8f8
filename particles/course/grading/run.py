"""The run stage of a grading run: batches graded somewhere, their results handed back as they complete.

Where the batches run is one small protocol, :class:`Runner`: submit a batch, take the outcomes as they
complete, close. :class:`LocalRunner` runs them on this machine's cores, ``jobs`` sessions at a time; a
runner that sends them to other machines implements the same three methods
(:class:`~particles.course.grading.cluster.ClusterRunner`: a Dask cluster), and may say how many batches
it grades at once (``slots``: the run's batches are sized for them). Whatever runs a batch runs
:func:`run_batch`, the same code everywhere: one pytest session for the batch
(:func:`particles.course.grading.session.grade_batch`), then each notebook that session did not finish
in a session of its own.

A runner may lose a batch (a machine that died with it): its outcome says so (``lost``).
:func:`run_all` then submits it again, at most ``retries`` times, then notebook by notebook, and a
notebook that still cannot be graded gets an incomplete record (every test failed, saying why) that
``--resume`` grades again: never a silent zero, never a run stopped by one batch.
"""

from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from ..results.records import SubmissionRecord, TestRecord
from . import session

__all__ = ["Outcome", "Runner", "LocalRunner", "SessionSettings", "run_batch", "run_all", "lost_record"]

RETRIES = 1
"""How many times a lost batch is submitted again whole, before it is cut into single notebooks."""


@dataclass(frozen=True)
class SessionSettings:
    """How every session of a run grades: the same for all its batches, wherever they run.

    Parameters
    ----------
    root : Path
        The course folder (its ``tests/exercises``).
    plan : particles.course.walls.isolation.Plan
        The workers' walls, decided once for the run.
    private : tuple of str
        Paths no worker may read (the submissions, the output folder, ...).
    logs : Path, optional
        Where the sessions' logs go (None: not kept).
    public_only, time_limit, memory_mb, python, audit_hook
        As in :class:`~particles.course.grading.options.GradeOptions`.
    """

    root: Path
    plan: object
    private: tuple = ()
    logs: Path = None
    public_only: bool = False
    time_limit: float = None
    memory_mb: float = None
    python: str = None
    audit_hook: bool = True

    def session_options(self):
        """The keyword arguments of :func:`~particles.course.grading.session.grade_batch` these settings give."""
        return {"public_only": self.public_only, "time_limit": self.time_limit, "memory_mb": self.memory_mb,
                "private": list(self.private), "python": self.python, "isolation": self.plan,
                "audit_hook": self.audit_hook}

    def log(self, name):
        """The log file `name` (None when logs are not kept)."""
        return None if self.logs is None else self.logs / name


def run_batch(batch, settings):
    """Grade one batch; the notebooks its session did not finish are graded again, each alone.

    Parameters
    ----------
    batch : particles.course.grading.plan.Batch
    settings : SessionSettings

    Returns
    -------
    list of SubmissionRecord
        One per notebook of the batch, in order.
    """
    options = settings.session_options()
    results = session.grade_batch(list(batch.units), settings.root, seeds=list(batch.seeds),
                                  log=settings.log(f"batch{batch.number:03d}-{batch.exercise}.log"), **options)
    if len(batch.units) > 1:  # a session that stopped early: grade its unfinished notebooks alone
        for i, (unit, result) in enumerate(zip(batch.units, results)):
            if not result.complete:
                results[i] = session.grade_unit(unit, settings.root, seed=batch.seeds[i],
                                                log=settings.log(f"{unit.student}-{unit.exercise}.log"), **options)
    return results


@dataclass
class Outcome:
    """What became of a submitted batch: its results, or why it was lost.

    Attributes
    ----------
    batch : Batch
    results : list of SubmissionRecord, optional
        One per notebook, in order (None when the batch was lost).
    lost : str, optional
        Why the batch came back without results (a machine that died with it).
    """

    batch: object
    results: list = None
    lost: str = None


class Runner(Protocol):
    """Where a run's batches are graded: this machine, or others."""

    def submit(self, batch, settings):
        """Start grading `batch` (a :class:`~particles.course.grading.plan.Batch`) with `settings`."""

    def completed(self):
        """The :class:`Outcome` of every submitted batch, as each completes; batches submitted while this
        is iterated are waited for too."""

    def close(self, cancel=False):
        """Wait for what is running (or, with `cancel`, drop what has not started) and free the runner."""


@dataclass
class LocalRunner:
    """Batches graded on this machine: `jobs` sessions at a time, each a process of its own.

    A batch is never lost here (a session that dies is handled by :func:`run_batch`); an exception
    raised while grading one is a fault of the grader and is raised by :meth:`completed`.
    """

    jobs: int = 1
    pending: dict = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self):
        self.pool = ThreadPoolExecutor(max_workers=self.jobs)
        session.STOPPING.clear()

    def submit(self, batch, settings):
        self.pending[self.pool.submit(run_batch, batch, settings)] = batch

    def completed(self):
        while self.pending:
            done, _ = wait(list(self.pending), return_when=FIRST_COMPLETED)
            for future in done:
                yield Outcome(self.pending.pop(future), results=future.result())

    def close(self, cancel=False):
        if cancel:  # the sessions running now are stopped, not waited for
            self.pool.shutdown(wait=False, cancel_futures=True)
            session.stop_sessions()
        self.pool.shutdown(wait=True, cancel_futures=cancel)


def lost_record(unit, seed, why, settings):
    """The incomplete record of a notebook no machine could grade: every test failed, saying why.

    ``complete`` is False, so ``particles grade --resume`` grades it again.
    """
    try:
        tests = session.catalog(settings.root, unit.exercise, settings.public_only, settings.python)
    except RuntimeError:
        tests = []
    reason = f"not graded: {why}; the instructor can grade it again with --resume"
    return SubmissionRecord(student=unit.student, exercise=unit.exercise, notebook=unit.where, seed=seed,
                            tests=[TestRecord.from_dict(t).failed(reason) for t in tests],
                            notes=[f"Not graded yet: {why}"], grader_status=None, complete=False,
                            sandbox="not run: the batch was lost")


def run_all(batches, runner, settings, collect, retries=RETRIES):
    """The run stage: every batch graded by `runner`, each result given to `collect` as its batch completes.

    Parameters
    ----------
    batches : list of Batch
    runner : Runner
    settings : SessionSettings
    collect : callable
        Called with each batch's list of records (the record stage).
    retries : int
        Times a lost batch is submitted again whole before it is cut into single notebooks; a single
        notebook lost more often gets :func:`lost_record`.

    Notes
    -----
    On any exception (Ctrl-C included) the batches not started are dropped and the runner is closed
    before the exception goes on.
    """
    losses = {}
    try:
        for batch in batches:
            runner.submit(batch, settings)
        for outcome in runner.completed():
            if outcome.lost is None:
                collect(outcome.results)
                continue
            batch = outcome.batch
            key = (batch.number, tuple(unit.where for unit in batch.units))
            losses[key] = losses.get(key, 0) + 1
            if losses[key] <= retries:
                runner.submit(batch, settings)
            elif len(batch.units) > 1:
                for single in batch.singles():
                    runner.submit(single, settings)
            else:
                collect([lost_record(batch.units[0], batch.seeds[0], outcome.lost, settings)])
    except BaseException:
        runner.close(cancel=True)
        raise
    runner.close()
