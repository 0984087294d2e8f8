"""``particles record OUT``: the term's record of a graded folder: its runs, a student's history, a result retired."""

import getpass
import sys


def _show(term):
    """The runs, and what no run has graded yet."""
    for run in term.runs():
        print(f"run {run['id']}: {run['status']:<11} {run['started']}  {run['planned']} notebook(s)  "
              f"{run['command']}")
    for student, exercise, run in term.pending():
        print(f"not graded yet: {student}'s {exercise} (run {run}); rerun it with --resume")


def _history(term, student):
    """Every result of one student, the current ones marked."""
    history = term.history(student)
    if not history:
        print(f"particles record: no result of {student!r} in {term.path}", file=sys.stderr)
        return 2
    for item in history:
        state = "current" if item["current"] else f"history: {item['ended_why']}"
        print(f"{item['exercise']:<22} run {item['run']:<4} {item['total']:g} / {item['total_max']:g}  {state}")
    return 0


def run(args):
    from ..course.term.database import DATABASE, TermRecord

    if not (args.out / DATABASE).exists():
        print(f"particles record: {args.out} holds no course record ({DATABASE})", file=sys.stderr)
        return 2
    term = TermRecord(args.out)
    try:
        if args.retire:
            if not args.why:
                print("particles record: --retire needs --why (the record keeps who retired what, and why)",
                      file=sys.stderr)
                return 2
            term.lock()
            term.retire(*args.retire, why=args.why, who=args.who or getpass.getuser())
            print(f"retired {args.retire[0]}'s current {args.retire[1]}: grade it again, or it counts as missing")
            return 0
        if args.history:
            return _history(term, args.history)
        _show(term)
        return 0
    except ValueError as error:  # another run holds the record, nothing to retire
        print(f"particles record: {error}", file=sys.stderr)
        return 2
    finally:
        term.close()


def register(commands):
    from pathlib import Path

    record = commands.add_parser(
        "record", help="show the term's record of a graded folder (runs, a student's history) or retire a result",
        description="Read OUT/course.sqlite, the term's record that `particles grade --out OUT` keeps: every run "
        "and how it ended, the notebooks not graded yet, a student's results (current and history). --retire "
        "makes a result history by hand (the record keeps who, when and why).")
    record.add_argument("out", type=Path, metavar="OUT", help="the output folder of the course's grading runs")
    record.add_argument("--history", metavar="STUDENT", help="every result of this student, current and history")
    record.add_argument("--retire", nargs=2, metavar=("STUDENT", "EXERCISE"),
                        help="make the student's current result of the exercise history")
    record.add_argument("--why", help="why the result is retired (kept in the record)")
    record.add_argument("--who", help="who retires it (default: this user)")
    record.set_defaults(run=run)
