"""The ``records/`` folder of a grader before the course record: imported once, when the record is made.

Each record file becomes the current result of its student and exercise, graded in one run whose command
says where it came from; a file that cannot be read is reported, never dropped silently. The folder is left as
it is and never read again.
"""

import json
from pathlib import Path

from ..results.records import SubmissionRecord
from .identity import Identity

__all__ = ["import_records"]


def import_records(term, folder):
    """Import every ``*.json`` record of `folder` into `term` (a :class:`~particles.course.term.database.TermRecord`).

    Returns
    -------
    int
        How many records were imported.

    Raises
    ------
    ValueError
        Naming a record file that cannot be read as a record (nothing is imported then).
    """
    records = []
    for path in sorted(Path(folder).glob("*.json")):
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            options = data.pop("options", {}) if isinstance(data, dict) else {}
            records.append((SubmissionRecord.from_dict(data), options))
        except (OSError, UnicodeDecodeError, ValueError, TypeError, AttributeError) as error:
            raise ValueError(f"cannot import the record {path} into the course record: {error}; move the file "
                             "away and grade that notebook again") from None
    if not records:
        return 0
    identity = Identity()
    for record, _ in records:
        identity.admit(record.student)
    term.remember(identity)
    run = term.start_run(f"imported from {folder} (records of a grader before the course record)", {})
    for record, options in records:
        term.save(run, record, options)
    term.finish_run(run)
    return len(records)
