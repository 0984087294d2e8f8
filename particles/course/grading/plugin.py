"""The pytest plugin that turns ``tests/exercises/test_NN_topic.py`` into an autograder.

An exercise test module declares its exercise and what it forbids, and its
tests declare points and visibility::

    EXERCISE = "00_warmup"
    FORBIDDEN = {"particles.integrators.euler": "it is the step you are asked to write"}

    @pytest.mark.points(2)
    @pytest.mark.hidden
    def test_euler_step_random(student, rng):
        '''euler_step matches the reference on random oscillators.'''
        ...

A stretch goal is marked ``@pytest.mark.optional`` (or, for one parameter,
``pytest.param("rk4", marks=pytest.mark.optional)``): its record carries
``optional`` and the label "stretch goal, not scored", and no score counts it.

Fixtures:

``student``
    A :class:`particles.course.worker.runner.Submission` for the notebook being
    graded (one worker per test module, restarted after a crash or a timeout).
    A ``@pytest.mark.time_limit(seconds)`` marker sets its per-call limit
    (``--time-limit`` sets the default of the tests without one). The
    functions a test calls name the one it judges (the record's
    ``function``); when every test of the module has run, the failure of a
    test whose function uses a helper that fails its own tests is blamed on
    that helper (:mod:`particles.course.grading.blame`).
``rng``
    A ``numpy.random.Generator`` for hidden tests, seeded from the grading
    seed and the test's name: the same seed reproduces the same parameters.
``grading_seed``
    The seed itself (an int), recorded in the results.
``feedback``
    A :class:`particles.course.grading.figures.Feedback`: ``feedback.curve(title,
    xlabel, ylabel, series=[{"label": "yours", "x": [...], "y": [...]},
    {"label": "reference", ...}], loglog=True)`` attaches the data of a
    figure to the test's record (``figures``: plain JSON, a few hundred
    points per series at most); the driver draws it in ``feedback.html``
    and Gradescope's output, ``particles.check`` in the notebook. Attach
    before the check that may fail, and keep a hidden test's parameters
    out of the texts.

Options: ``--submission NOTEBOOK`` (default: ``solutions/NN_topic.ipynb`` when
it exists, the master, else ``exercises/NN_topic.ipynb``, the student's own
copy), ``--grading-seed``, ``--public-only``, ``--grading-results FILE``
(one JSON record per test, read by :mod:`particles.course.grading.session`),
``--grading-batch FILE`` (several notebooks, each with its own seed, graded
one after the other in this session, each by its own worker: the pytest
start-up and the reference library are paid once per batch),
``--time-limit`` (the per-call limit of the tests without a ``time_limit``
marker: a marker wins), ``--memory-mb``, ``--private PATH`` (more paths the
submission may not read), ``--isolation`` (the workers' operating-system
walls, see :mod:`particles.course.walls.isolation`: ``auto``, ``strict`` or the
layers the driver chose; the layers each worker really had go into the
submission's record). Without them, ``pytest tests/exercises`` grades
the masters, which must score full marks.

When the driver passes a signing key (see
:data:`particles.course.results.signing.TOKEN_FD`), the records file holds
``{"body": JSON text, "signature": HMAC of it}``; the driver trusts it only
with a valid signature and a pytest exit status of 0 or 1.
"""

import json
import os
import re
import secrets
import time
import zlib
from pathlib import Path

import numpy as np
import pytest

from ..reading.submission import SubmissionCode, notebook_cells
from ..reading.provided import provided_cells
from .figures import Feedback
from ..walls.isolation import Plan, protect_this_process
from ..results.signing import TOKEN_FD, sign_records
from ..paths import project_root
from .blame import blame, function_of, stub_functions
from ..results.records import SessionRecord, TestRecord
from ..walls.limits import check_limit
from ..walls.syscalls import PARENT_VARIABLE, die_with_parent
from ..worker.runner import GradingFailure, Submission

__all__ = ["record_of"]


def _read_token():
    fd = os.environ.pop(TOKEN_FD, None)
    if fd is None:
        return None
    chunks = []
    try:
        while True:
            chunk = os.read(int(fd), 4096)
            if not chunk:
                break
            chunks.append(chunk)
    finally:
        os.close(int(fd))
    return b"".join(chunks)


def pytest_addoption(parser):
    group = parser.getgroup("particles", "particles course autograder")
    group.addoption("--submission", default=None, help="the notebook to grade")
    group.addoption("--grading-seed", type=int, default=None, help="seed of the hidden tests' random parameters")
    group.addoption("--grading-batch", default=None,
                    help="a JSON list of {id, notebook, seed}: grade several notebooks in this session")
    group.addoption("--public-only", action="store_true", default=False, help="run only the public tests")
    group.addoption("--grading-results", default=None, help="write the per-test records as JSON to this file")
    group.addoption("--time-limit", type=float, default=None,
                    help="per-call time limit, seconds, of tests without a time_limit marker")
    group.addoption("--memory-mb", type=int, default=None, help="memory a submission may use, MiB")
    group.addoption("--private", action="append", default=[], help="another path a submission may not read")
    group.addoption("--grading-catalog", default=None, help="write the collected tests (name, points, visibility) here")
    group.addoption("--no-audit-hook", action="store_true", default=False,
                    help="run the workers without the Python audit hook (to test that the operating system's "
                         "walls hold on their own; never for real grading)")
    group.addoption("--isolation", default="auto",
                    help="the workers' operating-system walls: auto, strict, or a list such as namespaces,uid,landlock")


def pytest_configure(config):
    for line in (
        "points(n): the test is worth n points in the autograder",
        "hidden: an autograder test students do not see before grades are published",
        "time_limit(seconds): per-call time limit of the student's code in this test",
        "optional: a stretch goal, shown as 'stretch goal, not scored' and left out of the score "
        "(also as pytest.param(..., marks=pytest.mark.optional))",
    ):
        config.addinivalue_line("markers", line)
    seed = config.getoption("--grading-seed", default=None)
    seed = secrets.randbelow(2**31) if seed is None else int(seed)
    batch = config.getoption("--grading-batch", default=None)
    if batch:
        jobs = json.loads(Path(batch).read_text())
    else:
        jobs = [{"id": "0", "notebook": config.getoption("--submission", default=None), "seed": seed}]
    config._particles_jobs = jobs
    config._particles_token = _read_token()
    protect_this_process()  # no process of the same uid may read this session's memory or environment
    if os.environ.get(PARENT_VARIABLE):  # a grading session: it ends with the driver or worker that started it
        die_with_parent(int(os.environ.pop(PARENT_VARIABLE)))
    config._particles_plan = None
    config._particles_seed = seed
    config._particles_results = {job["id"]: SessionRecord(id=job["id"], seed=job["seed"]) for job in jobs}


def pytest_report_header(config):
    seeds = sorted({job["seed"] for job in config._particles_jobs})
    return f"particles autograder: {len(config._particles_jobs)} submission(s), grading seed(s) {seeds}"


def pytest_generate_tests(metafunc):
    """In a batch, every test that uses a submission runs once per notebook (module-scoped)."""
    jobs = metafunc.config._particles_jobs
    if len(jobs) > 1 and "_particles_submission" in metafunc.fixturenames:
        metafunc.parametrize("_particles_job", jobs, ids=[f"__job{k}__" for k in range(len(jobs))],
                             scope="module")


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Drop the hidden tests with ``--public-only``; in a batch, run each notebook's tests together.

    Pytest groups the tests of a module-scoped parameter, but a test with parameters of its own
    (``test_x[__job0__-a]``, ``test_x[__job0__-b]``) breaks the groups: the notebooks then take
    turns, and each turn tears its worker down and starts (and loads the notebook in) a new one.
    Runs after pytest's own ordering (``trylast``) and keeps it within each notebook (a stable sort).
    """
    if config.getoption("--public-only", default=False):
        keep = [item for item in items if item.get_closest_marker("hidden") is None]
        dropped = [item for item in items if item.get_closest_marker("hidden") is not None]
        if dropped:
            config.hook.pytest_deselected(items=dropped)
            items[:] = keep
    jobs = {id(job): k for k, job in enumerate(config._particles_jobs)}
    if len(jobs) > 1:
        modules = {}
        for item in items:
            modules.setdefault(item.path, len(modules))
        items.sort(key=lambda item: (modules[item.path], jobs.get(id(_job_of(item)), -1)))


def _exercise_of(module):
    name = getattr(module, "EXERCISE", None)
    if name:
        return name
    stem = Path(module.__file__).stem
    return stem[len("test_"):] if stem.startswith("test_") else stem


def _default_notebook(root, exercise):
    master = root / "solutions" / f"{exercise}.ipynb"
    return master if master.exists() else root / "exercises" / f"{exercise}.ipynb"


def _job_of(item):
    callspec = getattr(item, "callspec", None)
    if callspec is not None and "_particles_job" in callspec.params:
        return callspec.params["_particles_job"]
    return item.config._particles_jobs[0]


def _test_key(item):
    """The test's name without the batch parameter: ``test_x`` or ``test_x[rk4]``."""
    name = item.name
    if "[" in name and name.endswith("]"):
        base, params = name[:-1].split("[", 1)
        parts = [p for p in params.split("-") if not re.fullmatch(r"__job\d+__", p)]
        name = base + (f"[{'-'.join(parts)}]" if parts else "")
    return name


@pytest.fixture(scope="module")
def _particles_job(request):
    """The notebook being graded: ``{"id", "notebook", "seed"}`` (parametrized in a batch)."""
    return request.config._particles_jobs[0]


@pytest.fixture(scope="module")
def _particles_submission(request, _particles_job):
    config = request.config
    module = request.module
    exercise = _exercise_of(module)
    root = project_root(Path(module.__file__).parent)
    path = _particles_job.get("notebook") or _default_notebook(root, exercise)
    deny = [root, *config.getoption("--private")]
    for option in ("--grading-results", "--grading-batch"):
        if config.getoption(option):
            deny.append(Path(config.getoption(option)).resolve().parent)
    start = time.perf_counter()
    try:
        code = SubmissionCode.from_cells(notebook_cells(path), provided=provided_cells(root, exercise))
        problem = None
    except ValueError as error:
        code, problem = SubmissionCode(), f"your notebook could not be read: {error}"
    if config._particles_plan is None:
        config._particles_plan = Plan.from_option(config.getoption("--isolation"))
    submission = Submission(
        code, forbidden=getattr(module, "FORBIDDEN", {}), deny=deny, isolation=config._particles_plan,
        time_limit=config.getoption("--time-limit"), memory_mb=config.getoption("--memory-mb"),
        audit_hook=not config.getoption("--no-audit-hook"),
    )
    submission.load_failure = problem
    result = config._particles_results[_particles_job["id"]]
    result.exercise, result.submission = exercise, str(path)
    yield submission
    # every test of the module has run: a failure downstream of a helper that fails its own tests names it
    blame([t for t in result.tests if t.test in _module_tests(request)], submission.code,
          written=stub_functions(root / "exercises" / f"{exercise}.ipynb"))
    submission.close()
    # a notebook whose tests did not run together had its fixture set up again: count every worker
    result.restarts = submission.restarts + (result.restarts if result.seconds is not None else 0)
    result.load_errors = submission.code.student_load_errors(submission.load_errors)
    result.skipped = [{"label": s.label, "line": s.line, "text": s.text, "reason": s.reason}
                      for s in submission.code.skipped]
    result.syntax_errors = [list(e) for e in submission.code.syntax_errors]
    result.isolation = dict(submission.layers or {}, planned=config._particles_plan.to_option())
    result.seconds = round(time.perf_counter() - start, 3)  # last: the notebook is complete


@pytest.fixture
def student(_particles_submission, request):
    """The submission being graded; ``student.call(name, *args)`` runs its code in the worker."""
    marker = request.node.get_closest_marker("time_limit")
    saved = dict(_particles_submission.limits)
    _particles_submission.called = request.node._particles_called = []  # which functions this test calls
    request.node._particles_defined = _particles_submission.code.defines()
    if marker is not None:  # the test's own limit wins over --time-limit, which is the default of the others
        _particles_submission.limits["time_limit"] = check_limit("time_limit", marker.args[0])
    yield _particles_submission
    _particles_submission.limits.update(saved)


@pytest.fixture
def grading_seed(request, _particles_job):
    """The grading seed of the notebook being graded (an int), recorded in the results."""
    request.node._particles_used_seed = True
    return int(_particles_job["seed"])


@pytest.fixture
def rng(request, _particles_job):
    """A random generator for hidden parameters: ``default_rng([seed, crc32(test name)])``."""
    request.node._particles_used_seed = True
    key = _test_key(request.node)
    return np.random.default_rng([int(_particles_job["seed"]), zlib.crc32(key.encode())])


@pytest.fixture
def feedback(request):
    """Figures for this test's feedback: ``feedback.curve(title, xlabel, ylabel, series, loglog=True)``."""
    board = Feedback(hidden=request.node.get_closest_marker("hidden") is not None)
    request.node._particles_feedback = board
    return board


def _module_tests(request):
    """The keys of the tests of the requesting module (in a batch, of every job)."""
    return {_test_key(item) for item in request.session.items if item.module is request.module}


def _reason(excinfo):
    error = excinfo.value
    if isinstance(error, GradingFailure):
        return str(error).strip().splitlines()[0] if str(error).strip() else "failed", False
    if isinstance(error, AssertionError):
        text = str(error).strip().splitlines()
        return (text[0] if text else "an assertion in the test failed"), False
    return f"internal grader error, not caused by your code ({type(error).__name__}: {error})", True


def record_of(item, outcome, excinfo, seconds):
    """The :class:`~particles.course.results.records.TestRecord` of one test."""
    points = item.get_closest_marker("points")
    doc = (getattr(item.obj, "__doc__", None) or item.name).strip().splitlines()[0]
    key = _test_key(item)
    if key.endswith("]"):  # one test function, several parameters: say which one (not the batch job)
        doc = f"{doc} [{key[key.index('[') + 1:-1]}]"
    record = TestRecord(
        test=_test_key(item),
        name=doc,
        points=float(points.args[0]) if points and points.args else 1.0,
        hidden=item.get_closest_marker("hidden") is not None,
        passed=outcome == "passed",
        seconds=round(seconds, 3),
        seed=int(_job_of(item)["seed"]) if getattr(item, "_particles_used_seed", False) else None,
        optional=item.get_closest_marker("optional") is not None,
        function=function_of(key, getattr(item, "_particles_called", []), getattr(item, "_particles_defined", {})),
    )
    if excinfo is not None and outcome != "passed":
        record.reason, record.grader_error = _reason(excinfo)
    board = getattr(item, "_particles_feedback", None)
    if board is not None and board.figures:  # data only: the driver draws
        record.figures = list(board.figures)
    return record


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    if "_particles_submission" not in getattr(item, "fixturenames", ()) and \
            not hasattr(getattr(item, "module", None), "EXERCISE"):
        return  # not a test of an exercise (another test of the same session): nothing to record
    report = outcome.get_result()
    if not hasattr(item, "_particles_start"):
        item._particles_start = time.perf_counter()
    records = item.config._particles_results[_job_of(item)["id"]].tests
    if report.when == "setup" and report.failed:
        records.append(record_of(item, "failed", call.excinfo, time.perf_counter() - item._particles_start))
    elif report.when == "call":
        status = "passed" if report.passed else "failed"
        records.append(record_of(item, status, call.excinfo, time.perf_counter() - item._particles_start))


def pytest_collection_finish(session):
    path = session.config.getoption("--grading-catalog", default=None)
    if path:
        first = session.config._particles_jobs[0]["id"]
        catalog = [record_of(item, "failed", None, 0.0).to_dict() for item in session.items
                   if _job_of(item)["id"] == first]
        Path(path).write_text(json.dumps(catalog, indent=1))


def pytest_sessionfinish(session):
    config = session.config
    path = config.getoption("--grading-results", default=None)
    if not path:
        return
    data = {"submissions": [record.to_dict() for record in config._particles_results.values()]}
    token = getattr(config, "_particles_token", None)
    if token is None:
        Path(path).write_text(json.dumps(data, indent=1))
        return
    body = json.dumps(data, indent=1)  # signed, so that a worker that wrote this file itself is found out
    Path(path).write_text(json.dumps({"body": body, "signature": sign_records(body, token)}))
