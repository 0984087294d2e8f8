"""The records of a grading run, on disk as they are made: what ``particles grade --resume`` reads back.

One JSON file per notebook graded, ``DIR/records/<student>__<exercise>.json``,
written (atomically: a temporary file, then a rename) as soon as the notebook's
batch is done. A run that is stopped anyway (Ctrl-C, power loss, a killed
driver) keeps every finished record; a resumed run keeps a record only when it
is complete, of the same notebook (same bytes: SHA-256), made with the same
options (public only, seed, limits) and graded by the same version of the tests
(``tests_version``, see :mod:`particles.course.grading.versions`), and grades
everything else again. ``particles grade --student ID`` reads every record
(:meth:`RecordStore.load_all`) and keeps the others' files as they are.
"""

import json
import os
import tempfile
from pathlib import Path

from ..grading.discovery import notebook_digest
from .records import SubmissionRecord

__all__ = ["RecordStore", "regrade_split"]


class RecordStore:
    """The ``records/`` folder of a grading run.

    Parameters
    ----------
    folder : path
        Where the records live (made when missing).
    options : dict
        The options of the run (JSON-able); a record made with other options
        is not kept by :meth:`load`.
    """

    def __init__(self, folder, options):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.options = json.loads(json.dumps(options))

    def path(self, student, exercise):
        """The record file of one student's notebook of one exercise."""
        return self.folder / f"{student}__{exercise}.json"

    def save(self, result):
        """Write one notebook's :class:`~particles.course.results.records.SubmissionRecord` (atomically: a new file, renamed)."""
        self._write(self.path(result.student, result.exercise), dict(result.to_dict(), options=self.options))

    def update(self, result, fields=("written", "late")):
        """Bring the record file of `result` up to date in `fields` only; True when it changed.

        After a rubric is merged (written grades) or a late decision is made again, the file on disk
        says so too, so that what reads ``records/`` (``particles export``, a later ``--student`` run)
        sees the same totals as the feedback; every other field of the file, its options included, is
        kept as it is. A record without a file is left alone (it was not graded in this folder).
        """
        path = self.path(result.student, result.exercise)
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError):
            return False
        new = {name: json.loads(json.dumps(getattr(result, name))) for name in fields}
        if not isinstance(data, dict) or all(data.get(name) == value for name, value in new.items()):
            return False
        self._write(path, dict(data, **new))
        return True

    def _write(self, target, data):
        # not "*.json" until renamed: a driver killed while writing leaves no file that reads as a record
        handle, name = tempfile.mkstemp(dir=self.folder, prefix=".record-", suffix=".part")
        try:
            with os.fdopen(handle, "w") as stream:
                json.dump(data, stream, indent=1)
                stream.flush()
                os.fsync(stream.fileno())
            os.replace(name, target)
        except BaseException:
            Path(name).unlink(missing_ok=True)
            raise

    def load(self, unit, tests_version=None):
        """The kept record of `unit` (a :class:`~particles.course.grading.discovery.Unit`), or None to grade it again.

        Parameters
        ----------
        unit : Unit
        tests_version : str, optional
            The current version of the unit's exercise's tests: a record graded by another is not kept.
        """
        try:
            data = json.loads(self.path(unit.student, unit.exercise).read_text())
        except (OSError, ValueError):
            return None
        if not isinstance(data, dict):
            return None
        same = (data.get("student") == unit.student and data.get("exercise") == unit.exercise
                and data.get("options") == self.options and data.get("complete") is True
                and data.get("grader_status") in (0, 1)
                and data.get("notebook_sha256") == notebook_digest(unit.notebook) != ""
                and (tests_version is None or data.get("tests_version") == tests_version))
        if not same:
            return None
        data.pop("options", None)
        try:
            record = SubmissionRecord.from_dict(data)
        except (TypeError, ValueError):
            return None
        record.notebook, record.resumed = str(unit.notebook), True
        return record

    def load_all(self):
        """Every record of the folder, as it is (whatever its options): (student, exercise) -> record.

        Raises
        ------
        ValueError
            When a record file cannot be read as a record (naming the file): nothing is silently dropped.
        """
        records = {}
        for path in sorted(self.folder.glob("*.json")):
            try:
                data = json.loads(path.read_text())
                data.pop("options", None)
                record = SubmissionRecord.from_dict(data)
            except (OSError, ValueError, TypeError, AttributeError) as error:
                raise ValueError(f"cannot read the record {path}: {error}") from None
            records[(record.student, record.exercise)] = record
        return records


def regrade_split(folder, units, students):
    """What ``particles grade --student`` grades and keeps: the students' units, and every other record.

    Parameters
    ----------
    folder : path
        The ``records/`` folder of an earlier run.
    units : list of Unit
        The notebooks found in the submissions.
    students : sequence of str
        The students to grade again.

    Returns
    -------
    units : list of Unit
        Those of `students`.
    others : dict
        (student, exercise) -> record, every record of `folder` but those the units grade again (kept
        as they are; their files are not written).

    Raises
    ------
    ValueError
        When `folder` holds no record, or a student has no notebook in the submissions (naming the
        students there are).
    """
    earlier = RecordStore(folder, {}).load_all() if Path(folder).is_dir() else {}
    if not earlier:
        raise ValueError(f"student needs the records of an earlier run; {folder} holds none")
    found = {u.student for u in units}
    unknown = [s for s in students if s not in found]
    if unknown:
        known = sorted(found | {student for student, _ in earlier})
        raise ValueError(f"unknown student {unknown[0]!r}: no notebook of theirs in the submissions; "
                         f"the students are {', '.join(known)}")
    units = [u for u in units if u.student in students]
    regraded = {(u.student, u.exercise) for u in units}
    return units, {key: record for key, record in earlier.items() if key not in regraded}
