"""What a grading run lets in: notebooks checked before they are graded, zips opened safely.

Two gates stand between the files an instructor is given and the grader:

* :func:`read_notebook` reads one submitted notebook within :class:`Limits` (file size, cell count,
  attachment size) and checks that it is a Jupyter notebook of format 4 (UTF-8 JSON, an object with a
  list of cells, each with a type and a source, no two cells with one id). A notebook that is not gets
  :class:`NotebookRejected`, whose message is one line for the student (``is not valid JSON (Expecting
  ',' delimiter at line 3, column 5)``): the driver records 0 for it with that reason and goes on.
* :func:`extract_zip` opens an export of an LMS (Canvas, Moodle, Gradescope) into a new private folder.
  It refuses the whole zip (:class:`ZipRefused`, naming the zip and the member) when a member would land
  outside the folder (an absolute path, ``..``), is a link, a device or a pipe, is encrypted, or when the
  zip is a bomb: too many members, a member or a total too large once uncompressed, or a compression
  ratio no notebook has. Only notebooks (and Gradescope's ``submission_metadata.yml``) are written; a zip
  inside the zip is not opened but reported; macOS's ``__MACOSX/`` and ``._*`` files are skipped.

Which notebooks are graded, and as which student, is decided in
:mod:`particles.course.grading.discovery`, which calls both.
"""

import json
import os
import re
import shutil
import stat
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Limits", "DEFAULT_LIMITS", "NotebookRejected", "ZipRefused", "read_notebook", "check_notebook",
           "extract_zip", "skipped_name", "METADATA_FILES"]

MiB = 1024 * 1024

METADATA_FILES = ("submission_metadata.yml",)
"""Files of an export that say who submitted what (Gradescope's), extracted beside the notebooks."""


@dataclass(frozen=True)
class Limits:
    """What a submitted notebook and an uploaded zip may hold.

    Attributes
    ----------
    notebook_bytes : int
        Size of one notebook file (default 64 MiB).
    cells : int
        Cells of one notebook (default 5000; the exercises have about a hundred).
    attachment_bytes : int
        Size of one attachment of a markdown cell, decoded (default 16 MiB).
    zip_members : int
        Entries of a zip, folders included (default 20000).
    member_bytes : int
        Uncompressed size of one member of a zip (default 256 MiB).
    total_bytes : int
        Uncompressed size of all the members of a zip (default 2 GiB).
    ratio : float
        Largest compression ratio (uncompressed / compressed size) of a member
        of at least `ratio_floor` bytes (default 200: notebooks compress about
        3 to 20 times, bombs a thousand times).
    ratio_floor : int
        Members smaller than this are not checked for their ratio (default 1 MiB).
    """

    notebook_bytes: int = 64 * MiB
    cells: int = 5000
    attachment_bytes: int = 16 * MiB
    zip_members: int = 20000
    member_bytes: int = 256 * MiB
    total_bytes: int = 2048 * MiB
    ratio: float = 200.0
    ratio_floor: int = 1 * MiB

    def __post_init__(self):
        for name in ("notebook_bytes", "cells", "attachment_bytes", "zip_members", "member_bytes", "total_bytes",
                     "ratio_floor"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise ValueError(f"{name} must be a non-negative integer, got {value!r}")
        if isinstance(self.ratio, bool) or not isinstance(self.ratio, (int, float)) or not self.ratio >= 1:
            raise ValueError(f"ratio must be a number >= 1, got {self.ratio!r}")


DEFAULT_LIMITS = Limits()
"""The limits of ``particles grade``."""


class NotebookRejected(ValueError):
    """A submitted file is not a notebook the grader reads; the message is one line for the student."""


class ZipRefused(ValueError):
    """A zip is not opened: its message names the zip, the member and why."""


def _size(n):
    """Bytes in words: ``512 bytes``, ``3.2 MB``."""
    if n < 1000:
        return f"{n} bytes"
    for unit, scale in (("kB", 1e3), ("MB", 1e6), ("GB", 1e9)):
        if n / scale < 999.5 or unit == "GB":
            return f"{n / scale:.3g} {unit}"


def _kind(value):
    """A JSON value's kind in words: "a list", "a string", "null"."""
    names = {dict: "an object", list: "a list", str: "a string", bool: "a boolean", int: "a number",
             float: "a number", type(None): "null"}
    return names.get(type(value), type(value).__name__)


def _one_line(text, width=300):
    text = " ".join(str(text).split())
    return text if len(text) <= width else text[:width - 3] + "..."


def read_notebook(path, limits=DEFAULT_LIMITS):
    """The notebook at `path` as a dict, checked within `limits`.

    Parameters
    ----------
    path : path
        A submitted file (a link is followed: discovery decides which links may be).
    limits : Limits

    Returns
    -------
    dict
        The notebook (nbformat 4).

    Raises
    ------
    NotebookRejected
        With one line saying what is wrong, worded after "the notebook", e.g.
        ``is nbformat 3, expected 4: open it in Jupyter and save it again``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> bad = pathlib.Path(tempfile.mkdtemp()) / "a.ipynb"
    >>> _ = bad.write_text('{"cells": [')
    >>> try:
    ...     read_notebook(bad)
    ... except NotebookRejected as error:
    ...     print(error)
    is not valid JSON (Expecting value at line 1, column 12)
    """
    path = Path(path)
    try:
        info = path.stat()
    except OSError as error:
        raise NotebookRejected(f"cannot be read ({error.strerror or error})") from None
    if stat.S_ISDIR(info.st_mode):
        raise NotebookRejected("is a folder, not a notebook file")
    if not stat.S_ISREG(info.st_mode):
        raise NotebookRejected("is not a regular file (a pipe, a socket or a device)")
    if info.st_size > limits.notebook_bytes:
        raise NotebookRejected(f"is {_size(info.st_size)}, more than the {_size(limits.notebook_bytes)} a notebook "
                               "may have (clear the outputs and remove large pictures)")
    try:
        with open(path, "rb") as stream:
            data = stream.read(limits.notebook_bytes + 1)  # never more, even if the file grew meanwhile
    except OSError as error:
        raise NotebookRejected(f"cannot be read ({error.strerror or error})") from None
    if len(data) > limits.notebook_bytes:
        raise NotebookRejected(f"is more than the {_size(limits.notebook_bytes)} a notebook may have")
    if not data.strip():
        raise NotebookRejected(f"is empty ({len(data)} bytes)")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise NotebookRejected(f"is not UTF-8 text (byte 0x{data[error.start]:02x} at offset {error.start}): "
                               "save it again from Jupyter") from None
    try:
        notebook = json.loads(text)
    except json.JSONDecodeError as error:
        message = error.msg.removesuffix(" at")  # "Unterminated string starting at": never "at at"
        raise NotebookRejected(f"is not valid JSON ({message} at line {error.lineno}, column {error.colno})") from None
    except ValueError as error:  # e.g. an integer of more digits than Python converts
        raise NotebookRejected(f"is not valid JSON ({_one_line(error, 120)})") from None
    except RecursionError:
        raise NotebookRejected("is not a notebook (JSON nested too deeply)") from None
    if not isinstance(notebook, dict):
        raise NotebookRejected(f"holds {_kind(notebook)} in JSON, not a notebook (an object with cells)")
    check_notebook(notebook, limits)
    return notebook


def check_notebook(notebook, limits=DEFAULT_LIMITS):
    """Check a notebook's JSON object against nbformat 4 and `limits` (see :func:`read_notebook`).

    Raises
    ------
    NotebookRejected
        With one line saying what is wrong.
    """
    version = notebook.get("nbformat")
    if "worksheets" in notebook and version is None:
        version = 3
    if version is None:
        raise NotebookRejected("has no nbformat: it is not a Jupyter notebook")
    if version != 4 or isinstance(version, bool):
        old = isinstance(version, int) and version < 4
        raise NotebookRejected(f"is nbformat {_one_line(repr(version), 20)}, expected 4"
                               + (": open it in Jupyter (which converts it) and save it again" if old else ""))
    if "cells" not in notebook:
        raise NotebookRejected("has no cells")
    cells = notebook["cells"]
    if not isinstance(cells, list):
        raise NotebookRejected(f"has cells that are {_kind(cells)}, not a list")
    if len(cells) > limits.cells:
        raise NotebookRejected(f"has {len(cells)} cells, more than the {limits.cells} a notebook may have")
    ids = {}
    for k, cell in enumerate(cells, start=1):
        if not isinstance(cell, dict):
            raise NotebookRejected(f"has a cell (cell {k}) that is {_kind(cell)}, not an object")
        kind = cell.get("cell_type")
        if kind not in ("code", "markdown", "raw"):
            raise NotebookRejected(f"has a cell (cell {k}) of type {_one_line(repr(kind), 40)}, "
                                   "expected code, markdown or raw")
        if "source" not in cell:
            raise NotebookRejected(f"has a {kind} cell (cell {k}) without a source")
        source = cell["source"]
        if isinstance(source, list) and not all(isinstance(s, str) for s in source):
            odd = next(s for s in source if not isinstance(s, str))
            raise NotebookRejected(f"has a {kind} cell (cell {k}) whose source is a list holding {_kind(odd)}, "
                                   "not only text")
        if not isinstance(source, (str, list)):
            raise NotebookRejected(f"has a {kind} cell (cell {k}) whose source is {_kind(source)}, not text")
        if "id" in cell:
            cell_id = cell["id"]
            if not isinstance(cell_id, str):
                raise NotebookRejected(f"has a cell (cell {k}) whose id is {_kind(cell_id)}, not a string")
            if cell_id in ids:
                raise NotebookRejected(f"has two cells (cells {ids[cell_id]} and {k}) with the same id "
                                       f"{_one_line(repr(cell_id), 70)}: open it in Jupyter and save it again")
            ids[cell_id] = k
        _check_attachments(cell.get("attachments"), k, limits)
    return notebook


def _check_attachments(attachments, k, limits):
    if attachments is None:
        return
    if not isinstance(attachments, dict):
        raise NotebookRejected(f"has a cell (cell {k}) whose attachments are {_kind(attachments)}, not an object")
    for name, bundle in attachments.items():
        if not isinstance(bundle, dict):
            raise NotebookRejected(f"has an attachment {_one_line(repr(name), 60)} (cell {k}) that is "
                                   f"{_kind(bundle)}, not an object")
        for data in bundle.values():
            parts = data if isinstance(data, list) else [data]
            size = sum(len(p) for p in parts if isinstance(p, str)) * 3 // 4  # base64: 4 characters, 3 bytes
            if size > limits.attachment_bytes:
                raise NotebookRejected(f"has an attachment {_one_line(repr(name), 60)} (cell {k}) of "
                                       f"{_size(size)}, more than the {_size(limits.attachment_bytes)} "
                                       "an attachment may have")


def skipped_name(name):
    """True for what is never a submission: macOS's ``__MACOSX`` folders and ``._*`` files, checkpoints."""
    return name in ("__MACOSX", ".ipynb_checkpoints") or name.startswith("._")


def _member_parts(name):
    """The path parts of a zip member's name (``/`` or ``\\`` separated), or a reason it is unsafe."""
    if name.startswith(("/", "\\")) or re.match(r"^[A-Za-z]:", name):
        return None, "is an absolute path"
    parts = [p for p in re.split(r"[/\\]+", name) if p not in ("", ".")]
    if ".." in parts:
        return None, "goes up out of the zip's folder (..)"
    if "\0" in name:
        return None, "has a NUL character in its name"
    return parts, None


def _mode_problem(info):
    """Why a member is not a plain file or folder, or None."""
    if info.flag_bits & 0x1:
        return "is encrypted"
    mode = info.external_attr >> 16
    if info.create_system == 3 and mode:  # made on Unix: the high bits are st_mode
        kind = stat.S_IFMT(mode)
        if kind == stat.S_IFLNK:
            return "is a symbolic link"
        if kind in (stat.S_IFCHR, stat.S_IFBLK, stat.S_IFIFO, stat.S_IFSOCK):
            return "is a device, a pipe or a socket"
    return None


def extract_zip(path, dest, limits=DEFAULT_LIMITS):
    """Extract the notebooks of the zip `path` into the new folder `dest`, safely (see the module's notes).

    Parameters
    ----------
    path : path
        The zip (an LMS export, or one student's upload).
    dest : path
        A folder that does not exist yet: made with mode 0700, removed again
        when the zip is refused.
    limits : Limits

    Returns
    -------
    list of str
        Members not extracted that the instructor should hear about (a zip
        inside the zip), one line each.

    Raises
    ------
    ZipRefused
        When the zip cannot be read or is refused; nothing is left in `dest`.
    FileExistsError
        When `dest` exists (nothing is written into a folder someone else made).
    """
    path, dest = Path(path), Path(dest)
    os.mkdir(dest, 0o700)
    try:
        return _extract(path, dest, limits)
    except BaseException:
        shutil.rmtree(dest, ignore_errors=True)
        raise


def _extract(path, dest, limits):
    def refuse(why):
        return ZipRefused(f"{path}: zip refused: {why}; nothing in it was graded")

    try:
        archive = zipfile.ZipFile(path)
    except (OSError, zipfile.BadZipFile, ValueError, NotImplementedError, EOFError) as error:
        raise ZipRefused(f"{path}: not a readable zip ({_one_line(error, 120)})") from None
    with archive:
        members = archive.infolist()
        if len(members) > limits.zip_members:
            raise refuse(f"it has {len(members)} members, more than {limits.zip_members} (a zip bomb?)")
        total, seen, wanted, reported = 0, set(), [], []
        for info in members:
            parts, why = _member_parts(info.filename)
            why = why or _mode_problem(info)
            if why:
                raise refuse(f"member {info.filename!r} {why}")
            if info.file_size > limits.member_bytes:
                raise refuse(f"member {info.filename!r} is {_size(info.file_size)} uncompressed, more than "
                             f"{_size(limits.member_bytes)} (a zip bomb?)")
            ratio = info.file_size / max(info.compress_size, 1)
            if info.file_size >= limits.ratio_floor and ratio > limits.ratio:
                raise refuse(f"member {info.filename!r} is compressed {ratio:.0f} times, more than "
                             f"{limits.ratio:g} (a zip bomb?)")
            total += info.file_size
            if total > limits.total_bytes:
                raise refuse(f"its members are more than {_size(limits.total_bytes)} uncompressed (a zip bomb?)")
            key = "/".join(parts)
            if key in seen and not info.is_dir():
                raise refuse(f"it holds two members named {key!r}")
            seen.add(key)
            if info.is_dir() or not parts or any(skipped_name(p) for p in parts):
                continue
            if parts[-1].lower().endswith(".zip"):
                reported.append(f"{path}: {info.filename}: a zip inside the zip is not opened; unzip it and "
                                "grade its notebooks separately")
            elif parts[-1].lower().endswith(".ipynb") or parts[-1] in METADATA_FILES:
                wanted.append((info, parts))
        written = 0
        for info, parts in wanted:
            written += _write_member(archive, info, dest.joinpath(*parts), limits, refuse)
            if written > limits.total_bytes:
                raise refuse(f"its members are more than {_size(limits.total_bytes)} uncompressed (a zip bomb?)")
    return reported


def _write_member(archive, info, target, limits, refuse):
    """Copy one member to `target` (a new file, never through a link, dated as in the zip); returns its bytes."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
    try:
        target.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        handle = os.open(target, flags, 0o600)
    except FileExistsError:
        raise refuse(f"member {info.filename!r} collides with another member (letter case aside)") from None
    except OSError as error:
        raise refuse(f"member {info.filename!r} cannot be written ({error.strerror or error})") from None
    count = 0
    try:
        with os.fdopen(handle, "wb") as out, archive.open(info) as member:
            while chunk := member.read(MiB):
                count += len(chunk)
                if count > min(info.file_size, limits.member_bytes):
                    raise refuse(f"member {info.filename!r} is larger than it says (a zip bomb?)")
                out.write(chunk)
    except ZipRefused:
        raise
    except (zipfile.BadZipFile, NotImplementedError, RuntimeError, EOFError, OSError, ValueError) as error:
        raise refuse(f"member {info.filename!r} cannot be read ({_one_line(error, 120)})") from None
    try:  # the member's own date: "the newest" of a student's notebooks means the same as in a folder
        when = time.mktime(info.date_time + (0, 0, -1))
        os.utime(target, (when, when))
    except (OverflowError, ValueError, OSError):
        pass
    return count
