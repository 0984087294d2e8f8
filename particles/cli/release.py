"""``particles release``: the student exercises generated from the instructor's masters."""

import sys

from .common import add_root, course_root


def _check(root):
    from ..course.release.notebooks import release

    problems = release(root, check=True)
    for problem in problems:
        print(f"out of date: {problem}")
    if problems:
        print("run `particles release` to regenerate exercises/ from solutions/", file=sys.stderr)
        return 1
    print("exercises/ is up to date with solutions/")
    return 0


def run(args):
    from ..course.release.notebooks import ReleaseError, release, write_bundle

    try:
        root = course_root(args)
        if args.check:
            return _check(root)
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


def register(commands):
    release = commands.add_parser("release", help="generate exercises/ from the masters in solutions/")
    release.add_argument("--check", action="store_true", help="only check that exercises/ is up to date")
    release.add_argument("--bundle", metavar="DIR", help="write what students receive into DIR (new or empty)")
    add_root(release)
    release.set_defaults(run=run)
