"""The report stage of a grading run: the gradebook, each student's feedback, Gradescope's file, the summary.

Students' outputs are written as their records arrive (:func:`progress_report`), and once more at the end
of the run from every record (:func:`write_reports`), when written grades and late decisions are brought
up to date in the record too. The formats themselves are :mod:`particles.course.results.reports`'.
"""

from pathlib import Path

from ..results.records import SubmissionRecord, TestRecord
from ..results.reports import gradescope_results, write_gradebook, write_json, write_outputs
from ..results.shown import for_students
from ..walls import isolation as isolation_module
from .session import NOT_RUN, catalog

__all__ = ["progress_report", "statuses", "write_partial_gradebook", "summarize", "write_reports", "write_gradescope",
           "LIBRARY_CHANGED"]

LIBRARY_CHANGED = "LIBRARY-CHANGED.txt"
"""The file in the output folder of a run during which the installed library changed."""


def statuses(done, pending, run=None):
    """student -> what their gradebook row is still waiting for ("" when nothing).

    Parameters
    ----------
    done : dict
        ``(student, exercise) -> SubmissionRecord``: an incomplete record (a notebook no machine could grade) is
        "not graded yet".
    pending : iterable of (student, exercise, run)
        Notebooks a run meant to grade and no run has graded since (run None: this run, still going).
    """
    waiting, said = {}, set()
    for (student, exercise), record in done.items():  # a notebook no machine could grade: says why
        lost = [note for note in record.notes if note.startswith("Not graded yet")]
        if not record.complete and lost:
            waiting.setdefault(student, []).append(f"{exercise} not graded yet ({lost[0][len('Not graded yet: '):]}; "
                                                   "rerun with --resume)")
            said.add((student, exercise))
    for student, exercise, started in pending:
        if (student, exercise) in said:
            continue
        why = "this run has not finished" if started is None else (
            f"run {started} did not grade it" if started == run else f"run {started} was interrupted")
        waiting.setdefault(student, []).append(f"{exercise} not graded yet ({why}; rerun with --resume)")
    return {student: "; ".join(items) for student, items in waiting.items()}


def progress_report(options, written):
    """``report(done, students, todo)``: the outputs of `students` written from the records `done` so far, the
    gradebook saying which notebooks (`todo`) this run has still to grade.

    Returns None when the run has no output folder (nothing is written).
    """
    if options.out is None:
        return None

    def report(done, students, todo):
        status = statuses(done, [(s, e, None) for s, e in todo])
        write_outputs(options.out, done, options.tests, options.hidden_visibility, students=students,
                      written=written, status=status)

    return report


def write_partial_gradebook(options, done, todo):
    """The gradebook of a run stopped early (Ctrl-C): every record so far, and what is not graded yet (no feedback
    is drawn: this must be quick)."""
    if options.out is None:
        return
    by_student = {}
    for (student, _), record in done.items():
        by_student.setdefault(student, []).append(record)
    exercises = [name for name in options.tests if any(e == name for _, e in [*done, *todo])]
    write_gradebook(options.out / "gradebook.csv", by_student, exercises,
                    statuses(done, [(s, e, None) for s, e in todo]))


def summarize(tests, units, done, problems, plan, kept, others):
    """What :func:`~particles.course.grading.driver.grade` returns.

    Parameters
    ----------
    tests : dict
        The course's exercises, in order (:attr:`~particles.course.grading.options.GradeOptions.tests`).
    units : list of Unit
        The run's notebooks (rejected ones too).
    done : dict
        ``(student, exercise) -> SubmissionRecord``, one for each unit (and the others' records kept).
    problems : list of str
    plan : particles.course.walls.isolation.Plan
        The walls planned (said when no notebook was run).
    kept : int
        Records kept from an earlier run (``--resume``).
    others : dict
        Records of other students kept as they were (``--student``).
    """
    results = [done[(u.student, u.exercise)] for u in units]
    graded = {}
    for result in results:
        graded.setdefault(result.student, []).append(result)
    exercises = [name for name in tests if any(u.exercise == name for u in units)]
    layers = [r.isolation for r in results if r.isolation]
    walls = (isolation_module.describe(layers[0] if layers else {}) if results
             else f"planned: {plan.to_option()}")
    return {"students": graded, "exercises": exercises, "problems": problems, "isolation": walls,
            "resumed": kept, "kept": len(others), "rejected": [u.where for u in units if u.rejected]}


def write_reports(options, done, recorder, written, changed):
    """The outputs of every student and the gradebook, from every record; the records brought up to date.

    Parameters
    ----------
    options : GradeOptions
    done : dict
        ``(student, exercise) -> SubmissionRecord``.
    recorder : particles.course.grading.record.Recorder
    written : particles.course.results.rubric.WrittenGrades
    changed : list of str
        Files of the library that changed during the run: said in ``LIBRARY-CHANGED.txt``.
    """
    if options.out is None:
        return
    status = statuses(done, recorder.pending(), getattr(recorder, "run", None))
    write_outputs(options.out, done, options.tests, options.hidden_visibility, written=written, status=status)
    for record in done.values():  # the record holds what the feedback says: written grades, late work
        recorder.update(record)
    if changed:
        (options.out / LIBRARY_CHANGED).write_text(
            "The installed particles library changed while these submissions were graded:\n"
            + "".join(f"  {name}\n" for name in changed) + "Do not trust these grades.\n")


def write_gradescope(options, results, problems, walls, written, changed):
    """Gradescope's ``results.json`` of one submission (``options.gradescope``) from its records.

    A submission without a gradable notebook of the exercise fails every test, saying why; a run during
    which the grader's own files changed scores nothing (no score is better than a forged one).
    """
    if not results and options.exercise is not None:
        why = "no notebook for this exercise was found in your submission" if not problems else problems[0]
        tests = catalog(options.root, options.exercise, options.public_only, options.python)
        results = [SubmissionRecord(student="submission", exercise=options.exercise, sandbox=walls,
                                    notes=[f"Not graded: {why}"],
                                    tests=[TestRecord.from_dict(t).failed(NOT_RUN) for t in tests])]
        problems = problems[1:]
    written.apply(results)
    data = gradescope_results("submission", results, options.hidden_visibility, manual=written.manual())
    said = {note.removeprefix("Not graded: ") for r in results for note in r.notes}
    problems = [p for p in problems if p.split(": 0 points: ", 1)[-1] not in said]  # each reason once
    if problems:
        data["output"] = "\n".join([data["output"], *map(for_students, problems)]).strip()
    if changed:
        data = {"score": 0, "output": "The autograder's own files changed while grading this submission; "
                "it was not graded. Please tell the instructors.", "tests": [], "visibility": "visible"}
    Path(options.gradescope).parent.mkdir(parents=True, exist_ok=True)
    write_json(options.gradescope, data)
