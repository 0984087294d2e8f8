"""What grading writes: Gradescope ``results.json``, a gradebook CSV, Markdown feedback.

All three are made from the same records: per submission (a student), per
exercise, one record per test with ``test``, ``name``, ``points``,
``hidden``, ``passed``, ``reason``, ``seed`` (see :mod:`particles.course.plugin`).
"""

import csv
import json

__all__ = ["score_of", "gradescope_results", "feedback_markdown", "write_gradebook", "VISIBILITIES"]

VISIBILITIES = ("hidden", "after_due_date", "after_published", "visible")
"""Gradescope's visibility settings of a test."""


def score_of(tests):
    """(score, max_score) of a list of test records."""
    return (sum(t["points"] for t in tests if t["passed"]), sum(t["points"] for t in tests))


def _fmt(x):
    return f"{x:g}"


def _test_output(test, seed):
    text = "passed" if test["passed"] else test["reason"]
    if test["hidden"] and test.get("seed") is not None:
        text += f" (random parameters, seed {test['seed']})"
    return text


def gradescope_results(student, results, hidden_visibility="after_published"):
    """A Gradescope ``results.json`` dict for one submission.

    Parameters
    ----------
    student : str
    results : list of dict
        One per exercise graded: ``exercise``, ``seed``, ``tests``, ``notes``
        (lines about loading the notebook) and ``seconds``.
    hidden_visibility : str
        Gradescope visibility of hidden tests (one of :data:`VISIBILITIES`).
    """
    if hidden_visibility not in VISIBILITIES:
        raise ValueError(f"hidden_visibility must be one of {VISIBILITIES}, got {hidden_visibility!r}")
    tests, lines = [], []
    for result in results:
        score, top = score_of(result["tests"])
        lines.append(f"{result['exercise']}: {_fmt(score)} / {_fmt(top)} points")
        lines += [f"  {note}" for note in result.get("notes", [])]
        if result.get("sandbox"):
            lines.append(f"  Sandbox of your code: {result['sandbox']}")
        for k, test in enumerate(result["tests"], start=1):
            tests.append({
                "name": f"{result['exercise']}: {test['name']}",
                "number": f"{result['exercise'][:2]}.{k}",
                "score": test["points"] if test["passed"] else 0.0,
                "max_score": test["points"],
                "status": "passed" if test["passed"] else "failed",
                "output": _test_output(test, result.get("seed")),
                "visibility": hidden_visibility if test["hidden"] else "visible",
                "tags": [result["exercise"]] + (["hidden"] if test["hidden"] else []),
                "extra_data": {"test": test["test"]},
            })
    score, top = score_of([t for r in results for t in r["tests"]])
    return {
        "score": score,
        "max_score": top,
        "execution_time": round(sum(r.get("seconds", 0.0) for r in results), 2),
        "output": "\n".join(lines),
        "visibility": "visible",
        "stdout_visibility": "hidden",
        "extra_data": {"student": student, "seeds": {r["exercise"]: r.get("seed") for r in results},
                       "sandbox": {r["exercise"]: r.get("isolation", {}) for r in results}},
        "tests": tests,
    }


def _cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def feedback_markdown(student, results):
    """Per-student feedback in Markdown: scores, a table of tests, reasons, how to reproduce."""
    score, top = score_of([t for r in results for t in r["tests"]])
    out = [f"# Feedback for {student}", "", f"**Total: {_fmt(score)} / {_fmt(top)} points**", ""]
    for result in results:
        s, m = score_of(result["tests"])
        out += [f"## {result['exercise']}: {_fmt(s)} / {_fmt(m)}", ""]
        if result.get("notebook"):
            out += [f"Graded notebook: `{result['notebook']}`", ""]
        out += ["| | test | points | what happened |", "| --- | --- | ---: | --- |"]
        for test in result["tests"]:
            mark = "✅" if test["passed"] else "❌"
            name = test["name"] + (" *(hidden)*" if test["hidden"] else "")
            got = test["points"] if test["passed"] else 0
            out.append(f"| {mark} | {_cell(name)} | {_fmt(got)} / {_fmt(test['points'])} | "
                       f"{_cell('' if test['passed'] else test['reason'])} |")
        out.append("")
        for note in result.get("notes", []):
            out.append(f"- {note}")
        if result.get("seed") is not None and any(t["hidden"] for t in result["tests"]):
            out.append(f"- Hidden tests drew their random parameters with seed {result['seed']}.")
        out.append("")
    return "\n".join(out).rstrip("\n") + "\n"


def write_gradebook(path, rows, exercises):
    """Write the gradebook CSV: one row per student, one column per exercise, total, max_total.

    Parameters
    ----------
    rows : dict
        student -> list of per-exercise results (as for :func:`gradescope_results`).
    exercises : list of str
        Column order. An exercise a student did not submit is left empty.
    """
    maxima = {}
    for results in rows.values():
        for r in results:
            maxima[r["exercise"]] = max(maxima.get(r["exercise"], 0), score_of(r["tests"])[1])
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["student", *exercises, "total", "max_total"])
        for student in sorted(rows):
            by_exercise = {r["exercise"]: score_of(r["tests"])[0] for r in rows[student]}
            total = sum(by_exercise.values())
            writer.writerow([student, *[_fmt(by_exercise[e]) if e in by_exercise else "" for e in exercises],
                             _fmt(total), _fmt(sum(maxima.get(e, 0) for e in exercises))])


def write_json(path, data):
    """Write `data` as indented JSON with a final newline."""
    with open(path, "w") as handle:
        json.dump(data, handle, indent=2)
        handle.write("\n")
