"""``particles export OUT --roster FILE``: the grades of a graded folder for Canvas and Moodle, and the feedback."""

import sys


def _warn(done, export, moodle_id):
    """The problems of an export, on stderr; True when a record or a student was left out, or cannot be matched."""
    from ..course.results.importers import moodle_left_out

    for student in done["name_only"]:
        print(f"warning: {student.submission_name} (roster line {student.line}) has no Canvas ID, SIS User ID or "
              "SIS Login ID: Canvas can match it only by name", file=sys.stderr)
    for student in done.get("by_hand", []):
        print(f"Canvas cannot match {student.submission_name} (roster line {student.line}): it lists the row as an "
              "unknown student, to match by hand on upload; give it its canvas_id (see lms-report.csv)",
              file=sys.stderr)
    for name, record in export.unmatched:
        print(f"not on the roster: {record.student} ({record.exercise}, {record.total:g}/{record.total_max:g} "
              f"points, {name}): not exported", file=sys.stderr)
    for student, exercise, run in export.pending:
        print(f"not graded yet: {student}'s {exercise} (grading run {run} was interrupted): these grades are "
              "partial; run particles grade --resume, then export again", file=sys.stderr)
    for fmt, students in done["left_out"].items():
        for student in students:
            print(f"left out of the {fmt} file: {student.submission_name} (roster line {student.line}) "
                  f"{moodle_left_out(student, moodle_id)}", file=sys.stderr)
    return bool(export.unmatched or export.pending or any(done["left_out"].values()) or done.get("by_hand"))


def run(args):
    from ..course.results.lms import ExportError, export_grades
    from ..course.term.roster import RosterError

    if not (args.canvas or args.moodle or args.canvas_feedback or args.moodle_feedback):
        print("particles export: nothing to write: pass --canvas FILE, --moodle FILE, --canvas-feedback ZIP or "
              "--moodle-feedback ZIP", file=sys.stderr)
        return 2
    status = 0
    if args.canvas or args.moodle:
        if not args.roster:
            print("particles export: --canvas and --moodle need --roster FILE", file=sys.stderr)
            return 2
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
        status = 1 if _warn(done, export, args.moodle_id) else 0
        print(f"report: {done['report']}")
    if args.canvas_feedback or args.moodle_feedback:
        status = max(status, _feedback(args))
    return status


def _feedback(args):
    """Write the feedback zips; 1 when a student's feedback could not go in (said on stderr), 2 on no records."""
    from pathlib import Path

    from ..course.results.lms import ExportError, read_records
    from ..course.results.returned import write_feedback_zips
    from ..course.term.roster import RosterError, read_roster

    try:
        records, _ = read_records(Path(args.out))
        roster = read_roster(args.roster, args.name_column) if args.roster else None
        done = write_feedback_zips(records.values(), canvas=args.canvas_feedback, moodle=args.moodle_feedback,
                                   roster=roster, downloads=args.download or ())
    except (ExportError, RosterError, ValueError) as error:
        print(f"particles export: {error}", file=sys.stderr)
        return 2
    for fmt, files in done["files"].items():
        for exercise, path in files.items():
            count = sum(1 for _, e, _ in done["written"][fmt] if e == exercise)
            print(f"wrote {path} ({fmt} feedback for {exercise}): {count} students")
    for fmt, left in done["left_out"].items():
        for student, exercise, why in left:
            print(f"no {fmt} feedback for {student} ({exercise}): {why}", file=sys.stderr)
    return 1 if any(done["left_out"].values()) else 0


def register(commands):
    export = commands.add_parser(
        "export", help="write the grades of a graded folder for Canvas and Moodle",
        description="Read the course record of OUT (written by `particles grade --out OUT`) and write Canvas's "
        "and Moodle's gradebook import CSVs: one row per student of the roster, one column per exercise (tests + "
        "written answers - late penalty) and a total. A roster student without a record gets 0 (\"missing\"); "
        "every problem is listed in OUT/lms-report.csv. With --canvas-feedback and --moodle-feedback, write the "
        "zips each LMS reads back as feedback files (one per exercise). Exit status 0; 1 when a record's student "
        "is not on the roster, a student was left out of a file or Canvas cannot match them, a notebook is not "
        "graded yet (an interrupted run) or a student's feedback could not go into a zip; 2 on a bad roster or an "
        "unreadable record.")
    export.add_argument("out", metavar="OUT", help="the output folder of a grading run")
    export.add_argument("--roster", help="CSV: submission_name and the students' LMS identifiers "
                        "(canvas_id, sis_user_id, sis_login_id, section, email, username, idnumber) and aliases; "
                        "Canvas's gradebook export also works, with --name-column")
    export.add_argument("--canvas", metavar="FILE", help="write Canvas's gradebook import CSV here")
    export.add_argument("--moodle", metavar="FILE", help="write Moodle's grade import CSV here")
    export.add_argument("--canvas-feedback", metavar="ZIP", help="write the zip for Canvas's \"Re-Upload "
                        "Submissions\": each student's feedback, attached to their submission as a comment")
    export.add_argument("--moodle-feedback", metavar="ZIP", help="write the zip for Moodle's \"Upload multiple "
                        "feedback files in a zip\": each student's feedback.html")
    export.add_argument("--download", action="append", metavar="ZIP", help="the LMS's submissions download "
                        "(zip or folder; repeatable): the ids of students graded from another layout, found "
                        "through the roster (Canvas: canvas_id, Moodle: name)")
    export.add_argument("--name-column", default="submission_name",
                        help="the roster's column of the names the grader files submissions under "
                             "(default submission_name)")
    export.add_argument("--moodle-id", choices=["email", "username", "idnumber"], default="email",
                        help="the identifier of the Moodle file (default email)")
    export.set_defaults(run=run)
