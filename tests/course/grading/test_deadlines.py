"""The course file and the late policy: deadlines, grace, caps, extensions, time zones."""

from datetime import datetime, timedelta, timezone

import pytest

from particles.course.grading.deadlines import (Course, LatePolicy, apply_late, decide, find_course, load_course,
                                                parse_time)
from particles.course.results.records import SubmissionRecord, TestRecord

EXERCISES = ["00_warmup", "01_integrator_order"]
PARIS = timezone(timedelta(hours=1))
DUE = datetime(2026, 10, 1, 23, 59, tzinfo=PARIS)
COURSE = """
[late]
penalty_per_day = 0.1
cap = 0.5
grace_minutes = 15

[exercises.00_warmup]
deadline = 2026-10-01T23:59:00+01:00

[exercises.01_integrator_order]
deadline = "2026-10-15T23:59:00Z"
penalty_per_day = 0.25
cap = 1

[extensions.alice]
00_warmup = 2026-10-03T23:59:00+01:00

[extensions.bob]
00_warmup = 1.5
"""


def _course(tmp_path, text=COURSE):
    path = tmp_path / "course.toml"
    path.write_text(text)
    return load_course(path, EXERCISES)


def _record(student="carol", exercise="00_warmup", points=30.0, passed=True):
    return SubmissionRecord(student=student, exercise=exercise,
                            tests=[TestRecord(test="t", name="t", points=points, passed=passed)])


POLICY = LatePolicy(penalty_per_day=0.1, cap=0.5, grace_minutes=15)


@pytest.mark.parametrize("after, days, penalty", [
    (timedelta(hours=-3), 0, 0.0),  # on time
    (timedelta(0), 0, 0.0),  # at the deadline itself
    (timedelta(minutes=14), 0, 0.0),  # within the grace period
    (timedelta(minutes=16), 1, 3.0),  # past it: one started day, counted from the deadline
    (timedelta(days=1), 1, 3.0),
    (timedelta(days=1, seconds=1), 2, 6.0),
    (timedelta(days=2, hours=3), 3, 9.0),
    (timedelta(days=40), 40, 15.0),  # capped at 50% of 30 points
])
def test_days_late_are_started_days_and_the_penalty_a_capped_fraction(after, days, penalty):
    """Each started day after the deadline (past the grace period) takes 10% of the points, at most 50%."""
    late = decide(DUE + after, DUE, POLICY, 30.0)
    assert (late["days_late"], late["penalty"]) == (days, penalty)
    assert late["fraction"] == pytest.approx(penalty / 30)


def test_the_reason_says_when_how_late_and_how_much():
    """One sentence: how late, the deadline in its own zone, the percentage and the cap (the points follow the record)."""
    late = decide(DUE + timedelta(days=2, hours=3), DUE, POLICY, 30.0, why="extension for alice")
    assert late["reason"] == ("submitted 2 days 3 hours after the deadline 2026-10-01 23:59 +01:00 "
                              "(extension for alice): -30% of the exercise's points (3 days late at 10% a day, "
                              "cap 50%)")
    assert "capped at 50%" in decide(DUE + timedelta(days=9), DUE, POLICY, 30.0)["reason"]
    assert "within the grace period of 15 minutes" in decide(DUE + timedelta(minutes=5), DUE, POLICY, 30)["reason"]
    assert decide(DUE - timedelta(hours=1), DUE, POLICY, 30)["reason"].endswith("no penalty")


def test_time_zones_compare_instants_and_show_the_deadlines_zone():
    """A UTC submission one minute after a +01:00 deadline is late; times are shown in the deadline's zone."""
    submitted = datetime(2026, 10, 1, 23, 0, tzinfo=timezone.utc)  # 00:00 in Paris, one minute late
    late = decide(submitted, DUE, LatePolicy(0.1, 0.5), 30.0)
    assert late["days_late"] == 1 and late["submitted"] == "2026-10-02T00:00:00+01:00"
    assert "1 minute after the deadline 2026-10-01 23:59 +01:00" in late["reason"]
    on_time = decide(datetime(2026, 10, 1, 22, 58, tzinfo=timezone.utc), DUE, LatePolicy(0.1, 0.5), 30.0)
    assert on_time["days_late"] == 0
    with pytest.raises(ValueError, match="submitted: 2026-10-01T22:58:00 has no time zone"):
        decide(datetime(2026, 10, 1, 22, 58), DUE, POLICY, 30.0)


def test_course_file_gives_deadlines_policies_and_extensions(tmp_path):
    """The file's default policy, an exercise's own, a new deadline and extra days per student."""
    course = _course(tmp_path)
    assert course.deadlines["01_integrator_order"] == datetime(2026, 10, 15, 23, 59, tzinfo=timezone.utc)
    assert course.policies["00_warmup"] == POLICY
    assert course.policies["01_integrator_order"] == LatePolicy(0.25, 1.0, 15.0)  # grace inherited
    assert course.deadline_of("alice", "00_warmup") == (datetime(2026, 10, 3, 23, 59, tzinfo=PARIS),
                                                        "extension for alice")
    assert course.deadline_of("bob", "00_warmup")[0] == DUE + timedelta(days=1.5)
    assert course.deadline_of("alice", "01_integrator_order")[1] == ""  # no extension of that one
    assert course.deadline_of("x", "00_warmup", aliases=("alice",))[1] == "extension for alice"
    assert Course().deadline_of("alice", "00_warmup") == (None, "")


def test_apply_late_uses_the_students_deadline_and_the_records_points(tmp_path):
    """alice's extension makes her on time; carol loses 20% of 30 points; total drops by the penalty."""
    course = _course(tmp_path)
    when = DUE + timedelta(days=1, hours=1)
    alice = apply_late(_record("alice"), course, when, "the times file")
    carol = apply_late(_record("carol"), course, when, "the times file")
    assert alice.late["days_late"] == 0 and alice.total == 30
    assert "(extension for alice)" in alice.late["reason"] and alice.late["source"] == "the times file"
    assert carol.late["penalty"] == 6 and carol.penalty == 6 and carol.total == 24
    assert apply_late(_record(passed=False), course, when).total == 0  # never below 0
    # no deadline, no course, no time: no decision
    assert apply_late(_record(exercise="02_stiffness"), course, when).late is None
    assert apply_late(_record(), None, when).late is None
    assert apply_late(_record(), course, None).late is None


@pytest.mark.parametrize("text, message", [
    ("[exercises.00_warmup]\ndeadline = 2026-10-01T23:59:00", r"exercises\.00_warmup\.deadline: .* has no time zone"),
    ('[exercises.00_warmup]\ndeadline = "2026-10-01 23:59"', r"exercises\.00_warmup\.deadline: .* no time zone"),
    ("[exercises.00_warmup]\ndeadline = 2026-10-01", r"00_warmup\.deadline: 2026-10-01 is not a date and a time"),
    ('[exercises.00_warmup]\ndeadline = "soon"', r"'soon' is not an ISO 8601 date-time"),
    ("[exercises.00_warmup]\npenalty_per_day = 0.1", r"exercises\.00_warmup: no deadline"),
    ("[exercises.99_nothing]\ndeadline = 2026-10-01T23:59:00Z", r"unknown exercise '99_nothing'; expected one of "
                                                                r"00_warmup, 01_integrator_order"),
    ("[exercises.00_warmup]\ndeadline = 2026-10-01T23:59:00Z\ndue = 1", r"exercises\.00_warmup\.due: unknown key"),
    ("[late]\npenalty_per_day = -0.1", r"late\.penalty_per_day: must be >= 0"),
    ("[late]\ncap = 1.5", r"late\.cap: .* in \[0, 1\]"),
    ('[late]\ncap = "half"', r"late\.cap: expected a number"),
    ("[late]\npenalty = 0.1", r"late\.penalty: unknown key"),
    ("[deadlines]\nx = 1", r"unknown key 'deadlines'"),
    ("exercises = 3", r"exercises: expected a table"),
    ("[exercises.00_warmup]\ndeadline = 2026-10-01T23:59:00Z\n[extensions.alice]\n00_warmup = -1",
     r"extensions\.alice\.00_warmup: extra days must be a number >= 0"),
    ("[exercises.00_warmup]\ndeadline = 2026-10-01T23:59:00Z\n[extensions.alice]\n01_integrator_order = 1",
     r"extensions\.alice\.01_integrator_order: an extension of an exercise without a deadline"),
    ("[exercises.00_warmup]\ndeadline = 2026-10-01T23:59:00Z\n[extensions.alice]\n00_warmup = 2026-10-03T12:00:00",
     r"extensions\.alice\.00_warmup: .* no time zone"),
    ("[exercises.00_warmup\n", r"is not valid TOML"),
    ('[exercises.00_warmup]\ndeadline = "2026-10-01T23:59 Mars/Olympus"', r"00_warmup\.deadline: unknown time zone "
                                                                          r"'Mars/Olympus'"),
    ('[exercises.00_warmup]\ndeadline = "2026-03-29T02:30 Europe/Berlin"', r"does not exist in Europe/Berlin"),
    ('[exercises.00_warmup]\ndeadline = "2026-10-25T02:30 Europe/Berlin"',
     r"happens twice in Europe/Berlin .*2026-10-25T02:30:00\+02:00 or 2026-10-25T02:30:00\+01:00"),
])
def test_bad_course_files_are_errors_naming_the_file_and_key(tmp_path, text, message):
    """Every mistake of a course file is a ValueError naming the file and the key at fault."""
    with pytest.raises(ValueError, match=message) as caught:
        _course(tmp_path, text)
    assert str(tmp_path / "course.toml") in str(caught.value)


def test_the_course_file_is_found_at_the_root_or_given(tmp_path):
    """course.toml at the root is read; --course FILE wins; none at all: no deadlines; a missing FILE: error."""
    assert find_course(tmp_path, EXERCISES) is None
    (tmp_path / "course.toml").write_text(COURSE)
    assert find_course(tmp_path, EXERCISES).deadlines["00_warmup"] == DUE
    other = tmp_path / "other.toml"
    other.write_text("[exercises.00_warmup]\ndeadline = 2030-01-01T00:00:00Z\n")
    assert find_course(tmp_path, EXERCISES, other).deadlines["00_warmup"].year == 2030
    with pytest.raises(ValueError, match="cannot read the course file .*missing.toml"):
        find_course(tmp_path, EXERCISES, tmp_path / "missing.toml")


def test_named_zones_follow_daylight_saving():
    """A deadline in Europe/Berlin is CEST in July and CET in November, in both spellings; an offset still works."""
    summer = parse_time("2026-07-01T23:59 Europe/Berlin", "deadline")
    winter = parse_time("2026-11-01T23:59:00[Europe/Berlin]", "deadline")
    assert (summer.utcoffset(), winter.utcoffset()) == (timedelta(hours=2), timedelta(hours=1))
    assert parse_time("2026-07-01T23:59:00+02:00", "deadline") == summer
    due = parse_time("2026-10-29T23:59 Europe/Berlin", "deadline")  # after the clocks went back (Oct 25)
    assert decide(due + timedelta(hours=2), due, LatePolicy(0.1, 0.5), 10)["reason"].endswith("cap 50%)")
    assert "2026-10-29 23:59 +01:00" in decide(due, due, LatePolicy(0.1, 0.5), 10)["reason"]


def test_every_error_of_a_course_file_at_once(tmp_path):
    """A course file with four mistakes is refused once, naming each key: none is left for the next run."""
    text = ("[late]\ncap = 2\npenalty_per_day = -1\n[exercises.00_warmup]\ndeadline = 2026-10-01T23:59:00\n"
            "[exercises.99_x]\ndeadline = 2026-10-01T23:59:00Z\n")
    with pytest.raises(ValueError) as caught:
        _course(tmp_path, text)
    message = str(caught.value)
    assert "4 problems:" in message and str(tmp_path / "course.toml") in message
    for key in ("late.cap:", "late.penalty_per_day:", "exercises.00_warmup.deadline:", "exercises.99_x:"):
        assert f"\n  {key}" in message, key
