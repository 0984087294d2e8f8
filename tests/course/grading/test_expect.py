"""The exercise tests' checks: a wrong result's message says what it most likely is (particles.course.grading.expect)."""

import numpy as np
import pytest

from particles.course.grading.expect import LN10, diagnose, expect_array, expect_float
from particles.course.worker.runner import GradingFailure


def _message(value, expected, **options):
    with pytest.raises(GradingFailure) as failure:
        expect_array(value, expected, "f(x)", **options)
    text = str(failure.value)
    assert "\n" not in text
    return text


def test_an_array_hint_names_the_wrong_answer():
    """A result equal to a typical wrong answer ends its message with that answer's name."""
    text = _message(np.array([1.0, 3.0]), np.array([1.0, 2.0]), hints={"a midpoint step": np.array([1.0, 3.0])})
    assert text.endswith("; your result matches a midpoint step")


def test_a_hint_of_another_shape_names_the_wrong_answer():
    """A result of the wrong shape is matched against hints of its own shape (a sum over particles)."""
    text = _message(np.array([3.0, 4.0]), np.ones((2, 2)), hints={"the sum over particles": np.array([3.0, 4.0])})
    assert "expected shape (2, 2); your result matches the sum over particles" in text


def test_a_predicate_hint_and_its_own_clause():
    """A hint may be a predicate; a label starting with 'your ' is the clause itself, a str result replaces it."""
    first = {"your first record is not X0": lambda X: X[0] != 1.0}
    assert _message(np.array([0.0, 2.0]), np.array([1.0, 2.0]), hints=first).endswith("; your first record is not X0")
    dynamic = {"ignored": lambda X: f"your result is {X[0]:g} at the start"}
    text = _message(np.array([0.0, 2.0]), np.array([1.0, 2.0]), hints=dynamic)
    assert text.endswith("; your result is 0 at the start")
    broken = {"never": lambda X: X.missing_attribute}  # a predicate that cannot judge does not match
    assert "; your" not in _message(np.array([0.0, 2.5]), np.array([1.0, 2.0]), hints=broken)


def test_hints_given_as_a_function_are_computed_only_for_a_wrong_result():
    """``hints=lambda: {...}`` costs nothing for a right result; a wrong one (value or shape) is still named."""
    asked = []

    def hints():
        asked.append(1)
        return {"a midpoint step": np.array([1.0, 3.0])}

    expect_array(np.array([1.0, 2.0]), np.array([1.0, 2.0]), "f(x)", hints=hints)
    expect_float(2.0, 2.0, "g(x)", hints=hints)
    assert asked == []
    assert _message(np.array([1.0, 3.0]), np.array([1.0, 2.0]), hints=hints).endswith(
        "; your result matches a midpoint step")
    assert "expected shape (2, 2); your result matches a midpoint step" in \
        _message(np.array([1.0, 3.0]), np.ones((2, 2)), hints=hints)
    assert len(asked) == 2


def test_float32_results_are_named():
    """A float32 result, or float64 numbers rounded to float32 on the way, is named single precision."""
    x = np.array([1 / 3, 2 / 3, 0.1])
    assert "your result is float32 (single precision" in _message(x.astype(np.float32), x)
    assert "rounded to single precision (float32) on the way" in _message(x.astype(np.float32).astype(float), x)


def test_constant_factors_are_named():
    """A result off by ln(10), 1/ln(10), -1, 2 or 1/2 everywhere says so; other factors only for arrays."""
    x = np.array([0.5, 2.0, -3.0])
    assert "times ln(10) = 2.303 everywhere: log10 and ln mixed" in _message(LN10 * x, x)
    assert "divided by ln(10) = 2.303 everywhere" in _message(x / LN10, x)
    assert "wrong sign everywhere" in _message(-x, x)
    assert "twice the expected one everywhere" in _message(2 * x, x)
    assert "1.7 times the expected one everywhere" in _message(1.7 * x, x)
    assert diagnose(np.array(1.7), np.array(1.0)) == ""  # one number: any wrong value is "a factor"
    assert diagnose(x, x) == ""  # nothing to say about a right answer


def test_hidden_messages_show_no_values():
    """With show_values=False the message gives the relative error and the index, not the numbers compared."""
    text = _message(np.array([1.0, 2.5]), np.array([1.0, 2.0]), show_values=False)
    assert "is off by a relative error of 0.25 at index (1,) (tolerance" in text
    assert "got" not in text and "2.5" not in text and "0.5" not in text
    zeros = _message(np.array([0.0, 0.0]), np.array([1.2345, 0.0]), show_values=False)
    assert "1.23" not in zeros  # a result of zeros is off by the expected value, which may be an input


def test_expect_float_takes_hints():
    """expect_float matches numbers as hints and keeps a float32 scalar's precision for the diagnosis."""
    with pytest.raises(GradingFailure, match="your result matches the slope of two points"):
        expect_float(1.5, 2.0, "slope", hints={"the slope of two points": 1.5})
    with pytest.raises(GradingFailure, match="float32"):
        expect_float(np.float32(1 / 3), 1 / 3, "third")
    expect_float(2.0, 2.0, "two", hints={"never": 3.0})
