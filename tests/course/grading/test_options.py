"""The options of a grading run: checked once, each bad value refused naming the option, paths made paths."""

import dataclasses
from pathlib import Path

import pytest

from particles.course.grading.options import GradeOptions

ROOT = Path(__file__).resolve().parents[3]


@pytest.mark.parametrize("changes, message", [
    ({"jobs": 0}, r"jobs must be a positive integer, got 0"),
    ({"jobs": True}, r"jobs must be a positive integer, got True"),
    ({"jobs": 1.5}, r"jobs must be a positive integer, got 1.5"),
    ({"exercise": "99_nothing"}, r"unknown exercise '99_nothing'; expected one of '00_warmup'"),
    ({"resume": True}, r"resume needs out"),
    ({"students": ["ann"]}, r"student needs out"),
    ({"students": ["ann"], "out": "o", "resume": True}, r"student needs out .* and no resume"),
    ({"time_limit": 0}, r"time_limit"),
    ({"memory_mb": float("nan")}, r"memory_mb"),
    ({"hidden_visibility": "secret"}, r"hidden_visibility must be one of hidden, after_due_date"),
    ({"root": "/nonexistent-course"}, r"no exercise tests in /nonexistent-course/tests/exercises"),
])
def test_a_bad_option_is_refused_naming_it(changes, message):
    """Each bad value raises ValueError naming the option and what was expected."""
    with pytest.raises(ValueError, match=message):
        GradeOptions(paths=("subs",), **{"root": ROOT, **changes})


def test_options_are_normalized_once_and_cannot_change():
    """Paths become Path objects, students lose their repeats, the root is resolved and its tests found; the
    object is frozen, and the options a record keeps are the five that change a grade."""
    options = GradeOptions(paths=["a.ipynb", "subs"], out="out", root=ROOT, students=["ann", "bob", "ann"],
                           rubric=["r.csv"], time_limit=2, seed=3)
    assert options.paths == (Path("a.ipynb"), Path("subs")) and options.out == Path("out")
    assert options.rubric == (Path("r.csv"),) and options.students == ("ann", "bob")
    assert options.root == ROOT.resolve() and "00_warmup" in options.tests
    assert options.logs == Path("out") / "logs"
    assert options.recorded == {"public_only": False, "seed": 3, "time_limit": 2.0, "memory_mb": None,
                                "audit_hook": True}
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.jobs = 4
