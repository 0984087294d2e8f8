"""The exercises' autograders on their corpora: masters full marks, stubs zero, wrong answers caught and told why.

Every ``cases_NN_topic.py`` of this folder is graded in one run (module
fixture, two jobs, fixed seed, the hidden tests' draws recorded); the tests
then read the verdicts. See ``exercise_corpus.py`` for the format of a case.
"""

import os
import re
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
import exercise_corpus  # noqa: E402

from particles.course.grading.driver import grade  # noqa: E402
from particles.course.results.reports import score_of  # noqa: E402

SEED = 20261201
ONLY = "PARTICLES_CORPORA"
"""Set to exercise numbers (``"01,03"``), only their corpora are graded: for working on one exercise."""
MODULES = [m for m in exercise_corpus.case_modules()
           if not os.environ.get(ONLY) or m.EXERCISE[:2] in os.environ[ONLY].split(",")]
EXERCISES = [m.EXERCISE for m in MODULES]
REJECTED = [(m.EXERCISE, name) for m in MODULES for name in sorted(m.REJECTED)]
CORRECT = [(m.EXERCISE, name) for m in MODULES for name in sorted(getattr(m, "CORRECT", {}))]
CASES = {m.EXERCISE: dict(m.REJECTED, **getattr(m, "CORRECT", {})) for m in MODULES}


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("exercise-corpora")
    students = exercise_corpus.write_corpora(tmp / "submissions", MODULES)
    with exercise_corpus.recording_draws(tmp / "draws") as folder:
        # no output folder: the verdicts are what these tests read; the feedback files and their figures
        # (a third of this run's time when drawn) are tested in tests/course/results and grading/test_driver.py
        summary = grade([tmp / "submissions"], None, jobs=2, seed=SEED, time_limit=10.0,
                        root=exercise_corpus.ROOT)
    return {"summary": summary, "students": students, "draws": exercise_corpus.read_draws(folder)}


def _tests(graded, exercise, case):
    (result,) = graded["summary"]["students"][f"{exercise}__{case}"]
    assert result["exercise"] == exercise
    return {t["test"]: t for t in result["tests"]}


@pytest.mark.parametrize("exercise", EXERCISES)
def test_each_exercise_has_at_least_two_wrong_submissions(exercise):
    """Every exercise's corpus holds at least two submissions that must lose points."""
    (module,) = [m for m in MODULES if m.EXERCISE == exercise]
    assert len(module.REJECTED) >= 2


@pytest.mark.parametrize("exercise", EXERCISES)
def test_master_scores_full_marks(graded, exercise):
    """The master notebook passes every public and hidden test of its exercise."""
    tests = _tests(graded, exercise, "master")
    assert tests and all(t["passed"] for t in tests.values()), \
        {k: t["reason"] for k, t in tests.items() if not t["passed"]}


@pytest.mark.parametrize("exercise", EXERCISES)
def test_released_stub_scores_zero(graded, exercise):
    """The released stub scores nothing, and the grader says why without failing itself."""
    tests = _tests(graded, exercise, "released_stub")
    assert score_of(list(tests.values()))[0] == 0
    assert all(t["grader_error"] is False for t in tests.values())
    assert all("not implemented yet" in t["reason"] for t in tests.values()), \
        [t["reason"] for t in tests.values()]


@pytest.mark.parametrize("exercise, case", REJECTED, ids=[f"{e}-{c}" for e, c in REJECTED])
def test_wrong_submission_loses_its_points(graded, exercise, case):
    """A wrong submission fails the tests it should, each with a one-line reason saying what is wrong."""
    tests = _tests(graded, exercise, case)
    spec = CASES[exercise][case]
    for test, reason in spec["fails"].items():
        assert not tests[test]["passed"], f"{test} should fail"
        assert reason in tests[test]["reason"], tests[test]["reason"]
        assert "\n" not in tests[test]["reason"]
    for test in spec.get("passes", []):
        assert tests[test]["passed"], f"{test} should pass: {tests[test]['reason']}"
    score, max_score = score_of(list(tests.values()))
    if all(tests[test].get("optional") for test in spec["fails"]):  # a wrong stretch goal: told, not scored
        assert score == max_score
    else:
        assert score < max_score


@pytest.mark.parametrize("exercise, case", REJECTED, ids=[f"{e}-{c}" for e, c in REJECTED])
def test_wrong_submission_is_told_its_mistake(graded, exercise, case):
    """A wrong submission's feedback names its mistake in words, not only that a number is off by so much."""
    tests = _tests(graded, exercise, case)
    named = [(test, phrase) for test, phrase in exercise_corpus.diagnoses(CASES[exercise][case])
             if not tests[test]["passed"] and exercise_corpus.names_a_mistake(phrase, tests[test]["reason"])]
    assert named, {test: tests[test]["reason"] for test in CASES[exercise][case]["fails"]}


_NUMBER = r"(-?\d+(?:\.\d+)?)"


@pytest.mark.parametrize("exercise", EXERCISES)
def test_figures_and_messages_show_the_same_numbers(graded, exercise):
    """A failed test's figure labels the student's curve with the order its message gives, never another one."""
    disagree = {}
    for student, (ex, case) in graded["students"].items():
        if ex != exercise:
            continue
        for test in _tests(graded, exercise, case).values():
            said = [float(x) for x in re.findall(rf"(?:with order|returned) {_NUMBER}", test["reason"])]
            figures = test.get("figures", []) if not test["passed"] else []
            for figure in figures[-1:]:  # the figure attached just before the check that failed
                for series in figure["series"]:
                    shown = [float(x) for x in re.findall(rf"slope {_NUMBER}", series["label"])[:1]]
                    if said and shown and series["label"].startswith("yours") \
                            and not any(abs(a - b) <= 0.006 for a in said for b in shown):
                        disagree[f"{case}: {test['test']}"] = (series["label"], test["reason"][:200])
    assert not disagree, disagree


@pytest.mark.parametrize("reason, shown", [
    ("expected 102 particles, got 101", ["102"]),
    ("n=102, h=0.25", ["102"]),
    ("a step of -102.00 s", ["102.00"]),
    ("took 1102 steps; 102.5 m; 3.102 m", []),  # inside longer numbers
    ("fails its tripwires: /tmp/ci102/particles/integrators/steppers.py", []),  # a folder of the checkout
    ("the variable x102 is unset", []),  # a name
])
def test_a_drawn_number_is_shown_on_its_own_not_inside_a_number_word_or_path(reason, shown):
    """The leak detector finds a draw standing on its own, and not digits of a longer number, a name or a path."""
    assert exercise_corpus.shown_numbers(reason, {"scalars": [102.0], "arrays": []}) == shown


@pytest.mark.parametrize("exercise", EXERCISES)
def test_hidden_messages_never_show_random_parameters(graded, exercise):
    """No failure message of a hidden test shows a number its random generator drew, in any usual format."""
    checked, shown = 0, {}
    for student, (ex, case) in graded["students"].items():
        if ex != exercise:
            continue
        for test in _tests(graded, exercise, case).values():
            if test["hidden"] and not test["passed"]:
                record = graded["draws"][(student, test["test"])]
                checked += 1
                numbers = exercise_corpus.shown_numbers(test["reason"], record)
                if numbers:
                    shown[f"{case}: {test['test']}"] = (numbers, test["reason"])
    assert checked >= 3, "too few failing hidden tests to check"
    assert not shown, shown


@pytest.mark.parametrize("exercise, case", REJECTED, ids=[f"{e}-{c}" for e, c in REJECTED])
def test_wrong_submission_is_told_the_mistake_and_the_function_that_holds_it(graded, exercise, case):
    """Every failing test names the function that holds the mistake (its `culprit`), also downstream of it,
    and one of them names the mistake in words."""
    tests = _tests(graded, exercise, case)
    spec = CASES[exercise][case]
    culprits = [spec["culprit"]] if isinstance(spec["culprit"], str) else spec["culprit"]  # a list: several wrong
    failed = {test: t["reason"] for test, t in tests.items() if not t["passed"]}
    assert failed
    def names(reason, seen=()):
        """The reason names a culprit, or blames a helper (fix `A` first) whose own failures name one."""
        if any(re.search(rf"\b{re.escape(c)}\b", reason) for c in culprits):
            return True
        blamed = re.match(r"`\w+` calls `(\w+)`.*?, which fails its own tests: fix `\w+` first", reason)
        helper = blamed.group(1) if blamed else None
        return bool(helper) and helper not in seen and any(
            names(r, seen + (helper,)) for t, r in failed.items() if tests[t].get("function") == helper)

    silent = {test: reason for test, reason in failed.items() if not names(reason)}
    assert not silent, f"these failures do not name {' or '.join(culprits)}: {silent}"
    named = [(test, phrase) for test, phrase in exercise_corpus.diagnoses(spec)
             if test in failed and exercise_corpus.names_a_mistake(phrase, failed[test])]
    assert named, failed


@pytest.mark.parametrize("exercise", EXERCISES)
def test_each_exercise_has_eight_typical_mistakes_with_their_culprits(exercise):
    """Every exercise's corpus holds at least eight wrong submissions, each naming the function at fault."""
    (module,) = [m for m in MODULES if m.EXERCISE == exercise]
    assert len(module.REJECTED) >= 8
    for name, case in module.REJECTED.items():
        culprits = [case["culprit"]] if isinstance(case.get("culprit"), str) else case.get("culprit") or []
        assert culprits and all(isinstance(c, str) and c for c in culprits), f"{name} has no culprit"
        for c in culprits:
            assert f"def {c}(" in exercise_corpus.master_code(exercise), f"{name}: the master defines no {c}"


def _label(test):
    """The label of an optional test: a record's property, or the key its JSON data has."""
    return test.label if hasattr(test, "label") else test["label"]


@pytest.mark.parametrize("exercise, case", CORRECT, ids=[f"{e}-{c}" for e, c in CORRECT])
def test_correct_variant_scores_full_marks(graded, exercise, case):
    """Correct code written differently from the master scores full marks; a stretch goal left undone fails
    only its own tests, labelled and not scored."""
    tests = _tests(graded, exercise, case)
    required = {k: t for k, t in tests.items() if not t.get("optional")}
    assert all(t["passed"] for t in required.values()), \
        {k: t["reason"] for k, t in required.items() if not t["passed"]}
    score, max_score = score_of(list(tests.values()))
    assert score == max_score > 0
    for test, piece in CASES[exercise][case].get("optional_fail", {}).items():
        assert tests[test]["optional"] and not tests[test]["passed"], test
        assert piece in tests[test]["reason"], tests[test]["reason"]
        assert _label(tests[test]) == "stretch goal, not scored"


@pytest.mark.parametrize("exercise", EXERCISES)
def test_optional_tests_are_marked_and_not_scored(graded, exercise):
    """A stretch goal's tests carry `optional` and their label in the master's record, and count for no score."""
    tests = list(_tests(graded, exercise, "master").values())
    optional = [t for t in tests if t.get("optional")]
    assert all(_label(t) == "stretch goal, not scored" for t in optional)
    assert score_of(tests)[1] == sum(t["points"] for t in tests if not t.get("optional"))
    if exercise == "01_integrator_order":
        assert sorted(t["test"] for t in optional) == sorted(
            f"{name}[rk4]" for name in ("test_step_circle", "test_step_driven_particles", "test_step_random",
                                        "test_measured_order_circle", "test_measured_order_random",
                                        "test_measured_order_coarse_steps"))


@pytest.mark.parametrize("exercise", EXERCISES)
def test_every_test_has_its_own_name(graded, exercise):
    """The names students see (feedback, Gradescope) are distinct, parametrized tests saying their case."""
    names = [t["name"] for t in _tests(graded, exercise, "master").values()]
    assert len(set(names)) == len(names), sorted(n for n in names if names.count(n) > 1)
    assert not [n for n in names if "__job" in n], "the batch parameter leaked into a test name"


@pytest.mark.parametrize("exercise", EXERCISES)
def test_written_answers_are_counted_for_the_instructor(graded, exercise):
    """The record says how many written answers were filled in: all in the master, none in the stub."""
    (master,) = graded["summary"]["students"][f"{exercise}__master"]
    (stub,) = graded["summary"]["students"][f"{exercise}__released_stub"]
    asked = stub["written_answers"]["asked"]
    assert asked >= 1
    assert master["written_answers"] == {"asked": asked, "answered": asked, "blank": []}
    assert stub["written_answers"] == {"asked": asked, "answered": 0, "blank": list(range(1, asked + 1))}
    assert any(f"Written answers: 0 of {asked} filled in" in note for note in stub["notes"])
