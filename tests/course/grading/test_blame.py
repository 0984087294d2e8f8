"""Whose fault a failure is (particles.course.grading.blame), and stretch goals listed apart by the student's check."""

from particles.course.grading.blame import blame, function_of, helpers
from particles.course.check import CheckResult
from particles.course.reading.submission import SubmissionCode
from particles.course.results.records import TestRecord

CELLS = [
    ("code cell 1", "import numpy as np"),
    ("code cell 2", "def euler_step(f, X, t, h):\n    return X + h * f(X, t + h)"),
    ("code cell 3", "def rk4_step(f, X, t, h):\n    raise NotImplementedError"),
    ("code cell 4", 'STEPPERS = {"euler": euler_step, "rk4": rk4_step}'),
    ("code cell 5", "def convergence_errors(method, f, X0, t0, t1, exact, n_steps):\n"
                    "    step = STEPPERS[method]\n    return step"),
    ("code cell 6", "def observed_order(h, e):\n    return np.polyfit(np.log(h), np.log(e), 1)[0]"),
    ("code cell 7", "def measured_order(method, f, X0, t0, t1, exact, n_steps):\n"
                    "    return observed_order(*convergence_errors(method, f, X0, t0, t1, exact, n_steps))"),
]


def _record(test, function, passed=False, reason="off by 0.1"):
    return TestRecord(test=test, name=test, passed=passed, reason="" if passed else reason, function=function)


def test_helpers_follow_functions_and_constants():
    """A function's helpers are the notebook's functions it reaches, through other functions and constants."""
    code = SubmissionCode.from_cells(CELLS)
    found = helpers(code, "measured_order")
    assert set(found) == {"observed_order", "convergence_errors", "euler_step", "rk4_step"}
    assert found["rk4_step"] == ["measured_order", "convergence_errors", "STEPPERS", "rk4_step"]
    assert helpers(code, "euler_step") == {}


def test_a_test_judges_the_function_in_its_name_else_the_first_it_calls():
    """The function of a test: the longest called function named in the test, else the first one called."""
    defined = {"measured_order", "convergence_errors", "midpoint_step"}
    assert function_of("test_measured_order_circle[rk4]", ["convergence_errors", "measured_order"], defined) \
        == "measured_order"
    assert function_of("test_step_circle[midpoint]", ["midpoint_step"], defined) == "midpoint_step"
    assert function_of("test_x", [], defined) == ""


def test_downstream_failures_are_blamed_on_the_helper_that_fails_its_own_tests():
    """measured_order's failure names euler_step when euler_step fails its own tests; other parameters are not blamed."""
    code = SubmissionCode.from_cells(CELLS)
    records = [_record("test_step_circle[euler]", "euler_step"),
               _record("test_convergence_errors_circle", "convergence_errors"),
               _record("test_measured_order_circle[euler]", "measured_order", reason="order 0.5, expected 1"),
               _record("test_measured_order_circle[midpoint]", "measured_order"),
               _record("test_observed_order_noisy", "observed_order", passed=True)]
    assert blame(records, code) == 3
    assert records[1].reason == ("`convergence_errors` calls `euler_step`, which fails its own tests: fix "
                                 "`euler_step` first; off by 0.1")
    assert records[2].reason.startswith("`measured_order` calls `euler_step` (through `convergence_errors`), "
                                        "which fails its own tests: fix `euler_step` first; order 0.5")
    assert records[3].reason.startswith("`measured_order` calls `convergence_errors`, which fails")  # not [euler]
    assert records[0].reason == "off by 0.1" and blame(records, code) == 0  # once only


def test_the_check_lists_stretch_goals_apart_and_scores_without_them():
    """particles.check's result: stretch goals after the scored tests, labelled, outside the score and `passed`."""
    tests = [TestRecord(test="test_a", name="a works", points=2.0, passed=True),
             TestRecord(test="test_b[rk4]", name="b works [rk4]", points=1.0, optional=True,
                        reason="`rk4_step` is not implemented yet")]
    result = CheckResult("01_integrator_order", tests, [], "the saved notebook x.ipynb")
    assert (result.score, result.max_score, result.passed) == (2.0, 2.0, True)
    text = str(result)
    assert "2 / 2 points" in text and "Stretch goals (not scored): 0 of 1 pass" in text
    assert text.index("a works") < text.index("Stretch goals") < text.index("b works [rk4]")
    assert "b works [rk4] (stretch goal, not scored)" in result._repr_markdown_()
    assert "b works [rk4] (stretch goal, not scored)" in result._repr_html_()


def test_untested_helpers_are_named_unless_a_passing_function_uses_them():
    """A failure no tested helper explains names the untested helpers it relies on, not those a passing test covers."""
    code = SubmissionCode.from_cells([
        ("code cell 1", "def amplitude(X):\n    return abs(X)"),
        ("code cell 2", "def blows_up(h):\n    return amplitude(h) > 1"),
        ("code cell 3", "def bisect_stable(unstable, lo, hi):\n    return hi"),
        ("code cell 4", "def max_stable_step(k):\n    return bisect_stable(blows_up, 0.0, k)"),
    ])
    records = [_record("test_blows_up_around_the_limits", "blows_up", passed=True),
               _record("test_max_stable_step_one_spring", "max_stable_step", reason="returned a step that blows up")]
    assert blame(records, code) == 1
    assert records[1].reason == ("returned a step that blows up (`max_stable_step` relies on `bisect_stable` of "
                                 "yours, which no test checks alone: the mistake may be there)")


def test_a_scatter_with_repeated_indices_is_named():
    """dx[i] += c at an index array is named on a failure (lost updates); an index a for loop binds is not."""
    code = SubmissionCode.from_cells([
        ("code cell 1", "import numpy as np"),
        ("code cell 2", "def spread(x, i, c):\n    dx = np.zeros_like(x)\n    dx[i] += c\n"
                        "    for k in range(len(i)):\n        dx[k] += c[k]\n    return dx"),
    ])
    from particles.course.grading.blame import scatter_hazards

    assert scatter_hazards(code, "spread") == [("code cell 2", 3, "dx[i]")]
    records = [_record("test_spread", "spread", reason="spread(x, i, c) is off by 0.1")]
    blame(records, code)
    assert "`spread` adds into `dx[i]` with += (code cell 2, line 3)" in records[0].reason
    assert "np.add.at" in records[0].reason


def test_a_boolean_mask_is_no_scatter_hazard():
    """x[inside] -= ... with a mask made of comparisons changes each row once: not named; an index array still is."""
    code = SubmissionCode.from_cells([
        ("code cell 1", "import numpy as np"),
        ("code cell 2", "def push(x, H, n, i):\n    inside = H < 0\n    deep = inside & ~(H > -1)\n"
                        "    x[inside] -= H[inside, None] * n[inside]\n    x[deep] += 1.0\n"
                        "    x[~inside] += 0.0\n    x[i[inside]] += 1.0\n    return x"),
    ])
    from particles.course.grading.blame import scatter_hazards

    assert scatter_hazards(code, "push") == [("code cell 2", 7, "x[i[inside]]")]
