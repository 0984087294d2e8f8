"""``particles.check("00_warmup")``: the public tests on a student's current code, from a notebook.

Which code is checked? By default, **the code you ran in this kernel**: the
sources of the cells in the order you executed them (IPython's ``In`` list),
reduced to definitions exactly as the autograder reduces a notebook (see
:mod:`particles.course.code`). So a function you redefined is checked in its
latest version, and you need not save first. The alternative, reading the
notebook file, needs its path, which a kernel does not reliably know, and
checks what was last *saved*, not what you see. Pass ``notebook=PATH`` to check
a saved file instead, which is exactly what the autograder will receive.

The tests run in a separate process, as in the autograder, so a stuck loop in
your code stops that process, not your kernel.
"""

import html
import tempfile
from pathlib import Path

import nbformat

from .paths import exercise_tests, project_root

__all__ = ["check", "CheckResult"]


class CheckResult:
    """The outcome of :func:`check`: shown as a table in a notebook, as text elsewhere.

    In a notebook (``_repr_html_``) the table is followed, under each test
    that attached some, by figures of your curve beside the reference's
    (inline PNG images, see :mod:`particles.course.figures`).

    Attributes
    ----------
    exercise : str
    score, max_score : float
    tests : list of particles.course.records.TestRecord
        One record per public test: ``name``, ``points``, ``passed``, ``reason``
        and, when the test drew some, ``figures``.
    notes : list of str
        Remarks from loading your code (errors at definition time, syntax errors).
    """

    def __init__(self, exercise, tests, notes, source):
        self.exercise, self.tests, self.notes, self.source = exercise, tests, notes, source
        self.score = sum(t.score for t in tests)
        self.max_score = sum(t.max_score for t in tests)

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

    @property
    def passed(self):
        """True when every scored public test passed (stretch goals left undone do not count)."""
        return all(t.passed for t in self.scored)

    def __str__(self):
        lines = [f"{self.exercise}: {self.score:g} / {self.max_score:g} points on the public tests "
                 f"(checked {self.source})"]
        for t in self.scored:
            lines.append(f"  {'PASS' if t.passed else 'FAIL'}  {t.name}")
            if not t.passed:
                lines.append(f"        {t.reason}")
        lines += self._stretch_lines()
        lines += [f"  note: {n}" for n in self.notes]
        if self.passed:
            lines.append("All public tests pass. The autograder adds hidden tests with random parameters.")
        return "\n".join(lines)

    __repr__ = __str__

    def _repr_markdown_(self):
        rows = [f"**{self.exercise}: {self.score:g} / {self.max_score:g} points on the public tests** "
                f"(checked {self.source})", "", "| | test | what to fix |", "| --- | --- | --- |"]
        for t in self.tests:  # the stretch goals last, labelled
            reason = "" if t.passed else t.reason.replace("|", "\\|")
            mark = "✅" if t.passed else ("➖" if t.optional else "❌")
            rows.append(f"| {mark} | {t.title} | {reason} |")
        rows += [""] + [f"- {n}" for n in self.notes]
        if self.passed:
            rows.append("All public tests pass. The autograder adds hidden tests with random parameters.")
        return "\n".join(rows)


    def _repr_html_(self):
        """The table, with the figures of the tests that attached some (inline PNG), for Jupyter."""
        from . import figures

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
        if self.passed:
            rows.append("<p>All public tests pass. The autograder adds hidden tests with random parameters.</p>")
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


def check(exercise, notebook=None, *, time_limit=None, root=None):
    """Run the public tests of `exercise` on your current code, in a separate process.

    Parameters
    ----------
    exercise : str
        The exercise, e.g. ``"00_warmup"``.
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
        Displays as a table in a notebook; ``.passed`` is True when all
        public tests pass.

    Raises
    ------
    ValueError
        For an unknown exercise, or when there is no kernel and no `notebook`.
    """
    from .grading import Unit, grade_unit

    root = Path(root) if root else project_root()
    tests = exercise_tests(root)
    if exercise not in tests:
        raise ValueError(f"unknown exercise {exercise!r}; expected one of {', '.join(map(repr, tests))}")
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
        else:
            path, source, labels = Path(notebook), f"the saved notebook {notebook}", {}
        result = grade_unit(Unit("you", exercise, path), root, public_only=True, time_limit=time_limit)
    records = sorted(result.tests, key=lambda t: t.optional)  # stretch goals last, listed apart
    for record in records:  # speak of "In [5]" rather than the temporary notebook's cell numbers
        for cell, label in sorted(labels.items(), key=lambda kv: -len(kv[0])):
            record.reason = record.reason.replace(cell, label)
    notes = list(result.notes)
    for cell, label in sorted(labels.items(), key=lambda kv: -len(kv[0])):
        notes = [n.replace(cell, label) for n in notes]
    return CheckResult(exercise, records, notes, source)
