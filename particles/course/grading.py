"""The grading driver: ``particles grade SUBMISSION... --out DIR --jobs N``.

Notebooks of one exercise are graded in batches by ``pytest`` processes that
run ``tests/exercises/test_NN_topic.py`` with the plugin of
:mod:`particles.course.plugin`; for each notebook such a process starts a
worker that runs the student's code. So three processes stand between a
submission and the gradebook: the worker (untrusted, limited, killed on a
timeout, one per notebook), the pytest session (trusted tests comparing with
the reference library) and this driver, which only reads JSON records. If a
pytest session stops early (it should not), the notebooks it had not finished
are graded again, each in a session of its own; a test that still has no
record is recorded as failed with the reason. So every submission yields a
record and the driver never stops on a submission. ``--jobs N`` runs N
sessions at a time.

The driver trusts a session's records only when pytest ended normally
(exit status 0 or 1) and the records file carries the signature of a key
that only the driver and that session know (:data:`TOKEN_FD`): a submission
that got out of its worker's walls and forged the file, or killed the
session, loses its records (and its classmates in the same batch are graded
again on their own). Workers may not read the submissions, the output folder
or the course folder.

Submissions and students:

* a notebook given on the command line is one submission; the student is its
  file name without ``.ipynb``;
* a folder: notebooks directly inside it are graded the same way; notebooks
  in sub-folders belong to the student named by the first sub-folder (the
  layout of an export with one folder per student).

The exercise of a notebook is read from its metadata (written by
``particles release``), else from its file name (``..._00_warmup...``), else
from ``--exercise``, which also overrides both. A student with several
notebooks of one exercise gets one graded (the one named exactly
``NN_topic.ipynb``, else the newest); the others are reported.
"""

import hashlib
import hmac
import json
import math
import os
import re
import secrets
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from .paths import exercise_tests, project_root
from .reports import feedback_markdown, gradescope_results, write_gradebook, write_json
from .process import library_parent
from .runner import check_limit

__all__ = ["Unit", "find_submissions", "grade_batch", "grade_unit", "grade", "catalog", "read_records",
           "sign_records", "TOKEN_FD", "written_answers"]

TOKEN_FD = "PARTICLES_GRADING_TOKEN_FD"
"""Environment variable of a pytest session naming an inherited pipe that holds its signing key.

:func:`grade_batch` makes a new random key per session, writes it into a
pipe, closes its end and starts pytest with the other end inherited; the
plugin reads the key at start-up, before any worker exists, closes the pipe
and signs its records with it (:func:`sign_records`). The key lives only in
the memory of the driver and of the session: the variable holds a file
descriptor number, and workers get a clean environment and no inherited
descriptors (:class:`particles.course.process.Worker`)."""


def sign_records(body, token):
    """The signature of a records file's `body` (str): hex HMAC-SHA256 under the session's key `token` (bytes)."""
    return hmac.new(token, body.encode("utf-8"), hashlib.sha256).hexdigest()


def read_records(path, token):
    """The submissions of a signed records file (id -> record), or None when it is missing, unsigned or altered.

    Parameters
    ----------
    path : path
        The file the pytest session wrote (``--grading-results``).
    token : bytes
        The session's key (see :data:`TOKEN_FD`).
    """
    try:
        signed = json.loads(Path(path).read_text())
        body, signature = signed["body"], signed["signature"]
        if not (isinstance(body, str) and isinstance(signature, str)
                and hmac.compare_digest(sign_records(body, token), signature)):
            return None
        return {str(s["id"]): s for s in json.loads(body)["submissions"]}
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError):
        return None


@dataclass
class Unit:
    """One notebook to grade: who submitted it, which exercise it is."""

    student: str
    exercise: str
    notebook: Path


def _exercise_of(notebook, exercises, override=None):
    if override:
        return override
    try:
        meta = json.loads(Path(notebook).read_text(encoding="utf-8")).get("metadata", {})
        name = meta.get("particles", {}).get("exercise")
        if name in exercises:
            return name
    except (OSError, UnicodeDecodeError, ValueError, AttributeError):
        pass
    for name in sorted(exercises, key=len, reverse=True):
        if name in Path(notebook).stem:
            return name
    return None


def _student_name(text):
    return re.sub(r"[^\w.@+-]+", "_", text).strip("_") or "submission"


def _preference(unit):
    """Which of two notebooks of one student and exercise to grade: the exact name, then the newest."""
    path = Path(unit.notebook)
    return (path.name == f"{unit.exercise}.ipynb", path.stat().st_mtime)


def find_submissions(paths, exercises, exercise=None):
    """Expand notebooks and folders into :class:`Unit` s and a list of problems.

    Returns
    -------
    units : list of Unit
    problems : list of str
        Notebooks whose exercise could not be told, and paths that do not exist.
    """
    units, problems = [], []
    for given in map(Path, paths):
        if given.is_file():
            found = [(given, given.stem)]
        elif given.is_dir():
            found = []
            for nb in sorted(given.rglob("*.ipynb")):
                if ".ipynb_checkpoints" in nb.parts:
                    continue
                rel = nb.relative_to(given)
                found.append((nb, rel.parts[0] if len(rel.parts) > 1 else nb.stem))
        else:
            problems.append(f"{given} does not exist")
            continue
        for nb, student in found:
            name = _exercise_of(nb, exercises, exercise)
            if name is None:
                problems.append(f"{nb}: cannot tell which exercise this is; pass --exercise")
                continue
            units.append(Unit(_student_name(student), name, nb))
    chosen = {}
    for unit in units:  # one notebook per student and exercise: the exact name, else the newest
        key = (unit.student, unit.exercise)
        if key not in chosen:
            chosen[key] = unit
            continue
        keep, drop = sorted([chosen[key], unit], key=_preference, reverse=True)
        chosen[key] = keep
        problems.append(f"{drop.notebook}: {unit.student} has several notebooks for {unit.exercise}; "
                        f"graded {keep.notebook}")
    return list(chosen.values()), problems


def _pytest_command(python, root, test_file, extra):
    return [python, "-m", "pytest", str(test_file), "-q", "-p", "particles.course.plugin",
            "-p", "no:cacheprovider", "--rootdir", str(root), "-o", "addopts=", *extra]


def _environment(root):
    env = dict(os.environ)
    parent = library_parent()
    env["PYTHONPATH"] = parent + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env["PARTICLES_COURSE_ROOT"] = str(root)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
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


def _answer_prompts(notebook):
    """Markdown cells of a notebook that still hold the release's answer prompt (0 if unreadable)."""
    from .release import ANSWER_PROMPT

    try:
        cells = json.loads(Path(notebook).read_text(encoding="utf-8")).get("cells", [])
        sources = ["".join(c.get("source", "")) if isinstance(c.get("source"), list) else str(c.get("source", ""))
                   for c in cells if isinstance(c, dict) and c.get("cell_type") == "markdown"]
    except (OSError, UnicodeDecodeError, ValueError, AttributeError, TypeError):
        return 0
    return sum(source.count(ANSWER_PROMPT) for source in sources)


def written_answers(notebook, root, exercise):
    """The written (hand-graded) answers of a submission: ``{"asked": M, "answered": k}``.

    ``asked`` counts the answer prompts of the released ``exercises/NN_topic.ipynb``;
    a prompt still present in the submission is unanswered. The autograder does
    not score these answers: the count tells the instructor what is left to read.
    """
    asked = _answer_prompts(Path(root) / "exercises" / f"{exercise}.ipynb")
    return {"asked": asked, "answered": max(asked - _answer_prompts(notebook), 0)}


def _result(unit, seed, data, status, tests, seconds, trouble=None, root=None):
    records = list(data.get("tests", []))
    if tests is not None:  # make sure every expected test has a record
        seen = {r["test"] for r in records}
        why = (f"not run: grading stopped early ({trouble or f'pytest exit status {status}'}); "
               "the instructor has the log")
        records += [dict(t, passed=False, reason=why, seed=None) for t in tests if t["test"] not in seen]
    notes = []
    for error in data.get("load_errors", []):
        where = f" ({error['where']})" if error.get("where") else ""
        notes.append(f"While loading your notebook, {error['label']}{where} raised "
                     f"{error['type']}: {error['message']}")
    for label, message in data.get("syntax_errors", []):
        notes.append(f"{label} has a syntax error ({message}) and was not run")
    if data.get("restarts", 1) > 1:
        notes.append(f"The worker running your code was restarted {data['restarts'] - 1} time(s) "
                     "after a timeout or a crash")
    written = written_answers(unit.notebook, root, unit.exercise) if root is not None else None
    if written and written["asked"]:
        notes.append(f"Written answers: {written['answered']} of {written['asked']} filled in; they are read "
                     "and graded by your instructor, not by the autograder")
    return {"student": unit.student, "exercise": unit.exercise, "notebook": str(unit.notebook), "seed": seed,
            "seconds": round(data.get("seconds", seconds), 2), "tests": records, "notes": notes,
            "written_answers": written, "grader_status": status, "complete": "seconds" in data}


def grade_batch(units, root, *, seeds=None, public_only=False, time_limit=None, memory_mb=None, private=(),
                python=None, log=None, tests=None, timeout=None):
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
    list of dict
        Per unit: ``student``, ``exercise``, ``notebook``, ``seed``,
        ``seconds``, ``tests`` (records), ``notes`` (lines about loading the
        notebook), ``complete`` (every test has its own record).

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
        extra += ["--time-limit", repr(time_limit)] if time_limit is not None else []
        extra += ["--memory-mb", str(math.ceil(memory_mb))] if memory_mb is not None else []
        for path in private:
            extra += ["--private", str(path)]
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
        if trouble is not None:
            output += f"\nparticles grade: records of this session discarded: {trouble}\n"
        if log is not None:
            Path(log).write_text(output)
    elapsed = time.perf_counter() - start
    if tests is None and any("seconds" not in data.get(str(k), {}) for k in range(len(units))):
        try:
            tests = catalog(root, units[0].exercise, public_only, python)
        except RuntimeError:
            tests = []
    return [_result(u, seed, data.get(str(k), {}), status, tests, elapsed / len(units), trouble, root)
            for k, (u, seed) in enumerate(zip(units, seeds))]


def grade_unit(unit, root, *, seed=None, **options):
    """Grade one notebook (see :func:`grade_batch`); returns its result dict."""
    return grade_batch([unit], root, seeds=None if seed is None else [seed], **options)[0]


def _batches(units, jobs, largest=20):
    """Split units into batches of one exercise, small enough to keep `jobs` processes busy."""
    by_exercise = {}
    for unit in units:
        by_exercise.setdefault(unit.exercise, []).append(unit)
    out = []
    for group in by_exercise.values():
        # about three batches per job for balance, and never fewer than six batches, so that the
        # cost of a start-up per batch does not depend on --jobs 1 or 2
        size = max(1, min(largest, math.ceil(len(group) / (3 * max(jobs, 2)))))
        out += [group[k:k + size] for k in range(0, len(group), size)]
    return out


def grade(paths, out=None, *, jobs=1, exercise=None, public_only=False, seed=None, time_limit=None,
          memory_mb=None, root=None, private=(), hidden_visibility="after_published", python=None,
          gradescope=None, progress=None):
    """Grade submissions; write results.json and feedback per student and a gradebook.

    Parameters
    ----------
    paths : sequence of path
        Notebooks, or folders of notebooks (see the module docstring).
    out : path, optional
        Output folder: ``gradebook.csv``, ``<student>/results.json``,
        ``<student>/feedback.md`` and ``logs/``. Nothing is written without it.
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

    Returns
    -------
    dict
        ``students`` (student -> list of per-exercise results), ``exercises``
        (names graded, in order) and ``problems`` (notebooks not graded).

    Raises
    ------
    ValueError
        On bad arguments (no exercise tests found, unknown exercise, jobs < 1,
        a `time_limit` or `memory_mb` that is not a finite number > 0).
    """
    root = Path(root).resolve() if root else project_root()
    tests = exercise_tests(root)
    if not tests:
        raise ValueError(f"no exercise tests in {root / 'tests' / 'exercises'}")
    if exercise is not None and exercise not in tests:
        raise ValueError(f"unknown exercise {exercise!r}; expected one of {', '.join(map(repr, tests))}")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    time_limit = None if time_limit is None else check_limit("time_limit", time_limit)
    memory_mb = None if memory_mb is None else check_limit("memory_mb", memory_mb)
    units, problems = find_submissions(paths, list(tests), exercise)
    if out is not None:
        out = Path(out)
        (out / "logs").mkdir(parents=True, exist_ok=True)
    # no worker may read the submissions (a classmate's notebook) or what grading writes; a worker gets
    # its own code from the grader, so it never needs to read its notebook either
    private = [*map(str, private), *(str(Path(p).resolve()) for p in paths if Path(p).exists())]
    private += [str(out.resolve())] if out is not None else []

    def work(batch):
        k = batches.index(batch)
        log = out / "logs" / f"batch{k:03d}-{batch[0].exercise}.log" if out is not None else None
        seeds = [seed if seed is not None else secrets.randbelow(2**31) for _ in batch]
        results = grade_batch(batch, root, seeds=seeds, public_only=public_only, time_limit=time_limit,
                              memory_mb=memory_mb, private=private, python=python, log=log)
        if len(batch) > 1:  # a session that stopped early: grade its unfinished notebooks alone
            for i, (unit, result) in enumerate(zip(batch, results)):
                if not result["complete"]:
                    retry_log = out / "logs" / f"{unit.student}-{unit.exercise}.log" if out is not None else None
                    results[i] = grade_unit(unit, root, seed=seeds[i], public_only=public_only,
                                            time_limit=time_limit, memory_mb=memory_mb, private=private,
                                            python=python, log=retry_log)
        if progress is not None:
            for result in results:
                progress(result)
        return results

    batches = _batches(units, jobs)
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        results = [r for batch_results in pool.map(work, batches) for r in batch_results]
    students = {}
    for result in results:
        students.setdefault(result["student"], []).append(result)
    exercises = [name for name in tests if any(u.exercise == name for u in units)]
    if out is not None:
        for student, per_exercise in students.items():
            folder = out / student
            folder.mkdir(parents=True, exist_ok=True)
            write_json(folder / "results.json", gradescope_results(student, per_exercise, hidden_visibility))
            (folder / "feedback.md").write_text(feedback_markdown(student, per_exercise))
        write_gradebook(out / "gradebook.csv", students, exercises)
    if gradescope is not None:
        if not results and exercise is not None:  # nothing gradable was submitted: every test fails, saying why
            why = "no notebook for this exercise was found in your submission" if not problems else problems[0]
            tests_of = catalog(root, exercise, public_only, python)
            results = [{"student": "submission", "exercise": exercise, "notebook": "", "seed": None, "seconds": 0.0,
                        "tests": [dict(t, passed=False, reason=why) for t in tests_of], "notes": []}]
        data = gradescope_results("submission", results, hidden_visibility)
        if problems:
            data["output"] = "\n".join([data["output"], *problems]).strip()
        Path(gradescope).parent.mkdir(parents=True, exist_ok=True)
        write_json(gradescope, data)
    return {"students": students, "exercises": exercises, "problems": problems}
