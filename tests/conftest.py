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
    temporary folder, one lock per lecture: whichever worker asks first runs
    the lecture, the other reads the result. A worker that asks for a lecture
    another one is running does not wait for it: it runs a lecture of the same
    folder that no one has started (waiting left a core idle for most of the
    lectures' time: two workers asking in the same order took turns). In a
    run of a few tests that may be a lecture no test asks for: one lecture's
    time at most per wait. Raises
    ``RuntimeError`` with the failing cell's message on the first failing cell,
    every time it is asked for (a failure is cached too, so it is not run twice).
    """
    import fcntl
    import json
    import os

    import nbformat

    from particles.course.release.site import execute_notebook

    shared = hasattr(request.config, "workerinput")  # an xdist worker: the base folder is per worker
    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if shared else base) / "executed-lectures"
    folder.mkdir(exist_ok=True)
    cache = {}

    def files(path):
        return folder / (path.stem + ".ipynb"), folder / (path.stem + ".error.json")

    def done(path):
        return any(f.exists() for f in files(path))

    def produce(path, wait):
        """Run `path` unless it is done; False, without waiting, if another worker holds it and not `wait`."""
        target, failure = files(path)
        with open(folder / (path.stem + ".lock"), "w") as lock:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
            except BlockingIOError:
                return False
            if not done(path):
                part = folder / (path.stem + ".part")  # written, then renamed: whole or absent for any reader
                try:
                    nbformat.write(execute_notebook(path, timeout=180), str(part))
                    os.replace(part, target)
                except Exception as error:  # noqa: BLE001 - re-raised below for every test that asks
                    part.write_text(json.dumps(f"{type(error).__name__}: {error}"))
                    os.replace(part, failure)
            return True

    def run(path):
        key = str(path)
        if key not in cache:
            while not done(path) and not produce(path, wait=False):
                others = (p for p in sorted(path.parent.glob("[0-9A][0-9]_*.ipynb")) if p != path and not done(p))
                if not any(produce(p, wait=False) for p in others):  # nothing else to run: wait for it
                    produce(path, wait=True)
            target, failure = files(path)
            cache[key] = (nbformat.read(str(target), as_version=4) if target.exists()
                          else RuntimeError(json.loads(failure.read_text())))
        if isinstance(cache[key], Exception):
            raise cache[key]
        return cache[key]

    return run
