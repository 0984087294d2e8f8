"""Reference results computed once per grading session (particles.course.grading.memo)."""

import numpy as np
import pytest

from particles.course.grading import memo
from particles.course.grading.memo import memoized


def _counting():
    calls = []

    @memoized
    def reference(x, scale=1.0):
        calls.append((x, scale))
        return {"values": np.asarray(x, dtype=float) * scale}

    return reference, calls


def test_equal_arguments_are_computed_once_and_every_caller_gets_its_own_copy():
    """The second call with equal arguments (an equal array too) computes nothing; mutating a result changes no other."""
    reference, calls = _counting()
    first = reference(np.array([1.0, 2.0]), scale=2.0)
    first["values"][0] = -99.0
    second = reference(np.array([1.0, 2.0]), scale=2.0)
    assert len(calls) == 1
    np.testing.assert_array_equal(second["values"], [2.0, 4.0])
    reference(np.array([1.0, 3.0]), scale=2.0)
    reference(np.array([1.0, 2.0]), scale=3.0)
    reference(np.array([1.0, 2.0]), 2.0)  # by position: another key, computed again, the same value
    assert len(calls) == 4


def test_an_exception_is_not_remembered():
    """A call that raised is computed again the next time."""
    attempts = []

    @memoized
    def flaky(x):
        attempts.append(x)
        if len(attempts) == 1:
            raise RuntimeError("first time")
        return x

    with pytest.raises(RuntimeError):
        flaky(1)
    assert flaky(1) == 1 and flaky(1) == 1 and len(attempts) == 2


def test_arguments_that_do_not_pickle_are_refused_naming_the_function():
    """A lambda as an argument is a TypeError naming the memoized function, never a silent recomputation."""
    reference, _ = _counting()
    with pytest.raises(TypeError, match="reference is memoized, so its arguments must pickle"):
        reference(lambda: 1)


def test_at_most_size_results_are_kept_the_least_recently_used_goes_first(monkeypatch):
    """With room for 2 results, a third drops the one used longest ago."""
    monkeypatch.setattr(memo, "SIZE", 2)
    reference, calls = _counting()
    reference(1.0), reference(2.0), reference(1.0), reference(3.0)  # 2.0 is the least recently used
    reference(1.0)
    assert len(calls) == 3
    reference(2.0)
    assert len(calls) == 4
    reference.cache_clear()
    reference(1.0)
    assert len(calls) == 5
