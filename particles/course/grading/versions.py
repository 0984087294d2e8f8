"""Which version of the tests graded a record: a digest of everything that judges an exercise.

A record's ``tests_version`` (see :class:`~particles.course.results.records.SubmissionRecord`) is
``tests=<digest> library=<version>+<digest>``:

* ``tests``: SHA-256 (first 12 hex digits) of the exercise's test module
  ``tests/exercises/test_NN_topic.py``, of every ``conftest.py`` pytest loads for it (``tests/`` and
  ``tests/exercises/``), and of the modules of ``tests/exercises/`` it imports (``import helpers``,
  ``from helpers import ...``; followed through their own imports);
* ``library``: the reference library's ``particles.__version__`` and SHA-256 (first 12 hex digits)
  of its source files (every file of the installed ``particles`` package but bytecode): the tests
  compare with the library, so a changed library may change a verdict.

``particles grade --resume`` keeps a record only when its ``tests_version`` is the current one of
its exercise: a changed test module regrades that exercise's notebooks and nothing else; a changed
``conftest.py`` or library regrades everything. Feedback and ``results.json`` say which version
graded each exercise.
"""

import ast
import hashlib
import threading
from pathlib import Path

from ..walls.integrity import library_checksum

__all__ = ["tests_version", "tests_files", "library_digest"]

_DIGITS = 12

_PARSING = threading.RLock()


def _parse(source, filename="<unknown>"):
    """``ast.parse``, one thread at a time, tried again once on CPython's spurious recursion-depth error.

    On CPython 3.11 (3.11.7 here) the syntax-tree builder keeps its recursion depth per interpreter, not per
    thread: two threads parsing at once (the local pool's sessions taking their tests' versions, a cluster
    worker's task beside its event loop) can fail with ``SystemError: AST constructor recursion depth
    mismatch`` (CPython issue 106905) although the source is fine.
    """
    with _PARSING:
        try:
            return ast.parse(source, filename=filename)
        except SystemError as error:
            if "recursion depth mismatch" not in str(error):
                raise
            return ast.parse(source, filename=filename)


def tests_files(root, exercise):
    """The files that define the tests of `exercise`, in a fixed order.

    Parameters
    ----------
    root : path
        The course folder (it holds ``tests/exercises/``).
    exercise : str
        ``NN_topic``.

    Returns
    -------
    list of Path
        The ``conftest.py`` files pytest loads (those that exist), the test module, then the modules of
        ``tests/exercises/`` it imports, directly or through each other.

    Raises
    ------
    ValueError
        When ``tests/exercises/test_<exercise>.py`` does not exist.
    """
    folder = Path(root) / "tests" / "exercises"
    module = folder / f"test_{exercise}.py"
    if not module.is_file():
        raise ValueError(f"no tests for exercise {exercise!r}: {module} does not exist")
    files = [p for p in (folder.parent / "conftest.py", folder / "conftest.py") if p.is_file()]
    todo, seen = [module], set()
    while todo:
        path = todo.pop(0)
        if path in seen:
            continue
        seen.add(path)
        files.append(path)
        todo += [p for p in _local_imports(path, folder) if p not in seen]
    return files


def _local_imports(path, folder):
    """The files of `folder` that the module `path` imports (top-level names only)."""
    try:
        tree = _parse(path.read_bytes(), filename=str(path))
    except (SyntaxError, ValueError):  # a broken test module: its bytes are digested all the same
        return []
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.append(node.module)
    found = []
    for name in names:
        head = name.split(".")[0]
        for candidate in (folder / f"{head}.py", folder / head / "__init__.py"):
            if candidate.is_file() and candidate not in found:
                found.append(candidate)
    return sorted(found)


def library_digest(package=None):
    """``<version>+<digest>`` of the reference library: ``particles.__version__`` and its source files.

    The digest is taken over :func:`~particles.course.walls.integrity.library_checksum` (the same
    walk the driver's integrity check makes), bytecode left out.

    Parameters
    ----------
    package : path, optional
        The package folder (default: the ``particles`` this module belongs to); the version is the
        ``__version__`` its ``__init__.py`` assigns ("unknown" when none).
    """
    package = Path(package) if package is not None else Path(__file__).resolve().parents[2]
    digest = hashlib.sha256()
    for name, value in sorted(library_checksum(package).items()):
        if "__pycache__" not in Path(name).parts and not name.endswith(".pyc"):
            digest.update(f"{name}\0{value}\n".encode())
    return f"{_version(package)}+{digest.hexdigest()[:_DIGITS]}"


def _version(package):
    """``__version__`` as the package's ``__init__.py`` assigns it ("unknown" when it does not)."""
    try:
        tree = _parse((package / "__init__.py").read_bytes())
    except (OSError, SyntaxError, ValueError):
        return "unknown"
    for node in tree.body:
        if (isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__version__" for t in node.targets)
                and isinstance(node.value, ast.Constant)):
            return str(node.value.value)
    return "unknown"


def tests_version(root, exercise, library=None):
    """The ``tests_version`` of a record of `exercise` graded now.

    Parameters
    ----------
    root : path
        The course folder.
    exercise : str
        ``NN_topic``.
    library : str, optional
        :func:`library_digest`, when the caller already has it (it reads every file of the package).

    Returns
    -------
    str
        ``tests=<12 hex digits> library=<version>+<12 hex digits>``.

    Raises
    ------
    ValueError
        When the exercise has no test module.

    Examples
    --------
    >>> tests_version(".", "00_warmup")  # doctest: +SKIP
    'tests=3f9a0c2b71de library=0.1.0+8be0a5c4d2f1'
    """
    root = Path(root)
    digest = hashlib.sha256()
    for path in tests_files(root, exercise):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(hashlib.sha256(path.read_bytes()).digest())
    return f"tests={digest.hexdigest()[:_DIGITS]} library={library or library_digest()}"
