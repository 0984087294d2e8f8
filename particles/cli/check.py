"""``particles check EXERCISE [NOTEBOOK]``: an exercise's public tests on a student's saved notebook."""

import sys
from pathlib import Path


def run(args):
    from ..course.check import CheckError, check
    from ..course.paths import exercise_tests, project_root

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


def register(commands):
    check = commands.add_parser("check", help="run an exercise's public tests on your saved notebook (exit 0: all "
                                "pass)", description="particles.check in a terminal: the public tests on the saved "
                                "notebook; exit status 0 when all pass, 1 when one fails, 2 when nothing could be "
                                "checked.")
    check.add_argument("exercise", help="e.g. 01_integrator_order")
    check.add_argument("notebook", nargs="?", help="the saved notebook (default: EXERCISE.ipynb here, else in "
                                                   "the course's exercises/)")
    check.add_argument("--time-limit", type=float, default=None, help="seconds per call of your functions")
    check.set_defaults(run=run)
