"""``particles.check("00_warmup")``: the public tests on a student's current code, from a notebook.

Which code is checked? By default, **the code you ran in this kernel**: the
sources of the cells in the order you executed them (IPython's ``In`` list),
reduced to definitions exactly as the autograder reduces a notebook (see
:mod:`particles.course.reading.submission`). So a function you redefined is checked in its
latest version, and you need not save first. The alternative, reading the
notebook file, needs its path, which a kernel does not reliably know, and
checks what was last *saved*, not what you see. Pass ``notebook=PATH`` to check
a saved file instead, which is exactly what the autograder will receive.

The tests run in a separate process, as in the autograder, so a stuck loop in
your code stops that process, not your kernel.
"""

import html
import importlib.util
import os
import re
import sys
import tempfile
from pathlib import Path

import nbformat

from .paths import exercise_tests, project_root

__all__ = ["check", "CheckResult", "CheckError"]

_UNWRITTEN = re.compile(r"`(\w+)`,? (?:which )?is not implemented yet")


class CheckError(RuntimeError):
    """The public tests could not run, so no verdict is given: the message says why and what to do."""


def _unwritten(tests):
    """Functions the failures name as not implemented yet, in the order the tests meet them."""
    names = []
    for t in tests:
        for name in _UNWRITTEN.findall("" if t.passed else (t.reason or "")):
            if name not in names:
                names.append(name)
    return names


class CheckResult:
    """The outcome of :func:`check`: shown as a table in a notebook, as text elsewhere.

    In a notebook (``_repr_html_``) the table is followed, under each test
    that attached some, by figures of your curve beside the reference's
    (inline PNG images, see :mod:`particles.course.grading.figures`).

    Attributes
    ----------
    exercise : str
    score, max_score : float
    tests : list of particles.course.results.records.TestRecord
        One record per public test: ``name``, ``points``, ``passed``, ``reason``
        and, when the test drew some, ``figures``.
    notes : list of str
        Remarks from loading your code (errors at definition time, syntax errors)
        and the count of your written answers.
    unwritten : list of str
        The functions the tests found still raising ``NotImplementedError``.
    written_answers : dict or None
        ``{"asked": N, "answered": k, "blank": [question numbers]}``, counted in
        the saved notebook.
    """

    def __init__(self, exercise, tests, notes, source, written_answers=None):
        self.exercise, self.tests, self.notes, self.source = exercise, tests, notes, source
        self.score = sum(t.score for t in tests)
        self.max_score = sum(t.max_score for t in tests)
        self.unwritten = _unwritten(self.scored)
        self.written_answers = written_answers

    # -- stretch goals: optional tests, listed apart and never scored ------------------------------
    @property
    def scored(self):
        """The tests that count for the score (all but the stretch goals)."""
        return [t for t in self.tests if not t.optional]

    @property
    def stretch_goals(self):
        """The optional tests (``@pytest.mark.optional``): shown apart, "stretch goal, not scored"."""
        return [t for t in self.tests if t.optional]

    def _stretch_lines(self):
        if not self.stretch_goals:
            return []
        done = sum(t.passed for t in self.stretch_goals)
        lines = [f"  Stretch goals (not scored): {done} of {len(self.stretch_goals)} pass"]
        for t in self.stretch_goals:
            lines.append(f"  {'PASS' if t.passed else 'TODO'}  {t.name}")
            if not t.passed:
                lines.append(f"        {t.reason}")
        return lines

    def _summary(self):
        """The closing lines: what is left to write, or that every public test passes."""
        lines = []
        if self.unwritten:
            lines.append("Not implemented yet: " + ", ".join(f"`{n}`" for n in self.unwritten) + ".")
        if self.passed:
            lines.append("All public tests pass. The autograder adds hidden tests with random parameters.")
        return lines

    @property
    def passed(self):
        """True when there are scored public tests and every one passed (stretch goals do not count)."""
        return bool(self.scored) and all(t.passed for t in self.scored)

    def __str__(self):
        lines = [f"{self.exercise}: {self.score:g} / {self.max_score:g} points on the public tests "
                 f"(checked {self.source})"]
        for t in self.scored:
            lines.append(f"  {'PASS' if t.passed else 'FAIL'}  {t.name}")
            if not t.passed:
                lines.append(f"        {t.reason}")
        lines += self._stretch_lines()
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines + self._summary())

    __repr__ = __str__

    def _repr_markdown_(self):
        rows = [f"**{self.exercise}: {self.score:g} / {self.max_score:g} points on the public tests** "
                f"(checked {self.source})", "", "| | test | what to fix |", "| --- | --- | --- |"]
        for t in self.tests:  # the stretch goals last, labelled
            reason = "" if t.passed else t.reason.replace("|", "\\|")
            mark = "✅" if t.passed else ("➖" if t.optional else "❌")
            rows.append(f"| {mark} | {t.title} | {reason} |")
        rows += [""] + [f"- {n}" for n in self.notes]
        return "\n".join(rows + [""] + self._summary())


    def _repr_html_(self):
        """The table, with the figures of the tests that attached some (inline PNG), for Jupyter."""
        from .grading import figures

        e = html.escape
        rows = [f"<p><b>{e(self.exercise)}: {self.score:g} / {self.max_score:g} points on the public tests</b> "
                f"(checked {e(self.source)})</p>",
                '<table><thead><tr><th></th><th style="text-align:left">test</th>'
                '<th style="text-align:left">what to fix</th></tr></thead><tbody>']
        for t in self.tests:
            reason = "" if t.passed else e(t.reason)
            mark = "✅" if t.passed else ("➖" if t.optional else "❌")
            rows.append(f"<tr><td>{mark}</td><td style=\"text-align:left\">{e(t.title)}</td>"
                        f"<td style=\"text-align:left\">{reason}</td></tr>")
            if t.figures:  # open under a failed test, folded under a passed one
                shown = "".join(f'<div style="display:inline-block;margin:0 .5em .5em 0">'
                                f"{figures.figure_html(f, css=False)}</div>" for f in t.figures)
                rows.append(f'<tr><td></td><td colspan="2" style="text-align:left"><details'
                            f'{"" if t.passed else " open"}><summary>your curve beside the reference</summary>'
                            f"{shown}</details></td></tr>")
        rows.append("</tbody></table>")
        if self.notes:
            rows.append("<ul>" + "".join(f"<li>{e(n)}</li>" for n in self.notes) + "</ul>")
        rows += [f"<p>{e(line)}</p>" for line in self._summary()]
        return "\n".join(rows)


def _kernel_cells():
    try:
        from IPython import get_ipython
    except ImportError:
        return None
    shell = get_ipython()
    if shell is None:
        return None
    history = shell.user_ns.get("In") or []
    return [(f"In [{k}]", source) for k, source in enumerate(history) if k and source.strip()]


def _saved_notebook(exercise):
    """The file of the notebook this kernel runs, when it can be told; else None.

    VS Code sets ``__vsc_ipynb_file__``, Jupyter Server ``__session__`` and
    ``JPY_SESSION_NAME``; failing those, ``NN_topic.ipynb`` in the current folder.
    """
    candidates = []
    try:
        from IPython import get_ipython

        shell = get_ipython()
        namespace = shell.user_ns if shell is not None else {}
    except ImportError:
        namespace = {}
    candidates += [namespace.get("__vsc_ipynb_file__"), namespace.get("__session__"),
                   os.environ.get("JPY_SESSION_NAME"), Path.cwd() / f"{exercise}.ipynb"]
    for candidate in candidates:
        if candidate and str(candidate).endswith(".ipynb") and Path(candidate).is_file():
            return Path(candidate)
    return None


def _needs_pytest():
    """A CheckError saying how to install pytest into this very Python, or None when it is there."""
    if importlib.util.find_spec("pytest") is not None:
        return None
    return CheckError(
        "particles.check runs the public tests with pytest, which is not installed in the Python this "
        f"notebook runs ({sys.executable}). Install it there, in a cell: `%pip install pytest`, or in a "
        f"terminal: `{sys.executable} -m pip install pytest` (or reinstall the course: "
        "`pip install -e .` in its folder, which brings pytest). No test has run: nothing was checked.")


def check(exercise, notebook=None, *, time_limit=None, root=None):
    """Run the public tests of an exercise on your code and show what to fix.

    Call it in the last cell of an exercise notebook, ``particles.check("03_provot")``.
    The public tests are the autograder's tests with fixed, readable inputs;
    the autograder adds hidden ones with random inputs, so passing here is
    necessary, not sufficient.

    What is checked? By default the code you ran in this kernel, in the order
    you ran it (so run your cells first; you need not save). With
    ``notebook="03_provot.ipynb"`` the saved file is checked instead, which is
    exactly what you hand in. Either way your code runs in a separate process
    under the autograder's rules: a function of the library that the exercise
    asks you to write yourself raises ``PermissionError`` when your code uses
    it (the cells the course gives you may use it), and an endless loop is
    stopped after `time_limit` seconds.

    What you get: one line per test (PASS, or FAIL with what to fix), the
    functions still ``NotImplementedError`` ("Not implemented yet: ..."), the
    written answers found in the saved notebook ("Written answers: 1 of 3
    filled in; not written yet: questions 2, 3": save to update it), and the
    tests marked as stretch goals, which score nothing.

    Parameters
    ----------
    exercise : str
        The exercise, e.g. ``"00_warmup"`` (the notebook's file name without ``.ipynb``).
    notebook : path, optional
        Check this saved notebook instead of the code run in the current
        kernel (required outside Jupyter/IPython).
    time_limit : float, optional
        Per-call time limit for your functions, in seconds.
    root : path, optional
        The course folder (default: found from the current directory).

    Returns
    -------
    CheckResult
        Shown as a table in a notebook; ``.passed`` is True when every public
        test passed, ``.score`` and ``.max_score`` are the public points,
        ``.unwritten`` the functions not implemented yet.

    Raises
    ------
    ValueError
        For an unknown exercise, or when there is no kernel and no `notebook`.
    CheckError
        When the tests cannot run (pytest missing, no test collected): the
        message says what to do. The check never reports a pass it did not test.
    """
    from .release.answers import answers_note
    from .grading.discovery import Unit, written_answers
    from .grading.session import grade_unit

    root = Path(root) if root else project_root()
    tests = exercise_tests(root)
    if exercise not in tests:
        raise ValueError(f"unknown exercise {exercise!r}; expected one of {', '.join(map(repr, tests))}")
    problem = _needs_pytest()
    if problem is not None:
        raise problem
    saved = None
    with tempfile.TemporaryDirectory(prefix="particles-check-") as tmp:
        if notebook is None:
            cells = _kernel_cells()
            if cells is None:
                raise ValueError("check() outside a notebook needs notebook='path/to/exercise.ipynb'")
            nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(src) for _, src in cells])
            nb.metadata["particles"] = {"exercise": exercise}
            path = Path(tmp) / f"{exercise}.ipynb"
            nbformat.write(nb, str(path))
            source = "the code run in this kernel"
            labels = {f"code cell {k}": label for k, (label, _) in enumerate(cells, start=1)}
            saved = _saved_notebook(exercise)
        else:
            path, source, labels = Path(notebook), f"the saved notebook {notebook}", {}
        result = grade_unit(Unit("you", exercise, path), root, public_only=True, time_limit=time_limit)
    records = sorted(result.tests, key=lambda t: t.optional)  # stretch goals last, listed apart
    if not records:
        raise CheckError(
            f"no public test of {exercise} ran (pytest status {result.grader_status}), so nothing was checked. "
            f"Run `{sys.executable} -m pytest {tests[exercise]}` in a terminal to see why"
            + (f"; the grader said: {'; '.join(result.notes)}" if result.notes else "."))
    for record in records:  # speak of "In [5]" rather than the temporary notebook's cell numbers
        for cell, label in sorted(labels.items(), key=lambda kv: -len(kv[0])):
            record.reason = record.reason.replace(cell, label)
    notes = list(result.notes)
    written = result.written_answers
    if notebook is None:  # the kernel's cells hold no answers: count them in the saved file
        notes = [n for n in notes if not n.startswith("Written answers:")]
        written = written_answers(saved, root, exercise) if saved is not None else None
        if written and written["asked"]:
            notes.append(answers_note(written, f" (counted in the saved {saved.name}: save to update)"))
        elif saved is None:
            notes.append("Written answers: not counted (the saved notebook was not found; "
                         f"check(\"{exercise}\", notebook=\"{exercise}.ipynb\") counts them)")
    for cell, label in sorted(labels.items(), key=lambda kv: -len(kv[0])):
        notes = [n.replace(cell, label) for n in notes]
    return CheckResult(exercise, records, notes, source, written)
