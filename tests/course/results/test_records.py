"""The typed records of a grading run (particles.course.results.records): round trips, errors, Gradescope's format."""

import json

import pytest

from particles.course.results.records import (SessionRecord, SubmissionRecord, TestRecord, score_of, to_gradescope)


def _tests():
    return [TestRecord(test="test_a", name="a works", points=2.0, passed=True),
            TestRecord(test="test_b[rk4]", name="b works [rk4]", hidden=True, reason="order 1.02, expected 4",
                       seed=7)]


def test_a_submission_record_survives_json():
    """to_dict -> JSON -> from_dict gives back an equal record, tests typed again."""
    tests = _tests()
    tests[1].figures = [{"title": "t", "series": []}]
    record = SubmissionRecord(student="ada", exercise="01_integrator_order", seed=7, tests=tests,
                              notes=["note"], complete=True, grader_status=1)
    again = SubmissionRecord.from_dict(json.loads(json.dumps(record.to_dict())))
    assert again == record and isinstance(again.tests[1], TestRecord)
    assert (again.score, again.max_score) == (2.0, 3.0) == score_of(again.tests)


def test_records_read_as_mappings():
    """record["passed"] is record.passed, dict(record) has every field, an unknown key is a KeyError."""
    test = _tests()[0]
    assert test["passed"] is True and dict(test)["points"] == 2.0 and test.get("nothing") is None
    with pytest.raises(KeyError):
        test["score_of_the_student"]


def test_missing_fields_are_named():
    """from_dict names the missing field and refuses what is not a dict."""
    with pytest.raises(ValueError, match="'student'"):
        SubmissionRecord.from_dict({"exercise": "01_x"})
    with pytest.raises(ValueError, match="'name'"):
        TestRecord.from_dict({"test": "test_a"})
    with pytest.raises(TypeError, match="must be a dict"):
        SessionRecord.from_dict(["id", 1])


def test_a_session_is_complete_only_with_its_time():
    """A session record without seconds is incomplete, and to_dict leaves seconds out (as the plugin writes it)."""
    session = SessionRecord(id="0", seed=3, tests=_tests())
    assert not session.complete and "seconds" not in session.to_dict()
    session.seconds = 1.5
    assert SessionRecord.from_dict(session.to_dict()).complete


def test_failed_copies_a_test_without_its_seed():
    """failed(reason) is a failed copy (no seed); the record itself is unchanged."""
    test = _tests()[1]
    copy = test.failed("not run")
    assert (copy.passed, copy.reason, copy.seed) == (False, "not run", None) and test.seed == 7


def test_gradescope_output():
    """to_gradescope: scores, numbers NN.k, visibility of hidden tests, tags, the seed of a hidden test's draw."""
    record = SubmissionRecord(student="ada", exercise="01_integrator_order", tests=_tests(), seconds=2.25,
                              sandbox="namespaces, uid")
    data = to_gradescope("ada", [record], hidden_visibility="after_due_date")
    assert (data["score"], data["extra_data"]["max_score"], data["execution_time"]) == (2.0, 3.0, 2.25)
    first, second = data["tests"]
    assert first["number"] == "01.1" and first["status"] == "passed" and first["visibility"] == "visible"
    assert second["visibility"] == "after_due_date" and second["tags"] == ["01_integrator_order", "hidden"]
    assert "seed 7" in second["output"] and "Sandbox of your code: namespaces, uid" in data["output"]
    with pytest.raises(ValueError, match="hidden_visibility"):
        to_gradescope("ada", [record], hidden_visibility="never")


def _with_stretch_goal():
    return _tests() + [TestRecord(test="test_c[rk4]", name="c works [rk4]", points=2.0, passed=True, optional=True),
                       TestRecord(test="test_d[rk4]", name="d works [rk4]", points=1.0, optional=True,
                                  reason="`rk4_step` is not implemented yet")]


def test_an_optional_test_is_labelled_and_not_scored():
    """An optional test carries its flag and the label "stretch goal, not scored" through JSON; no score counts it."""
    tests = _with_stretch_goal()
    record = SubmissionRecord(student="ada", exercise="01_integrator_order", tests=tests)
    data = json.loads(json.dumps(record.to_dict()))
    assert [t.get("optional") for t in data["tests"]] == [False, False, True, True]
    assert [t.get("label") for t in data["tests"]] == [None, None] + ["stretch goal, not scored"] * 2
    again = SubmissionRecord.from_dict(data)
    assert again == record
    assert (again.score, again.max_score) == (2.0, 3.0) == score_of(again.tests) == score_of(data["tests"])
    assert (tests[2].score, tests[2].max_score, tests[2].label) == (0.0, 0.0, "stretch goal, not scored")
    assert tests[2].title == "c works [rk4] (stretch goal, not scored)" and tests[0].title == "a works"


def test_gradescope_gives_a_stretch_goal_no_points_and_its_label():
    """In results.json an optional test has score and max_score 0, the label in its name, a tag and extra data."""
    record = SubmissionRecord(student="ada", exercise="01_integrator_order", tests=_with_stretch_goal())
    results = to_gradescope("ada", [record])
    assert (results["score"], results["extra_data"]["max_score"]) == (2.0, 3.0)
    scored, stretch = results["tests"][:2], results["tests"][2:]
    assert [t["max_score"] for t in scored] == [2.0, 1.0]
    for entry in stretch:
        assert entry["score"] == 0 and entry["max_score"] == 0
        assert entry["name"].endswith("(stretch goal, not scored)") and "stretch goal" in entry["tags"]
        assert entry["extra_data"]["optional"] is True
        assert entry["extra_data"]["label"] == "stretch goal, not scored"
    assert stretch[0]["status"] == "passed" and stretch[1]["status"] == "failed"
    assert "01_integrator_order: 2 / 2 points on the tests you can see" in results["output"]  # b is hidden


def test_a_late_penalty_follows_the_points_written_grades_add():
    """A late decision is a fraction: merged written grades raise total_max, and the penalty in points with it."""
    record = SubmissionRecord(student="ann", exercise="01_x", tests=[TestRecord("t", "t", points=10.0, passed=True)],
                              late={"submitted": "", "deadline": "", "days_late": 2, "fraction": 0.2,
                                    "penalty": 2.0, "reason": "2 days late", "source": ""})
    assert (record.penalty, record.total, record.total_max) == (2.0, 8.0, 10.0)
    record.written = [{"question": "1", "points": 4.0, "max_points": 5.0, "comment": "", "rubric": "r"}]
    assert (record.penalty, record.total, record.total_max) == (3.0, 11.0, 15.0)
    assert "penalty -3 of 15 points" in " ".join(record.late_lines())


def test_the_students_summary_never_counts_hidden_tests():
    """Gradescope's top output says 2 / 2 on the visible tests (not 2 / 3) while a hidden test's points are hidden."""
    record = SubmissionRecord(student="ada", exercise="01_integrator_order", tests=_tests(), seconds=1.0,
                              late={"submitted": "x", "deadline": "y", "days_late": 1, "fraction": 0.1,
                                    "penalty": 0.3, "reason": "submitted 2 hours after the deadline: -10%",
                                    "source": "the times file"})
    hidden = to_gradescope("ada", [record], hidden_visibility="after_published")
    first = hidden["output"].splitlines()[0]
    assert first.startswith("01_integrator_order: 2 / 2 points on the tests you can see")
    assert "3" not in hidden["output"].replace("seed 7", "") and "max_score" not in hidden
    assert "Late: submitted 2 hours after the deadline: -10%." in hidden["output"]
    assert hidden["score"] == pytest.approx(2.0 - 0.3) and hidden["extra_data"]["max_score"] == 3.0
    shown = to_gradescope("ada", [record], hidden_visibility="visible")
    assert shown["output"].splitlines()[0] == "01_integrator_order: 2 / 3 points"
    assert "raw score 2, penalty -0.3 of 3 points" in shown["output"]
