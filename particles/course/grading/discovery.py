"""Which notebooks a grading run grades: submissions, students, exercises, written answers.

Layouts read (:func:`find_submissions`):

* a notebook given on the command line is one submission; the student is its
  file name without ``.ipynb``;
* a folder: notebooks directly inside it are graded the same way; notebooks
  in sub-folders belong to the student named by the first sub-folder (the
  layout of an export with one folder per student);
* Canvas's file names ``login_[LATE_]userid_attachmentid_name[-N].ipynb`` belong to Canvas user ``userid``
  (login ``login``): two students with one login are two students. Of one user's files for one exercise, the
  latest upload is graded (the largest attachment id, then Canvas's ``-N`` copy number) and the report says
  which; ``LATE_`` is kept as Canvas's flag, checked against the submission time;
* Moodle's folders ``Full Name_12345_assignsubmission_file_`` belong to ``Full_Name_12345``;
* Gradescope's ``submission_NNN/`` folders belong to every submitter that ``submission_metadata.yml`` beside
  them lists (a group submission is graded once per submitter), each known by their e-mail and SID, and
  were submitted at its ``created_at`` (read with a YAML library: Ruby's symbol keys, its timestamps);
* a ``.zip`` (an LMS export, or one student's upload) is opened safely into a
  private folder (:func:`particles.course.grading.intake.extract_zip`: a zip
  with links, paths out of it or the shape of a bomb is refused, saying why)
  and read as a folder; a single folder at its top holding the students'
  folders (``export/alice/...``) is looked into. A zip inside a folder is
  not opened (it is reported).

Inside a folder, links are not followed out of it: a link to a file or a
folder outside the folder, and any link to a folder, is reported and not
read; ``__MACOSX``, ``._*`` and ``.ipynb_checkpoints`` are skipped.

The exercise of a notebook is read from its metadata (written by
``particles release``), else from its file name (``..._00_warmup...``), else
from ``--exercise``, which also overrides both.

Who a submission belongs to is decided by the course's
:class:`~particles.course.term.identity.Identity` (the roster and the students' aliases, else the students the
course's record knows), every name matched case- and Unicode-insensitively: ``Alice/`` and ``alice.ipynb`` are
one student, and so are Canvas's ``alicesmith`` and Gradescope's ``alice@uni.edu`` when the roster says so. A
submission whose names are no roster student's is graded under its own name and reported. A student with
several notebooks of one exercise in one place (their own folder, or one Canvas user's files) gets one graded:
Canvas's latest upload, else the one named exactly ``NN_topic.ipynb``, else the newest; the others are
reported. Notebooks of one student and exercise from *different* places (a file and a folder, ``Alice/`` and
``alice/``, two folders given) are a conflict: none of them is graded, the student gets a :class:`Unit`
rejected with a reason naming all of them, and the problem is reported.

A notebook that is not one the grader reads (:func:`particles.course.grading.intake.read_notebook`:
not UTF-8 JSON, not nbformat 4, duplicate cell ids, too large...) is a
:class:`Unit` rejected with the one-line reason, and is reported: the driver
records 0 for it, saying why, and grades the others.
"""

import dataclasses
import hashlib
import json
import os
import re
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

import yaml

from ..release.answers import count_answers
from ..term.identity import Identity, filing_name, name_key
from .intake import DEFAULT_LIMITS, NotebookRejected, ZipRefused, extract_zip, read_notebook, skipped_name

__all__ = ["Unit", "find_submissions", "written_answers", "released_exercise", "notebook_digest", "student_key",
           "gradescope_submissions"]

CANVAS = re.compile(r"^(?P<login>[^_]+)_(?P<late>late_|LATE_)?(?P<user>\d+)_(?P<submission>\d+)_(?P<name>.+?)"
                    r"(?:-(?P<copy>\d+))?(?P<suffix>\.ipynb)?$", re.IGNORECASE)
"""Canvas's names of the files of a submissions download (``-N``: Canvas's copy number of a re-upload)."""

MOODLE = re.compile(r"^(?P<name>.+_\d+)_assign(?:submission|feedback)_[a-z]+_?$")
"""Moodle's names of the folders of a submissions download."""


@dataclass
class Unit:
    """One notebook to grade: who submitted it, which exercise it is.

    Attributes
    ----------
    student, exercise : str
    notebook : Path
        The file graded (inside a private folder when it came out of a zip).
    rejected : str
        Why it is not graded, in one line ("" to grade it): the driver records 0 with this reason.
    origin : str
        Where it came from as the instructor named it (``export.zip:alice/00_warmup.ipynb``; "" when it is
        `notebook` itself).
    aliases : tuple of (kind, value)
        The names the submission gave its student (Canvas's user id and login, Gradescope's e-mail and SID).
    submitted : datetime, optional
        When it was submitted, when the LMS's download says so (Gradescope's ``created_at``).
    time_source : str
        Where `submitted` came from.
    late_flag : bool
        Canvas marked it late (``LATE_`` in its file name).
    on_roster : bool
        Its student is one the course knows (False: a name no roster student has).
    place : tuple
        The place it came from (a folder, a Canvas user's files in one download, a Gradescope submission):
        one student's notebooks of one exercise from two places are a conflict.
    handed_in : str
        The notebook as the student handed it in: its path inside the zip or folder given (``alice/00_warmup.ipynb``),
        or its name; what the student reads of it, with none of the instructor's folders.
    """

    student: str
    exercise: str
    notebook: Path
    rejected: str = ""
    origin: str = ""
    aliases: tuple = ()
    submitted: datetime = None
    time_source: str = ""
    late_flag: bool = False
    on_roster: bool = True
    place: tuple = ()
    handed_in: str = ""
    _digest: str = field(default=None, init=False, repr=False, compare=False)

    @property
    def where(self):
        """Where the notebook came from, in words."""
        return self.origin or str(self.notebook)

    def digest(self):
        """The notebook's SHA-256 (:func:`notebook_digest`), read once."""
        if self._digest is None:
            self._digest = notebook_digest(self.notebook)
        return self._digest


def _exercise_of(notebook, content, exercises, override=None):
    if override:
        return override
    if isinstance(content, dict) and isinstance(content.get("metadata"), dict):
        meta = content["metadata"].get("particles")
        name = meta.get("exercise") if isinstance(meta, dict) else None
        if name in exercises:
            return name
    for name in sorted(exercises, key=len, reverse=True):
        if name in Path(notebook).stem:
            return name
    return None


def student_key(text):
    """The key two names of one student compare equal by (:func:`particles.course.term.identity.name_key`)."""
    return name_key(text)


def _upload(path):
    """Which of one Canvas user's files is the latest upload: (attachment id, copy number); (-1, -1) if not
    Canvas's."""
    match = CANVAS.match(Path(path).name)
    return (int(match.group("submission")), int(match.group("copy") or 0)) if match else (-1, -1)


def _preference(unit):
    """Which of two notebooks of one student and exercise to grade: Canvas's latest upload, the exact name
    (after Canvas's prefix), then the newest (then the last in sorted order, so that the choice never depends on
    the order of discovery)."""
    path = Path(unit.notebook)
    match = CANVAS.match(path.name)
    name = f"{match.group('name')}.ipynb" if match else path.name
    try:
        mtime = path.stat().st_mtime
    except OSError:
        mtime = float("-inf")
    return (_upload(path), name == f"{unit.exercise}.ipynb", mtime, str(path))


def _created_at(value):
    """Gradescope's ``created_at`` as an aware datetime, or None (a date alone, no zone, unreadable)."""
    if isinstance(value, str):
        try:
            value = datetime.fromisoformat(re.sub(r"(\.\d{6})\d+", r"\1", value.strip()).replace(" -", "-")
                                           .replace(" +", "+"))
        except ValueError:
            return None
    if isinstance(value, datetime) and value.tzinfo is not None:
        return value
    return None


def gradescope_submissions(folder):
    """``submission_NNN`` -> ``(submitters, created_at)`` from Gradescope's ``submission_metadata.yml`` in `folder`.

    ``submitters`` is a list of (name, aliases), one per submitter: the name is the e-mail (else the SID, else
    the name), the aliases the e-mail and the SID; ``created_at`` an aware datetime or None. Keys are read with
    or without Ruby's leading ``:``. A file that is missing or not YAML gives ``{}``.
    """
    try:
        data = yaml.safe_load((Path(folder) / "submission_metadata.yml").read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return {}
    plain = lambda d: {str(k).lstrip(":"): v for k, v in d.items()} if isinstance(d, dict) else {}  # noqa: E731
    out = {}
    for key, entry in (data.items() if isinstance(data, dict) else ()):
        entry = plain(entry)
        submitters = []
        for person in entry.get("submitters") or []:
            person = {k: str(v).strip() for k, v in plain(person).items() if v not in (None, "")}
            name = person.get("email") or person.get("sid") or person.get("name")
            if name:
                aliases = [("email", person["email"])] if "email" in person else []
                submitters.append((name, tuple(aliases + ([("sid", person["sid"])] if "sid" in person else []))))
        out[str(key).lstrip(":")] = (submitters, _created_at(entry.get("created_at")))
    return out


def _walk(root, problems):
    """The notebooks under folder `root`, never through a link out of it: a list of (path, relative parts)."""
    root = Path(root)
    real_root = os.path.realpath(root)
    out, stack = [], [(root, ())]
    while stack:
        folder, rel = stack.pop()
        try:
            entries = sorted(os.scandir(folder), key=lambda e: e.name, reverse=True)
        except OSError as error:
            problems.append(f"{folder}: cannot be read ({error.strerror or error})")
            continue
        for entry in entries:
            if skipped_name(entry.name):
                continue
            path, parts = Path(entry.path), rel + (entry.name,)
            notebook = entry.name.lower().endswith(".ipynb")
            if entry.is_symlink():
                target = os.path.realpath(path)
                inside = os.path.commonpath([real_root, target]) == real_root
                if os.path.isdir(target) or not inside:
                    if notebook or os.path.isdir(target):
                        where = "outside the folder" if not inside else "a folder"
                        problems.append(f"{path}: a link to {target} ({where}); not followed")
                    continue
                if notebook:
                    out.append((path, parts))
            elif entry.is_dir(follow_symlinks=False) and not notebook:
                stack.append((path, parts))
            elif notebook:
                out.append((path, parts))
            elif entry.name.lower().endswith(".zip"):
                problems.append(f"{path}: a zip in a folder is not opened; give it as a SUBMISSION of its own")
    return sorted(out)


def _unwrap(folder):
    """Into a zip's single top folder while it holds students' folders (``export/alice/..., export/bob/...``,
    or Gradescope's ``submission_metadata.yml`` beside them) and no notebook."""
    folder = Path(folder)
    while True:
        entries = [e for e in folder.iterdir() if not skipped_name(e.name)]
        if len(entries) != 1 or not entries[0].is_dir():
            return folder
        inner = [e for e in entries[0].iterdir() if not skipped_name(e.name)]
        folders = sum(e.is_dir() for e in inner)
        if any(e.name.lower().endswith(".ipynb") for e in inner) or not (
                folders >= 2 or folders and any(e.name == "submission_metadata.yml" for e in inner)):
            return folder
        folder = entries[0]


@dataclass
class _Found:
    """A notebook found, before its students are known: who it names, where it came from."""

    notebook: Path
    submitters: list  # of (name, aliases)
    source: tuple
    origin: str = ""
    submitted: datetime = None
    time_source: str = ""
    late_flag: bool = False
    handed_in: str = ""


def _candidates(given, problems, workdir, limits):
    """The :class:`_Found` notebooks of one path given on the command line."""
    if given.suffix.lower() == ".zip" and given.exists() and not given.is_dir():
        if workdir is None:
            problems.append(f"{given}: zips are opened by particles grade only; unzip it first")
            return []
        folder = Path(workdir) / f"zip{len(list(Path(workdir).iterdir())):03d}"
        try:
            problems += extract_zip(given, folder, limits)
        except ZipRefused as error:
            problems.append(str(error))
            return []
        top = _unwrap(folder)
        return [_who(nb, top, parts, ("zip", str(given)), f"{given}:{Path(*parts)}")
                for nb, parts in _walk(top, problems)]
    if given.is_dir():
        return [_who(nb, given, parts, ("folder", str(given)), "") for nb, parts in _walk(given, problems)]
    if given.exists() or given.is_symlink():
        return [_Found(given, [(given.stem, ())], ("file", str(given.resolve())), handed_in=given.name)]
    problems.append(f"{given} does not exist")
    return []


def _who(notebook, root, parts, place, origin):
    """Who the notebook at `parts` under `root` names, and the place it came from."""
    found = _named(notebook, root, parts, place, origin)
    found.handed_in = Path(*parts).as_posix()
    return found


def _named(notebook, root, parts, place, origin):
    if len(parts) > 1:
        folder = parts[0]
        match = MOODLE.match(folder)
        if re.fullmatch(r"submission_\d+", folder):
            submitters, created = gradescope_submissions(root).get(folder, ([(folder, ())], None))
            return _Found(notebook, submitters or [(folder, ())], (*place, "folder", folder), origin, created,
                          "Gradescope's submission_metadata.yml" if created else "")
        if match:
            folder = match.group("name")
        return _Found(notebook, [(folder, ())], (*place, "folder", parts[0]), origin)
    match = CANVAS.match(parts[0])
    if match:
        login, user = match.group("login"), match.group("user")
        return _Found(notebook, [(login, (("canvas_id", user), ("login", login)))], (*place, "canvas", user),
                      origin, late_flag=bool(match.group("late")))
    return _Found(notebook, [(Path(parts[0]).stem, ())], (*place, "file", parts[0]), origin)


def find_submissions(paths, exercises, exercise=None, *, workdir=None, limits=DEFAULT_LIMITS, identity=None):
    """Expand notebooks, folders and zips into :class:`Unit` s and a list of problems.

    Parameters
    ----------
    paths : sequence of path
        Notebooks, folders of them, zips of them (see the module's notes).
    exercises : sequence of str
        The exercises' names (``NN_topic``).
    exercise : str, optional
        Every notebook is this exercise.
    workdir : path, optional
        A private folder (mode 0700) to open zips into, kept while their
        notebooks are graded; without it a zip is a problem.
    limits : particles.course.grading.intake.Limits
        What a notebook and a zip may hold.
    identity : particles.course.term.identity.Identity, optional
        Who is in the course (default: whoever the submissions name); students it admits are added to it.

    Returns
    -------
    units : list of Unit
        One per student and exercise; a unit with ``rejected`` set is not to
        be graded (a notebook the grader does not read, or a conflict).
    problems : list of str
        One line each: notebooks whose exercise could not be told, paths that
        do not exist, zips refused, links not followed, notebooks not graded
        and why, submissions of names that are no roster student's.
    """
    identity = Identity() if identity is None else identity
    problems, found, seen = [], [], set()
    for given in map(Path, paths):
        for candidate in _candidates(given, problems, workdir, limits):
            key = (os.path.realpath(candidate.notebook), tuple(name_key(n) for n, _ in candidate.submitters))
            if key in seen:  # the same file given twice: one submission
                continue
            seen.add(key)
            unit = _read(candidate, exercises, exercise, problems, limits)
            if unit is not None:
                found += [(unit, candidate, who) for who in candidate.submitters]
    admitted = {}  # students admitted in the sorted order of their names (the first spelling names them) ...
    for k in sorted(range(len(found)), key=lambda k: (filing_name(found[k][2][0]), found[k][0].where)):
        unit, _, (name, aliases) = found[k]
        admitted[k] = _admitted(unit, name, aliases, identity, problems)
    units = [admitted[k] for k in range(len(found))]  # ... their notebooks kept in the order they were found
    return _one_per_student(units, problems), problems


def _read(candidate, exercises, exercise, problems, limits):
    """The unit of a found notebook (its student still to decide), or None when its exercise is unknown."""
    nb, origin = candidate.notebook, candidate.origin
    where = origin or str(nb)
    try:
        content, rejected = read_notebook(nb, limits), ""
    except NotebookRejected as error:
        content, rejected = None, f"your notebook {Path(origin or nb).name} could not be read: it {error}"
    except (ValueError, MemoryError) as error:  # never a run stopped by one file
        content, rejected = None, (f"your notebook {Path(origin or nb).name} could not be read "
                                   f"({type(error).__name__}: {' '.join(str(error).split())[:200]})")
    name = _exercise_of(nb, content, exercises, exercise)
    if name is None:
        problems.append(f"{where}: cannot tell which exercise this is; pass --exercise"
                        + (f" ({rejected})" if rejected else ""))
        return None
    if rejected:
        problems.append(f"{where}: 0 points: {rejected}")
    return Unit("", name, nb, rejected, origin, submitted=candidate.submitted, time_source=candidate.time_source,
                late_flag=candidate.late_flag, place=candidate.source, handed_in=candidate.handed_in)


def _admitted(unit, name, aliases, identity, problems):
    """A copy of `unit` for the submitter `name`, as the course's identity knows them."""
    person = identity.admit(name, aliases)
    own = dataclasses.replace(unit, student=person.name if person is not None else filing_name(name),
                              aliases=tuple(aliases))
    if person is None:
        own.on_roster = False
        problems.append(f"{unit.where}: {name!r} is no student of the roster (nor an alias of one): graded as "
                        f"{own.student}; add the name to their roster line's aliases")
    return own


def _one_per_student(units, problems):
    """One unit per student and exercise: of one place, the preferred notebook; of several places, a conflict."""
    groups = {}
    for unit in units:
        groups.setdefault((unit.student, unit.exercise), {}).setdefault(unit.place, []).append(unit)
    out = []
    for (student, name), sources in groups.items():
        picks = []
        for own in sources.values():  # one place: the latest upload, the exact name, the newest
            keep = max(own, key=_preference)
            picks.append(keep)
            which = "the latest upload, " if _upload(keep.notebook) > (-1, -1) else ""
            problems += [f"{drop.where}: {student} has several notebooks for {name}; graded {which}{keep.where}"
                         for drop in own if drop is not keep]
        if len(picks) == 1:
            out.append(picks[0])
            continue
        both = " and ".join(p.where for p in picks)
        yours = " and ".join(p.handed_in or Path(p.notebook).name for p in picks)  # without our folders
        reason = f"{len(picks)} notebooks from different places are yours for {name} ({yours}); none was graded"
        problems.append(f"{student}: 0 points: {len(picks)} notebooks from different places map to student "
                        f"{student} for {name} ({both}); none was graded: keep one and grade again")
        out.append(Unit(student, name, picks[0].notebook, reason, both, aliases=picks[0].aliases))
    return out


def released_exercise(root, exercise):
    """The released notebook of `exercise` as a dict: generated from its master when there is one.

    Returns None when neither ``solutions/NN_topic.ipynb`` nor
    ``exercises/NN_topic.ipynb`` can be read.
    """
    from ..release.notebooks import ReleaseError, read_master, release_notebook

    root = Path(root)
    master = root / "solutions" / f"{exercise}.ipynb"
    try:
        if master.exists():
            return json.loads(json.dumps(release_notebook(read_master(master), exercise)))
        return json.loads((root / "exercises" / f"{exercise}.ipynb").read_text(encoding="utf-8"))
    except (ReleaseError, OSError, UnicodeDecodeError, ValueError):
        return None


def written_answers(notebook, root, exercise):
    """The written (hand-graded) answers of a submission: ``{"asked": N, "answered": k, "blank": [...]}``.

    One answer slot per question of the released exercise
    (:func:`particles.course.release.answers.count_answers`): a slot left with its
    prompt, white space or nothing is blank. The autograder does not score
    these answers: the count tells the student and the instructor what is
    left to write and to read.
    """
    released = released_exercise(root, exercise)
    if released is None:
        return {"asked": 0, "answered": 0, "blank": []}
    return count_answers(notebook, released)


def notebook_digest(path):
    """SHA-256 of a notebook file's bytes (hex), or "" when it cannot be read: what a resumed run compares."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return ""
