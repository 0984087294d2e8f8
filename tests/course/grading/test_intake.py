"""What grading lets in: bad notebooks rejected with one line each, zips refused when unsafe, and a whole run."""

import contextlib
import csv
import json
import os
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from particles.course.term.database import TermRecord
from particles.course.grading.intake import (DEFAULT_LIMITS, Limits, NotebookRejected, ZipRefused, extract_zip,
                                             read_notebook)
from particles.course.grading.session import NOT_RUN

ROOT = Path(__file__).resolve().parents[3]
MASTER = ROOT / "solutions" / "00_warmup.ipynb"


def notebook(cells=None, **fields):
    """A small nbformat 4 notebook (as a dict) with `cells` (default: one code cell)."""
    cells = [{"cell_type": "code", "id": "c1", "source": "x = 1", "metadata": {}, "outputs": [],
              "execution_count": None}] if cells is None else cells
    return dict({"nbformat": 4, "nbformat_minor": 5, "metadata": {}, "cells": cells}, **fields)


def code(source="x = 1", **fields):
    return dict({"cell_type": "code", "source": source, "metadata": {}, "outputs": [], "execution_count": None},
                **fields)


def picture(size):
    """A markdown cell with an attachment of about `size` bytes (base64)."""
    data = "A" * (4 * size // 3 + 4)
    return {"cell_type": "markdown", "source": "![x](attachment:x.png)", "metadata": {},
            "attachments": {"x.png": {"image/png": data}}}


def sparse(path, size):
    """A file of `size` bytes that takes no room on disk (a hole)."""
    with open(path, "wb") as stream:
        stream.truncate(size)


def _json(data):
    return json.dumps(data).encode()


# kind -> (the file's bytes, or a function making the file at a path; a piece of the expected reason)
MALFORMED = {
    "not_json": (b'{"cells": [', "is not valid JSON (Expecting value at line 1"),
    "unterminated": (b'{"cells": ["abc', "is not valid JSON (Unterminated string starting at line 1, column 12)"),
    "control_character": (b'{"cells": ["a\tb"]}', "is not valid JSON (Invalid control character at line 1, column 14)"),
    "truncated": (_json(notebook())[:-7], "is not valid JSON"),
    "nbformat3": (_json({"nbformat": 3, "nbformat_minor": 0, "metadata": {}, "worksheets": [{"cells": []}]}),
                  "is nbformat 3, expected 4: open it in Jupyter"),
    "no_nbformat": (_json({"cells": []}), "has no nbformat"),
    "nbformat_string": (_json(notebook(nbformat="4")), "is nbformat '4', expected 4"),
    "duplicate_ids": (_json(notebook([code(id="same"), code(id="other"), code(id="same")])),
                      "has two cells (cells 1 and 3) with the same id 'same'"),
    "id_not_string": (_json(notebook([code(id=7)])), "whose id is a number"),
    "latin1": ('{"nbformat": 4, "metadata": {}, "cells": [], "x": "caf\u00e9"}'.encode("latin-1"),
               "is not UTF-8 text (byte 0xe9 at offset"),
    "utf16": (_json(notebook()).decode().encode("utf-16"), "is not UTF-8 text (byte 0xff at offset 0)"),
    "empty": (b"", "is empty (0 bytes)"),
    "blank": (b"  \n\n", "is empty (4 bytes)"),
    "json_list": (b"[1, 2]", "holds a list in JSON, not a notebook"),
    "json_string": (b'"a notebook"', "holds a string in JSON"),
    "null": (b"null", "holds null in JSON"),
    "cells_dict": (_json(notebook({"0": code()})), "has cells that are an object, not a list"),
    "no_cells": (_json({"nbformat": 4, "metadata": {}}), "has no cells"),
    "cell_not_object": (_json(notebook([code(), "print(1)"])), "has a cell (cell 2) that is a string"),
    "bad_cell_type": (_json(notebook([dict(code(), cell_type="python")])), "of type 'python', expected code"),
    "missing_source": (_json(notebook([{"cell_type": "code", "metadata": {}, "outputs": []}])),
                       "has a code cell (cell 1) without a source"),
    "source_numbers": (_json(notebook([code(["x = 1\n", 2])])), "whose source is a list holding a number, not only text"),
    "deep": (b"[" * 100_000 + b"]" * 100_000, "nested too deeply"),
    "huge_integer": (b'{"nbformat": 4, "cells": [], "x": ' + b"9" * 10_000 + b"}", "is not valid JSON (Exceeds"),
    "many_cells": (_json(notebook([code()] * 100_000)), "has 100000 cells, more than the 5000"),
    "directory": (lambda path: path.mkdir(), "is a folder, not a notebook file"),
    "fifo": (lambda path: os.mkfifo(path), "is not a regular file"),
    "huge_sparse": (lambda path: sparse(path, 100_000_000),
                    "is 100 MB, more than the 67.1 MB a notebook may have"),
}


def make(folder, kind):
    """The file of `kind` (a key of MALFORMED) in `folder`; returns its path."""
    path = folder / f"{kind}.ipynb"
    content = MALFORMED[kind][0]
    if callable(content):
        content(path)
    else:
        path.write_bytes(content)
    return path


@pytest.mark.parametrize("kind", sorted(MALFORMED))
def test_a_malformed_notebook_is_rejected_with_one_line(tmp_path, kind):
    """Each kind of broken notebook a class produces is rejected, the reason one line saying what is wrong."""
    path = make(tmp_path, kind)
    with pytest.raises(NotebookRejected) as caught:
        read_notebook(path)
    reason = str(caught.value)
    assert MALFORMED[kind][1] in reason
    assert "\n" not in reason and len(reason) <= 300


def test_an_attachment_larger_than_the_limit_is_rejected(tmp_path):
    """An attachment over the limit is named with its cell; one under it passes."""
    path = tmp_path / "pictures.ipynb"
    path.write_text(json.dumps(notebook([code(), picture(1000), picture(5000)])))
    with pytest.raises(NotebookRejected, match=r"attachment 'x.png' \(cell 3\) of 5 kB, more than the 2 kB"):
        read_notebook(path, Limits(attachment_bytes=2000))
    assert len(read_notebook(path, Limits(attachment_bytes=6000))["cells"]) == 3


def test_every_limit_is_a_parameter(tmp_path):
    """The size and cell limits are the limits given: one byte or one cell more is rejected."""
    path = tmp_path / "n.ipynb"
    path.write_text(json.dumps(notebook([code()] * 3)))
    size = path.stat().st_size
    assert read_notebook(path, Limits(notebook_bytes=size, cells=3))["nbformat"] == 4
    with pytest.raises(NotebookRejected, match="more than the"):
        read_notebook(path, Limits(notebook_bytes=size - 1))
    with pytest.raises(NotebookRejected, match="has 3 cells, more than the 2"):
        read_notebook(path, Limits(cells=2))


@pytest.mark.parametrize("name", ["00_warmup", "01_integrator_order"])
def test_the_course_notebooks_are_read(name):
    """The masters and the released exercises pass the checks at the default limits."""
    for folder in ("solutions", "exercises"):
        assert read_notebook(ROOT / folder / f"{name}.ipynb")["cells"]


@pytest.mark.parametrize("field, value", [("cells", -1), ("notebook_bytes", 1.5), ("zip_members", True),
                                          ("ratio", 0.5), ("ratio", float("nan"))])
def test_bad_limits_are_refused_by_name(field, value):
    """A limit that is not a non-negative integer (ratio: a number >= 1) is refused, naming it."""
    with pytest.raises(ValueError, match=field):
        Limits(**{field: value})


# -- zips --------------------------------------------------------------------------------------------------------

GOOD = json.dumps(notebook())


def make_zip(path, members, compression=zipfile.ZIP_DEFLATED):
    """A zip of `members`: (name, bytes or str) or (ZipInfo, data)."""
    with zipfile.ZipFile(path, "w", compression) as archive:
        for name, data in members:
            archive.writestr(name, data)
    return path


def link(name, target):
    info = zipfile.ZipInfo(name)
    info.create_system, info.external_attr = 3, (stat.S_IFLNK | 0o777) << 16
    return info, target


def fifo(name):
    info = zipfile.ZipInfo(name)
    info.create_system, info.external_attr = 3, (stat.S_IFIFO | 0o644) << 16
    return info, ""


def encrypted(path):
    """Mark every member of the zip at `path` as encrypted (bit 0 of the flags in the central directory)."""
    data = bytearray(path.read_bytes())
    at = data.find(b"PK\x01\x02")
    while at >= 0:
        data[at + 8] |= 1
        at = data.find(b"PK\x01\x02", at + 4)
    path.write_bytes(bytes(data))
    return path


# kind -> (members, limits, a piece of the expected message)
BAD_ZIPS = {
    "traversal": ([("alice/00_warmup.ipynb", GOOD), ("../evil.ipynb", GOOD)], DEFAULT_LIMITS,
                  "member '../evil.ipynb' goes up out of the zip's folder"),
    "traversal_inner": ([("alice/../../evil.ipynb", GOOD)], DEFAULT_LIMITS, "goes up out"),
    "traversal_backslash": ([("alice\\..\\..\\evil.ipynb", GOOD)], DEFAULT_LIMITS, "goes up out"),
    "absolute": ([("/tmp/evil.ipynb", GOOD)], DEFAULT_LIMITS, "member '/tmp/evil.ipynb' is an absolute path"),
    "drive": ([("C:/Users/evil.ipynb", GOOD)], DEFAULT_LIMITS, "is an absolute path"),
    "symlink": ([("alice/00_warmup.ipynb", GOOD), link("bob/00_warmup.ipynb", "/etc/passwd")], DEFAULT_LIMITS,
                "member 'bob/00_warmup.ipynb' is a symbolic link"),
    "symlink_folder": ([link("carol", "/home")], DEFAULT_LIMITS, "is a symbolic link"),
    "fifo": ([fifo("alice/00_warmup.ipynb")], DEFAULT_LIMITS, "is a device, a pipe or a socket"),
    "ratio": ([("a/00_warmup.ipynb", b" " * 300_000)], Limits(ratio=50, ratio_floor=1000),
              "is compressed"),
    "ratio_default": ([("a/00_warmup.ipynb", bytes(20_000_000))], DEFAULT_LIMITS,
                      "more than 200 (a zip bomb?)"),
    "count": ([(f"s{k}/00_warmup.ipynb", GOOD) for k in range(11)], Limits(zip_members=10),
              "it has 11 members, more than 10 (a zip bomb?)"),
    "member_size": ([("a/00_warmup.ipynb", "x" * 5000)], Limits(member_bytes=4000), "5 kB uncompressed"),
    "total_size": ([(f"s{k}/00_warmup.ipynb", "y" * 3000) for k in range(4)], Limits(total_bytes=10_000),
                   "more than 10 kB uncompressed"),
    "duplicate": ([("alice/00_warmup.ipynb", GOOD), ("alice/00_warmup.ipynb", "{}")], DEFAULT_LIMITS,
                  "two members named 'alice/00_warmup.ipynb'"),
}


@pytest.mark.parametrize("kind", sorted(BAD_ZIPS))
def test_an_unsafe_zip_is_refused_whole(tmp_path, kind):
    """Paths out, links, devices, bombs by ratio, size or count: the zip is refused naming why, nothing is left."""
    members, limits, message = BAD_ZIPS[kind]
    with pytest.warns(UserWarning) if kind == "duplicate" else contextlib.nullcontext():
        path = make_zip(tmp_path / f"{kind}.zip", members)
    with pytest.raises(ZipRefused) as caught:
        extract_zip(path, tmp_path / "out", limits)
    assert message in str(caught.value) and str(path) in str(caught.value)
    assert not (tmp_path / "out").exists() and not (tmp_path / "evil.ipynb").exists()


def test_an_encrypted_or_broken_zip_is_refused(tmp_path):
    """An encrypted member, or a file that is not a zip, is refused with the reason."""
    path = encrypted(make_zip(tmp_path / "secret.zip", [("alice/00_warmup.ipynb", GOOD)]))
    with pytest.raises(ZipRefused, match="is encrypted"):
        extract_zip(path, tmp_path / "out")
    junk = tmp_path / "junk.zip"
    junk.write_bytes(b"PK\x03\x04 not really")
    with pytest.raises(ZipRefused, match="junk.zip: not a readable zip"):
        extract_zip(junk, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_zip_is_opened_privately_with_its_notebooks_only(tmp_path):
    """Notebooks and Gradescope's metadata are written (0600 in 0700 folders); other files, macOS's
    __MACOSX and ._ files are not; a zip inside the zip is reported, not opened."""
    inner = make_zip(tmp_path / "inner.zip", [("dave/00_warmup.ipynb", GOOD)]).read_bytes()
    path = make_zip(tmp_path / "export.zip", [
        ("export/alice/00_warmup.ipynb", GOOD), ("export/bob/notes.txt", "hello"), ("export/bob/x.IPYNB", GOOD),
        ("export/submission_metadata.yml", "x: 1\n"), ("__MACOSX/export/alice/._00_warmup.ipynb", "junk"),
        ("export/carol/upload.zip", inner), ("export/empty/", "")])
    reported = extract_zip(path, tmp_path / "out")
    written = sorted(str(p.relative_to(tmp_path / "out")) for p in (tmp_path / "out").rglob("*") if p.is_file())
    assert written == ["export/alice/00_warmup.ipynb", "export/bob/x.IPYNB", "export/submission_metadata.yml"]
    assert len(reported) == 1 and "export/carol/upload.zip: a zip inside the zip is not opened" in reported[0]
    assert stat.S_IMODE((tmp_path / "out").stat().st_mode) == 0o700
    assert stat.S_IMODE((tmp_path / "out" / "export" / "alice" / "00_warmup.ipynb").stat().st_mode) == 0o600
    assert json.loads((tmp_path / "out" / "export" / "alice" / "00_warmup.ipynb").read_text()) == notebook()
    with pytest.raises(FileExistsError):  # never into a folder that exists
        extract_zip(path, tmp_path / "out")


# -- a whole run ------------------------------------------------------------------------------------------------

def test_a_run_over_bad_input_grades_everyone_and_loses_no_one(tmp_path):
    """One CLI run over a folder mixing a good notebook, each kind of bad one, a conflict, a link out of the
    folder, an LMS zip and an unsafe zip: every student has a record, the good ones full marks, each bad one 0
    with its one-line reason; the conflict names both notebooks; nothing outside the folder is read."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    subs.mkdir()
    good = MASTER.read_bytes()
    (subs / "good.ipynb").write_bytes(good)
    bad = ["not_json", "nbformat3", "duplicate_ids", "latin1", "many_cells", "empty", "json_list", "cells_dict",
           "missing_source", "directory", "huge_sparse"]
    for kind in bad:
        make(subs, kind)
    (subs / "Alice").mkdir()
    (subs / "Alice" / "00_warmup.ipynb").write_bytes(good)
    (subs / "alice.ipynb").write_bytes(good)
    (tmp_path / "elsewhere.ipynb").write_bytes(good)
    (subs / "mallory.ipynb").symlink_to(tmp_path / "elsewhere.ipynb")
    lms = make_zip(tmp_path / "canvas.zip", [("zoe_late_11_22_00_warmup.ipynb", good)])
    bomb = make_zip(tmp_path / "bomb.zip", [("../zed/00_warmup.ipynb", good)])
    done = subprocess.run([sys.executable, "-m", "particles.cli", "grade", str(subs), str(lms), str(bomb),
                           "--out", str(out), "--exercise", "00_warmup", "--seed", "3"],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 1, done.stderr  # every record written, and the rejected ones said loudly
    assert f"{len(bad) + 1} notebook(s) scored 0 without being run" in done.stderr
    with open(out / "gradebook.csv", newline="") as stream:
        rows = {row["student"]: row for row in csv.DictReader(stream)}
    assert sorted(rows) == sorted(["good", "zoe", "Alice", *bad])
    assert rows["good"]["00_warmup"] == rows["good"]["max_total"] == rows["zoe"]["00_warmup"]
    assert float(rows["good"]["max_total"]) > 0
    term = TermRecord(out)
    records = {student: r.to_dict() for (student, _), r in term.current().items()}
    term.close()
    for student in ["Alice", *bad]:
        assert float(rows[student]["00_warmup"]) == 0, student
        record = records[student]
        reasons = {t["reason"] for t in record["tests"]}
        assert len(record["tests"]) > 5 and len(reasons) == 1 and "\n" not in reasons.pop()
        assert record["grader_status"] is None  # never kept by --resume: checked again next time
    record = records["latin1"]
    assert record["tests"][0]["reason"] == NOT_RUN  # the reason once, in the notes, not in every test
    assert "Not graded: your notebook latin1.ipynb could not be read: it is not UTF-8" in record["notes"][0]
    feedback = (out / "latin1" / "feedback.md").read_text()
    assert feedback.count("could not be read") == 1 and str(subs) not in feedback
    conflict = records["Alice"]["notes"][0]
    assert "00_warmup.ipynb" in conflict and "alice.ipynb" in conflict and str(subs) not in conflict
    assert "grade again" not in conflict and f"{subs / 'alice.ipynb'}" in done.stderr
    assert "mallory" not in rows and f"{subs / 'mallory.ipynb'}: a link to" in done.stderr
    assert "bomb.zip: zip refused: member '../zed/00_warmup.ipynb' goes up" in done.stderr
    assert "canvas.zip:zoe_late_11_22_00_warmup.ipynb" in records["zoe"]["notebook"]
    assert not (tmp_path / "zed").exists()


def test_a_member_that_cannot_be_written_refuses_the_zip(tmp_path):
    """A notebook member under another notebook member's name (x.ipynb, then x.ipynb/y.ipynb) is refused."""
    path = make_zip(tmp_path / "odd.zip", [("a/x.ipynb", GOOD), ("a/x.ipynb/y.ipynb", GOOD)])
    with pytest.raises(ZipRefused, match=r"member 'a/x.ipynb/y.ipynb' collides with another member"):
        extract_zip(path, tmp_path / "out")
    assert not (tmp_path / "out").exists()
