"""A record's tests version: it changes with the exercise's tests, the helpers they import and the library."""

import shutil
from pathlib import Path

import pytest

from particles.course.grading import versions
from particles.course.grading.versions import library_digest

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture
def course(tmp_path):
    """A course folder with two exercises' tests, one importing a helper module of tests/exercises."""
    folder = tmp_path / "tests" / "exercises"
    folder.mkdir(parents=True)
    (tmp_path / "tests" / "conftest.py").write_text("# top\n")
    (folder / "conftest.py").write_text("# fixtures\n")
    (folder / "helpers.py").write_text("import shared\nLIMIT = 1\n")
    (folder / "shared.py").write_text("X = 1\n")
    (folder / "test_00_a.py").write_text("from helpers import LIMIT\nimport numpy\n\ndef test_a():\n    pass\n")
    (folder / "test_01_b.py").write_text("def test_b():\n    pass\n")
    return tmp_path


def test_the_files_of_an_exercise_are_its_module_its_conftests_and_local_imports(course):
    """conftest.py files, the test module, then the tests/exercises modules it imports, through each other."""
    names = [p.relative_to(course).as_posix() for p in versions.tests_files(course, "00_a")]
    assert names == ["tests/conftest.py", "tests/exercises/conftest.py", "tests/exercises/test_00_a.py",
                     "tests/exercises/helpers.py", "tests/exercises/shared.py"]
    assert [p.name for p in versions.tests_files(course, "01_b")] == ["conftest.py", "conftest.py", "test_01_b.py"]
    with pytest.raises(ValueError, match="no tests for exercise '02_c'"):
        versions.tests_files(course, "02_c")


def test_a_changed_test_changes_the_version_of_what_it_affects_only(course):
    """Editing exercise a's helper changes a's version, not b's; a conftest changes both; so does the library."""
    before = {name: versions.tests_version(course, name, library="L") for name in ("00_a", "01_b")}
    assert before["00_a"].startswith("tests=") and before["00_a"].endswith(" library=L")
    assert versions.tests_version(course, "00_a", library="L") == before["00_a"]  # deterministic
    (course / "tests" / "exercises" / "shared.py").write_text("X = 2\n")
    after = {name: versions.tests_version(course, name, library="L") for name in ("00_a", "01_b")}
    assert after["00_a"] != before["00_a"] and after["01_b"] == before["01_b"]
    (course / "tests" / "exercises" / "conftest.py").write_text("# other fixtures\n")
    assert all(versions.tests_version(course, n, library="L") != after[n] for n in after)
    assert versions.tests_version(course, "01_b", library="M") != versions.tests_version(course, "01_b", library="L")


def test_the_library_digest_follows_its_sources_not_its_bytecode(tmp_path):
    """A changed source file changes the digest; a new __pycache__ does not."""
    package = tmp_path / "particles"
    shutil.copytree(ROOT / "particles" / "course" / "results", package, ignore=shutil.ignore_patterns("__pycache__"))
    first = library_digest(package)
    assert first.startswith("unknown+")  # that copy has no __init__.py assigning __version__
    (package / "__pycache__").mkdir()
    (package / "__pycache__" / "records.cpython-311.pyc").write_bytes(b"x")
    assert library_digest(package) == first
    (package / "records.py").write_text((package / "records.py").read_text() + "\n# edited\n")
    assert library_digest(package) != first


def test_the_course_exercises_have_versions():
    """Every exercise of this course has a version (its test module exists and parses)."""
    found = {p.stem[5:]: versions.tests_version(ROOT, p.stem[5:]) for p in (ROOT / "tests" / "exercises").glob("test_*.py")}
    assert len(set(found.values())) == len(found) >= 6


def test_a_spurious_recursion_depth_error_of_the_parser_is_tried_again(course, monkeypatch):
    """CPython 3.11's parser can fail spuriously when two threads parse at once (its issue 106905): the version is
    taken all the same; any other SystemError of the parser still raises."""
    expected = versions.tests_version(course, "00_a", "L")
    real, calls = versions.ast.parse, []

    def flaky(source, filename="<unknown>", message="AST constructor recursion depth mismatch (before=54, after=65)"):
        calls.append(filename)
        if len(calls) == 1:
            raise SystemError(message)
        return real(source, filename=filename)

    monkeypatch.setattr(versions.ast, "parse", flaky)
    assert versions.tests_version(course, "00_a", "L") == expected and len(calls) > 2
    calls.clear()
    monkeypatch.setattr(versions.ast, "parse", lambda *a, **k: flaky(*a, **k, message="another fault"))
    with pytest.raises(SystemError, match="another fault"):
        versions.tests_version(course, "00_a", "L")
