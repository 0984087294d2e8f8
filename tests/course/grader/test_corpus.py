"""The grader on a corpus of submissions: right verdicts, clear reasons, a record for everything.

All notebooks are graded once (module fixture, two jobs, per-call time limit
2 s, fixed seed, the hidden tests' draws recorded); the tests then read the
verdicts.
"""

import csv
import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
import corpus  # noqa: E402
import exercise_corpus  # noqa: E402

from particles.course.grading.driver import grade  # noqa: E402
from particles.course.results.reports import score_of  # noqa: E402

SEED = 20240611
CASES = dict(corpus.REJECTED, **corpus.CORRECT)


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("corpus")
    names = corpus.write_corpus(tmp / "submissions")
    with exercise_corpus.recording_draws(tmp / "draws") as folder:
        summary = grade([tmp / "submissions"], tmp / "out", jobs=2, seed=SEED, time_limit=2.0, root=corpus.ROOT)
    return {"summary": summary, "out": tmp / "out", "names": names, "draws": exercise_corpus.read_draws(folder)}


def _tests(graded, student):
    (result,) = graded["summary"]["students"][student]
    return {t["test"]: t for t in result["tests"]}


def test_corpus_is_large_enough():
    """The corpus holds at least 20 submissions to reject and 3 correct variants."""
    assert len(corpus.REJECTED) >= 20 and len(corpus.CORRECT) >= 3


def test_every_submission_yields_a_record(graded):
    """Every notebook gets results.json, feedback and a gradebook row, whatever it did."""
    assert graded["summary"]["problems"] == []
    assert set(graded["summary"]["students"]) == set(graded["names"])
    rows = list(csv.DictReader(open(graded["out"] / "gradebook.csv")))
    assert {r["student"] for r in rows} == set(graded["names"])
    for name in graded["names"]:
        data = json.loads((graded["out"] / name / "results.json").read_text())
        tests = [t for t in data["tests"] if not t["extra_data"].get("written")]  # + its written question, by hand
        assert data["extra_data"]["max_score"] == 11 and len(tests) == 8 and len(data["tests"]) == 9
        assert (graded["out"] / name / "feedback.md").read_text().startswith(f"# Feedback for {name}")
        assert all(t["grader_error"] is False for t in _tests(graded, name).values())


def test_master_scores_full_marks(graded):
    """The master solution passes every public and hidden test."""
    tests = _tests(graded, "master")
    assert all(t["passed"] for t in tests.values()), [t["reason"] for t in tests.values() if not t["passed"]]


def test_released_stub_scores_zero(graded):
    """The released stub scores 0, each test saying the function is not implemented yet."""
    tests = _tests(graded, "released_stub")
    assert score_of(list(tests.values()))[0] == 0
    assert all("is not implemented yet" in t["reason"] for t in tests.values())


@pytest.mark.parametrize("name", sorted(corpus.REJECTED))
def test_rejected_on_the_right_test_with_a_clear_reason(graded, name):
    """A bad submission fails the tests it should, each with its one-line reason."""
    tests = _tests(graded, name)
    case = corpus.REJECTED[name]
    for test, reason in case["fails"].items():
        assert not tests[test]["passed"], f"{test} should fail"
        assert reason in tests[test]["reason"], tests[test]["reason"]
        assert "\n" not in tests[test]["reason"]
    for test in case.get("passes", []):
        assert tests[test]["passed"], f"{test} should pass: {tests[test]['reason']}"
    assert score_of(list(tests.values()))[0] < 11


@pytest.mark.parametrize("name", sorted(corpus.REJECTED))
def test_rejected_submission_is_told_its_mistake(graded, name):
    """A bad submission's feedback names what it did in words, not only that a number is off by so much."""
    tests = _tests(graded, name)
    named = [(test, phrase) for test, phrase in exercise_corpus.diagnoses(corpus.REJECTED[name])
             if not tests[test]["passed"] and exercise_corpus.names_a_mistake(phrase, tests[test]["reason"])]
    assert named, {test: tests[test]["reason"] for test in corpus.REJECTED[name]["fails"]}


def test_hidden_messages_never_show_random_parameters(graded):
    """No failure message of a hidden test of the corpus shows a number its random generator drew."""
    checked, shown = 0, {}
    for name in graded["names"]:
        for test in _tests(graded, name).values():
            if test["hidden"] and not test["passed"]:
                checked += 1
                numbers = exercise_corpus.shown_numbers(test["reason"], graded["draws"][(name, test["test"])])
                if numbers:
                    shown[f"{name}: {test['test']}"] = (numbers, test["reason"])
    assert checked >= 10
    assert not shown, shown


def test_prints_in_a_loop_are_named(graded):
    """A print in a loop fills the worker's output file: the student is told so, not 'OSError: File too large'."""
    tests = _tests(graded, "prints_in_a_loop")
    reasons = [t["reason"] for t in tests.values() if not t["passed"]]
    assert reasons and all("printed more than 16 MiB (the limit)" in r for r in reasons), reasons
    assert not any("File too large" in r or "OSError" in r for r in reasons)


@pytest.mark.parametrize("name", sorted(corpus.CORRECT))
def test_correct_variants_score_full_marks(graded, name):
    """Correct code written differently from the master scores full marks."""
    tests = _tests(graded, name)
    assert all(t["passed"] for t in tests.values()), {k: t["reason"] for k, t in tests.items() if not t["passed"]}


def test_hidden_tests_record_their_seed(graded):
    """Hidden tests record the grading seed; results.json and feedback show it."""
    tests = _tests(graded, "hard_codes_public_answers")
    assert tests["test_euler_step_random"]["seed"] == SEED
    data = json.loads((graded["out"] / "hard_codes_public_answers" / "results.json").read_text())
    assert data["extra_data"]["seeds"] == {"00_warmup": SEED}
    hidden = [t for t in data["tests"] if "hidden" in t["tags"]]
    assert hidden and all(t["visibility"] == "after_published" for t in hidden)
    assert f"seed {SEED}" in (graded["out"] / "hard_codes_public_answers" / "feedback.md").read_text()


def test_worker_restarts_are_reported(graded):
    """A submission that kills its worker gets a note that the worker was restarted."""
    (result,) = graded["summary"]["students"]["calls_os_exit"]
    assert any("restarted" in note for note in result["notes"])


def test_fake_results_do_not_leak(graded):
    """A submission that writes a fake results.json cannot touch the grader's outputs."""
    data = json.loads((graded["out"] / "writes_a_fake_results_json" / "results.json").read_text())
    assert data["score"] < 11 and len([t for t in data["tests"] if not t["extra_data"].get("written")]) == 8
