"""The records folder: a record is kept for --resume only when nothing that graded it changed; load_all reads all."""

import json

import pytest

from particles.course.grading.discovery import Unit, notebook_digest
from particles.course.results.records import SubmissionRecord, TestRecord
from particles.course.results.store import RecordStore, regrade_split

OPTIONS = {"public_only": False, "seed": 3}


def _saved(tmp_path, student="alice", version="tests=aaa library=0.1.0+bbb", options=OPTIONS):
    notebook = tmp_path / f"{student}.ipynb"
    notebook.write_text('{"cells": []}')
    record = SubmissionRecord(student=student, exercise="00_warmup", notebook=str(notebook), complete=True,
                              grader_status=0, notebook_sha256=notebook_digest(notebook), tests_version=version,
                              tests=[TestRecord(test="t", name="t", points=2, passed=True)],
                              late={"submitted": "2026-10-02T00:00:00+01:00", "deadline": "2026-10-01T23:59:00+01:00",
                                    "days_late": 1, "penalty": 0.2, "reason": "late", "source": "the times file"})
    store = RecordStore(tmp_path / "records", options)
    store.save(record)
    return store, Unit(student, "00_warmup", notebook), record


def test_a_record_is_kept_only_for_the_current_tests_version(tmp_path):
    """The same tests version: kept (late and version included); another one: graded again."""
    store, unit, record = _saved(tmp_path)
    kept = store.load(unit, "tests=aaa library=0.1.0+bbb")
    assert kept.resumed and kept.tests_version == record.tests_version and kept.late == record.late
    assert kept.total == 1.8
    assert store.load(unit, "tests=ccc library=0.1.0+bbb") is None  # a changed test
    assert store.load(unit, "tests=aaa library=0.1.1+ddd") is None  # a changed library
    assert store.load(unit) is not None  # no version asked: as before
    assert RecordStore(tmp_path / "records", {"seed": 4}).load(unit, record.tests_version) is None


def test_a_record_without_a_tests_version_is_graded_again(tmp_path):
    """Records of a run before tests versions existed ("") are not kept when a version is asked."""
    store, unit, _ = _saved(tmp_path, version="")
    assert store.load(unit, "tests=aaa library=0.1.0+bbb") is None


def test_load_all_reads_every_record_whatever_its_options_and_names_a_broken_one(tmp_path):
    """load_all returns every record by (student, exercise), without the options; a broken file is an error."""
    store, _, alice = _saved(tmp_path, "alice")
    _saved(tmp_path, "bob", options={"other": True})
    records = RecordStore(tmp_path / "records", {}).load_all()
    assert sorted(records) == [("alice", "00_warmup"), ("bob", "00_warmup")]
    assert records[("alice", "00_warmup")] == alice
    on_disk = json.loads(store.path("bob", "00_warmup").read_text())
    assert on_disk["options"] == {"other": True}  # reading changed nothing
    store.path("carol", "00_warmup").write_text("{not json")
    with pytest.raises(ValueError, match="cannot read the record .*carol__00_warmup.json"):
        store.load_all()


def test_regrade_split_keeps_the_others_and_names_the_students(tmp_path):
    """--student: the student's units are graded again, every other record is kept; unknown names are listed."""
    store, alice_unit, _ = _saved(tmp_path, "alice")
    _, bob_unit, bob = _saved(tmp_path, "bob")
    units, others = regrade_split(tmp_path / "records", [alice_unit, bob_unit], ["alice"])
    assert units == [alice_unit] and others == {("bob", "00_warmup"): bob}
    with pytest.raises(ValueError, match="unknown student 'carol'.*the students are alice, bob"):
        regrade_split(tmp_path / "records", [alice_unit, bob_unit], ["carol"])
    with pytest.raises(ValueError, match="holds none"):
        regrade_split(tmp_path / "nothing", [alice_unit], ["alice"])
    assert not (tmp_path / "nothing").exists()  # asking made no folder
