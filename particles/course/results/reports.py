"""What grading writes: Gradescope ``results.json``, a gradebook CSV, Markdown and HTML feedback.

All are made from the same records (:mod:`particles.course.results.records`): per
student, one :class:`~particles.course.results.records.SubmissionRecord` per
exercise, holding one :class:`~particles.course.results.records.TestRecord` per
test; Gradescope's format itself is written by the records
(:func:`~particles.course.results.records.to_gradescope`). Figures are drawn here, as inline PNG
images: in ``feedback.html`` (one self-contained page per student: inline
CSS and images, no scripts, no network) and in the Gradescope output of
the tests that have them (``"output_format": "html"``; the others stay
plain text). Importing this module loads Matplotlib's Agg canvas, so that
the grading driver has all its code loaded before its first worker starts.

Written answers graded by people (merged from a rubric, :mod:`particles.course.results.rubric`) appear
per question with their points and comment in the feedback, in each exercise's total and in the
gradebook; in Gradescope's output each written question is an entry of its own, marked for Gradescope's
manual grading when no rubric graded it (:func:`gradescope_results`).

:func:`write_outputs` writes them all into a grading run's folder, per student, as its records come in
(the driver calls it after each batch, :mod:`particles.course.grading.report`).
"""

import csv
import hashlib
import html
import json

from ..grading import figures
from .records import VISIBILITIES, SubmissionRecord, score_of, to_gradescope
from .rubric import WrittenGrades
from .shown import for_students, submitted_name

__all__ = ["score_of", "gradescope_results", "to_gradescope", "feedback_markdown", "feedback_html",
           "write_gradebook", "write_outputs", "VISIBILITIES"]

figures.load()


def _fmt(x):
    return f"{x:g}"


def _records(results):
    """`results` as :class:`SubmissionRecord` objects (dicts of JSON data are read as records)."""
    return [r if isinstance(r, SubmissionRecord) else SubmissionRecord.from_dict(r) for r in results]


MANUAL_OUTPUT = "Written answer, graded by hand on Gradescope ({points} points)"
"""What Gradescope shows under a written question that no rubric graded here (to add it as a manual question
of the assignment's outline is the instructors' part: ``GRADESCOPE.md`` of the bundle says so)."""


def _written_entry(exercise, k, top, entry, answered):
    """One written question as an entry of Gradescope's ``tests`` list."""
    graded = entry is not None and entry.get("points") is not None
    if graded:
        output = "Graded by hand" + (f": {entry['comment']}" if entry.get("comment") else "")
    elif entry is not None:
        output = "Written answer: not graded yet" + (f" ({entry['comment']})" if entry.get("comment") else "")
    else:
        output = MANUAL_OUTPUT.format(points=_fmt(top))
    extra = {"question": k, "points": top, "written": True, "answered": answered}
    if entry is not None and entry.get("rubric"):
        extra["rubric"] = entry["rubric"]
    return {"name": f"{exercise}: Question {k} (written answer, {_fmt(top)} points)",
            "number": f"{exercise[:2]}.w{k}",
            "score": float(entry["points"]) if graded else 0.0,
            "max_score": float(top) if entry is not None else 0.0,
            "output": output, "output_format": "text", "visibility": "visible",
            "tags": [exercise, "written", "manual grading" if entry is None else "rubric"],
            "extra_data": extra}


def gradescope_results(student, results, hidden_visibility="after_published", manual=None):
    """Gradescope's ``results.json`` (a dict), with the written questions marked.

    Parameters
    ----------
    student : str
    results : list of SubmissionRecord
    hidden_visibility : str
        Gradescope visibility of hidden tests (one of :data:`VISIBILITIES`).
    manual : dict, optional
        exercise -> ``{k: points}`` of its written questions
        (:meth:`particles.course.results.rubric.WrittenGrades.manual`).

    Returns
    -------
    dict
        :func:`~particles.course.results.records.to_gradescope`'s, and one entry per written question
        after each exercise's tests. A question a rubric graded (the record's ``written``) scores its
        points out of ``max_points``, and the top-level ``score`` and ``max_score`` (the records'
        :attr:`~particles.course.results.records.SubmissionRecord.total`) include them; any
        other written question scores 0 out of 0 and says that it is graded by hand on Gradescope, worth
        its points (a manual question of the assignment's outline).
    """
    results = _records(results)
    data = to_gradescope(student, results, hidden_visibility)
    manual = manual or {}
    tests, rest = [], list(data["tests"])
    for result in results:
        tests += rest[:len(result.tests)]
        rest = rest[len(result.tests):]
        blank = set((result.written_answers or {}).get("blank") or [])
        if result.written:
            questions = {int(w["question"]): w for w in result.written}
            points = {k: float(w.get("max_points", 0)) for k, w in questions.items()}
        else:
            questions, points = {}, manual.get(result.exercise, {})
        tests += [_written_entry(result.exercise, k, top, questions.get(k), k not in blank)
                  for k, top in sorted(points.items())]
    data["tests"] = tests + rest  # the top-level score is already the records' totals (written grades included)
    if any(r.written for r in results):
        data["extra_data"]["written"] = {r.exercise: r.written for r in results if r.written}
        data["output"] = "\n".join([data["output"], *(f"{r.exercise}: {_written_summary(r, hidden_visibility)}"
                                                      for r in results if r.written)]).strip()
    return data


def _cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def _totals(results):
    """(total, total_max) of a student's records: tests, written answers, late penalties."""
    return sum(r.total for r in results), sum(r.total_max for r in results)


def _written_points(entry):
    top = _fmt(float(entry.get("max_points", 0)))
    return f"{_fmt(float(entry['points']))} / {top}" if entry.get("points") is not None else \
        f"not graded yet / {top}"


def _written_summary(result, hidden_visibility="visible"):
    """Tests and written answers in one line; on Gradescope (`hidden_visibility`) the visible tests only."""
    score, top = result.visible_score(hidden_visibility)
    hidden = score_of(result.tests) != (score, top)
    return (f"Tests {_fmt(score)} / {_fmt(top)}{' (the tests you can see)' if hidden else ''}; written answers, "
            f"graded by people, {_fmt(result.written_score)} / {_fmt(result.written_max)}")


def _written_markdown(result):
    """The lines of a record's written answers: a table of points and comments (none without a rubric)."""
    if not result.written:
        return []
    out = [_written_summary(result) + ":", "", "| question | points | comment |", "| --- | ---: | --- |"]
    out += [f"| Question {_cell(w['question'])} | {_written_points(w)} | {_cell(w.get('comment', ''))} |"
            for w in result.written]
    versions = sorted({for_students(w["rubric"]) for w in result.written if w.get("rubric")})
    return out + ["", *(f"- Written answers graded with the rubric {v}" for v in versions)]


def feedback_markdown(student, results):
    """Per-student feedback in Markdown: scores, a table of tests, reasons, late work, how to reproduce."""
    results = _records(results)
    score, top = _totals(results)
    out = [f"# Feedback for {student}", "", f"**Total: {_fmt(score)} / {_fmt(top)} points**", ""]
    if any(t.figures for r in results for t in r.tests):
        out += ["Figures of your curves beside the reference's are in `feedback.html`, beside this file.", ""]
    for result in results:
        out += [f"## {result.exercise}: {_fmt(result.total)} / {_fmt(result.total_max)}", ""]
        if result.notebook:
            out += [f"Graded notebook: `{submitted_name(result.notebook)}`", ""]
        out += ["| | test | points | what happened |", "| --- | --- | ---: | --- |"]
        for test in result.tests:
            mark = "✅" if test.passed else "❌"
            name = test.title + (" *(hidden)*" if test.hidden else "")
            out.append(f"| {mark} | {_cell(name)} | {_fmt(test.score)} / {_fmt(test.max_score)} | "
                       f"{_cell('' if test.passed else for_students(test.reason))} |")
        out.append("")
        out += _written_markdown(result)
        out += [f"- {for_students(note)}" for note in result.notes]
        if result.seed is not None and any(t.hidden for t in result.tests):
            out.append(f"- Hidden tests drew their random parameters with seed {result.seed}.")
        out += [f"- {line}" for line in result.late_lines()]
        out.append("")
    return "\n".join(out).rstrip("\n") + "\n"


_CSS = """
body { font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: #1d1d1f;
       background: #fafafa; margin: 0; }
main { max-width: 60rem; margin: 0 auto; padding: 1.5rem 1.25rem 3rem; }
h1 { font-size: 1.6rem; margin: 0 0 .25rem; }
h2 { font-size: 1.2rem; margin: 2rem 0 .5rem; padding-bottom: .25rem; border-bottom: 1px solid #ddd; }
.total { font-size: 1.1rem; font-weight: 600; }
.meta, .notes { color: #555; font-size: .9rem; }
table { border-collapse: collapse; width: 100%; background: #fff; table-layout: fixed; }
col.mark { width: 2rem; } col.test { width: 42%; } col.points { width: 5.5rem; }
td { overflow-wrap: anywhere; }
th, td { text-align: left; vertical-align: top; padding: .4rem .55rem; border-bottom: 1px solid #e5e5e5; }
th { font-size: .85rem; color: #555; font-weight: 600; }
td.points { white-space: nowrap; text-align: right; }
td.mark { width: 1.5rem; font-weight: 700; }
tr.passed td.mark { color: #1a7f37; }
tr.failed td.mark { color: #c62828; }
tr.failed td.reason { color: #8a1c1c; }
.hidden-tag { font-size: .75rem; color: #666; border: 1px solid #bbb; border-radius: .6rem; padding: 0 .4rem; }
tr.figures td { border-bottom: 1px solid #e5e5e5; padding-top: 0; }
details summary { cursor: pointer; color: #0b57d0; font-size: .9rem; margin: .2rem 0 .4rem; }
.figure-list { display: flex; flex-wrap: wrap; gap: .75rem; }
figure.feedback-figure { margin: 0; background: #fff; border: 1px solid #e0e0e0; padding: .35rem; max-width: 100%; }
figure.feedback-figure img { display: block; max-width: 100%; height: auto; }
figcaption { font-size: .8rem; color: #555; max-width: 26rem; margin-top: .25rem; }
code { font-size: .85em; background: #eee; padding: 0 .2rem; border-radius: .2rem; }
"""


def _figures_row(test):
    if not test.figures:
        return ""
    count = f"{len(test.figures)} figure{'s' if len(test.figures) > 1 else ''}"
    inner = "".join(figures.figure_html(f) for f in test.figures)
    return (f'<tr class="figures"><td></td><td colspan="3"><details{"" if test.passed else " open"}>'
            f"<summary>Your curve beside the reference ({count})</summary>"
            f'<div class="figure-list">{inner}</div></details></td></tr>')


def _written_html(result):
    """A record's written answers as an HTML table ("" without a rubric)."""
    if not result.written:
        return ""
    e = html.escape
    rows = "".join(f'<tr><td>Question {e(str(w["question"]))}</td><td class="points">{e(_written_points(w))}'
                   f'</td><td>{e(w.get("comment", ""))}</td></tr>' for w in result.written)
    versions = sorted({for_students(w["rubric"]) for w in result.written if w.get("rubric")})
    return (f'<p class="meta">{e(_written_summary(result))}</p>'
            '<table class="written"><colgroup><col class="test"><col class="points"><col></colgroup>'
            f"<thead><tr><th>written answer</th><th>points</th><th>comment</th></tr></thead><tbody>{rows}"
            "</tbody></table>" + "".join(f'<p class="meta">Graded with the rubric <code>{e(v)}</code></p>'
                                         for v in versions))


def feedback_html(student, results):
    """Per-student feedback as one self-contained HTML page: scores, tests, reasons, figures.

    Parameters
    ----------
    student : str
    results : list of SubmissionRecord
        One per exercise graded.

    Returns
    -------
    str
        The page: inline CSS, figures as inline PNG images (open under the
        failed tests, folded under the passed ones), no scripts and no
        external resources (its Content-Security-Policy forbids them).
    """
    e = html.escape
    results = _records(results)
    score, top = _totals(results)
    out = ['<!DOCTYPE html>', '<html lang="en">', "<head>", '<meta charset="utf-8">',
           '<meta http-equiv="Content-Security-Policy" content="default-src \'none\'; img-src data:; '
           'style-src \'unsafe-inline\'">',
           '<meta name="viewport" content="width=device-width, initial-scale=1">',
           f"<title>Feedback for {e(student)}</title>", f"<style>{_CSS}</style>", "</head>", "<body><main>",
           f"<h1>Feedback for {e(student)}</h1>", f'<p class="total">Total: {_fmt(score)} / {_fmt(top)} points</p>']
    for result in results:
        out.append(f'<section class="exercise"><h2>{e(result.exercise)}: {_fmt(result.total)} / '
                   f'{_fmt(result.total_max)}</h2>')
        if result.notebook:
            out.append(f'<p class="meta">Graded notebook: <code>{e(submitted_name(result.notebook))}</code></p>')
        out.append('<table><colgroup><col class="mark"><col class="test"><col class="points"><col></colgroup>'
                   "<thead><tr><th></th><th>test</th><th>points</th><th>what happened</th></tr></thead><tbody>")
        for test in result.tests:
            status = "passed" if test.passed else "failed"
            hidden = ' <span class="hidden-tag">hidden</span>' if test.hidden else ""
            out.append(f'<tr class="{status}"><td class="mark">{"✓" if test.passed else "✗"}</td>'
                       f"<td>{e(test.title)}{hidden}</td>"
                       f'<td class="points">{_fmt(test.score)} / {_fmt(test.max_score)}</td>'
                       f'<td class="reason">{"" if test.passed else e(for_students(test.reason))}</td></tr>')
            out.append(_figures_row(test))
        out.append("</tbody></table>")
        out.append(_written_html(result))
        notes = [e(for_students(n)) for n in result.notes]
        if result.seed is not None and any(t.hidden for t in result.tests):
            notes.append(f"Hidden tests drew their random parameters with seed {e(str(result.seed))}.")
        notes += [e(line) for line in result.late_lines()]
        if notes:
            out.append('<ul class="notes">' + "".join(f"<li>{n}</li>" for n in notes) + "</ul>")
        out.append("</section>")
    out += ["</main></body>", "</html>"]
    return "\n".join(line for line in out if line) + "\n"


def write_gradebook(path, rows, exercises, status=None):
    """Write the gradebook CSV: one row per student, one column per exercise, total, max_total, status.

    An exercise's cell is the record's :attr:`~particles.course.results.records.SubmissionRecord.total`
    (tests, written answers graded by people, minus the late penalty).

    Parameters
    ----------
    rows : dict
        student -> list of :class:`~particles.course.results.records.SubmissionRecord`, one per exercise.
    exercises : list of str
        Column order. An exercise a student did not submit is left empty.
    status : dict, optional
        student -> what their row still waits for (a notebook not graded yet, a run interrupted): a row is
        never silently partial. A student with a status and no record gets a row of empty cells.
    """
    status = status or {}
    rows = {student: _records(results) for student, results in rows.items()}
    rows.update({student: [] for student in status if student not in rows})
    maxima = {}
    for results in rows.values():
        for r in results:
            maxima[r.exercise] = max(maxima.get(r.exercise, 0), r.total_max)
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["student", *exercises, "total", "max_total", "status"])
        for student in sorted(rows):
            by_exercise = {r.exercise: r.total for r in rows[student]}
            total = sum(by_exercise.values())
            writer.writerow([student, *[_fmt(by_exercise[e]) if e in by_exercise else "" for e in exercises],
                             _fmt(total), _fmt(sum(maxima.get(e, 0) for e in exercises)),
                             status.get(student, "complete")])


def write_json(path, data):
    """Write `data` as indented JSON with a final newline."""
    with open(path, "w") as handle:
        json.dump(data, handle, indent=2)
        handle.write("\n")


_written = {}  # (folder, hidden_visibility) -> digest of the results its files were last written from


def write_outputs(out, done, tests, hidden_visibility, students=None, written=None, status=None):
    """A grading run's folder `out`: results.json, feedback.md and feedback.html of `students` (default: all),
    and the gradebook, as far as the records of `done` (``(student, exercise) -> SubmissionRecord``) go.

    `written` (a :class:`~particles.course.results.rubric.WrittenGrades`) is merged first into every
    record, so that a changed rubric rewrites exactly the students whose grades it changes; `status` (student ->
    text) goes into the gradebook's ``status`` column.

    A student's files are rewritten only when their results changed since this
    process last wrote them (the final call of a run then draws no figure again).
    """
    written = written or WrittenGrades()
    written.apply(done.values())
    for record in done.values():  # a late penalty is a fraction of the points, written grades included
        if record.late:
            record.late["penalty"] = record.penalty
    by_student = {}
    for (student, _), result in done.items():
        by_student.setdefault(student, []).append(result)
    order = {name: k for k, name in enumerate(tests)}
    for results in by_student.values():
        results.sort(key=lambda r: order.get(r.exercise, len(order)))
    for student in (by_student if students is None else set(students)):
        folder = out / student
        results = by_student[student]
        key = (str(folder.resolve()), hidden_visibility)
        digest = hashlib.sha256(json.dumps([r.to_dict() for r in results], sort_keys=True,
                                           default=str).encode()).hexdigest()
        names = ("results.json", "feedback.md", "feedback.html")
        if _written.get(key) == digest and all((folder / name).exists() for name in names):
            continue
        folder.mkdir(parents=True, exist_ok=True)
        write_json(folder / "results.json", gradescope_results(student, results, hidden_visibility,
                                                               manual=written.manual()))
        (folder / "feedback.md").write_text(feedback_markdown(student, results))
        (folder / "feedback.html").write_text(feedback_html(student, results), encoding="utf-8")
        _written[key] = digest
    exercises = [name for name in tests if any(r.exercise == name for rs in by_student.values() for r in rs)]
    write_gradebook(out / "gradebook.csv", by_student, exercises, status)
