"""What students read of a record: the instructor's folders taken out of every text.

A record keeps where its notebook was (``/home/prof/course/subs/alice/00_warmup.ipynb``), and the grader's messages
may name files of the course (a test module, the library) by their full path. Students read the feedback files,
Gradescope's output and the LMS feedback: those show only the last part of each path, the name the student knows
(:func:`for_students`), and the graded notebook by its own name (:func:`submitted_name`).
"""

import re

__all__ = ["for_students", "submitted_name", "posix"]

# an absolute path: "/" (not inside a word, a URL or a relative path), folders, then the last part
_POSIX = re.compile(r"(?<![\w.~:/\\-])/(?:[^\s/:`'\"()\[\]<>|,;]+/)+([^\s/`'\"()\[\]<>|,;]*)")
_WINDOWS = re.compile(r"(?<![\w])[A-Za-z]:\\(?:[^\s\\:`'\"()\[\]<>|,;]+\\)+([^\s\\`'\"()\[\]<>|,;]*)")


def for_students(text):
    """`text` with every absolute path cut to its last part (``/srv/course/subs/a/x.ipynb`` -> ``x.ipynb``).

    Examples
    --------
    >>> for_students("read /home/prof/subs/alice/00_warmup.ipynb (see https://example.org/a/b)")
    'read 00_warmup.ipynb (see https://example.org/a/b)'
    >>> for_students("m/s and 1/2 stay")
    'm/s and 1/2 stay'
    """
    text = _POSIX.sub(lambda m: m.group(1), str(text))
    return _WINDOWS.sub(lambda m: m.group(1), text)


def posix(path):
    """A record's path with ``/`` between its parts: a Windows path's ``\\`` turned to ``/`` (a POSIX path, which
    holds a ``/``, keeps its backslashes: they may be part of a name)."""
    text = str(path)
    return text if "/" in text or not re.match(r"^([A-Za-z]:)?\\", text) else text.replace("\\", "/")


def submitted_name(notebook):
    """The graded notebook's own name: the last part of a record's ``notebook`` (a path, or ``zip:member``)."""
    tail = posix(notebook).rsplit(".zip:", 1)[-1]
    return tail.rstrip("/").rsplit("/", 1)[-1]
