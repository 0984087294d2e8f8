"""The exercise tests' own fixture: ``rng`` can record what a hidden test drew.

When the environment variable ``PARTICLES_RECORD_DRAWS`` names a folder (the
grader's tests set it, see ``tests/course/grader/exercise_corpus.py``), the ``rng``
of every test is the plugin's generator behind a recorder: each number it
returns is kept, and at the end of the test one JSON line
``{"notebook", "seed", "test", "scalars", "arrays"}`` is appended to a file of
that folder (one file per pytest process). The tests of the grader then check
that no failure message of a hidden test shows a number its generator drew.
Without the variable the fixture is the plugin's, unchanged.
"""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from particles.course.grading.plugin import _test_key

DRAWS = "PARTICLES_RECORD_DRAWS"


class _Recorder:
    """A ``numpy.random.Generator`` that keeps the floats it draws (scalars, and arrays by call)."""

    def __init__(self, generator):
        self._generator = generator
        self.scalars, self.arrays = [], []

    def __getattr__(self, name):
        attr = getattr(self._generator, name)
        if not callable(attr):
            return attr

        def draw(*args, **kwargs):
            value = attr(*args, **kwargs)
            numbers = np.asarray(value)
            if numbers.dtype.kind == "f":
                flat = [float(v) for v in numbers.ravel()]
                (self.scalars if numbers.size == 1 else self.arrays).append(flat[0] if numbers.size == 1 else flat)
            return value

        return draw


@pytest.fixture
def rng(rng, request, _particles_job):
    """The plugin's ``rng``; with ``PARTICLES_RECORD_DRAWS`` set, one that records its draws for the grader's tests."""
    folder = os.environ.get(DRAWS)
    if not folder:
        yield rng
        return
    recorder = _Recorder(rng)
    yield recorder
    line = {"notebook": str(_particles_job.get("notebook")), "seed": int(_particles_job["seed"]),
            "test": _test_key(request.node), "scalars": recorder.scalars, "arrays": recorder.arrays}
    with open(Path(folder) / f"draws-{os.getpid()}.jsonl", "a") as out:
        out.write(json.dumps(line) + "\n")
