"""particles.check never reports a pass it did not test."""

from pathlib import Path

import pytest

from particles.course import check as check_module
from particles.course.grading import session as grading
from particles.course.check import CheckError, CheckResult, check
from particles.course.results.records import SubmissionRecord, TestRecord

ROOT = Path(__file__).resolve().parents[2]


def test_no_test_collected_is_an_error_not_a_pass(monkeypatch):
    """A check that collected no test raises CheckError saying nothing was checked."""
    empty = SubmissionRecord(student="you", exercise="00_warmup", notebook="x.ipynb", seed=0, tests=[],
                             notes=["cannot collect"], grader_status=5)
    monkeypatch.setattr(grading, "grade_unit", lambda *a, **k: empty)
    with pytest.raises(CheckError, match=r"no public test of 00_warmup ran \(pytest status 5\).*nothing was checked"):
        check("00_warmup", notebook=ROOT / "exercises" / "00_warmup.ipynb", root=ROOT)


def test_without_pytest_the_check_refuses_before_grading(monkeypatch):
    """Without pytest the check raises CheckError with the pip command, before grading."""
    real = check_module.importlib.util.find_spec
    monkeypatch.setattr(check_module.importlib.util, "find_spec",
                        lambda name, *a: None if name == "pytest" else real(name, *a))
    monkeypatch.setattr(grading, "grade_unit", lambda *a, **k: pytest.fail("graded without pytest"))
    with pytest.raises(CheckError, match=r"-m pip install pytest"):
        check("00_warmup", notebook=ROOT / "exercises" / "00_warmup.ipynb", root=ROOT)


def test_an_empty_result_never_passes_and_unwritten_functions_are_named():
    """An empty result never passes; the functions not implemented yet are named, upstream ones too."""
    assert not CheckResult("00_warmup", [], [], "x").passed
    failed = TestRecord(test="t", name="t", points=1, passed=False,
                        reason="`measured_order` calls `rk4_step`, which is not implemented yet")
    other = TestRecord(test="u", name="u", points=1, passed=False, reason="`run` is not implemented yet: it raised")
    result = CheckResult("01", [failed, other], [], "x")
    assert result.unwritten == ["rk4_step", "run"]
    assert "Not implemented yet: `rk4_step`, `run`." in str(result) and "All public tests pass" not in str(result)
