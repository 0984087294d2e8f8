"""The grading driver: ``particles grade SUBMISSION... --out DIR --jobs N [--resume]``.

Notebooks of one exercise are graded in batches by ``pytest`` processes that
run ``tests/exercises/test_NN_topic.py`` with the plugin of
:mod:`particles.course.grading.plugin`; for each notebook such a process starts a
worker that runs the student's code. So three processes stand between a
submission and the gradebook: the worker (untrusted, walled in by the
operating system, see :mod:`particles.course.walls.isolation`, killed on a
timeout, one per notebook), the pytest session (trusted tests comparing with
the reference library) and this driver, which only reads JSON records. If a
pytest session stops early (it should not), the notebooks it had not finished
are graded again, each in a session of its own; a test that still has no
record is recorded as failed with the reason. So every submission yields a
record and the driver never stops on a submission. ``--jobs N`` runs N
sessions at a time.

The driver trusts a session's records only when pytest ended normally
(exit status 0 or 1) and the records file carries the signature of a key
that only the driver and that session know (:mod:`particles.course.results.signing`).

What the driver does against a submission that gets out of its worker:

* it decides the walls once (``--isolation auto|strict``) and every record
  says which were active;
* it imports everything it needs before the first worker starts, turns off
  its own ``PR_SET_DUMPABLE``, gives its sessions a private bytecode cache
  (``PYTHONPYCACHEPREFIX``, so a planted ``.pyc`` in the library is never
  loaded), and checks at the end that the installed library is unchanged
  (:class:`LibraryChanged` otherwise: the run fails loudly);
* it writes each notebook's record as soon as its batch is done
  (``DIR/records/``), so a run that is stopped anyway keeps them and
  ``--resume`` grades only the rest (:mod:`particles.course.results.store`).

Each record says which version of the tests graded it (``tests_version``,
:mod:`particles.course.grading.versions`: ``--resume`` grades again what a
changed test affects) and, when the course file gives its exercise a deadline,
the late-work decision (``late``, :mod:`particles.course.grading.deadlines`).
``--student ID`` regrades one student's notebooks, keeps every other record of
``DIR/records/`` as it is and writes the gradebook and the outputs from all.

Which notebooks are graded, and as which student and exercise, is decided in
:mod:`particles.course.grading.discovery`; zips are opened, and notebooks
checked before they are graded, in :mod:`particles.course.grading.intake`. A
notebook rejected there is never given to a session: its record fails every
test of the exercise's catalog with the one-line reason.
"""

import itertools
import json
import math
import os
import secrets
import stat
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from ..walls import isolation as isolation_module
from ..release.answers import answers_note
from .discovery import Unit, find_submissions, notebook_digest, written_answers
from ..paths import exercise_tests, project_root
from ..worker.process import library_parent
from ..results.records import SessionRecord, SubmissionRecord, TestRecord
from ..results.reports import gradescope_results, write_json, write_outputs
from ..walls.limits import check_limit
from ..results.signing import TOKEN_FD, read_records, sign_records
from ..results.store import RecordStore
from ..results.rubric import WrittenGrades
from ..results.store import RecordStore, regrade_split
from .deadlines import SubmissionTimes, apply_late, find_course
from .versions import library_digest, tests_version

__all__ = ["Unit", "find_submissions", "grade_batch", "grade_unit", "grade", "catalog", "read_records",
           "sign_records", "TOKEN_FD", "written_answers", "LibraryChanged"]


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


def _private_folder(name):
    """A folder only this user may enter, kept between runs (made anew if it is not safely ours)."""
    folder = Path(tempfile.gettempdir()) / f"{name}-{os.geteuid()}"
    try:
        folder.mkdir(mode=0o700)
    except FileExistsError:
        pass
    info = os.lstat(folder)
    if not stat.S_ISDIR(info.st_mode) or info.st_uid != os.geteuid() or info.st_mode & 0o077:
        return Path(tempfile.mkdtemp(prefix=f"{name}-"))
    return folder


def _pytest_command(python, root, test_file, extra):
    # --tb=native: tracebacks in the log as Python prints them (pytest's style parses each frame's source file)
    return [python, "-m", "pytest", str(test_file), "-q", "--tb=native", "-p", "particles.course.grading.plugin",
            "-p", "no:cacheprovider", "--rootdir", str(root), "-o", "addopts=", *extra]


def _environment(root):
    env = dict(os.environ)
    parent = library_parent()
    env["PYTHONPATH"] = parent + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env["PARTICLES_COURSE_ROOT"] = str(root)
    # the sessions' bytecode lives in a folder only the grader may write, never in the library's __pycache__
    env["PYTHONPYCACHEPREFIX"] = str(_private_folder("particles-grader-pycache"))
    # only the grader's plugin (named with -p): a plugin installed beside pytest would change the sessions
    # (pytest-randomly reorders the tests and reseeds the generators), and loading them (pytest-xdist,
    # platformdirs' own) took a tenth of a session's start
    env["PYTEST_DISABLE_PLUGIN_AUTOLOAD"] = "1"
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def catalog(root, exercise, public_only=False, python=None):
    """The tests of an exercise (records with ``passed=False``), from ``pytest --collect-only``."""
    root = Path(root)
    test_file = exercise_tests(root)[exercise]
    with tempfile.TemporaryDirectory(prefix="particles-catalog-") as tmp:
        out = Path(tmp) / "catalog.json"
        extra = ["--collect-only", "--grading-catalog", str(out)] + (["--public-only"] if public_only else [])
        subprocess.run(_pytest_command(python or sys.executable, root, test_file, extra), cwd=tmp,
                       env=_environment(root), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=300)
        try:
            return json.loads(out.read_text())
        except (OSError, ValueError):
            raise RuntimeError(f"cannot collect the tests of {test_file}; run pytest on it to see why") from None


def _result(unit, seed, data, status, tests, seconds, trouble=None, root=None, version=""):
    """The :class:`SubmissionRecord` of `unit` from its session's record `data` (None: the session gave none)."""
    session = data if data is not None else SessionRecord(id="", seed=seed)
    records = list(session.tests)
    if tests is not None:  # make sure every expected test has a record
        seen = {r.test for r in records}
        why = (f"not run: grading stopped early ({trouble or f'pytest exit status {status}'}); "
               "the instructor has the log")
        records += [TestRecord.from_dict(t).failed(why) for t in tests if t["test"] not in seen]
    notes = []
    for error in session.load_errors:
        where = f" ({error['where']})" if error.get("where") else ""
        notes.append(f"While loading your notebook, {error['label']}{where} raised "
                     f"{error['type']}: {error['message']}")
    for label, message in session.syntax_errors:
        notes.append(f"{label} has a syntax error ({message}) and was not run")
    if session.restarts > 1:
        notes.append(f"The worker running your code was restarted {session.restarts - 1} time(s) "
                     "after a timeout or a crash")
    written = written_answers(unit.notebook, root, unit.exercise) if root is not None else None
    if written and written["asked"]:
        notes.append(answers_note(written))
    layers = session.isolation or {}
    return SubmissionRecord(
        student=unit.student, exercise=unit.exercise, notebook=unit.where, seed=seed,
        seconds=round(session.seconds if session.complete else seconds, 2), tests=records, notes=notes,
        written_answers=written, grader_status=status, complete=session.complete, isolation=layers,
        sandbox=isolation_module.describe(layers), notebook_sha256=notebook_digest(unit.notebook),
        tests_version=version)


def _rejected(unit, tests):
    """The record of a unit discovery rejected: every test of `tests` failed with its reason; never resumed."""
    return SubmissionRecord(
        student=unit.student, exercise=unit.exercise, notebook=unit.where, seconds=0.0,
        tests=[TestRecord.from_dict(t).failed(unit.rejected) for t in tests],
        notes=[f"Not graded: {unit.rejected}"], grader_status=None, complete=True,
        sandbox="not run: the notebook was not graded")


def grade_batch(units, root, *, seeds=None, public_only=False, time_limit=None, memory_mb=None, private=(),
                python=None, log=None, tests=None, timeout=None, isolation=None, audit_hook=True):
    """Grade notebooks of one exercise in one pytest session; never raises on a bad submission.

    Each notebook still gets its own worker; only the pytest process (and the
    reference library it imports) is shared, which makes a batch several
    times cheaper than one session per notebook.

    Parameters
    ----------
    units : list of Unit
        All of the same exercise.
    seeds : list of int, optional
        One per unit (default: new random seeds).
    tests : list of dict, optional
        The exercise's catalog (see :func:`catalog`): tests a notebook has no
        record for are recorded as failed, "not run".
    isolation : Plan or str, optional
        The workers' walls (default: the strongest available, see
        :func:`particles.course.walls.isolation.plan`).
    audit_hook : bool
        False runs the workers without their Python-level walls, leaving only
        the operating system's: for tests that those hold on their own, never
        for real grading (default True).

    Notes
    -----
    The session's records are trusted only when pytest exited with status 0
    or 1 (the tests ran to the end) and the records file carries the
    signature of the session's key (see :data:`TOKEN_FD`); otherwise they are
    all discarded, and every test of every notebook of the batch is recorded
    as "not run: grading stopped early" (:func:`grade` then grades each of
    them again in a session of its own).

    Returns
    -------
    list of SubmissionRecord
        One per unit, in order (``complete`` is False when its session did
        not finish it: its missing tests are recorded as failed, "not run").

    Raises
    ------
    ValueError
        When the units are of several exercises, or `time_limit` or
        `memory_mb` is not a finite number > 0.
    """
    root = Path(root)
    if len({u.exercise for u in units}) != 1:
        raise ValueError("a batch must hold notebooks of one exercise")
    time_limit = None if time_limit is None else check_limit("time_limit", time_limit)
    memory_mb = None if memory_mb is None else check_limit("memory_mb", memory_mb)
    seeds = [secrets.randbelow(2**31) for _ in units] if seeds is None else [int(s) for s in seeds]
    test_file = exercise_tests(root)[units[0].exercise]
    version = tests_version(root, units[0].exercise)  # before the session reads them
    timeout = timeout or 300 + 120 * len(units)
    token = secrets.token_bytes(32)  # this session's signing key, never written to a file or an environment
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="particles-grade-") as tmp:
        private_dir = Path(tmp) / "grader"
        private_dir.mkdir()
        batch, results = private_dir / "batch.json", private_dir / "records.json"
        batch.write_text(json.dumps([{"id": str(k), "notebook": str(Path(u.notebook).resolve()), "seed": seed}
                                     for k, (u, seed) in enumerate(zip(units, seeds))]))
        extra = ["--grading-batch", str(batch), "--grading-results", str(results)]
        extra += ["--public-only"] if public_only else []
        extra += [] if audit_hook else ["--no-audit-hook"]
        extra += ["--time-limit", repr(time_limit)] if time_limit is not None else []
        extra += ["--memory-mb", str(math.ceil(memory_mb))] if memory_mb is not None else []
        for path in private:
            extra += ["--private", str(path)]
        plan = isolation if isinstance(isolation, isolation_module.Plan) else (
            isolation_module.plan("auto") if isolation is None else isolation_module.Plan.from_option(isolation))
        extra += ["--isolation", plan.to_option()]
        status, output = None, ""
        key_in, key_out = os.pipe()
        try:
            os.write(key_out, token)
            os.close(key_out)
            env = dict(_environment(root), **{TOKEN_FD: str(key_in)})
            done = subprocess.run(_pytest_command(python or sys.executable, root, test_file, extra), cwd=tmp,
                                  env=env, capture_output=True, text=True, timeout=timeout, pass_fds=(key_in,))
            status, output = done.returncode, done.stdout + done.stderr
        except subprocess.TimeoutExpired as expired:
            output = f"grading stopped after {timeout} s\n{expired.stdout or ''}"
        finally:
            os.close(key_in)
        # the records count only if the tests ran to the end (exit status 0: all passed, 1: some failed)
        # and the file is the one the session signed: a submission that escaped its worker could kill
        # the session after writing records of its own, or rewrite the file
        data, trouble = {}, None
        if status not in (0, 1):
            trouble = f"pytest exit status {status}" if status is not None else f"no result within {timeout} s"
        else:
            data = read_records(results, token)
            if data is None:
                data, trouble = {}, "the session's records were missing or not the ones it signed"
        try:
            data = {key: SessionRecord.from_dict(record) for key, record in data.items()}
        except (TypeError, ValueError) as error:
            data, trouble = {}, f"the session's records could not be read ({error})"
        if trouble is not None:
            output += f"\nparticles grade: records of this session discarded: {trouble}\n"
        if log is not None:
            Path(log).write_text(output)
    elapsed = time.perf_counter() - start
    if tests is None and any(str(k) not in data or not data[str(k)].complete for k in range(len(units))):
        try:
            tests = catalog(root, units[0].exercise, public_only, python)
        except RuntimeError:
            tests = []
    return [_result(u, seed, data.get(str(k)), status, tests, elapsed / len(units), trouble, root, version)
            for k, (u, seed) in enumerate(zip(units, seeds))]


def grade_unit(unit, root, *, seed=None, **options):
    """Grade one notebook (see :func:`grade_batch`); returns its :class:`SubmissionRecord`."""
    return grade_batch([unit], root, seeds=None if seed is None else [seed], **options)[0]


def _batches(units, jobs, largest=20):
    """Split units into batches of one exercise for `jobs` processes: large first, smaller towards the end.

    Each batch is one pytest session, whose start-up (about 1 s of CPU) and reference results are paid
    once, so a batch should be large; but the last batches decide when the run ends, so they should be
    small. Guided self-scheduling does both: each batch takes about a ``2 * jobs``-th of the notebooks not
    yet batched (at most `largest`, never across exercises). A corpus of 95 notebooks over six exercises
    on two jobs makes 14 batches instead of 36 (six per exercise); one exercise of 17 makes 6 (5, 3, 3, 2, 2, 2).
    """
    by_exercise = {}
    for unit in units:
        by_exercise.setdefault(unit.exercise, []).append(unit)
    out, left = [], len(units)
    for group in by_exercise.values():
        sizes, rest = [], len(group)
        while rest:
            size = min(largest, rest, max(2, math.ceil(left / (2 * max(jobs, 1)))))
            if rest - size == 1:  # no batch of one left behind: take it too, or leave two
                size = rest if rest <= largest else size - 1
            sizes.append(size)
            rest, left = rest - size, left - size
        starts = list(itertools.accumulate(sorted(sizes, reverse=True), initial=0))  # a tail that grew goes first
        out += [group[a:b] for a, b in zip(starts[:-1], starts[1:])]
    return out


def grade(paths, out=None, *, jobs=1, exercise=None, public_only=False, seed=None, time_limit=None,
          memory_mb=None, root=None, private=(), hidden_visibility="after_published", python=None,
          gradescope=None, progress=None, isolation="auto", resume=False, audit_hook=True, rubric=(),
          course=None, times=None, metadata=None, students=None, limits=None):
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
        tests' figures), ``records/`` (one record per notebook,
        written as soon as it is graded) and ``logs/``. Nothing is written
        without it.
    jobs : int
        Notebooks graded at the same time (each takes one core).
    exercise : str, optional
        Grade every notebook as this exercise.
    public_only : bool
        Run only the public tests.
    seed : int, optional
        Seed of the hidden tests' random parameters (default: a new random
        seed per notebook, recorded in the results).
    time_limit, memory_mb : float, optional
        Per-call time limit (s) of the tests without their own ``time_limit``
        marker, and memory (MiB) of the student's code; finite and > 0.
    root : path, optional
        The course folder (default: found from the current directory).
    private : sequence of path
        More paths the submissions may not read (on top of the course folder,
        the submissions given in `paths` and `out`).
    hidden_visibility : str
        Gradescope visibility of hidden tests.
    gradescope : path, optional
        Also write one combined Gradescope ``results.json`` for all the
        notebooks graded here (one Gradescope submission).
    progress : callable, optional
        Called with each per-exercise result as it completes.
    isolation : {"auto", "strict"}
        The workers' operating-system walls: ``auto`` uses the strongest this
        machine allows, ``strict`` refuses to grade without the namespace
        sandbox (see :mod:`particles.course.walls.isolation`).
    resume : bool
        Keep the records already in ``out/records/`` of notebooks that have
        not changed since (same bytes, same options, same tests version) and
        grade only the rest.
    audit_hook : bool
        False leaves the workers with the operating system's walls only (see
        :func:`grade_batch`); for tests of those walls, never for grading.
    rubric : sequence of path
        Rubric files (or folders of them) of the written answers, checked before anything is graded
        and merged into every record when the outputs are written
        (:mod:`particles.course.results.rubric`).
    course : path, optional
        The course file of deadlines and late policies (default: ``course.toml`` at `root`, when there
        is one; see :mod:`particles.course.grading.deadlines`).
    times : path, optional
        A CSV ``student,exercise,submitted`` of submission times (default: the notebooks' file times).
    metadata : path, optional
        Gradescope's ``submission_metadata.json``: its ``created_at`` is the time of every notebook.
    students : sequence of str, optional
        Regrade only these students' notebooks (needs `out` with the records of an earlier run): every
        other record in ``out/records/`` is kept as it is, and the gradebook and every student's
        outputs are written again from all the records.
    limits : particles.course.grading.intake.Limits, optional
        What a notebook and a zip may hold (default
        :data:`~particles.course.grading.intake.DEFAULT_LIMITS`).

    Returns
    -------
    dict
        ``students`` (student -> list of per-exercise results), ``exercises``
        (names graded, in order), ``problems`` (one line per notebook not
        graded, zip refused, link not followed...),
        ``isolation`` (one line: the walls the workers had), ``resumed``
        (how many records were kept from an earlier run), ``kept`` (how
        many records of other students `students` kept as they were).

    Raises
    ------
    ValueError
        On bad arguments (no exercise tests found, unknown exercise, jobs < 1,
        a `time_limit` or `memory_mb` that is not a finite number > 0, an
        unknown isolation mode, `resume` without `out`, a rubric that does not fit the submissions:
        :class:`~particles.course.results.rubric.RubricError`, a bad course, times or metadata file,
        `students` without the records of an earlier run in `out` or with an unknown student).
    particles.course.walls.isolation.IsolationUnavailable
        When `isolation` is ``strict`` and the namespace sandbox cannot start.
    LibraryChanged
        When the installed library is not the same at the end of the run as
        at its start (after the outputs are written, marked as untrusted).
    """
    root = Path(root).resolve() if root else project_root()
    tests = exercise_tests(root)
    if not tests:
        raise ValueError(f"no exercise tests in {root / 'tests' / 'exercises'}")
    if exercise is not None and exercise not in tests:
        raise ValueError(f"unknown exercise {exercise!r}; expected one of {', '.join(map(repr, tests))}")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    if resume and out is None:
        raise ValueError("resume needs out: the folder whose records/ an earlier run wrote")
    students = None if students is None else list(dict.fromkeys(students))
    if students is not None and (out is None or resume):
        raise ValueError("student needs out (the folder whose records/ an earlier run wrote) and no resume")
    deadlines = find_course(root, list(tests), course)
    submitted = SubmissionTimes(metadata, times)
    versions = {}  # the tests' versions before anything is graded, for --resume's comparison with the kept records
    if resume:  # (each batch takes its own for its records)
        library = library_digest()
        versions = {name: tests_version(root, name, library) for name in tests}
    time_limit = None if time_limit is None else check_limit("time_limit", time_limit)
    memory_mb = None if memory_mb is None else check_limit("memory_mb", memory_mb)
    # ValueError or IsolationUnavailable before anything is graded (a Plan itself: for tests and benchmarks)
    plan = isolation if isinstance(isolation, isolation_module.Plan) else isolation_module.plan(isolation)
    isolation_module.protect_this_process()
    before = isolation_module.library_checksum()  # everything the driver needs is imported by now
    with tempfile.TemporaryDirectory(prefix="particles-intake-") as intake:  # the zips' notebooks, while graded
        units, problems = find_submissions(paths, list(tests), exercise, workdir=intake,
                                           **({"limits": limits} if limits is not None else {}))
        written = WrittenGrades.load(rubric, units, root, [exercise] if exercise else [])  # a bad rubric: no grading
        others = {}
        if students is not None:
            units, others = regrade_split(Path(out) / "records", units, students)
        if out is not None:
            out = Path(out)
            (out / "logs").mkdir(parents=True, exist_ok=True)
        # no worker may read the submissions (a classmate's notebook) or what grading writes; a worker gets
        # its own code from the grader, so it never needs to read its notebook either
        private = [*map(str, private), *(str(Path(p).resolve()) for p in paths if Path(p).exists())]
        private += [str(out.resolve())] if out is not None else []
        private.append(str(Path(intake).resolve()))
        options = {"public_only": bool(public_only), "seed": seed, "time_limit": time_limit, "memory_mb": memory_mb,
                   "audit_hook": bool(audit_hook)}
        store = RecordStore(out / "records", options) if out is not None else None
        done = dict(others)
        by_key = {(u.student, u.exercise): u for u in units}

        def late(result):  # the late-work decision, from the course file and the submission's time
            when, source = submitted.of(by_key[(result.student, result.exercise)])
            return apply_late(result, deadlines, when, source, submitted.aliases())

        if resume:
            for unit in units:
                kept = store.load(unit, versions[unit.exercise]) if not unit.rejected else None
                if kept is not None:
                    kept.notebook = unit.where
                    decided = kept.late
                    done[(unit.student, unit.exercise)] = late(kept)
                    if kept.late != decided:  # a new deadline or extension: the same grade, a new decision
                        store.save(kept)
        todo = [u for u in units if (u.student, u.exercise) not in done and not u.rejected]
        lock = threading.Lock()

        def finished(results):
            with lock:
                for result in results:
                    late(result)
                    done[(result.student, result.exercise)] = result
                    if store is not None:
                        store.save(result)
                if out is not None:  # what a stopped run leaves is already usable
                    write_outputs(out, done, tests, hidden_visibility, students=[r.student for r in results],
                                  written=written)
            if progress is not None:
                for result in results:
                    progress(result)

        def work(batch):
            k = batches.index(batch)
            log = out / "logs" / f"batch{k:03d}-{batch[0].exercise}.log" if out is not None else None
            seeds = [seed if seed is not None else secrets.randbelow(2**31) for _ in batch]
            results = grade_batch(batch, root, seeds=seeds, public_only=public_only, time_limit=time_limit,
                                  memory_mb=memory_mb, private=private, python=python, log=log, isolation=plan,
                                  audit_hook=audit_hook)
            if len(batch) > 1:  # a session that stopped early: grade its unfinished notebooks alone
                for i, (unit, result) in enumerate(zip(batch, results)):
                    if not result.complete:
                        retry_log = out / "logs" / f"{unit.student}-{unit.exercise}.log" if out is not None else None
                        results[i] = grade_unit(unit, root, seed=seeds[i], public_only=public_only,
                                                time_limit=time_limit, memory_mb=memory_mb, private=private,
                                                python=python, log=retry_log, isolation=plan, audit_hook=audit_hook)
            finished(results)
            return results

        catalogs = {}
        for unit in units:  # a notebook not graded gets its record at once: 0, saying why
            if unit.rejected:
                if unit.exercise not in catalogs:
                    try:
                        catalogs[unit.exercise] = catalog(root, unit.exercise, public_only, python)
                    except RuntimeError as error:
                        catalogs[unit.exercise] = []
                        problems.append(str(error))
                finished([_rejected(unit, catalogs[unit.exercise])])
        batches = _batches(todo, jobs)
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            list(pool.map(work, batches))
        results = [done[(u.student, u.exercise)] for u in units]
        kept = sum(1 for u in units if not u.rejected) - len(todo)
        graded = {}
        for result in results:
            graded.setdefault(result.student, []).append(result)
        exercises = [name for name in tests if any(u.exercise == name for u in units)]
        layers = [r.isolation for r in results if r.isolation]
        summary = {"students": graded, "exercises": exercises, "problems": problems,
                   "isolation": isolation_module.describe(layers[0] if layers else {}) if results else
                   f"planned: {plan.to_option()}", "resumed": kept, "kept": len(others),
                   "rejected": [u.where for u in units if u.rejected]}
        changed = isolation_module.library_changes(before)
        if out is not None:
            write_outputs(out, done, tests, hidden_visibility, written=written)
            for record in done.values():  # records/ holds what the feedback says: written grades, late work
                store.update(record)
            if changed:
                (out / "LIBRARY-CHANGED.txt").write_text(
                    "The installed particles library changed while these submissions were graded:\n"
                    + "".join(f"  {name}\n" for name in changed) + "Do not trust these grades.\n")
        if gradescope is not None:
            if not results and exercise is not None:  # nothing gradable was submitted: every test fails, saying why
                why = "no notebook for this exercise was found in your submission" if not problems else problems[0]
                tests_of = catalog(root, exercise, public_only, python)
                results = [SubmissionRecord(student="submission", exercise=exercise, sandbox=summary["isolation"],
                                            tests=[TestRecord.from_dict(t).failed(why) for t in tests_of])]
            written.apply(results)
            data = gradescope_results("submission", results, hidden_visibility, manual=written.manual())
            if problems:
                data["output"] = "\n".join([data["output"], *problems]).strip()
            if changed:  # a compromised container: no score is better than a forged one
                data = {"score": 0, "output": "The autograder's own files changed while grading this submission; "
                        "it was not graded. Please tell the instructors.", "tests": [], "visibility": "visible"}
            Path(gradescope).parent.mkdir(parents=True, exist_ok=True)
            write_json(gradescope, data)
        if changed:
            raise LibraryChanged(changed, summary)
        return summary
