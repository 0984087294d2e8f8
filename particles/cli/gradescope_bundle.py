"""``particles gradescope-bundle``: the Gradescope autograder zip of the course's exercises."""

import sys

from .common import add_root, course_root


def run(args):
    from ..course.paths import exercise_names
    from ..course.results.gradescope import manual_questions, write_bundle

    try:
        root = course_root(args)
        names = write_bundle(root, args.out, exercise=args.exercise)
    except ValueError as error:
        print(f"particles gradescope-bundle: {error}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}: {len(names)} files (setup.sh, run_autograder, the library and the exercise tests)")
    manual = manual_questions(root, [args.exercise] if args.exercise else exercise_names(root))
    for name, questions in manual.items():
        listed = ", ".join(f"question {k} ({p:g} points)" for k, p in sorted(questions.items()))
        print(f"add manual questions on Gradescope for {name}: {listed} (see GRADESCOPE.md in the zip)")
    return 0


def register(commands):
    bundle = commands.add_parser("gradescope-bundle", help="write the Gradescope autograder zip")
    bundle.add_argument("--out", default="autograder.zip", help="the zip to write (default autograder.zip)")
    bundle.add_argument("--exercise", help="grade every submitted notebook as this exercise")
    add_root(bundle)
    bundle.set_defaults(run=run)
