"""Shared test configuration: the autograder plugin (fixtures ``student`` and ``rng``, markers
``points``, ``hidden`` and ``time_limit``) for the exercise tests in ``tests/exercises/``."""

pytest_plugins = ["particles.course.plugin"]
