"""The ``particles`` command line: the tour, demos, studies, the course site, and the course tools."""

import argparse
import sys
from pathlib import Path

__all__ = ["main"]


def _tour(args):
    from .tour import run_tour

    run_tour(args.out)
    return 0


def _demo(args):
    from .demos import DEMOS, write_demo

    names = list(DEMOS) if args.name == "all" else [args.name]
    for name in names:  # a loop over demos
        data, paths = write_demo(name, args.out, seconds=args.seconds, fps=args.fps, seed=args.seed,
                                 html=args.html)
        info = ", ".join(f"{k} {v}" for k, v in data.info.items())
        print(f"{name}: {len(data)} frames, {info} -> {', '.join(str(p) for p in paths)}")
    return 0


def _study(args):
    from .studies.report import write_study

    write_study(args.name, args.out)
    return 0


def _site(args):
    from .course.release.site import build_site

    try:
        build_site(args.out, args.lectures, timeout=args.timeout)
    except ValueError as error:  # a missing or empty lectures folder
        print(f"particles site: {error}", file=sys.stderr)
        return 2
    return 0


def _check(args):
    from .course.check import CheckError, check
    from .course.paths import exercise_tests, project_root

    try:
        root = project_root()
        known = exercise_tests(root)
        if args.exercise not in known:
            raise ValueError(f"unknown exercise {args.exercise!r}; expected one of {', '.join(known)}")
        notebook = args.notebook
        if notebook is None:  # the exercise's notebook here, else in the course's exercises/
            here = Path(f"{args.exercise}.ipynb")
            notebook = here if here.is_file() else root / "exercises" / here
        if not Path(notebook).is_file():
            raise ValueError(f"no notebook {notebook}; name it: particles check {args.exercise} PATH.ipynb")
        result = check(args.exercise, notebook=str(notebook), time_limit=args.time_limit, root=root)
    except (ValueError, CheckError) as error:  # no course folder, an unknown exercise, pytest missing, ...
        print(f"particles check: {error}", file=sys.stderr)
        return 2
    print(result)
    return 0 if result.passed else 1


def _root(args):
    from .course.paths import project_root

    return Path(args.root).resolve() if args.root else project_root()


def _release(args):
    from .course.release.notebooks import release, ReleaseError, write_bundle

    try:
        root = _root(args)
        if args.check:
            problems = release(root, check=True)
            for problem in problems:
                print(f"out of date: {problem}")
            if problems:
                print("run `particles release` to regenerate exercises/ from solutions/", file=sys.stderr)
                return 1
            print("exercises/ is up to date with solutions/")
            return 0
        if args.bundle:
            files = write_bundle(root, args.bundle)
            print(f"wrote the student bundle: {len(files)} files in {args.bundle}")
            return 0
        written = release(root)
        for name in written:
            print(f"wrote {name}")
        if not written:
            print("exercises/ is up to date with solutions/")
        return 0
    except (ReleaseError, ValueError) as error:
        print(f"particles release: {error}", file=sys.stderr)
        return 2


def _grade(args):
    from .course.grading.driver import grade, LibraryChanged
    from .course.walls.isolation import IsolationUnavailable
    def progress(result):
        print(f"  graded {result.student:<24} {result.exercise:<16} {result.score:>5g} / {result.max_score:<5g}"
              f" ({result.seconds:.1f} s)" + (f", late: -{result.penalty:g}" if result.penalty else ""), flush=True)

    try:
        summary = grade(
            args.submissions, args.out, jobs=args.jobs, exercise=args.exercise, public_only=args.public,
            seed=args.seed, time_limit=args.time_limit, memory_mb=args.memory_mb, root=_root(args),
            private=args.private, hidden_visibility=args.hidden_visibility, gradescope=args.gradescope,
            progress=progress, isolation=args.isolation, resume=args.resume, rubric=args.rubric, course=args.course,
            times=args.times, metadata=args.metadata, students=args.student,
        )
    except (ValueError, IsolationUnavailable) as error:
        print(f"particles grade: {error}", file=sys.stderr)
        return 2
    except LibraryChanged as error:
        print(f"particles grade: GRADING FAILED: {error}", file=sys.stderr)
        return 3
    print(f"sandbox: {summary['isolation']}")
    if summary.get("resumed"):
        print(f"resumed: {summary['resumed']} record(s) kept from the earlier run")
    if args.student:
        print(f"regraded: {', '.join(args.student)}; "
              f"kept {summary.get('kept', 0)} record(s) of the others as they were")
    for problem in summary["problems"]:
        print(f"not graded: {problem}", file=sys.stderr)
    exercises = summary["exercises"]
    if summary["students"]:
        print()
        print(f"{'student':<24}" + "".join(f"{e:>14}" for e in exercises) + f"{'total':>12}")
        for student, results in sorted(summary["students"].items()):
            by = {r.exercise: (r.total, r.total_max) for r in results}  # tests + written - late penalty
            cells = "".join(f"{(f'{by[e][0]:g}/{by[e][1]:g}' if e in by else '-'):>14}" for e in exercises)
            total = sum(s for s, _ in by.values()), sum(m for _, m in by.values())
            print(f"{student:<24}{cells}{f'{total[0]:g}/{total[1]:g}':>12}")
    if args.out:
        print(f"\ngradebook: {Path(args.out) / 'gradebook.csv'}; per student: results.json, feedback.md and feedback.html")
    if not summary["students"] and not args.gradescope:
        print("particles grade: no notebooks were graded", file=sys.stderr)
        return 1
    if summary.get("rejected"):  # every record is written, but someone must look at these
        print(f"particles grade: {len(summary['rejected'])} notebook(s) scored 0 without being run (see "
              "'not graded' above): a malformed notebook, or one student's notebooks from two places",
              file=sys.stderr)
        return 1
    return 0


def _export(args):
    from .course.results.lms import ExportError, RosterError, export_grades

    try:
        done = export_grades(args.out, args.roster, canvas=args.canvas, moodle=args.moodle,
                             name_column=args.name_column, moodle_id=args.moodle_id)
    except (RosterError, ExportError, ValueError) as error:
        print(f"particles export: {error}", file=sys.stderr)
        return 2
    export = done["export"]
    print(f"{len(export.students)} students on the roster; exercises: {', '.join(export.exercises) or 'none'}")
    for fmt, path in done["files"].items():
        left = len(done["left_out"].get(fmt, []))
        print(f"wrote {path} ({fmt}): {len(export.students) - left} students")
    for student, exercise in export.missing():
        print(f"missing: {student.submission_name} has no graded {exercise}: exported as 0")
    for student in done["name_only"]:
        print(f"warning: {student.submission_name} (roster line {student.line}) has no Canvas ID, SIS User ID or "
              "SIS Login ID: Canvas can match it only by name", file=sys.stderr)
    for name, record in export.unmatched:
        print(f"not on the roster: {record.student} ({record.exercise}, {record.total:g}/{record.total_max:g} "
              f"points, records/{name}): not exported", file=sys.stderr)
    for fmt, students in done["left_out"].items():
        for student in students:
            print(f"left out of the {fmt} file: {student.submission_name} (roster line {student.line}) has no "
                  f"{args.moodle_id}", file=sys.stderr)
    print(f"report: {done['report']}")
    return 1 if export.unmatched or any(done["left_out"].values()) else 0


def _review(args):
    from .course.results.review import write_review

    try:
        summary = write_review(args.submissions, args.out, root=_root(args), exercise=args.exercise)
    except ValueError as error:  # an unknown exercise, a master's unreadable points, a file in the way
        print(f"particles review: {error}", file=sys.stderr)
        return 2
    for problem in summary["problems"]:
        print(f"not reviewed: {problem}", file=sys.stderr)
    if not summary["pages"]:
        print("particles review: no written answers to review", file=sys.stderr)
        return 1
    print(f"wrote {len(summary['pages'])} question pages of {summary['students']} students: "
          f"{Path(args.out) / 'index.html'}")
    for path in summary["rubrics"]:
        print(f"rubric to fill in: {path}")
    if summary["kept"]:
        print(f"kept {summary['kept']} graded row(s) already in the rubrics")
    print(f"then: particles grade ... --rubric {args.out}")
    return 0


def _gradescope_bundle(args):
    from .course.results.gradescope import write_bundle

    try:
        names = write_bundle(_root(args), args.out, exercise=args.exercise)
    except ValueError as error:
        print(f"particles gradescope-bundle: {error}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}: {len(names)} files (setup.sh, run_autograder, the library and the exercise tests)")
    from .course.results.gradescope import manual_questions
    from .course.paths import exercise_names

    root = _root(args)
    manual = manual_questions(root, [args.exercise] if args.exercise else exercise_names(root))
    for name, questions in manual.items():
        listed = ", ".join(f"question {k} ({p:g} points)" for k, p in sorted(questions.items()))
        print(f"add manual questions on Gradescope for {name}: {listed} (see GRADESCOPE.md in the zip)")
    return 0


def _new_exercise(args):
    from .course.release.newexercise import new_exercise

    try:
        root = _root(args)
        written = new_exercise(root, args.name)
    except (ValueError, FileExistsError) as error:  # a malformed name, a taken number, files that exist
        print(f"particles new-exercise: {error}", file=sys.stderr)
        return 2
    for path in written:
        print(f"wrote {path.relative_to(root)}")
    print(f"next: edit both, run `particles release`, then `pytest {written[1].relative_to(root)}` "
          "(the master must score full marks)")
    if (Path(root) / "course.toml").exists():
        print(f"deadline: add [exercises.{args.name}] with its deadline to course.toml (else it has none)")
    return 0


def _similarity(args):
    from .course.similarity.compare import format_table, similarity, write_report

    try:
        report = similarity(args.submissions, threshold=args.threshold, exercise=args.exercise,
                            root=_root(args), min_nodes=args.min_nodes)
    except ValueError as error:  # a missing folder, a threshold outside [0, 1], an unknown exercise
        print(f"particles similarity: {error}", file=sys.stderr)
        return 2
    for problem in report.problems:
        print(f"not compared: {problem}", file=sys.stderr)
    print(format_table(report, per_cluster=None if args.all else 10))
    if args.out:
        paths = write_report(report, args.out)
        print(f"\nwrote {', '.join(str(p) for p in paths)}")
    return 0  # a report, whatever it found


def _warm(args):
    from .backends.warm import command
    return command(args.jobs)


def build_parser():
    from .demos import DEMOS

    parser = argparse.ArgumentParser(
        prog="particles",
        description="Particle systems and mass-spring simulation: the course package's tools.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    tour = sub.add_parser("tour", help="run the course tour: figures, animations and tables")
    tour.add_argument("--out", default="out", help="output folder (default: out)")
    tour.set_defaults(run=_tour)

    listing = "; ".join(f"{name}: {demo.description}" for name, demo in DEMOS.items())
    demo = sub.add_parser("demo", help="write a particle-effect animation (GIF) to a folder",
                          description=f"Simulate a demo and write NAME.gif. Demos: {listing}.")
    demo.add_argument("name", choices=[*DEMOS, "all"], metavar="NAME",
                      help=f"one of {', '.join(DEMOS)}, or all")
    demo.add_argument("--out", default="out", help="output folder (default: out)")
    demo.add_argument("--seconds", type=float, default=None, help="simulated time (default: the demo's)")
    demo.add_argument("--fps", type=int, default=None, help="frames per second (default: the demo's)")
    demo.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    demo.add_argument("--html", action="store_true", help="also write NAME.html, an HTML/JavaScript player")
    demo.set_defaults(run=_demo)

    study = sub.add_parser("study", help="run a measured study and write its figure (PNG, SVG) and table (CSV)")
    study.add_argument("name", choices=["order", "stability", "provot", "discretization", "bounce", "all"])
    study.add_argument("--out", default="out/studies", help="output folder (default: out/studies)")
    study.set_defaults(run=_study)

    warm = sub.add_parser("warm", help="compile the numba kernels into their disk cache, ahead of use")
    warm.add_argument("--jobs", type=int, default=1, help="processes sharing the work (default 1)")
    warm.set_defaults(run=_warm)

    site = sub.add_parser("site", help="execute the lectures and write a static HTML course site")
    site.add_argument("--out", default="site", help="output folder (default: site)")
    site.add_argument("--lectures", default="lectures", help="folder of NN_topic.ipynb lectures")
    site.add_argument("--timeout", type=float, default=600, help="seconds allowed per cell")
    site.set_defaults(run=_site)

    check = sub.add_parser("check", help="run an exercise's public tests on your saved notebook (exit 0: all pass)",
                           description="particles.check in a terminal: the public tests on the saved notebook; exit "
                                       "status 0 when all pass, 1 when one fails, 2 when nothing could be checked.")
    check.add_argument("exercise", help="e.g. 01_integrator_order")
    check.add_argument("notebook", nargs="?", help="the saved notebook (default: EXERCISE.ipynb here, else in "
                                                   "the course's exercises/)")
    check.add_argument("--time-limit", type=float, default=None, help="seconds per call of your functions")
    check.set_defaults(run=_check)

    release = sub.add_parser("release", help="generate exercises/ from the masters in solutions/")
    release.add_argument("--check", action="store_true", help="only check that exercises/ is up to date")
    release.add_argument("--bundle", metavar="DIR", help="write what students receive into DIR (new or empty)")
    release.add_argument("--root", help="the course folder (default: found from the current directory)")
    release.set_defaults(run=_release)

    grade = sub.add_parser("grade", help="grade notebooks (files or folders) with the exercise tests")
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
    grade.add_argument("--root", help="the course folder (default: found from the current directory)")
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
                       help="submission times, a CSV student,exercise,submitted (default: the notebooks' file times)")
    grade.add_argument("--metadata", metavar="FILE",
                       help="Gradescope's submission_metadata.json: its created_at is the submission time")
    grade.add_argument("--student", action="append", metavar="ID",
                       help="regrade only this student (repeatable); needs --out with the records of an earlier "
                            "run, keeps the others' and rewrites the gradebook")
    grade.set_defaults(run=_grade)

    review = sub.add_parser("review", help="write one page per written question with every student's answer, "
                            "and a rubric (CSV) to fill in",
                            description="For each exercise and written question, write DIR/<exercise>/"
                            "question-<k>.html (every student's answer side by side, with the figures it refers "
                            "to; self-contained, no scripts) and DIR/<exercise>/rubric.csv (points and comments "
                            "to fill in; rows already filled are kept), then grade with `particles grade ... "
                            "--rubric DIR`.")
    review.add_argument("submissions", nargs="+", metavar="SUBMISSION", help="a notebook or a folder of them")
    review.add_argument("--out", required=True, metavar="DIR", help="the folder to write the pages and rubrics to")
    review.add_argument("--exercise", help="read every notebook as this exercise (as `particles grade` does)")
    review.add_argument("--root", help="the course folder (default: found from the current directory)")
    review.set_defaults(run=_review)

    new = sub.add_parser("new-exercise", help="write a template master and test module for a new exercise NN_topic",
                         description="Write solutions/NN_topic.ipynb and tests/exercises/test_NN_topic.py from a "
                         "template that passes (the master scores full marks, its released stub zero). Refuses "
                         "a malformed name, a number already taken, or files that exist (exit status 2).")
    new.add_argument("name", metavar="NN_topic", help="two digits, an underscore and a lower-case topic")
    new.add_argument("--root", help="the course folder (default: found from the current directory)")
    new.set_defaults(run=_new_exercise)

    export = sub.add_parser("export", help="write the grades of a graded folder for Canvas and Moodle",
                            description="Read OUT/records (written by `particles grade --out OUT`) and write "
                            "Canvas's and Moodle's gradebook import CSVs: one row per student of the roster, one "
                            "column per exercise (tests + written answers - late penalty) and a total. A roster "
                            "student without a record gets 0 (\"missing\"); every problem is listed in "
                            "OUT/lms-report.csv. Exit status 0; 1 when a record's student is not on the roster or "
                            "a student was left out of a file; 2 on a bad roster or unreadable records.")
    export.add_argument("out", metavar="OUT", help="the output folder of a grading run")
    export.add_argument("--roster", required=True, help="CSV: submission_name and the students' LMS identifiers "
                        "(canvas_id, sis_user_id, sis_login_id, section, email, username, idnumber); Canvas's "
                        "gradebook export also works, with --name-column")
    export.add_argument("--canvas", metavar="FILE", help="write Canvas's gradebook import CSV here")
    export.add_argument("--moodle", metavar="FILE", help="write Moodle's grade import CSV here")
    export.add_argument("--name-column", default="submission_name",
                        help="the roster's column of the names the grader files submissions under "
                             "(default submission_name)")
    export.add_argument("--moodle-id", choices=["email", "username", "idnumber"], default="email",
                        help="the identifier of the Moodle file (default email)")
    export.set_defaults(run=_export)

    bundle = sub.add_parser("gradescope-bundle", help="write the Gradescope autograder zip")
    bundle.add_argument("--out", default="autograder.zip", help="the zip to write (default autograder.zip)")
    bundle.add_argument("--exercise", help="grade every submitted notebook as this exercise")
    bundle.add_argument("--root", help="the course folder (default: found from the current directory)")
    bundle.set_defaults(run=_gradescope_bundle)

    similar = sub.add_parser("similarity", help="report submitted functions structurally equal to the library, "
                             "a master or a classmate",
                             description="Compare the asked functions of every submission (normalized syntax "
                             "trees) with the library, the masters and each other; print the matching pairs "
                             "by cluster. Exit status 0 whatever is found.")
    similar.add_argument("submissions", nargs="+", metavar="DIR", help="a folder of submissions (or notebooks)")
    similar.add_argument("--out", metavar="DIR", help="write similarity.csv and similarity.md here")
    similar.add_argument("--threshold", type=float, default=0.8,
                         help="smallest similarity reported, 0 to 1 (default 0.8; 1: identical structure only)")
    similar.add_argument("--exercise", help="read every notebook as this exercise")
    similar.add_argument("--all", action="store_true", help="print every pair (default: 10 per cluster)")
    similar.add_argument("--min-nodes", type=int, default=10,
                         help="ignore functions with fewer normalized syntax nodes (default 10)")
    similar.add_argument("--root", help="the course folder (default: found from the current directory)")
    similar.set_defaults(run=_similarity)
    return parser


def main(argv=None):
    """Entry point of the ``particles`` console script."""
    args = build_parser().parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())
