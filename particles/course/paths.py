"""Where the course's folders are: the project root and its exercise files."""

import os
from pathlib import Path

__all__ = ["project_root", "exercise_tests", "exercise_names"]


def _is_root(folder):
    return (folder / "tests" / "exercises").is_dir() or (folder / "solutions").is_dir()


def project_root(start=None):
    """The course project folder (it holds ``tests/exercises/`` or ``solutions/``).

    Looks at ``$PARTICLES_COURSE_ROOT``, then `start` (default: the current
    directory) and its parents, then the folder above the installed
    ``particles`` package (an editable install or a student bundle).

    Raises
    ------
    ValueError
        When no such folder is found.
    """
    if os.environ.get("PARTICLES_COURSE_ROOT"):
        return Path(os.environ["PARTICLES_COURSE_ROOT"]).resolve()
    here = Path(start or os.getcwd()).resolve()
    for folder in [here, *here.parents]:
        if _is_root(folder):
            return folder
    package_parent = Path(__file__).resolve().parents[2]
    if _is_root(package_parent):
        return package_parent
    raise ValueError(
        f"cannot find the course folder (with tests/exercises/ or solutions/) from {here}; "
        "run from inside it or set PARTICLES_COURSE_ROOT"
    )


def exercise_tests(root):
    """Test files ``tests/exercises/test_NN_topic.py`` by exercise name ``NN_topic``."""
    folder = Path(root) / "tests" / "exercises"
    return {p.stem[len("test_"):]: p for p in sorted(folder.glob("test_*.py"))}


def exercise_names(root):
    """Names of the exercises that have tests, in order."""
    return list(exercise_tests(root))
