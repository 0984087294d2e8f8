"""What several verbs of the command line share: the course folder."""

from pathlib import Path

__all__ = ["add_root", "course_root"]


def add_root(parser):
    """Add ``--root``, the course folder, to a verb's parser."""
    parser.add_argument("--root", help="the course folder (default: found from the current directory)")


def course_root(args):
    """The course folder of a verb's arguments: ``--root``, else found from the current directory."""
    from ..course.paths import project_root

    return Path(args.root).resolve() if args.root else project_root()
