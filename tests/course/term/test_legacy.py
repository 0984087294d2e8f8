"""A records/ folder of an older grader: imported once into a new course record, never read again."""

import json

import pytest

from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.term.database import TermRecord


def test_old_records_are_imported_once_as_the_current_results(tmp_path):
    """Each record file becomes the current result of its student and exercise, in one run that says where it came
    from; a second opening imports nothing again, and a later change of the folder is not read."""
    records = tmp_path / "records"
    records.mkdir()
    for student, passed in (("ann", True), ("bob", False)):
        record = SubmissionRecord(student=student, exercise="00_warmup", complete=True, grader_status=0,
                                  tests=[TestRecord(test="t", name="t", points=4, passed=passed)])
        (records / f"{student}__00_warmup.json").write_text(json.dumps(dict(record.to_dict(), options={"seed": 1})))
    term = TermRecord(tmp_path)
    assert term.imported == 2
    assert {k[0]: r.score for k, r in term.current().items()} == {"ann": 4, "bob": 0}
    assert "imported from" in term.db.execute("SELECT command FROM runs").fetchone()[0]
    term.close()
    (records / "carl__00_warmup.json").write_text("{}")
    again = TermRecord(tmp_path)
    assert again.imported == 0 and len(again.current()) == 2


def test_a_record_that_cannot_be_read_stops_the_import_naming_it(tmp_path):
    """An unreadable old record is an error naming the file: nothing is imported silently without it."""
    (tmp_path / "records").mkdir()
    (tmp_path / "records" / "zoe__00_warmup.json").write_text('{"student": "zoe"}')
    with pytest.raises(ValueError, match=r"zoe__00_warmup.json into the course record: .*'exercise'"):
        TermRecord(tmp_path)
