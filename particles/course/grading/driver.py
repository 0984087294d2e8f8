"""The grading driver: ``particles grade SUBMISSION... --out DIR --jobs N [--resume]``.

A grading run is a pipeline of stages, each in its own module, strung together by :func:`run_grading`:

1. **options** (:mod:`~particles.course.grading.options`): what the run is asked to do, checked once;
2. **read** the course file and the submission times (:mod:`~particles.course.grading.deadlines`), then
   **discover** the notebooks, their students and exercises, each notebook read and checked
   (:mod:`~particles.course.grading.discovery`, :mod:`~particles.course.grading.intake`), and the rubric
   of the written answers checked against them (:mod:`particles.course.results.rubric`);
3. **plan** the batches and draw each notebook's seed (:mod:`~particles.course.grading.plan`);
4. **run** the batches, on this machine or elsewhere (:mod:`~particles.course.grading.run`: a
   :class:`~particles.course.grading.run.Runner`; :mod:`~particles.course.grading.cluster`: a Dask
   cluster, ``--scheduler``), each a pytest session (:mod:`~particles.course.grading.session`);
5. **record** each result as it arrives: its late decision made, saved, its student's outputs written
   (:mod:`~particles.course.grading.record`: a :class:`~particles.course.grading.record.Recorder`);
6. **report**: the gradebook, every student's feedback and Gradescope's file
   (:mod:`~particles.course.grading.report`).

Three processes stand between a submission and the gradebook: the worker (untrusted, walled in by the
operating system, see :mod:`particles.course.walls.isolation`, killed on a timeout, one per notebook),
the pytest session (trusted tests comparing with the reference library) and this driver, which only
reads the sessions' signed JSON records. Every submission yields a record and the driver never stops on a
submission.

What the driver does against a submission that gets out of its worker: it decides the walls once
(``--isolation auto|strict``) and every record says which were active; it imports everything it needs
before the first worker starts, turns off its own ``PR_SET_DUMPABLE``, gives its sessions a private
bytecode cache, and checks at the end that the installed library is unchanged (:class:`LibraryChanged`
otherwise: the run fails loudly); it writes each notebook's record as soon as its batch is done, so a
run that is stopped anyway keeps them and ``--resume`` grades only the rest. ``--student ID`` regrades
one student's notebooks, keeps every other record as it is and writes the gradebook and the outputs from
all.
"""

import tempfile
from pathlib import Path

from ..results.rubric import WrittenGrades
from ..term.identity import Identity
from ..term.recorder import DatabaseRecorder
from ..term.roster import read_roster
from ..walls import isolation as isolation_module
from .deadlines import LateWork, find_course, resolve_extensions
from .times import SubmissionTimes, check_times
from .discovery import find_submissions
from .options import GradeOptions
from .plan import plan_batches
from .record import Collector, MemoryRecorder
from .report import progress_report, summarize, write_gradescope, write_partial_gradebook, write_reports
from .run import LocalRunner, SessionSettings, run_all
from .session import catalog, rejected_record
from .versions import library_digest, tests_version

__all__ = ["grade", "run_grading", "LibraryChanged", "GradingInterrupted"]


class GradingInterrupted(KeyboardInterrupt):
    """A run stopped by Ctrl-C (SIGINT): its sessions stopped, every record made so far kept, the run marked
    interrupted in the course record.

    Attributes
    ----------
    graded, planned : int
        Notebooks with a record of this run, and notebooks it was to grade.
    """

    def __init__(self, graded, planned):
        self.graded, self.planned = graded, planned
        super().__init__(f"interrupted: {graded} of {planned} graded; rerun with --resume")


class LibraryChanged(RuntimeError):
    """The installed library changed while grading: the grades of the run must not be trusted.

    Attributes
    ----------
    changed : list of str
        The files (relative to the package) that differ.
    summary : dict
        What :func:`grade` would have returned.
    """

    def __init__(self, changed, summary):
        self.changed, self.summary = list(changed), summary
        shown = ", ".join(self.changed[:5]) + (" ..." if len(self.changed) > 5 else "")
        super().__init__(f"the installed library changed during grading ({len(self.changed)} file(s): {shown}); "
                         "do not trust these grades: reinstall the package and grade again")


def decide_walls(options):
    """The workers' walls (a :class:`~particles.course.walls.isolation.Plan`) and the library's checksum.

    This process is protected from its workers first; everything the driver needs is imported by now,
    so a library file that changes from here on is one the run's submissions changed. On a cluster the
    plan asks for every layer and each worker grades within the strongest it allows (``strict``: none
    without namespaces); this machine's own walls do not matter there.
    """
    if isinstance(options.isolation, isolation_module.Plan):
        plan = options.isolation
    elif options.cluster:
        plan = isolation_module.Plan(namespaces=True, separate_uid=True, landlock=True, mode=options.isolation,
                                     why="each worker of the cluster uses the strongest walls it allows")
    else:
        plan = isolation_module.plan(options.isolation)
    isolation_module.protect_this_process()
    return plan, isolation_module.library_checksum()


def choose_runner(options):
    """The run stage: this machine's pool of ``options.jobs``, or a Dask cluster (``options.scheduler``).

    The cluster's modules (and Dask) are imported only for a cluster run, here, before any worker starts.
    """
    if not options.cluster:
        return LocalRunner(options.jobs)
    try:
        from .cluster import ClusterRunner
    except ModuleNotFoundError as error:
        if error.name not in ("dask", "distributed"):
            raise
        raise ValueError(f"scheduler needs Dask's distributed, which is not installed ({error}): "
                         "pip install 'particles[cluster]'") from None

    mode = options.isolation.mode if isinstance(options.isolation, isolation_module.Plan) else options.isolation
    return ClusterRunner(options.scheduler, options.scheduler_file, root=options.root, isolation=mode)


def session_settings(options, plan, intake):
    """How the run's sessions grade; no worker may read the submissions, the outputs or the opened zips."""
    private = [*map(str, options.private), *(str(p.resolve()) for p in options.paths if p.exists())]
    private += [str(options.out.resolve())] if options.out is not None else []
    private.append(str(Path(intake).resolve()))
    return SessionSettings(root=options.root, plan=plan, private=tuple(private), logs=options.logs,
                           public_only=options.public_only, time_limit=options.time_limit,
                           memory_mb=options.memory_mb, python=options.python, audit_hook=options.audit_hook)


def open_record(options, roster, recorder=None):
    """The record stage of the run, and who is in the course.

    With an output folder: its course record (:class:`~particles.course.term.recorder.DatabaseRecorder`), locked
    for this run, whose students are the roster's (else the ones it knows). Without: the run's results in
    memory, and the roster's students (else whoever the submissions name).
    """
    if recorder is not None:
        return recorder, roster.identity() if roster is not None else Identity()
    if options.out is None:
        return MemoryRecorder(), roster.identity() if roster is not None else Identity()
    recorder = DatabaseRecorder.open(options.out, options.recorded)
    try:
        recorder.identity = recorder.term.identity(roster)
        return recorder, recorder.identity
    except Exception:
        recorder.finish(complete=False)
        raise


def check_inputs(options, course, identity, units, recorder):
    """Every name the instructor wrote is a student's, every deadline has real submission times.

    Returns the course with its extensions under the students' grader names, the submission times, the rubric's
    written grades and the problems to report; raises ValueError (nothing graded) on an unknown name in the
    course file's extensions, the times file or a rubric, or a notebook of an exercise with a deadline and no
    submission time.
    """
    if options.metadata is None or identity.closed:  # Gradescope's one submission: its own names only
        course = resolve_extensions(course, identity)
    earlier = getattr(getattr(recorder, "term", None), "submission_time", None)
    times = SubmissionTimes(options.metadata, options.times, identity, list(options.tests),
                            options.times_from == "mtime", earlier)
    written = WrittenGrades.load(options.rubric, units, options.root, list(options.tests), identity)
    return course, times, written, check_times(units, course, times)


def select_students(options, units, recorder, identity):
    """``(units, others)``: the units this run grades (with ``--student``, those students' only) and the current
    records of every other notebook of the term, kept as they are."""
    current = recorder.current()
    if options.students is not None:
        if not current:
            raise ValueError(f"student needs the records of an earlier run; {options.out} holds none")
        found = {u.student for u in units}
        names = [identity.find(s).name if identity.find(s) else s for s in options.students]
        unknown = [s for s, name in zip(options.students, names) if name not in found]
        if unknown:
            known = sorted(found | {student for student, _ in current})
            raise ValueError(f"unknown student {unknown[0]!r}: no notebook of theirs in the submissions; "
                             f"the students are {', '.join(known)}")
        units = [u for u in units if u.student in names]
    graded = {(u.student, u.exercise) for u in units}
    return units, {key: record for key, record in current.items() if key not in graded}


def resume(options, units, recorder, collect):
    """The units left to grade; with ``--resume``, the unchanged ones' records are kept (`collect`)."""
    todo = [u for u in units if not u.rejected]
    if not options.resume:
        return todo
    library = library_digest()
    versions = {name: tests_version(options.root, name, library) for name in options.tests}
    left = []
    for unit in todo:
        kept = recorder.kept(unit, versions[unit.exercise])
        if kept is None:
            left.append(unit)
            continue
        kept.notebook = unit.where
        collect.keep(kept)
    return left


def collect_rejected(units, settings, collect, problems):
    """A notebook discovery refused gets its record at once: every test of its exercise failed, saying why."""
    catalogs = {}
    for unit in (u for u in units if u.rejected):
        if unit.exercise not in catalogs:
            try:
                catalogs[unit.exercise] = catalog(settings.root, unit.exercise, settings.public_only, settings.python)
            except RuntimeError as error:
                catalogs[unit.exercise] = []
                problems.append(str(error))
        collect([rejected_record(unit, catalogs[unit.exercise])])


def run_grading(options, progress=None, runner=None, recorder=None):
    """Run the grading pipeline of `options` (a :class:`~particles.course.grading.options.GradeOptions`).

    Parameters
    ----------
    options : GradeOptions
    progress : callable, optional
        Called with each notebook's record as it is made.
    runner : particles.course.grading.run.Runner, optional
        Where the batches are graded (default: :func:`choose_runner`'s: this machine, ``options.jobs`` at a
        time, or the cluster of ``options.scheduler``); its ``slots``, when it has them, size the batches.
    recorder : particles.course.grading.record.Recorder, optional
        Where the records are kept (default: the course record of ``out``, or memory without `out`).

    Returns
    -------
    dict
        See :func:`grade`.
    """
    course = find_course(options.root, list(options.tests), options.course)                    # read
    # Gradescope's one submission (--metadata) checks only its own names: the course's roster is not needed
    roster_path = options.roster or (course.roster if course is not None and options.metadata is None else None)
    roster = read_roster(roster_path, options.name_column) if roster_path is not None else None
    runner = runner or choose_runner(options)
    plan, before = decide_walls(options)
    recorder, identity = open_record(options, roster, recorder)
    complete, state = False, {}
    try:
        with tempfile.TemporaryDirectory(prefix="particles-intake-") as intake:
            summary, changed = _stages(options, course, identity, plan, before, recorder, runner, progress, intake,
                                       state)
        complete = True
    except KeyboardInterrupt:
        collect = state.get("collect")
        if collect is not None:  # the gradebook says what is not graded yet
            write_partial_gradebook(options, collect.done, sorted(collect.todo))
        graded = collect.collected if collect is not None else 0
        raise GradingInterrupted(graded, graded + (len(collect.todo) if collect is not None else 0)) from None
    finally:
        recorder.finish(complete)
    if changed:
        raise LibraryChanged(changed, summary)
    return summary


def _stages(options, course, identity, plan, before, recorder, runner, progress, intake, state):
    """The stages from discovery to the reports (see :func:`run_grading`); returns (summary, changed files).

    `state` receives the run's collector (``"collect"``), for what an interrupted run says."""
    limits = {"limits": options.limits} if options.limits is not None else {}
    units, problems = find_submissions(options.paths, list(options.tests), options.exercise,      # discover
                                       workdir=intake, identity=identity, **limits)
    course, times, written, late_flags = check_inputs(options, course, identity, units, recorder)
    problems += late_flags
    units, others = select_students(options, units, recorder, identity)
    if options.out is not None:
        options.logs.mkdir(parents=True, exist_ok=True)
    recorder.start(units, times.of)
    recorder.keep_course(course)
    written = recorder.keep_written(written)
    collect = Collector(recorder, LateWork(course, times, units), progress_report(options, written),
                        progress, done=others)
    collect.todo = {(u.student, u.exercise) for u in units if not u.rejected}
    state["collect"] = collect
    todo = resume(options, units, recorder, collect)
    settings = session_settings(options, plan, intake)
    collect_rejected(units, settings, collect, problems)
    slots = getattr(runner, "slots", options.jobs) if todo else options.jobs  # a cluster: its workers
    batches = plan_batches(todo, slots, options.seed)                                              # plan
    run_all(batches, runner, settings, collect)                                                    # run, record
    kept = sum(1 for u in units if not u.rejected) - len(todo)
    summary = summarize(options.tests, units, collect.done, problems, plan, kept, others)
    changed = isolation_module.library_changes(before)
    if course is not None:  # a new deadline or extension: every decision made again, from the kept times
        for record in others.values():
            collect.late(record)
    write_reports(options, collect.done, recorder, written, changed)                               # report
    if options.gradescope is not None:
        results = [collect.done[(u.student, u.exercise)] for u in units]
        write_gradescope(options, results, problems, summary["isolation"], written, changed)
    return summary, changed


def grade(paths, out=None, *, progress=None, runner=None, recorder=None, **options):
    """Grade submissions; write results.json and feedback per student and a gradebook.

    Parameters
    ----------
    paths : sequence of path
        Notebooks, folders of notebooks, zips of them (LMS exports; see
        :mod:`particles.course.grading.discovery`). A notebook the grader does
        not read (:func:`particles.course.grading.intake.read_notebook`), or
        several notebooks of one student and exercise from different places,
        get a record where every test failed with the one-line reason, and
        are among the ``problems``.
    out : path, optional
        Output folder: ``gradebook.csv``, ``<student>/results.json``,
        ``<student>/feedback.md`` and ``<student>/feedback.html`` (with the
        tests' figures), ``course.sqlite`` (the term's record: every result, kept as
        soon as it is made) and ``logs/``. Nothing is written without it.
    progress : callable, optional
        Called with each per-exercise result as it completes.
    runner, recorder : optional
        The run and record stages (see :func:`run_grading`).
    **options
        The other fields of :class:`~particles.course.grading.options.GradeOptions`: ``jobs``,
        ``exercise``, ``public_only``, ``seed``, ``time_limit``, ``memory_mb``, ``root``, ``private``,
        ``hidden_visibility``, ``python``, ``gradescope``, ``isolation``, ``resume``, ``audit_hook``,
        ``rubric``, ``course``, ``times``, ``metadata``, ``students``, ``limits``, ``scheduler``,
        ``scheduler_file``.

    Returns
    -------
    dict
        ``students`` (student -> list of per-exercise results), ``exercises``
        (names graded, in order), ``problems`` (one line per notebook not
        graded, zip refused, link not followed...),
        ``isolation`` (one line: the walls the workers had), ``resumed``
        (how many records were kept from an earlier run), ``kept`` (how
        many records of other students `students` kept as they were),
        ``rejected`` (the notebooks scored 0 without being run).

    Raises
    ------
    ValueError
        On bad arguments (see :class:`~particles.course.grading.options.GradeOptions`), a rubric that
        does not fit the submissions (:class:`~particles.course.results.rubric.RubricError`), a bad
        course, times or metadata file, `students` without the records of an earlier run in `out` or
        with an unknown student.
    particles.course.walls.isolation.IsolationUnavailable
        When `isolation` is ``strict`` and the namespace sandbox cannot start.
    LibraryChanged
        When the installed library is not the same at the end of the run as
        at its start (after the outputs are written, marked as untrusted).
    """
    return run_grading(GradeOptions(paths=tuple(paths), out=out, **options), progress=progress, runner=runner,
                       recorder=recorder)
