"""``particles new-exercise NN_topic``: a template master and test module for a new exercise."""

import sys
from pathlib import Path

from .common import add_root, course_root


def run(args):
    from ..course.release.newexercise import new_exercise

    try:
        root = course_root(args)
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


def register(commands):
    new = commands.add_parser(
        "new-exercise", help="write a template master and test module for a new exercise NN_topic",
        description="Write solutions/NN_topic.ipynb and tests/exercises/test_NN_topic.py from a template that "
        "passes (the master scores full marks, its released stub zero). Refuses a malformed name, a number "
        "already taken, or files that exist (exit status 2).")
    new.add_argument("name", metavar="NN_topic", help="two digits, an underscore and a lower-case topic")
    add_root(new)
    new.set_defaults(run=run)
