"""``particles grade SUBMISSION... --out DIR``: the autograder (see :mod:`particles.course.grading.driver`)."""

import sys
from pathlib import Path

from .common import add_root, course_root


def options(args):
    """The :class:`~particles.course.grading.options.GradeOptions` of the command line's arguments."""
    from ..course.grading.options import GradeOptions

    return GradeOptions(
        paths=tuple(args.submissions), out=args.out, jobs=args.jobs, exercise=args.exercise,
        public_only=args.public, seed=args.seed, time_limit=args.time_limit, memory_mb=args.memory_mb,
        root=course_root(args), private=tuple(args.private), hidden_visibility=args.hidden_visibility,
        gradescope=args.gradescope, isolation=args.isolation, resume=args.resume, rubric=tuple(args.rubric),
        course=args.course, times=args.times, times_from=args.times_from, roster=args.roster,
        name_column=args.name_column, metadata=args.metadata, students=args.student, scheduler=args.scheduler,
        scheduler_file=args.scheduler_file)


def progress(result):
    """One line per notebook graded, as it is."""
    print(f"  graded {result.student:<24} {result.exercise:<16} {result.score:>5g} / {result.max_score:<5g}"
          f" ({result.seconds:.1f} s)" + (f", late: -{result.penalty:g}" if result.penalty else ""), flush=True)


def print_table(summary):
    """The gradebook of the run: a row per student, a column per exercise (tests + written - late)."""
    exercises = summary["exercises"]
    print()
    print(f"{'student':<24}" + "".join(f"{e:>14}" for e in exercises) + f"{'total':>12}")
    for student, results in sorted(summary["students"].items()):
        by = {r.exercise: (r.total, r.total_max) for r in results}
        cells = "".join(f"{(f'{by[e][0]:g}/{by[e][1]:g}' if e in by else '-'):>14}" for e in exercises)
        total = sum(s for s, _ in by.values()), sum(m for _, m in by.values())
        print(f"{student:<24}{cells}{f'{total[0]:g}/{total[1]:g}':>12}")


def _ungraded(summary):
    """Say the written answers a rubric names but does not grade yet (they count 0 until it does)."""
    left = [(r.student, r.exercise, w["question"]) for results in summary["students"].values() for r in results
            for w in r.written if w.get("points") is None]
    if left:
        shown = ", ".join(f"{s} {e} question {q}" for s, e, q in sorted(left)[:10])
        print(f"rubric: {len(left)} written answer(s) not graded yet, counted 0 until they are: {shown}"
              + (", ..." if len(left) > 10 else ""), file=sys.stderr)


def report(args, summary):
    """What the run did, and its exit status: 1 when nothing was graded or a notebook was scored unseen."""
    print(f"sandbox: {summary['isolation']}")
    if summary.get("resumed"):
        print(f"resumed: {summary['resumed']} record(s) kept from the earlier run")
    if args.student:
        print(f"regraded: {', '.join(args.student)}; "
              f"kept {summary.get('kept', 0)} record(s) of the others as they were")
    for problem in summary["problems"]:
        print(f"not graded: {problem}", file=sys.stderr)
    if summary["students"]:
        print_table(summary)
    if args.rubric:
        _ungraded(summary)
    if args.out:
        print(f"\ngradebook of the term: {Path(args.out) / 'gradebook.csv'}; per student: results.json, feedback.md "
              f"and feedback.html; the record: {Path(args.out) / 'course.sqlite'}")
    if not summary["students"] and not args.gradescope:
        print("particles grade: no notebooks were graded", file=sys.stderr)
        return 1
    if summary.get("rejected"):  # every record is written, but someone must look at these
        print(f"particles grade: {len(summary['rejected'])} notebook(s) scored 0 without being run (see "
              "'not graded' above): a malformed notebook, or one student's notebooks from two places",
              file=sys.stderr)
        return 1
    return 0


def run(args):
    from ..course.grading.cluster_tasks import ClusterError
    from ..course.grading.driver import GradingInterrupted, LibraryChanged, run_grading
    from ..course.walls.isolation import IsolationUnavailable

    try:
        summary = run_grading(options(args), progress=progress)
    except GradingInterrupted as stopped:  # Ctrl-C: one line, the record consistent
        print(f"particles grade: {stopped}", file=sys.stderr)
        return 130
    except (ValueError, IsolationUnavailable, ClusterError) as error:
        print(f"particles grade: {error}", file=sys.stderr)
        return 2
    except LibraryChanged as error:
        print(f"particles grade: GRADING FAILED: {error}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:  # the batches not finished are dropped (on a cluster: cancelled); records are kept
        print("particles grade: interrupted; the records made so far are kept: run the same command with "
              "--resume to grade the rest", file=sys.stderr)
        return 130
    return report(args, summary)


def register(commands):
    grade = commands.add_parser("grade", help="grade notebooks (files or folders) with the exercise tests")
    grade.add_argument("submissions", nargs="+", metavar="SUBMISSION",
                       help="a notebook, a folder of them (a folder per student) or an LMS's zip of them")
    grade.add_argument("--out", help="write gradebook.csv, <student>/results.json and feedback.md here")
    grade.add_argument("--jobs", type=int, default=1, help="notebooks graded in parallel (default 1)")
    grade.add_argument("--exercise", help="grade every notebook as this exercise")
    grade.add_argument("--public", action="store_true", help="run only the public tests (what students run)")
    grade.add_argument("--seed", type=int, help="seed of the hidden tests (default: random, recorded)")
    grade.add_argument("--time-limit", type=float, help="seconds per call of student code (default 5)")
    grade.add_argument("--memory-mb", type=int, help="memory the student code may use, MiB (default 1024)")
    grade.add_argument("--private", action="append", default=[], help="another path submissions may not read")
    grade.add_argument("--gradescope", metavar="FILE", help="also write one combined Gradescope results.json")
    grade.add_argument("--hidden-visibility", default="after_published",
                       choices=["hidden", "after_due_date", "after_published", "visible"],
                       help="Gradescope visibility of hidden tests (default after_published)")
    add_root(grade)
    grade.add_argument("--isolation", choices=["auto", "strict"], default="auto",
                       help="auto: the strongest sandbox this machine allows (default); strict: refuse to grade "
                            "without the namespace sandbox")
    grade.add_argument("--resume", action="store_true",
                       help="keep the records in OUT/records of unchanged notebooks and grade only the rest")
    grade.add_argument("--rubric", action="append", default=[], metavar="FILE",
                       help="a rubric of the written answers (CSV, as `particles review` writes it) or a folder "
                            "of them, merged into the records; repeatable; checked before grading (exit 2)")
    grade.add_argument("--course", metavar="FILE",
                       help="deadlines and late policy (TOML; default: course.toml in the course folder, if any)")
    grade.add_argument("--times", metavar="FILE",
                       help="submission times, a CSV student,exercise,submitted (Gradescope's export carries its own)")
    grade.add_argument("--times-from", choices=["mtime"],
                       help="mtime: accept the notebook files' modification times as submission times where nothing "
                            "else gives one (by default a deadline without submission times stops the run, exit 2)")
    grade.add_argument("--roster", metavar="FILE",
                       help="who is in the course: a CSV of students, their LMS identifiers and aliases (default: "
                            "the course file's roster); every name the run meets must be a roster student's")
    grade.add_argument("--name-column", default="submission_name",
                       help="the roster's column of the grader's names (default submission_name; Canvas's "
                            "gradebook export: \"SIS Login ID\")")
    grade.add_argument("--metadata", metavar="FILE",
                       help="Gradescope's submission_metadata.json: its created_at is the submission time")
    grade.add_argument("--student", action="append", metavar="ID",
                       help="regrade only this student (repeatable); needs --out with the records of an earlier "
                            "run, keeps the others' and rewrites the gradebook")
    grade.add_argument("--scheduler", metavar="ADDRESS",
                       help="grade on a Dask cluster (pip install 'particles[cluster]'): local:N for N worker "
                            "processes on this machine, or a running scheduler's tcp://HOST:PORT (this machine "
                            "only) or tls://HOST:PORT, whose workers run particles grade-worker")
    grade.add_argument("--scheduler-file", metavar="FILE",
                       help="grade on the Dask cluster of this scheduler file (dask scheduler --scheduler-file)")
    grade.set_defaults(run=run)
