"""``particles review``: one page per written question with every student's answer, and a rubric to fill in."""

import sys
from pathlib import Path

from .common import add_root, course_root


def run(args):
    from ..course.results.review import write_review

    try:
        summary = write_review(args.submissions, args.out, root=course_root(args), exercise=args.exercise,
                               roster=args.roster, name_column=args.name_column)
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
    return 1 if summary["problems"] else 0


def register(commands):
    review = commands.add_parser(
        "review", help="write one page per written question with every student's answer, and a rubric (CSV) to "
        "fill in", description="For each exercise and written question, write DIR/<exercise>/question-<k>.html "
        "(every student's answer side by side, with the figures it refers to; self-contained, no scripts) and "
        "DIR/<exercise>/rubric.csv (points and comments to fill in; rows already filled are kept), then grade "
        "with `particles grade ... --rubric DIR`. Exit status 0; 1 when a notebook was not read or an exercise has "
        "no written question (said on stderr); 2 on bad arguments.")
    review.add_argument("submissions", nargs="+", metavar="SUBMISSION", help="a notebook, a folder of them, or a "
                        "zip (an LMS's submissions download), as for particles grade")
    review.add_argument("--out", required=True, metavar="DIR", help="the folder to write the pages and rubrics to")
    review.add_argument("--exercise", help="read every notebook as this exercise (as `particles grade` does)")
    review.add_argument("--roster", metavar="FILE", help="who is in the course (default: the course file's roster): "
                        "students named as `particles grade` names them")
    review.add_argument("--name-column", default="submission_name",
                        help="the roster's column of the grader's names (default submission_name)")
    add_root(review)
    review.set_defaults(run=run)
