"""Every name an exercise forbids is one the library has: a stale name would forbid nothing, silently."""

import importlib.util
from pathlib import Path

import pytest

from particles.course.reading.forbidden import _resolve_object

EXERCISE_TESTS = sorted((Path(__file__).resolve().parents[2] / "exercises").glob("test_[0-9][0-9]_*.py"))


def _forbidden(path):
    spec = importlib.util.spec_from_file_location(f"forbidden_of_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return getattr(module, "FORBIDDEN", {})


def test_the_exercises_are_found():
    """The exercises' test files are found where the graders keep them (a wrong path would check nothing)."""
    assert len(EXERCISE_TESTS) >= 8


@pytest.mark.parametrize("path", EXERCISE_TESTS, ids=lambda p: p.stem)
def test_every_forbidden_name_resolves_to_a_library_object(path):
    """Each name in an exercise's FORBIDDEN resolves, as the grader resolves it, to an object of the library."""
    stale = [name for name in _forbidden(path) if _resolve_object(name) is None]
    assert not stale, f"{path.name} forbids names the library does not have: {stale}"
