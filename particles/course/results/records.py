"""The records of a grading run, defined once: one per test, one per graded notebook.

Three processes hand records on (see :mod:`particles.course.grading.driver`):

1. the pytest session (:mod:`particles.course.grading.plugin`) makes a
   :class:`TestRecord` per test and a :class:`SessionRecord` per notebook, and
   writes them as JSON (signed, :mod:`particles.course.results.signing`);
2. the driver reads them back with :meth:`SessionRecord.from_dict` and
   completes each into a :class:`SubmissionRecord` (student, notes for the
   student, the sandbox's layers, the notebook's digest);
3. the reports (:mod:`particles.course.results.reports`) and the course record
   (:mod:`particles.course.term.database`) read only these classes.

Every record converts to plain JSON data with ``to_dict()`` and back with
``from_dict()``, which rejects a missing or mistyped field by name. For
reading, a record also behaves as a read-only mapping of its fields
(``record["passed"]`` is ``record.passed``), so that scripts written for the
JSON files keep working; code in the package uses the attributes.
:meth:`SubmissionRecord.to_gradescope` and :func:`to_gradescope` make
Gradescope's ``results.json`` (its specification:
https://gradescope-autograders.readthedocs.io/en/latest/specs/).
"""

import dataclasses
import html
from collections.abc import Mapping
from dataclasses import dataclass, field

from .shown import for_students

__all__ = ["TestRecord", "SessionRecord", "SubmissionRecord", "score_of", "to_gradescope", "VISIBILITIES",
           "STRETCH_GOAL"]

VISIBILITIES = ("hidden", "after_due_date", "after_published", "visible")
"""Gradescope's visibility settings of a test."""

STRETCH_GOAL = "stretch goal, not scored"
"""The label of an optional test (``@pytest.mark.optional``) wherever it is shown."""


class _Fields(Mapping):
    """Read-only mapping access to a dataclass's fields (``record["name"]``, ``dict(record)``)."""

    def __getitem__(self, key):
        if key not in self._names():
            raise KeyError(key)
        return getattr(self, key)

    def __iter__(self):
        return iter(self._names())

    def __len__(self):
        return len(self._names())

    @classmethod
    def _names(cls):
        return [f.name for f in dataclasses.fields(cls)]

    @classmethod
    def _take(cls, data, what):
        """The keyword arguments of `cls` from the dict `data`, with a clear error on what is missing."""
        if not isinstance(data, Mapping):
            raise TypeError(f"{what} must be a dict, got {type(data).__name__}")
        fields = {f.name: f for f in dataclasses.fields(cls)}
        required = [name for name, f in fields.items() if f.default is dataclasses.MISSING
                    and f.default_factory is dataclasses.MISSING]
        missing = [name for name in required if name not in data]
        if missing:
            raise ValueError(f"{what} has no {', '.join(map(repr, missing))}")
        return {name: data[name] for name in fields if name in data}


@dataclass(eq=True)
class TestRecord(_Fields):
    """The result of one test of one notebook.

    Attributes
    ----------
    test : str
        The test's key: its function name and parameters (``test_order[rk4]``).
    name : str
        What it checks, in words (the first line of its docstring).
    points : float
    hidden : bool
        Hidden tests are not shown before grades are published.
    passed : bool
    reason : str
        Why it failed, for the student ("" when it passed).
    grader_error : bool
        The failure is the grader's fault, not the submission's.
    seconds : float
    seed : int or None
        The grading seed, when the test drew random parameters.
    figures : list of dict
        Curves to draw beside the reference's (:mod:`particles.course.grading.figures`).
    optional : bool
        A stretch goal (``@pytest.mark.optional``): shown with :data:`STRETCH_GOAL`, never scored.
    function : str
        The student's function the test judges ("" when unknown): the grader's blame of a failure
        on a helper of it that fails its own tests is worded with it.
    """

    __test__ = False  # not a pytest test class, whatever its name

    test: str
    name: str
    points: float = 1.0
    hidden: bool = False
    passed: bool = False
    reason: str = ""
    grader_error: bool = False
    seconds: float = 0.0
    seed: int | None = None
    figures: list = field(default_factory=list)
    optional: bool = False
    function: str = ""

    @property
    def score(self):
        """The points earned: all of them or none (an optional test earns none: it is not scored)."""
        return self.points if self.passed and not self.optional else 0.0

    @property
    def max_score(self):
        """The points the test counts for: its points, 0 for an optional test."""
        return 0.0 if self.optional else self.points

    @property
    def label(self):
        """:data:`STRETCH_GOAL` for an optional test, else ""."""
        return STRETCH_GOAL if self.optional else ""

    @property
    def title(self):
        """The name as shown: with ``(stretch goal, not scored)`` for an optional test."""
        return f"{self.name} ({self.label})" if self.optional else self.name

    def failed(self, reason):
        """This test as failed for `reason` (a copy; the record itself is unchanged)."""
        return dataclasses.replace(self, passed=False, reason=reason, seed=None)

    def to_dict(self):
        """The record as JSON data (``figures`` only when there are some, ``label`` with ``optional``)."""
        data = dataclasses.asdict(self)
        if not self.figures:
            del data["figures"]
        if self.optional:
            data["label"] = self.label
        return data

    @classmethod
    def from_dict(cls, data):
        """The record of JSON data as :meth:`to_dict` writes it."""
        kwargs = cls._take(data, "a test record")
        kwargs["points"] = float(kwargs.get("points", 1.0))
        return cls(**kwargs)

    def output(self):
        """What the student reads under the test: "passed", or the reason (with the seed of hidden tests), no path
        of the instructor's in it (:func:`~particles.course.results.shown.for_students`)."""
        text = "passed" if self.passed else for_students(self.reason)
        if self.hidden and self.seed is not None:
            text += f" (random parameters, seed {self.seed})"
        return text

    def to_gradescope(self, exercise, number, hidden_visibility="after_published"):
        """This test as one entry of Gradescope's ``tests`` list.

        Parameters
        ----------
        exercise : str
            ``NN_topic``: prefixes the name and tags the entry.
        number : str
            Gradescope's test number (``"02.3"``).
        hidden_visibility : str
            The visibility of a hidden test, one of :data:`VISIBILITIES`.
        """
        output, output_format = self.output(), "text"
        if self.figures:  # the student's curve beside the reference's, inline
            from ..grading import figures  # Matplotlib: only when there is something to draw

            output = (f"<p>{html.escape(output)}</p>"
                      + "".join(figures.figure_html(f, css=False) for f in self.figures))
            output_format = "html"
        return {
            "name": f"{exercise}: {self.title}",
            "number": number,
            "score": self.score,
            "max_score": self.max_score,
            "status": "passed" if self.passed else "failed",
            "output": output,
            "output_format": output_format,
            "visibility": hidden_visibility if self.hidden else "visible",
            "tags": [exercise] + (["hidden"] if self.hidden else []) + (["stretch goal"] if self.optional else []),
            "extra_data": dict({"test": self.test}, **({"optional": True, "label": self.label} if self.optional
                                                       else {})),
        }


def score_of(tests):
    """(score, max_score) of a list of test records (records or their JSON data): optional tests count for neither."""
    tests = [t for t in tests if not t.get("optional", False)]
    return (sum(t["points"] for t in tests if t["passed"]), sum(t["points"] for t in tests))


def _tests(items):
    return [t if isinstance(t, TestRecord) else TestRecord.from_dict(t) for t in items]


class _HoldsTests(_Fields):
    """A record with a list of :class:`TestRecord` in ``tests``: JSON data and back, the tests typed again."""

    _what = "a record"

    def to_dict(self):
        """The record as JSON data."""
        data = dataclasses.asdict(self)
        data["tests"] = [t.to_dict() for t in self.tests]
        return data

    @classmethod
    def from_dict(cls, data):
        """The record of JSON data as :meth:`to_dict` writes it (a missing field is named)."""
        kwargs = cls._take(data, cls._what)
        kwargs["tests"] = _tests(kwargs.get("tests", []))
        return cls(**kwargs)


@dataclass
class SessionRecord(_HoldsTests):
    """What one pytest session reports about one notebook it graded (written by the plugin).

    Attributes
    ----------
    id : str
        The notebook's job in the session's batch.
    seed : int
        Its grading seed.
    exercise, submission : str
    tests : list of TestRecord
    restarts : int
        Workers started for it (1 when none was restarted).
    load_errors : list of dict
        Errors raised while its definitions were loaded (``label``, ``type``, ``message``, ``where``).
    skipped : list of dict
        Statements not run and why (``label``, ``line``, ``text``, ``reason``).
    syntax_errors : list of [label, message]
    isolation : dict
        The worker's walls as it reported them.
    seconds : float or None
        Time of the whole notebook; None while it is not finished.
    """

    _what = "a session record"

    id: str
    seed: int
    exercise: str = ""
    submission: str = ""
    tests: list = field(default_factory=list)
    restarts: int = 1
    load_errors: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    syntax_errors: list = field(default_factory=list)
    isolation: dict = field(default_factory=dict)
    seconds: float | None = None

    @property
    def complete(self):
        """True when the session finished the notebook (its fixture closed)."""
        return self.seconds is not None

    def to_dict(self):
        """The record as JSON data (``seconds`` only once the notebook is complete)."""
        data = super().to_dict()
        if self.seconds is None:
            del data["seconds"]
        return data


@dataclass
class SubmissionRecord(_HoldsTests):
    """The grade of one student's notebook of one exercise: what the driver keeps and reports.

    Attributes
    ----------
    student, exercise, notebook : str
    seed : int or None
        The grading seed of its hidden tests.
    seconds : float
    tests : list of TestRecord
        One per test of the exercise (a test that did not run is recorded as failed, saying why).
    notes : list of str
        Lines for the student about loading the notebook (errors, syntax errors, restarts, written answers).
    written_answers : dict or None
        ``asked`` and ``answered`` counts of the written questions.
    grader_status : int or None
        The pytest session's exit status (0 or 1 when it ended normally).
    complete : bool
        The session finished this notebook.
    isolation : dict
        The worker's walls (:func:`particles.course.walls.isolation.describe` says them in words: ``sandbox``).
    sandbox : str
    notebook_sha256 : str
        Digest of the graded file (``--resume`` keeps a record only for the same file).
    resumed : bool
        The record was kept from an earlier run.
    written : list of dict
        The people's grades of the written questions (merged from a rubric): one dict per question,
        ``question`` (str), ``points`` (float or None: not graded yet), ``max_points`` (float),
        ``comment`` (str), ``rubric`` (which rubric file and version).
    late : dict or None
        The late-work decision, None when no deadline applies: ``submitted`` and ``deadline`` (ISO 8601),
        ``days_late`` (int), ``penalty`` (points taken off the total) and ``reason`` (one sentence); also
        ``fraction`` (of the points) and ``source`` (where the submission time came from), see
        :func:`particles.course.grading.deadlines.decide`.
    tests_version : str
        Digest of the exercise's tests that graded this record (a changed test regrades what it affects).
    run : dict or None
        The grading run that made this record, as the course record keeps it: ``id`` and ``started``
        (:mod:`particles.course.term.database`); None for a record no course record holds.
    worker : str
        The machine that graded it, when a grading cluster did (its host, worker name and address; "" on the
        driver's own machine); ``isolation`` says the walls it had.

    Notes
    -----
    The total of a record is ``score + written_score - penalty`` out of ``max_score + written_max``
    (:attr:`total`, :attr:`total_max`): the tests, the people's grades of the written answers, and the
    late penalty. Reports, the gradebook and the LMS exports use these two.
    """

    _what = "a submission record"

    student: str
    exercise: str
    notebook: str = ""
    seed: int | None = None
    seconds: float = 0.0
    tests: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    written_answers: dict | None = None
    grader_status: int | None = None
    complete: bool = False
    isolation: dict = field(default_factory=dict)
    sandbox: str = ""
    notebook_sha256: str = ""
    resumed: bool = False
    written: list = field(default_factory=list)
    late: dict | None = None
    tests_version: str = ""
    run: dict | None = None
    worker: str = ""

    @property
    def score(self):
        """Points of the autograded tests."""
        return score_of(self.tests)[0]

    @property
    def max_score(self):
        """Points the autograded tests can give."""
        return score_of(self.tests)[1]

    @property
    def written_score(self):
        """Points the people gave the written answers (questions not graded yet count 0)."""
        return sum(float(w["points"]) for w in self.written if w.get("points") is not None)

    @property
    def written_max(self):
        """Points the written questions can give."""
        return sum(float(w.get("max_points", 0)) for w in self.written)

    @property
    def penalty(self):
        """Points taken off for late work (0 when on time or no deadline applies)."""
        if not self.late:
            return 0.0
        if self.late.get("fraction") is not None:  # a fraction of the points there are now (written grades too)
            return round(float(self.late["fraction"]) * self.total_max, 6)
        return float(self.late["penalty"])

    @property
    def total(self):
        """The exercise's grade: tests + written answers - late penalty, never below 0."""
        return max(0.0, self.score + self.written_score - self.penalty)

    @property
    def total_max(self):
        """The points the exercise can give: tests and written questions."""
        return self.max_score + self.written_max

    def late_lines(self):
        """Sentences on the late work and the tests version, for the feedback (plain text).

        The late line gives the raw score, the penalty and why, and the total; the last line says
        which version of the tests graded the record (:mod:`particles.course.grading.versions`).
        """
        lines = []
        if self.late:
            if self.penalty:
                lines.append(f"Late: raw score {self.score + self.written_score:g}, penalty -{self.penalty:g} "
                             f"of {self.total_max:g} points ({self.late['reason']}); "
                             f"total {self.total:g} / {self.total_max:g}.")
            else:
                lines.append(f"On time: {self.late['reason']}.")
            if self.late.get("source"):
                lines[-1] += f" Submission time from {self.late['source']}."
        if self.tests_version:
            ran = f" in grading run {self.run['id']} of {self.run['started']}" if self.run else ""
            lines.append(f"Graded by tests version {self.tests_version}{ran}.")
        return lines

    def visible_score(self, hidden_visibility="after_published"):
        """(score, max_score) of the tests a student sees on Gradescope before grades are published.

        Hidden tests count only when their visibility is ``"visible"``; Gradescope keeps the total from
        students while a test is hidden, so what they read must not count them either.
        """
        shown = [t for t in self.tests if not t.hidden or hidden_visibility == "visible"]
        return score_of(shown)

    def summary_lines(self, hidden_visibility="after_published"):
        """The lines of Gradescope's top output for this exercise: visible score, notes, sandbox, late work.

        With hidden tests that students do not see yet, the score is that of the visible tests only, and the
        late line gives the reason and the percentage, never points that would tell the hidden total.
        """
        hidden = hidden_visibility != "visible" and any(t.hidden for t in self.tests)
        score, top = self.visible_score(hidden_visibility)
        line = f"{self.exercise}: {score:g} / {top:g} points"
        if hidden:
            line += " on the tests you can see; the hidden tests are shown when grades are published"
        lines = [line]
        lines += [f"  {for_students(note)}" for note in self.notes]
        if self.sandbox:
            lines.append(f"  Sandbox of your code: {self.sandbox}")
        late = self.late_lines()
        if hidden and self.late and self.penalty:
            late[0] = f"Late: {self.late['reason']}."
            if self.late.get("source"):
                late[0] += f" Submission time from {self.late['source']}."
        lines += [f"  {line}" for line in late]
        return lines

    def to_gradescope(self, hidden_visibility="after_published"):
        """This exercise's entries of Gradescope's ``tests`` list (numbered ``NN.k``)."""
        return [t.to_gradescope(self.exercise, f"{self.exercise[:2]}.{k}", hidden_visibility)
                for k, t in enumerate(self.tests, start=1)]


def to_gradescope(student, results, hidden_visibility="after_published"):
    """Gradescope's ``results.json`` (a dict) for one student's submission.

    Parameters
    ----------
    student : str
    results : list of SubmissionRecord
        One per exercise graded.
    hidden_visibility : str
        Gradescope visibility of hidden tests (one of :data:`VISIBILITIES`).

    Returns
    -------
    dict
        The keys of Gradescope's specification only: ``score`` (the records' totals), ``execution_time``,
        ``output`` (a summary per exercise that counts only the tests students see before grades are published:
        :meth:`SubmissionRecord.summary_lines`), ``output_format``, ``visibility``, ``stdout_visibility``,
        ``tests`` and ``extra_data`` (the student, ``max_score``: the points of the records, the seeds and the
        sandbox layers per exercise).
    """
    if hidden_visibility not in VISIBILITIES:
        raise ValueError(f"hidden_visibility must be one of {VISIBILITIES}, got {hidden_visibility!r}")
    results = [r if isinstance(r, SubmissionRecord) else SubmissionRecord.from_dict(r) for r in results]
    lines, tests = [], []
    for result in results:
        lines += result.summary_lines(hidden_visibility)
        tests += result.to_gradescope(hidden_visibility)
    # the tests' points minus late penalties (and plus written grades, once merged): Gradescope takes this
    # top-level score over the sum of the tests' (the specification has no top-level max_score: the
    # assignment's points are set on Gradescope; ours are kept in extra_data)
    score, top = sum(r.total for r in results), sum(r.total_max for r in results)
    return {
        "score": score,
        "execution_time": round(sum(r.seconds for r in results), 2),
        "output": "\n".join(lines),
        "output_format": "simple_format",
        "visibility": "visible",
        "stdout_visibility": "hidden",
        "extra_data": {"student": student, "max_score": top, "seeds": {r.exercise: r.seed for r in results},
                       "sandbox": {r.exercise: r.isolation for r in results},
                       "tests_version": {r.exercise: r.tests_version for r in results},
                       "late": {r.exercise: r.late for r in results if r.late}},
        "tests": tests,
    }
