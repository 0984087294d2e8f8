"""Shared test configuration.

* The autograder plugin (fixtures ``student`` and ``rng``, markers ``points``,
  ``hidden`` and ``time_limit``) for the exercise tests in ``tests/exercises/``.
* ``executed_lecture``: each lecture notebook executed once per test session in
  a fresh kernel, shared by the notebook tests and the course-site test, so
  that the slowest thing the suite does is done only once per lecture.
"""

import pytest

pytest_plugins = ["particles.course.plugin"]


@pytest.fixture(scope="session")
def executed_lecture():
    """``executed_lecture(path)``: the lecture at `path` run top to bottom (cached per session).

    Raises the cell's ``CellExecutionError`` on the first failing cell, every
    time it is asked for (a failure is cached too, so it is not run twice).
    """
    from particles.site import execute_notebook

    cache = {}

    def run(path):
        key = str(path)
        if key not in cache:
            try:
                cache[key] = execute_notebook(path, timeout=180)
            except Exception as error:  # noqa: BLE001 - re-raised below for every test that asks
                cache[key] = error
        if isinstance(cache[key], Exception):
            raise cache[key]
        return cache[key]

    return run
