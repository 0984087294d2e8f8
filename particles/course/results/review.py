r"""``particles review SUBMISSION... --out DIR``: every student's answer to a written question, side by side.

For each exercise and each of its written questions
(:mod:`particles.course.release.answers`), one self-contained page
``DIR/<exercise>/question-<k>.html``: the question, the master's answer
(folded), then each student's answer, rendered from Markdown with nothing of
the student's kept as markup (:mod:`particles.course.results.markup`), with
the figures of the code cells it refers to, blank answers shown as blank.
``DIR/index.html`` links them all. The pages load nothing from the network:
inline CSS, figures as ``data:`` URIs, and the equations (``$...$`` and
``$$...$$`` of the question, the master's answer and the students' answers)
typeset by the course site's offline MathJax 3, copied into ``DIR/mathjax/``
(SVG output). The TeX is the students', so MathJax runs safe: its ``html``
package (``\href``, ``\class``, ``\style``, ``\cssId``), ``\require`` and the menu
are off, its safe extension allows no URL, class, id or style, and it typesets
only the math spans :mod:`~particles.course.results.markup` made (a ``$`` in
prose stays a dollar). Each page's Content-Security-Policy allows scripts only
from the review folder itself (the two MathJax files: its configuration and
MathJax), no inline script, nothing else; no markup of the students' reaches
the page in the first place.

The figures of an answer are the images (PNG, JPEG) that the submitted
notebook's code cells show between the previous answer, or the last section
heading above the answer (whichever is later), and the next cell of the
course after the answer: the cells a student ran for the question, above or
below their answer. A submission saved without outputs has none.

Beside the pages, ``DIR/<exercise>/rubric.csv`` is the rubric to fill in (its
format: :mod:`particles.course.results.rubric`), one row per student and
question, ``points`` and ``comment`` empty. Run again (new submissions, say),
it keeps every row already there with its points and comment, adds the
missing rows, and rewrites only the maxima from the master. The students are
found as ``particles grade`` finds them
(:func:`particles.course.grading.discovery.find_submissions`, the same
``--exercise``), so the rubric's names are those of the records.
"""

import base64
import binascii
import csv
import html
import io
import os
import tempfile
from pathlib import Path

from ..grading.deadlines import find_course
from ..grading.discovery import find_submissions, released_exercise
from ..term.roster import read_roster
from ..grading.intake import NotebookRejected, read_notebook
from ..paths import exercise_tests, project_root
from ..release.site import copy_mathjax
from ..release.answers import (answer_cells, answers_of, cell_source, model_answers, question_points, questions_of,
                               is_blank)
from .markup import markdown_html
from .rubric import COLUMNS

__all__ = ["write_review", "answer_figures", "MAX_FIGURES", "MAX_FIGURE_BYTES"]

MAX_FIGURES = 8
"""Figures shown per answer at most (the others are counted)."""
MAX_FIGURE_BYTES = 2_000_000
"""The largest image shown (bytes, decoded)."""

_MAGIC = {"image/png": b"\x89PNG\r\n\x1a\n", "image/jpeg": b"\xff\xd8\xff"}

_CSS = """
body { font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: #1d1d1f;
       background: #fafafa; margin: 0; }
main { max-width: 62rem; margin: 0 auto; padding: 1.5rem 1.25rem 3rem; }
h1 { font-size: 1.5rem; margin: 0 0 .5rem; }
nav, .meta { color: #555; font-size: .9rem; }
section.question { background: #fff; border: 1px solid #ddd; padding: .5rem 1rem; margin: 1rem 0; }
section.answer { background: #fff; border: 1px solid #e0e0e0; border-left: 4px solid #0b57d0;
                 padding: .25rem 1rem .75rem; margin: 1rem 0; }
section.answer.blank { border-left-color: #bbb; color: #777; }
section.answer h2 { font-size: 1.05rem; margin: .5rem 0; }
.tag { font-size: .75rem; color: #666; border: 1px solid #bbb; border-radius: .6rem; padding: 0 .4rem; }
.figures { display: flex; flex-wrap: wrap; gap: .5rem; }
figure { margin: 0; border: 1px solid #e0e0e0; padding: .25rem; max-width: 100%; }
figure img { display: block; max-width: 28rem; height: auto; }
figcaption { font-size: .8rem; color: #555; }
pre { background: #f3f3f3; padding: .5rem; overflow-x: auto; }
code { font-size: .85em; background: #eee; padding: 0 .2rem; border-radius: .2rem; }
table { border-collapse: collapse; background: #fff; }
th, td { text-align: left; padding: .3rem .6rem; border-bottom: 1px solid #e5e5e5; }
details summary { cursor: pointer; color: #0b57d0; }
"""


MATHJAX_CONFIG = """window.MathJax = {
  tex: {packages: {'[-]': ['html', 'require', 'autoload', 'noundefined']},
        inlineMath: [['$', '$']], displayMath: [['$$', '$$']], processEscapes: false},
  loader: {load: ['ui/safe']},
  options: {ignoreHtmlClass: 'no-math', processHtmlClass: 'math', enableMenu: false,
            safeOptions: {allow: {URLs: 'none', classes: 'none', cssIDs: 'none', styles: 'none'}}},
  svg: {fontCache: 'global'}
};
"""
"""MathJax's configuration for the review pages (``DIR/mathjax/review-config.js``): students' TeX, typeset safely."""


def _page(title, body, math=False):
    """A page; with `math`, MathJax from ``../mathjax/`` typesets its math spans (the only scripts it may run)."""
    e = html.escape
    scripts = ['<script src="../mathjax/review-config.js"></script>',
               '<script id="MathJax-script" src="../mathjax/tex-svg-full.js"></script>'] if math else []
    policy = ("default-src 'none'; img-src data:; style-src 'unsafe-inline'"
              + ("; script-src 'self'" if math else ""))
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        f'<meta http-equiv="Content-Security-Policy" content="{policy}">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">', f"<title>{e(title)}</title>",
        f"<style>{_CSS}</style>", *scripts, "</head>", '<body class="no-math"><main>', *body, "</main></body>",
        "</html>", ""])


def _fmt(x):
    return f"{x:g}"


def _images(cell):
    """The images a code cell's outputs show: ``[(mime, base64), ...]``, checked to be what they say."""
    found = []
    outputs = cell.get("outputs") if isinstance(cell.get("outputs"), list) else []
    for output in outputs:
        data = output.get("data") if isinstance(output, dict) else None
        if not isinstance(data, dict):
            continue
        for mime, magic in _MAGIC.items():
            raw = data.get(mime)
            raw = "".join(raw) if isinstance(raw, list) else raw
            if not isinstance(raw, str):
                continue
            try:
                image = base64.b64decode("".join(raw.split()), validate=True)
            except (binascii.Error, ValueError):
                continue
            if image.startswith(magic):
                found.append((mime, image))
            break
    return found


def answer_figures(notebook, released):
    """The figures each answer of a submission refers to: ``{k: [(mime, bytes), ...]}``.

    Parameters
    ----------
    notebook, released : dict
        The submitted notebook and the released exercise.

    Returns
    -------
    dict
        Slot number -> the images of the code cells between the previous
        answer (or the last heading above this one, whichever is later) and
        the next cell of the course below it; valid PNG or JPEG images only.
    """
    cells = notebook.get("cells") if isinstance(notebook.get("cells"), list) else []
    known = {c.get("id") for c in released.get("cells", []) if isinstance(c, dict)}
    where = answer_cells(notebook, released)
    out, previous_end = {}, -1
    for k in sorted(where):
        indices = where[k]
        if not indices:
            out[k] = []
            continue
        first, last = indices[0], indices[-1]
        start = previous_end + 1
        for i in range(first - 1, start - 1, -1):  # the last heading above the answer
            cell = cells[i] if isinstance(cells[i], dict) else {}
            if cell.get("cell_type") == "markdown" and cell_source(cell).lstrip().startswith("#"):
                start = i + 1
                break
        end = next((i for i in range(last + 1, len(cells)) if isinstance(cells[i], dict)
                    and cells[i].get("cell_type") == "markdown" and cells[i].get("id") in known), len(cells))
        out[k] = [image for i in range(start, end) if i not in indices and isinstance(cells[i], dict)
                  and cells[i].get("cell_type") == "code" for image in _images(cells[i])]
        previous_end = last
    return out


def _answers(unit, released, slots):
    """``{k: (text, figures)}`` of one notebook, and why when it is not read (as ``particles grade`` says it)."""
    try:
        if unit.rejected:
            raise NotebookRejected(unit.rejected)
        notebook = read_notebook(unit.notebook)  # the grader's checks and limits: no 100 MB page
    except NotebookRejected as error:
        return {k: ("", []) for k in slots}, str(error)
    texts = answers_of(notebook, released)
    figures = answer_figures(notebook, released)
    if not any(answer_cells(notebook, released).values()) and model_answers(notebook):  # a master
        texts = {k: "" if is_blank(t) else t for k, t in model_answers(notebook).items()}
    return {k: (texts.get(k, ""), figures.get(k, [])) for k in slots}, ""


def _figures_html(figures, student):
    e = html.escape
    shown = [(m, b) for m, b in figures if len(b) <= MAX_FIGURE_BYTES][:MAX_FIGURES]
    items = "".join(f'<figure><img src="data:{m};base64,{base64.b64encode(b).decode()}" '
                    f'alt="figure {n} of {e(student)}"><figcaption>figure {n}</figcaption></figure>'
                    for n, (m, b) in enumerate(shown, start=1))
    left = len(figures) - len(shown)
    note = f'<p class="meta">{left} more figure(s) not shown (too many or too large)</p>' if left else ""
    return (f'<div class="figures">{items}</div>' if items else "") + note


def _question_page(exercise, k, count, text, points, model, rows):
    e = html.escape
    nav = ['<a href="../index.html">all questions</a>']
    nav += [f'<a href="question-{k - 1}.html">question {k - 1}</a>'] if k > 1 else []
    nav += [f'<a href="question-{k + 1}.html">question {k + 1}</a>'] if k < count else []
    blank = sum(1 for _, answer, _, _ in rows if not answer)
    body = [f"<h1>{e(exercise)}: question {k} ({_fmt(points)} points)</h1>", f"<nav>{' · '.join(nav)}</nav>",
            f'<section class="question">{markdown_html(text)}</section>']
    if model:
        body.append(f"<details><summary>The master's answer</summary>{markdown_html(model)}</details>")
    body.append(f'<p class="meta">{len(rows)} students, {blank} blank. Grade them in <code>rubric.csv</code> '
                f"(rows {e(exercise)}, student, {k}).</p>")
    for student, answer, figures, note in rows:
        tag = ' <span class="tag">blank</span>' if not answer else ""
        body.append(f'<section class="answer{" blank" if not answer else ""}" id="{e(student)}">'
                    f"<h2>{e(student)}{tag}</h2>"
                    + (markdown_html(answer) if answer else "<p><em>(blank: no answer written)</em></p>")
                    + _figures_html(figures, student)
                    + (f'<p class="meta">{e(note)}</p>' if note else "") + "</section>")
    return _page(f"{exercise}, question {k}", body, math=True)


def _write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, name = tempfile.mkstemp(dir=path.parent, prefix=".review-", suffix=".part")
    with os.fdopen(handle, "w", encoding="utf-8", newline="") as stream:
        stream.write(text)
    os.replace(name, path)


def _rubric(path, exercise, students, points):
    """The rubric's text: a row per student and question, keeping the rows (points, comments) already there."""
    fresh = [(s, str(k)) for s in students for k in sorted(points)]
    kept, extra = {}, []
    if path.exists():
        reader = csv.DictReader(io.StringIO(path.read_bytes().decode("utf-8-sig")))
        if reader.fieldnames is None or set(reader.fieldnames) != set(COLUMNS):
            raise ValueError(f"{path} exists and is not a rubric (expected the columns {','.join(COLUMNS)}); "
                             "move it away or pass another --out")
        for row in reader:
            key = (row["student"], row["question"])
            if row["exercise"] == exercise and key in set(fresh) and key not in kept:
                kept[key] = row
            else:
                extra.append(row)  # never dropped: `particles grade --rubric` says what is wrong with it
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(COLUMNS)
    for student, k in fresh:
        old = kept.get((student, k), {})
        writer.writerow([exercise, student, k, _fmt(points[int(k)]), old.get("points", ""), old.get("comment", "")])
    for row in extra:
        writer.writerow([row.get(c, "") for c in COLUMNS])
    return stream.getvalue(), sum(1 for row in kept.values() if (row.get("points") or row.get("comment")))


def write_review(paths, out, *, root=None, exercise=None, roster=None, name_column="submission_name"):
    """Write the review pages and the rubrics of the written answers of `paths`.

    Parameters
    ----------
    paths : sequence of path
        Notebooks, folders of them or zips (an LMS's download), as for ``particles grade``.
    out : path
        The folder to write: ``index.html``, ``<exercise>/question-<k>.html``, ``<exercise>/rubric.csv``.
    root : path, optional
        The course folder (default: found from the current directory).
    exercise : str, optional
        Read every notebook as this exercise (``particles grade --exercise``).
    roster : path, optional
        The roster (default: the course file's ``roster``, if any): the students are named as ``particles grade``
        names them, their aliases matched (:mod:`particles.course.term.identity`).
    name_column : str
        The roster's column of the grader's names (as ``particles export --name-column``).

    Returns
    -------
    dict
        ``pages`` and ``rubrics`` (paths written), ``students`` (how many), ``kept`` (rubric rows already
        graded and kept), ``problems`` (notebooks not read, exercises without written questions).

    Raises
    ------
    ValueError
        On an unknown exercise, a master whose points cannot be read, or an existing ``rubric.csv`` that is
        not a rubric.
    """
    root = Path(root).resolve() if root else project_root()
    tests = exercise_tests(root)
    if exercise is not None and exercise not in tests:
        raise ValueError(f"unknown exercise {exercise!r}; expected one of {', '.join(map(repr, tests))}")
    if roster is None:
        course = find_course(root, list(tests))
        roster = course.roster if course is not None else None
    identity = read_roster(roster, name_column).identity() if roster is not None else None
    with tempfile.TemporaryDirectory(prefix="particles-review-") as work:  # zips opened as grade opens them
        return _write_review(paths, Path(out), root, tests, exercise, work, identity)


def _write_review(paths, out, root, tests, exercise, work, identity=None):
    """:func:`write_review` with `work`, the private folder zips are opened into."""
    units, problems = find_submissions(paths, list(tests), exercise, workdir=work, identity=identity)
    pages, rubrics, index, kept = [], [], [], 0
    for name in [n for n in tests if any(u.exercise == n for u in units)]:
        released = released_exercise(root, name)
        questions = questions_of(released) if released is not None else {}
        if not questions:
            problems.append(f"{name}: no written question to review")
            continue
        try:
            points = question_points(released)
        except ValueError as error:
            raise ValueError(f"solutions/{name}.ipynb: {error}") from None
        try:
            master = read_notebook(root / "solutions" / f"{name}.ipynb")
        except NotebookRejected:
            master = {}
        models = model_answers(master)
        mine = sorted((u for u in units if u.exercise == name), key=lambda u: u.student)
        answers = {}
        for unit in mine:
            answers[unit.student] = _answers(unit, released, questions)
            if answers[unit.student][1]:
                problems.append(f"{unit.notebook}: {answers[unit.student][1]}; its answers are shown blank")
        for k, text in sorted(questions.items()):
            rows = [(u.student, *answers[u.student][0][k], answers[u.student][1]) for u in mine]
            path = out / name / f"question-{k}.html"
            _write(path, _question_page(name, k, len(questions), text, points[k], models.get(k, ""), rows))
            pages.append(path)
            index.append((name, k, points[k], sum(1 for r in rows if r[1]), len(rows)))
        text, graded = _rubric(out / name / "rubric.csv", name, [u.student for u in mine], points)
        _write(out / name / "rubric.csv", text)
        rubrics.append(out / name / "rubric.csv")
        kept += graded
    if pages:
        try:
            copy_mathjax(out)
            _write(out / "mathjax" / "review-config.js", MATHJAX_CONFIG)
        except (ValueError, OSError) as error:  # the pages still show every answer, the TeX as written
            problems.append(f"equations not typeset: {error}")
    e = html.escape
    body = ["<h1>Written answers to review</h1>",
            '<p class="meta">Grade each question in its exercise\'s <code>rubric.csv</code>, then run '
            "<code>particles grade ... --rubric DIR</code>.</p>", "<table><thead><tr><th>exercise</th>"
            "<th>question</th><th>points</th><th>answered</th><th>rubric</th></tr></thead><tbody>"]
    body += [f'<tr><td>{e(n)}</td><td><a href="{e(n)}/question-{k}.html">question {k}</a></td>'
             f"<td>{_fmt(p)}</td><td>{a} of {t}</td><td>{e(n)}/rubric.csv</td></tr>" for n, k, p, a, t in index]
    body.append("</tbody></table>")
    if problems:
        body.append('<ul class="meta">' + "".join(f"<li>{e(p)}</li>" for p in problems) + "</ul>")
    if units:
        _write(out / "index.html", _page("Written answers to review", body))
    return {"pages": pages, "rubrics": rubrics, "students": len({u.student for u in units}), "kept": kept,
            "problems": problems}
