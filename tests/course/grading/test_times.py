"""Submission times: never guessed; Gradescope's, then a times file, then the course record's; files checked."""

import json
import os
from datetime import datetime, timezone

import pytest

from particles.course.grading.discovery import Unit
from particles.course.grading.times import SubmissionTimes, read_times


def test_submission_times_come_from_gradescope_then_the_times_file_then_the_file(tmp_path):
    """Gradescope's created_at wins over a times file, which wins over the course record's earlier time; the
    notebook's modification time counts only when the instructor accepts it (--times-from mtime)."""
    notebook = tmp_path / "alice.ipynb"
    notebook.write_text("{}")
    os.utime(notebook, (1e9, 1e9))
    unit = Unit("alice", "00_warmup", notebook)
    assert SubmissionTimes().of(unit) == (None, "")  # never guessed
    assert SubmissionTimes(from_mtime=True).of(unit) == (datetime.fromtimestamp(1e9, timezone.utc),
                                                         "the notebook file's modification time")
    earlier = datetime(2026, 10, 1, tzinfo=timezone.utc)
    kept = SubmissionTimes(from_mtime=True, earlier=lambda student, exercise: (earlier, "run 1"))
    assert kept.of(unit) == (earlier, "run 1")
    yml = Unit("alice", "00_warmup", notebook, submitted=earlier, time_source="Gradescope's submission_metadata.yml")
    assert SubmissionTimes().of(yml) == (earlier, "Gradescope's submission_metadata.yml")
    times = tmp_path / "times.csv"
    times.write_text("student,exercise,submitted,comment\nalice,00_warmup,2026-10-02T10:00:00+02:00,x\n"
                     "bob,,2026-10-03T10:00:00Z,\n")
    assert SubmissionTimes(times=times).of(unit) == (datetime(2026, 10, 2, 8, tzinfo=timezone.utc), "the times file")
    bob = Unit("bob", "01_integrator_order", notebook)  # an empty exercise cell: every exercise
    assert SubmissionTimes(times=times).of(bob)[0] == datetime(2026, 10, 3, 10, tzinfo=timezone.utc)
    metadata = tmp_path / "submission_metadata.json"
    metadata.write_text(json.dumps({"id": 1, "created_at": "2026-10-02T14:22:32.365935-07:00",
                                    "users": [{"email": "alice@example.com", "id": 1234, "name": "A"}]}))
    source = SubmissionTimes(metadata=metadata, times=times)
    assert source.of(unit) == (datetime(2026, 10, 2, 21, 22, 32, 365935, tzinfo=timezone.utc),
                               "Gradescope's submission metadata")
    assert source.aliases() == ("alice@example.com", "1234")


@pytest.mark.parametrize("text, message", [
    ("student,when\nalice,2026-10-02T10:00:00Z\n", "no column exercise, submitted"),
    ("student,exercise,submitted\nalice,00_warmup,2026-10-02 10:00\n", r"line 2, submitted: .* no time zone"),
    ("student,exercise,submitted\nalice,00_warmup,yesterday\n", r"line 2, submitted: 'yesterday' is not ISO 8601"),
    ("student,exercise,submitted\nalice,00_warmup,2026-10-02T10:00Z\nalice,00_warmup,2026-10-02T11:00Z\n",
     "line 3: alice 00_warmup is given twice"),
    ("student,exercise,submitted\n,00_warmup,2026-10-02T10:00Z\n", "line 2: no student"),
])
def test_bad_times_files_name_the_line(tmp_path, text, message):
    """A times file without a column, with a time without a zone or a duplicate is an error naming the line."""
    path = tmp_path / "times.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=message.replace("not ISO", "not an ISO")):
        read_times(path)


def test_bad_gradescope_metadata_is_an_error(tmp_path):
    """Metadata that is not JSON, or has no created_at, or one without a zone, is an error naming the file."""
    path = tmp_path / "submission_metadata.json"
    for text, message in (("nope", "cannot read Gradescope's submission metadata"), ("{}", "has no created_at"),
                          ('{"created_at": "2026-10-02T10:00:00"}', "created_at: .* no time zone")):
        path.write_text(text)
        with pytest.raises(ValueError, match=message):
            SubmissionTimes(metadata=path)
