"""Rubrics: people's grades of the written answers, read from CSV files and merged into the records.

A rubric is a UTF-8 CSV file (``particles review`` writes one per exercise,
pre-filled: ``DIR/<exercise>/rubric.csv``) with the header::

    exercise,student,question,max_points,points,comment

one row per student and question: ``exercise`` is ``NN_topic``, ``student``
the name ``particles grade`` gives the student (the same discovery,
:func:`particles.course.grading.discovery.find_submissions`), ``question`` the
question's number, ``max_points`` what the master says it is worth
(:func:`particles.course.release.answers.question_points`), ``points`` the
grade (a number in ``[0, max_points]``, empty: not graded yet) and
``comment`` what the student reads under it. Blank lines are skipped. A student is
named by any of their names or aliases (:mod:`particles.course.term.identity`), compared as the grader
compares names (case and Unicode forms aside).

``particles grade ... --rubric FILE`` (repeatable; a folder stands for every
``*.csv`` file under it, read per exercise: the rows of the course's exercises
that the run does not grade are left for the run that grades them, as
``particles review`` writes one rubric per exercise) checks every row first and refuses the whole run
(exit status 2, before anything is graded) on: an unknown exercise, student
or question, points that are not a number or fall outside
``[0, max_points]``, a ``max_points`` that disagrees with the master, a row
given twice (in one file or two), a missing or unknown column. Each problem
names its file, its line and what was expected.

The merge (:meth:`WrittenGrades.apply`) runs when the outputs are written,
over every record of the run (those kept by ``--resume`` too), so a changed
rubric changes exactly the records it covers and no test runs again. For
each exercise that a rubric names, every record of it gets one entry per
question in :attr:`~particles.course.results.records.SubmissionRecord.written`:
the row's points and comment; a question without a row, or with empty
points, is "not graded yet" (points None), except a blank answer, which
scores 0 with the comment "no answer". Each entry's ``rubric`` is the file
and its SHA-256 digest (``rubric.csv sha256:0123abcd...``): the version of the
rubric that graded it. Exercises no rubric names are left as they are.
"""

import csv
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

from ..grading.discovery import released_exercise
from ..paths import exercise_tests
from ..release.answers import question_points
from ..term.identity import Identity

__all__ = ["COLUMNS", "NO_ANSWER", "RubricError", "Grade", "rubric_files", "exercise_questions",
           "WrittenGrades"]

COLUMNS = ("exercise", "student", "question", "max_points", "points", "comment")
"""The columns of a rubric file, in the order ``particles review`` writes them."""

NO_ANSWER = "no answer"
"""The comment of a blank answer that no rubric row grades."""


class RubricError(ValueError):
    """One or more rubric rows cannot be used; ``problems`` lists each (file, line, what was expected)."""

    def __init__(self, problems):
        self.problems = list(problems)
        shown = self.problems[:20] + ([f"... and {len(self.problems) - 20} more"] if len(self.problems) > 20 else [])
        super().__init__("the rubric cannot be merged, nothing was graded:\n  " + "\n  ".join(shown))


@dataclass(frozen=True)
class Grade:
    """One row of a rubric, checked.

    Attributes
    ----------
    exercise, student : str
    question : int
    max_points : float
    points : float or None
        None: not graded yet.
    comment : str
    rubric : str
        The file and its digest: the rubric's version.
    where : str
        ``file, line n``.
    """

    exercise: str
    student: str
    question: int
    max_points: float
    points: float | None
    comment: str
    rubric: str
    where: str


def rubric_files(paths):
    """The rubric files of `paths`: files as given, folders as the ``*.csv`` files under them (sorted).

    Raises
    ------
    RubricError
        When a path does not exist or a folder holds no CSV file.
    """
    files, problems = [], []
    for given in map(Path, paths):
        if given.is_file():
            files.append(given)
        elif given.is_dir():
            found = sorted(p for p in given.rglob("*.csv") if p.is_file())
            if not found:
                problems.append(f"{given}: a folder without any rubric (*.csv) file")
            files += found
        else:
            problems.append(f"{given}: no such rubric file or folder")
    if problems:
        raise RubricError(problems)
    return files


def exercise_questions(root, exercise):
    """The written questions of `exercise` and their points, ``{k: points}`` ({} when it has none).

    Read from the master, or the released notebook when there is no master
    (:func:`particles.course.grading.discovery.released_exercise`).
    """
    released = released_exercise(root, exercise)
    return {} if released is None else question_points(released)


def _number(text):
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _fmt(x):
    return f"{x:g}"


def _version(path):
    return f"{path} sha256:{hashlib.sha256(path.read_bytes()).hexdigest()[:16]}"


def _read(path, questions, students, seen, problems, others=()):
    """The checked :class:`Grade` s of one file; what is wrong goes to `problems` (``seen``: rows so far).

    Rows of the exercises `others` (of the course, not graded in this run) are skipped: a folder of rubrics is
    read per exercise.
    """
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except (OSError, UnicodeDecodeError) as error:
        problems.append(f"{path}: cannot be read as UTF-8 text ({error})")
        return []
    version = _version(path)
    rows = csv.reader(text.splitlines())
    header = next(rows, None)
    if header is None:
        problems.append(f"{path}, line 1: empty file; expected the header {','.join(COLUMNS)}")
        return []
    header = [h.strip() for h in header]
    missing = [c for c in COLUMNS if c not in header]
    unknown = [h for h in header if h not in COLUMNS]
    if missing or unknown or len(set(header)) != len(header):
        problems.append(f"{path}, line 1: the header is {','.join(header)!r}; expected the columns "
                        f"{','.join(COLUMNS)}" + (f" (missing {', '.join(missing)})" if missing else "")
                        + (f" (unknown {', '.join(unknown)})" if unknown else ""))
        return []
    grades = []
    for line, row in enumerate(rows, start=2):
        if not any(cell.strip() for cell in row):
            continue
        where = f"{path}, line {line}"
        if len(row) != len(header):
            problems.append(f"{where}: {len(row)} fields; expected {len(header)} ({','.join(header)})")
            continue
        cell = {name: value.strip() for name, value in zip(header, row)}
        exercise, student = cell["exercise"], cell["student"]
        if exercise in others and exercise not in questions:
            continue
        if exercise not in questions:
            problems.append(f"{where}: unknown exercise {exercise!r}; expected one of "
                            f"{', '.join(sorted(questions)) or '(none graded here)'}")
            continue
        asked = questions[exercise]
        person = students.find(student)
        if person is None:
            names = sorted(students.people)
            shown = ", ".join(names[:5]) + (", ..." if len(names) > 5 else "")
            problems.append(f"{where}: unknown student {student!r}; expected one of {students.describe()} "
                            f"({shown or 'none'}) or one of their aliases")
            continue
        student = person.name
        k = cell["question"]
        if not k.isdigit() or int(k) not in asked:
            problems.append(f"{where}: unknown question {k!r} of {exercise}; expected one of "
                            f"{', '.join(map(str, sorted(asked))) or '(it has no written question)'}")
            continue
        k, bad = int(k), False
        top = _number(cell["max_points"])
        if top != asked[k]:
            problems.append(f"{where}: max_points {cell['max_points']!r} disagrees with the master: question {k} "
                            f"of {exercise} is worth {_fmt(asked[k])} points")
            bad = True
        points = None
        if cell["points"]:
            points = _number(cell["points"])
            if points is None:
                problems.append(f"{where}: points {cell['points']!r} is not a number; expected a number in "
                                f"[0, {_fmt(asked[k])}], or nothing while not graded")
                bad = True
            elif not 0 <= points <= asked[k]:
                problems.append(f"{where}: points {cell['points']} outside [0, {_fmt(asked[k])}] "
                                f"(question {k} of {exercise} is worth {_fmt(asked[k])} points)")
                bad = True
        key = (exercise, student, k)
        if key in seen:
            problems.append(f"{where}: {student}'s question {k} of {exercise} is graded twice (also {seen[key]}); "
                            "expected one row per student and question")
            continue
        seen[key] = where
        if not bad:
            grades.append(Grade(exercise, student, k, asked[k], points, cell["comment"], version, where))
    return grades


class WrittenGrades:
    """The rubrics of one grading run, checked against its submissions; merged into its records.

    Parameters
    ----------
    grades : list of Grade
    versions : dict
        exercise -> the versions of the rubric files that name it.
    questions : dict
        exercise -> ``{k: points}`` of every exercise of the run (for Gradescope's manual questions too).
    """

    def __init__(self, grades=(), versions=None, questions=None):
        self.grades = {(g.exercise, g.student, g.question): g for g in grades}
        if versions is None:  # the rubric files that named each exercise
            versions = {}
            for g in grades:
                if g.rubric not in versions.setdefault(g.exercise, []):
                    versions[g.exercise].append(g.rubric)
        self.versions = dict(versions)
        self.questions = dict(questions or {})

    @classmethod
    def load(cls, paths, units, root, exercises=(), identity=None):
        """Read and check the rubric files `paths` against the course's students.

        Parameters
        ----------
        paths : sequence of path
            Rubric files, or folders of them (may be empty: nothing is merged).
        units : list of Unit
            The run's notebooks (:func:`particles.course.grading.discovery.find_submissions`).
        root : path
            The course folder (the masters say what each question is worth).
        exercises : sequence of str
            More exercises whose questions to know (``--exercise`` when no notebook was found, the course's
            other exercises).
        identity : particles.course.term.identity.Identity, optional
            Who is in the course: a row's student is any name or alias of one of its students, written down as
            their grader name (default: the students of `units`, names compared as the grader compares them).

        Raises
        ------
        RubricError
            Listing every problem of every file (a ``ValueError``).
        """
        exercises = sorted({u.exercise for u in units} | set(exercises))
        questions = {name: exercise_questions(root, name) for name in exercises}
        if identity is None:
            identity = Identity()
            for unit in units:
                identity.admit(unit.student)
        grades, problems, seen = [], [], {}
        named = {Path(p).resolve() for p in paths or () if Path(p).is_file()}
        course = set(exercise_tests(root))  # a folder's rubrics of the course's other exercises: not this run's
        for path in rubric_files(paths or ()):
            others = () if path.resolve() in named else course
            grades += _read(path, questions, identity, seen, problems, others)
        if problems:
            raise RubricError(problems)
        return cls(grades, None, questions)

    def covers(self, exercise):
        """Whether a rubric names `exercise` (its records are then graded from the rubrics)."""
        return exercise in self.versions

    def entries(self, record):
        """The ``written`` entries of one record (see the module's docstring for the rules)."""
        blank = set((record.written_answers or {}).get("blank") or [])
        fallback = "; ".join(self.versions.get(record.exercise, []))
        out = []
        for k, top in sorted(self.questions.get(record.exercise, {}).items()):
            grade = self.grades.get((record.exercise, record.student, k))
            entry = {"question": str(k), "points": None, "max_points": top, "comment": "",
                     "rubric": grade.rubric if grade else fallback}
            if grade is not None:
                entry.update(points=grade.points, comment=grade.comment)
            if entry["points"] is None and k in blank:
                entry.update(points=0.0, comment=entry["comment"] or NO_ANSWER)
            out.append(entry)
        return out

    def apply(self, records):
        """Fill ``written`` of every record of an exercise a rubric names (in place); returns how many changed."""
        changed = 0
        for record in records:
            if self.covers(record.exercise):
                entries = self.entries(record)
                changed += entries != record.written
                record.written = entries
        return changed

    def manual(self):
        """exercise -> ``{k: points}`` of its written questions: what Gradescope grades by hand."""
        return {name: q for name, q in self.questions.items() if q}
