"""``particles similarity DIR``: submitted functions structurally equal to the library, a master or a classmate."""

import sys

from .common import add_root, course_root


def run(args):
    from ..course.similarity.compare import format_table, similarity, write_report

    try:
        report = similarity(args.submissions, threshold=args.threshold, exercise=args.exercise,
                            root=course_root(args), min_nodes=args.min_nodes)
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


def register(commands):
    similar = commands.add_parser(
        "similarity", help="report submitted functions structurally equal to the library, a master or a classmate",
        description="Compare the asked functions of every submission (normalized syntax trees) with the library, "
        "the masters and each other; print the matching pairs by cluster. Exit status 0 whatever is found.")
    similar.add_argument("submissions", nargs="+", metavar="DIR", help="a folder of submissions (or notebooks)")
    similar.add_argument("--out", metavar="DIR", help="write similarity.csv and similarity.md here")
    similar.add_argument("--threshold", type=float, default=0.8,
                         help="smallest similarity reported, 0 to 1 (default 0.8; 1: identical structure only)")
    similar.add_argument("--exercise", help="read every notebook as this exercise")
    similar.add_argument("--all", action="store_true", help="print every pair (default: 10 per cluster)")
    similar.add_argument("--min-nodes", type=int, default=10,
                         help="ignore functions with fewer normalized syntax nodes (default 10)")
    add_root(similar)
    similar.set_defaults(run=run)
