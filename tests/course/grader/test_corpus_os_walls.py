"""The warm-up corpus's attacks graded with the Python walls switched off: the operating system's walls hold alone.

The worker's audit hook gives the clear messages ("read its private files");
the namespaces, the uid of its own, Landlock and the limits must hold without
it (DESIGN.md, the grading model). So the attacks of the corpus (and, as a
control, correct submissions) are graded again with ``audit_hook=False``,
under the strongest walls this machine allows: every test an attack must fail
still fails, with the operating system's error in place of the hook's
message, and correct notebooks keep full marks.
"""

import shutil
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
import corpus  # noqa: E402

from particles.course.grading.driver import grade  # noqa: E402

SEED = 20240611

# attacks on the grader, and the submissions that test a limit: a wall, not a rule of the exercise, stops them
ATTACKS = ["reads_the_solution_file", "spies_on_the_grader_process", "writes_a_fake_results_json",
           "disables_the_audit_hook_and_forges_the_records", "disables_the_audit_hook_and_reads_the_master",
           "finds_the_hook_with_gc", "takes_the_original_from_the_tripwires",
           "loads_the_library_with_a_loader_of_its_own", "monkeypatches_builtins", "monkeypatches_numpy_checks",
           "prints_a_passing_results_line", "huge_allocation", "infinite_loop", "crashes_the_interpreter",
           "calls_os_exit"]

# not graded here: imports_the_library_past_the_tripwires breaks a rule of the exercise (do not call the
# library's stepper) that only the Python walls can see; the library is public (mounted read-only in every
# sandbox), so loading it is no escape, and without the hook that submission passes the test it should fail

CONTROLS = ["master", "lambda_stepper", "own_integrate_shadows_the_library_import"]


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("os-walls")
    keep = set(ATTACKS) | set(CONTROLS)
    for name in corpus.write_corpus(tmp / "submissions"):
        if name not in keep:
            shutil.rmtree(tmp / "submissions" / name)
    summary = grade([tmp / "submissions"], tmp / "out", jobs=2, seed=SEED, time_limit=2.0, root=corpus.ROOT,
                    audit_hook=False)
    return summary


def _result(graded, name):
    (result,) = graded["students"][name]
    return result


def test_the_hook_was_off_and_the_os_walls_on(graded):
    """Every record says the audit hook was off, and names the operating system's walls that were on."""
    for name in graded["students"]:
        result = _result(graded, name)
        assert result.isolation.get("audit_hook") is False, name
        assert "no audit hook" in result.sandbox
        assert any(layer in result.sandbox for layer in ("namespaces", "Landlock", "uid")), result.sandbox


@pytest.mark.parametrize("name", ATTACKS)
def test_an_attack_fails_without_the_hook(graded, name):
    """Each test the attack must fail still fails (the walls, not the hook, stop it), with a one-line reason."""
    tests = {t.test: t for t in _result(graded, name).tests}
    for test in corpus.REJECTED[name]["fails"]:
        assert not tests[test].passed, f"{name}: {test} passed without the audit hook"
        assert tests[test].reason and "\n" not in tests[test].reason
        assert not tests[test].grader_error, tests[test].reason


def test_reading_the_master_meets_the_mount_namespace_or_landlock(graded):
    """Without the hook, reading the master or the grader's /proc fails with the system's own error."""
    for name in ("reads_the_solution_file", "disables_the_audit_hook_and_reads_the_master",
                 "spies_on_the_grader_process"):
        reasons = " ".join(t.reason for t in _result(graded, name).tests if not t.passed)
        assert any(error in reasons for error in ("FileNotFoundError", "PermissionError", "ProcessLookupError")), \
            (name, reasons)


@pytest.mark.parametrize("name", CONTROLS)
def test_correct_notebooks_keep_full_marks(graded, name):
    """Correct notebooks score full marks without the hook too."""
    result = _result(graded, name)
    assert result.score == result.max_score == 11, [t.reason for t in result.tests if not t.passed]
