"""Shared test configuration.

* The autograder plugin (fixtures ``student`` and ``rng``, markers ``points``,
  ``hidden`` and ``time_limit``) for the exercise tests in ``tests/exercises/``.
* ``executed_lecture``: each lecture notebook executed once per test session in
  a fresh kernel (also across the two xdist workers of ``make test``), shared
  by the notebook tests, the claims test and the course-site test, so that
  the slowest thing the suite does is done only once per lecture.
"""

import pytest

pytest_plugins = ["particles.course.grading.plugin"]


@pytest.fixture(scope="session")
def executed_lecture(tmp_path_factory, request):
    """``executed_lecture(path)``: the lecture at `path` run top to bottom, once per test session.

    With pytest-xdist (``make test`` runs two workers) the executed notebooks
    are shared between the worker processes through files in the session's
    temporary folder, under a lock: whichever worker asks first runs the
    lecture, the other reads the result. Raises ``RuntimeError`` with the
    failing cell's message on the first failing cell, every time it is asked
    for (a failure is cached too, so it is not run twice).
    """
    import fcntl
    import json

    import nbformat

    from particles.course.release.site import execute_notebook

    shared = hasattr(request.config, "workerinput")  # an xdist worker: the base folder is per worker
    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if shared else base) / "executed-lectures"
    folder.mkdir(exist_ok=True)
    cache = {}

    def run(path):
        key = str(path)
        if key not in cache:
            target = folder / (path.stem + ".ipynb")
            failure = folder / (path.stem + ".error.json")
            with open(folder / (path.stem + ".lock"), "w") as lock:
                fcntl.flock(lock, fcntl.LOCK_EX)
                if not target.exists() and not failure.exists():
                    try:
                        nbformat.write(execute_notebook(path, timeout=180), str(target))
                    except Exception as error:  # noqa: BLE001 - re-raised below for every test that asks
                        failure.write_text(json.dumps(f"{type(error).__name__}: {error}"))
            cache[key] = (nbformat.read(str(target), as_version=4) if target.exists()
                          else RuntimeError(json.loads(failure.read_text())))
        if isinstance(cache[key], Exception):
            raise cache[key]
        return cache[key]

    return run
