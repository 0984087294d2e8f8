"""The options of one grading run: one typed object, checked once, read by the stages that need them.

``particles grade`` builds a :class:`GradeOptions` from its command line; :func:`~particles.course.grading.driver.grade`
builds one from its keyword arguments. Every check of a value the instructor gave happens here, when the
object is made, so that a run with a bad option stops before anything is read or graded.
"""

import re
from dataclasses import dataclass, field
from pathlib import Path

from ..paths import exercise_tests, project_root
from ..walls.limits import check_limit

__all__ = ["GradeOptions", "VISIBILITIES"]

VISIBILITIES = ("hidden", "after_due_date", "after_published", "visible")
"""Gradescope's visibilities of a test."""

SCHEDULER = re.compile(r"local:[1-9][0-9]*|(tcp|tls)://\S+:[0-9]+")
"""The forms of ``scheduler``: an embedded cluster of N processes, or a running scheduler's address."""


def _paths(values):
    return tuple(Path(v) for v in values)


def _optional_path(value):
    return None if value is None else Path(value)


@dataclass(frozen=True)
class GradeOptions:
    """What one grading run is asked to do.

    Parameters
    ----------
    paths : sequence of path
        Notebooks, folders of notebooks, zips of them (LMS exports; see
        :mod:`particles.course.grading.discovery`).
    out : path, optional
        Output folder: ``gradebook.csv``, ``<student>/results.json``, ``<student>/feedback.md`` and
        ``<student>/feedback.html``, ``course.sqlite`` (the term's record, every result kept as soon as it
        is made) and ``logs/``. Nothing is written without it.
    jobs : int
        Notebooks graded at the same time (each takes one core).
    exercise : str, optional
        Grade every notebook as this exercise.
    public_only : bool
        Run only the public tests.
    seed : int, optional
        Seed of the hidden tests' random parameters (default: a new random seed per notebook,
        recorded in the results).
    time_limit, memory_mb : float, optional
        Per-call time limit (s) of the tests without their own ``time_limit`` marker, and memory (MiB)
        of the student's code; finite and > 0.
    root : path, optional
        The course folder (default: found from the current directory).
    private : sequence of path
        More paths the submissions may not read (on top of the course folder, the submissions and `out`).
    hidden_visibility : str
        Gradescope visibility of hidden tests, one of :data:`VISIBILITIES`.
    python : str, optional
        The interpreter of the grading sessions (default: this one).
    gradescope : path, optional
        Also write one combined Gradescope ``results.json`` for all the notebooks graded here.
    isolation : {"auto", "strict"} or Plan
        The workers' operating-system walls (see :mod:`particles.course.walls.isolation`).
    resume : bool
        Keep the records of notebooks that have not changed since an earlier run; grade the rest.
    audit_hook : bool
        False leaves the workers with the operating system's walls only: for tests of those walls.
    rubric : sequence of path
        Rubric files (or folders of them) of the written answers.
    course : path, optional
        The course file of deadlines and late policies (default: ``course.toml`` at `root`).
    times : path, optional
        A CSV ``student,exercise,submitted`` of submission times.
    times_from : {None, "mtime"}
        ``"mtime"`` accepts the notebook files' modification times as submission times when nothing else
        gives one (by default a deadline without a real submission time stops the run).
    roster : path, optional
        The roster (default: the course file's ``roster``, if any): who is in the course.
    name_column : str
        The roster's column of the grader's names of the students (default ``submission_name``; for Canvas's
        gradebook export, e.g. ``"SIS Login ID"``).
    metadata : path, optional
        Gradescope's ``submission_metadata.json``: its ``created_at`` is the time of every notebook.
    students : sequence of str, optional
        Regrade only these students' notebooks (needs `out` with the records of an earlier run).
    limits : particles.course.grading.intake.Limits, optional
        What a notebook and a zip may hold.
    scheduler : str, optional
        Grade on a Dask cluster (:mod:`particles.course.grading.cluster`): ``local:N`` (N worker processes on
        this machine), ``tcp://HOST:PORT`` or ``tls://HOST:PORT`` (a running scheduler; off this machine only
        ``tls://``). Default: this machine's pool of `jobs`.
    scheduler_file : path, optional
        Dask's scheduler file of a running cluster (instead of `scheduler`).

    Attributes
    ----------
    tests : dict
        Exercise name -> its test file (``tests/exercises/test_NN_topic.py`` of `root`).

    Raises
    ------
    ValueError
        On a bad value, naming the option: no exercise tests under `root`, an unknown exercise,
        ``jobs < 1``, a limit that is not a finite number > 0, `resume` or `students` without `out`,
        `students` with `resume`, an unknown visibility, a `times_from` other than ``"mtime"``, a malformed
        `scheduler`, `scheduler` with `scheduler_file`, `jobs` or `python`.
    """

    paths: tuple
    out: Path = None
    jobs: int = 1
    exercise: str = None
    public_only: bool = False
    seed: int = None
    time_limit: float = None
    memory_mb: float = None
    root: Path = None
    private: tuple = ()
    hidden_visibility: str = "after_published"
    python: str = None
    gradescope: Path = None
    isolation: object = "auto"
    resume: bool = False
    audit_hook: bool = True
    rubric: tuple = ()
    course: Path = None
    times: Path = None
    times_from: str = None
    roster: Path = None
    name_column: str = "submission_name"
    metadata: Path = None
    students: tuple = None
    limits: object = None
    scheduler: str = None
    scheduler_file: Path = None
    tests: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        fix = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731 (frozen: set once, here)
        root = Path(self.root).resolve() if self.root else project_root()
        fix("root", root)
        fix("tests", exercise_tests(root))
        if not self.tests:
            raise ValueError(f"no exercise tests in {root / 'tests' / 'exercises'}")
        if self.exercise is not None and self.exercise not in self.tests:
            raise ValueError(f"unknown exercise {self.exercise!r}; expected one of "
                             f"{', '.join(map(repr, self.tests))}")
        if isinstance(self.jobs, bool) or not isinstance(self.jobs, int) or self.jobs < 1:
            raise ValueError(f"jobs must be a positive integer, got {self.jobs!r}")
        if self.resume and self.out is None:
            raise ValueError("resume needs out: the folder whose course record an earlier run wrote")
        if self.students is not None:
            fix("students", tuple(dict.fromkeys(self.students)))
            if self.out is None or self.resume:
                raise ValueError("student needs out (the folder whose course record an earlier run wrote) and no resume")
        if self.hidden_visibility not in VISIBILITIES:
            raise ValueError(f"hidden_visibility must be one of {', '.join(VISIBILITIES)}, "
                             f"got {self.hidden_visibility!r}")
        for name in ("time_limit", "memory_mb"):
            value = getattr(self, name)
            fix(name, None if value is None else check_limit(name, value))
        fix("paths", _paths(self.paths))
        fix("private", _paths(self.private))
        fix("rubric", _paths(self.rubric))
        if self.times_from not in (None, "mtime"):
            raise ValueError(f"times_from must be None or 'mtime', got {self.times_from!r}")
        for name in ("out", "gradescope", "course", "times", "metadata", "roster", "scheduler_file"):
            fix(name, _optional_path(getattr(self, name)))
        self._check_cluster()

    def _check_cluster(self):
        """The cluster's options: one scheduler, well formed, and none of this machine's pool."""
        if self.scheduler is not None and self.scheduler_file is not None:
            raise ValueError("give scheduler or scheduler_file, not both")
        if self.scheduler is not None and not SCHEDULER.fullmatch(str(self.scheduler)):
            raise ValueError(f"scheduler must be local:N (N worker processes on this machine), tcp://HOST:PORT or "
                             f"tls://HOST:PORT, got {self.scheduler!r}")
        if self.scheduler_file is not None and not self.scheduler_file.is_file():
            raise ValueError(f"scheduler_file {self.scheduler_file} does not exist")
        if self.cluster and self.jobs != 1:
            raise ValueError("jobs is this machine's pool; with scheduler the cluster's workers grade (local:N for "
                             "N worker processes here)")
        if self.cluster and self.python is not None:
            raise ValueError("python cannot be given with scheduler: each worker grades with its own interpreter")

    @property
    def cluster(self):
        """True when a Dask cluster grades the run (`scheduler` or `scheduler_file`)."""
        return self.scheduler is not None or self.scheduler_file is not None

    @property
    def recorded(self):
        """The options a record keeps: a record made with others is graded again by ``--resume``."""
        return {"public_only": bool(self.public_only), "seed": self.seed, "time_limit": self.time_limit,
                "memory_mb": self.memory_mb, "audit_hook": bool(self.audit_hook)}

    @property
    def logs(self):
        """The folder of the sessions' logs (None without `out`)."""
        return None if self.out is None else self.out / "logs"
