"""One grading session: a pytest process that grades a batch of notebooks of one exercise.

``tests/exercises/test_NN_topic.py`` runs with the plugin of :mod:`particles.course.grading.plugin`
(and no other); for each notebook the session starts a worker that runs the student's code
(:mod:`particles.course.worker`), walled in by the operating system
(:mod:`particles.course.walls.isolation`) and killed on a timeout. The session writes its records to a
JSON file that it signs with a key only it and this process know
(:mod:`particles.course.results.signing`); :func:`grade_batch` trusts them only when pytest ended
normally (exit status 0 or 1) and the signature holds, and turns them into one
:class:`~particles.course.results.records.SubmissionRecord` per notebook. A session that stopped early
leaves its unfinished notebooks' tests "not run"; the run stage grades those again alone
(:func:`particles.course.grading.run.run_batch`).

:func:`catalog` lists an exercise's tests without grading (``pytest --collect-only``);
:func:`rejected_record` is the record of a notebook that discovery refused: every test failed, saying why.
"""

import json
import math
import os
import secrets
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from ..paths import exercise_tests
from ..release.answers import answers_note
from ..results.records import SessionRecord, SubmissionRecord, TestRecord
from ..results.signing import TOKEN_FD, read_records
from ..walls import isolation as isolation_module
from ..walls.limits import check_limit
from ..walls.syscalls import PARENT_VARIABLE
from ..worker.process import library_parent
from .discovery import notebook_digest, written_answers
from .versions import tests_version

__all__ = ["catalog", "grade_batch", "grade_unit", "rejected_record", "stop_sessions", "STOPPING"]


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
    env[PARENT_VARIABLE] = str(os.getpid())  # the session dies with this process (a cluster's worker killed)
    # the sessions' bytecode lives in a folder only the grader may write, never in the library's __pycache__
    env["PYTHONPYCACHEPREFIX"] = str(_private_folder("particles-grader-pycache"))
    # only the grader's plugin (named with -p): a plugin installed beside pytest would change the sessions
    # (pytest-randomly reorders the tests and reseeds the generators), and loading them (pytest-xdist,
    # platformdirs' own) took a tenth of a session's start
    env["PYTEST_DISABLE_PLUGIN_AUTOLOAD"] = "1"
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


_RUNNING = set()  # the sessions running now (Popen objects), so that a stopped run can stop them at once
_RUNNING_LOCK = threading.Lock()
PARSING = threading.Lock()
"""Held while a grading thread parses Python (the tests' imports, a notebook's answers): CPython 3.11's parser is
not safe in two threads at once ("AST constructor recursion depth mismatch", python/cpython#106905)."""
STOPPING = threading.Event()
"""Set while a stopped run ends: no new session starts (cleared when a run starts: :class:`~particles.course.grading.run.LocalRunner`)."""


def _run_session(command, cwd, env, timeout, key_fd):
    """Run one session; (exit status or None after `timeout`, its output). The session has a process group of its
    own (a Ctrl-C at the terminal reaches the driver only, which stops it: :func:`stop_sessions`) and dies with
    the driver (the plugin asks the kernel for it)."""
    with _RUNNING_LOCK:
        if STOPPING.is_set():
            return None, "grading stopped: the run was interrupted"
        process = subprocess.Popen(command, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                   text=True, pass_fds=(key_fd,), start_new_session=True)
        _RUNNING.add(process)
    try:
        output, _ = process.communicate(timeout=timeout)
        return process.returncode, output
    except subprocess.TimeoutExpired:
        _kill_group(process)
        output, _ = process.communicate()
        return None, f"grading stopped after {timeout} s\n{output or ''}"
    finally:
        with _RUNNING_LOCK:
            _RUNNING.discard(process)


def _kill_group(process):
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def stop_sessions():
    """SIGKILL every grading session this process runs (a run that was interrupted); returns how many."""
    with _RUNNING_LOCK:
        STOPPING.set()
        running = list(_RUNNING)
    for process in running:
        _kill_group(process)
    return len(running)


def catalog(root, exercise, public_only=False, python=None):
    """The tests of an exercise (records with ``passed=False``), from ``pytest --collect-only``."""
    root = Path(root)
    test_file = exercise_tests(root)[exercise]
    if STOPPING.is_set():
        raise RuntimeError(f"the run was interrupted before the tests of {exercise} were listed")
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


NOT_RUN = "not run: your notebook was not graded (why: in the notes of this exercise)"
"""The reason of each test of a notebook that was not graded: the reason itself is said once, in the notes."""


def rejected_record(unit, tests):
    """The record of a unit discovery rejected: every test of `tests` failed, not run; its reason once, in the
    notes; never resumed."""
    return SubmissionRecord(
        student=unit.student, exercise=unit.exercise, notebook=unit.where, seconds=0.0,
        tests=[TestRecord.from_dict(t).failed(NOT_RUN) for t in tests],
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
    as "not run: grading stopped early" (:func:`~particles.course.grading.run.run_batch` then grades each of
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
    with PARSING:
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
            status, output = _run_session(_pytest_command(python or sys.executable, root, test_file, extra), tmp,
                                          env, timeout, key_in)
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
    with PARSING:
        return [_result(u, seed, data.get(str(k)), status, tests, elapsed / len(units), trouble, root, version)
                for k, (u, seed) in enumerate(zip(units, seeds))]


def grade_unit(unit, root, *, seed=None, **options):
    """Grade one notebook (see :func:`grade_batch`); returns its :class:`SubmissionRecord`."""
    return grade_batch([unit], root, seeds=None if seed is None else [seed], **options)[0]
