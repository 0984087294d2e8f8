"""Deadlines and late work: the course file, the time of a submission, and the penalty.

The course file is TOML, ``course.toml`` at the course root or given with
``particles grade --course FILE``::

    roster = "roster.csv"    # who is in the course (see particles.course.term.roster); optional

    # the late policy of every exercise (each may override it)
    [late]
    penalty_per_day = 0.10   # fraction of the exercise's points taken off per started day late
    cap = 0.50               # never more than this fraction of the exercise's points
    grace_minutes = 15       # submitted at most this long after the deadline: on time

    [exercises.00_warmup]
    deadline = 2026-10-01T23:59:00+01:00   # ISO 8601 with a time zone (a TOML date-time or a string)

    [exercises.01_integrator_order]
    deadline = "2026-10-29T23:59 Europe/Berlin"  # a local time and a named zone: CET or CEST, as that day has it
    penalty_per_day = 0.2                  # this exercise's own policy

    [extensions.alice]                     # per student: a new deadline, or extra days
    00_warmup = 2026-10-03T23:59:00+01:00
    01_integrator_order = 2

The penalty is a fraction of the exercise's points (the record's
:attr:`~particles.course.results.records.SubmissionRecord.total_max`): ``penalty_per_day`` per
*started* day after the student's deadline (one minute late is one day late), at most ``cap``, in
[0, 1]. The grace period only forgives: a submission after the grace period counts its days late
from the deadline itself. An exercise the file does not name has no deadline (its records'
``late`` is None). Every key is checked: an unknown exercise or key, a deadline without a time
zone, a negative penalty, a cap outside [0, 1] are errors naming the key, all of a file's errors
at once.

A time (a deadline, an extension's new deadline, a submission time) is a TOML date-time with an
offset (``2026-10-01T23:59:00+01:00``, ``Z`` for UTC), or a string: ISO 8601 with an offset, or a
local date and time followed by a named zone of the IANA database (``"2026-10-29T23:59
Europe/Berlin"``, also ``"2026-10-29T23:59[Europe/Berlin]"``), whose offset is the one that zone
has on that day, daylight saving included (Python's ``zoneinfo``: the system's zone database, or
the ``tzdata`` package where the system has none). A local time that does not exist in the zone
(the hour skipped when clocks go forward) or happens twice (when they go back) is an error: write
it with its offset.

The time of a submission is never guessed (:mod:`particles.course.grading.times` says where it comes from).

Every name is checked: an ``[extensions.NAME]`` or a times file's ``student`` that is no student of the course
(:mod:`particles.course.term.identity`: the roster's students and aliases, else the students the course's
record and the run know) stops the run before anything is graded, naming the file and the key or line. The
course file may name the roster: ``roster = "roster.csv"`` (relative to the course file).
"""

import math
import re
import tomllib
from dataclasses import dataclass, field
from datetime import date, datetime, time, timedelta, timezone
from pathlib import Path
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

from .discovery import Unit

__all__ = ["LatePolicy", "Course", "load_course", "find_course", "decide", "apply_late", "LateWork", "parse_time",
           "resolve_extensions", "shown_time", "COURSE_FILE"]

COURSE_FILE = "course.toml"
"""The course file's name at the course root."""

_POLICY_KEYS = ("penalty_per_day", "cap", "grace_minutes")
_DAY = timedelta(days=1)
_NAMED = re.compile(r"^(?P<when>\d{4}-\d\d-\d\d[T ]\d\d:\d\d(?::\d\d(?:\.\d+)?)?)"
                    r"(?:\s+(?P<zone>[A-Za-z][\w+-]*(?:/[\w+-]+)*)|\[(?P<bracket>[^\]]+)\])$")


def _in_zone(when, name, key):
    """A local date and time `when` (ISO 8601, no offset) in the IANA zone `name`, checked to exist once."""
    try:
        zone = ZoneInfo(name)
    except (ZoneInfoNotFoundError, ValueError):
        raise ValueError(f"{key}: unknown time zone {name!r}; expected a name of the IANA time zone database "
                         "such as Europe/Berlin or America/New_York, or an offset (+01:00)") from None
    local = datetime.fromisoformat(when)
    first, second = local.replace(tzinfo=zone, fold=0), local.replace(tzinfo=zone, fold=1)
    exists = [a for a in (first, second) if a.astimezone(timezone.utc).astimezone(zone).replace(tzinfo=None) == local]
    if not exists:
        raise ValueError(f"{key}: {when} does not exist in {name} (the clocks go forward over it); write the "
                         "time with its offset")
    if first.utcoffset() != second.utcoffset():
        raise ValueError(f"{key}: {when} happens twice in {name} (the clocks go back over it); write it with its "
                         f"offset ({first.isoformat()} or {second.isoformat()})")
    return first


def parse_time(value, key):
    """An aware :class:`~datetime.datetime` from a TOML date-time or an ISO 8601 string.

    Parameters
    ----------
    value : datetime or str
        A date-time with an offset, or a string: ISO 8601 with an offset, or a local date and time and a named
        zone (``"2026-10-29T23:59 Europe/Berlin"`` or ``"2026-10-29T23:59[Europe/Berlin]"``, see the module's
        notes).
    key : str
        Where the value was given, for the error (``exercises.00_warmup.deadline``).

    Raises
    ------
    ValueError
        When `value` is not a date-time, has no time zone, names an unknown zone, or a local time that does not
        exist or happens twice in its zone (naming `key`).

    Examples
    --------
    >>> parse_time("2026-07-01T23:59 Europe/Berlin", "deadline").isoformat()
    '2026-07-01T23:59:00+02:00'
    >>> parse_time("2026-11-01T23:59[Europe/Berlin]", "deadline").isoformat()
    '2026-11-01T23:59:00+01:00'
    """
    if isinstance(value, str):
        named = _NAMED.match(value.strip())
        if named:
            return _in_zone(named.group("when"), named.group("zone") or named.group("bracket").strip(), key)
        try:
            value = datetime.fromisoformat(value.strip())
        except ValueError:
            raise ValueError(f"{key}: {value!r} is not an ISO 8601 date-time "
                             "(expected e.g. 2026-10-01T23:59:00+01:00 or \"2026-10-01T23:59 Europe/Berlin\")") \
                from None
    if isinstance(value, date) and not isinstance(value, datetime) or isinstance(value, time):
        raise ValueError(f"{key}: {value.isoformat()} is not a date and a time with a time zone "
                         "(expected e.g. 2026-10-01T23:59:00+01:00)")
    if not isinstance(value, datetime):
        raise ValueError(f"{key}: expected a date-time with a time zone, got {type(value).__name__} {value!r}")
    if value.tzinfo is None or value.utcoffset() is None:
        raise ValueError(f"{key}: {value.isoformat()} has no time zone; write it with one "
                         f"(e.g. {value.isoformat()}+01:00, Z for UTC, or \"{value.isoformat()} Europe/Berlin\")")
    return value


@dataclass(frozen=True)
class LatePolicy:
    """How late work loses points.

    Attributes
    ----------
    penalty_per_day : float
        Fraction of the exercise's points taken off per started day late (>= 0).
    cap : float
        The largest fraction taken off, in [0, 1].
    grace_minutes : float
        A submission at most this long after the deadline is on time (>= 0).
    """

    penalty_per_day: float = 0.0
    cap: float = 1.0
    grace_minutes: float = 0.0

    @classmethod
    def from_table(cls, table, key, base=None):
        """The policy of a TOML table (keys of :data:`_POLICY_KEYS`), defaults from `base`."""
        base = base or cls()
        values = {name: getattr(base, name) for name in _POLICY_KEYS}
        problems = []
        for name in _POLICY_KEYS:
            if name not in table:
                continue
            value = table[name]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                problems.append(f"{key}.{name}: expected a number, got {value!r}")
            elif value < 0:
                problems.append(f"{key}.{name}: must be >= 0, got {value!r}")
            elif name == "cap" and value > 1:
                problems.append(f"{key}.cap: a fraction of the exercise's points, in [0, 1], got {value!r}")
            else:
                values[name] = float(value)
        if problems:
            raise ValueError("\n".join(problems))
        return cls(**values)


@dataclass
class Course:
    """The deadlines of a course file (see the module's docstring).

    Attributes
    ----------
    deadlines : dict
        exercise -> aware datetime.
    policies : dict
        exercise -> :class:`LatePolicy`.
    extensions : dict
        student -> {exercise -> aware datetime (a new deadline) or float (extra days)}.
    path : str
        The file read ("" when made in code).
    roster : Path or None
        The roster the course file names (``roster = "roster.csv"``, relative to the course file).
    """

    deadlines: dict = field(default_factory=dict)
    policies: dict = field(default_factory=dict)
    extensions: dict = field(default_factory=dict)
    path: str = ""
    roster: Path = None

    def deadline_of(self, student, exercise, aliases=()):
        """(deadline, why) of `student` for `exercise`, after extensions; (None, "") when none applies.

        `aliases` are other names of the student (Gradescope's e-mail or id) an extension may use.
        """
        deadline = self.deadlines.get(exercise)
        if deadline is None:
            return None, ""
        for name in (student, *aliases):
            given = self.extensions.get(str(name), {}).get(exercise)
            if isinstance(given, datetime):
                return given, f"extension for {name}"
            if given is not None:
                return deadline + timedelta(days=given), f"extension of {_fmt(given)} day(s) for {name}"
        return deadline, ""


def load_course(path, exercises):
    """Read and check a course file.

    Parameters
    ----------
    path : path
        The TOML file.
    exercises : sequence of str
        The course's exercises (``NN_topic``): any other name in the file is an error.

    Returns
    -------
    Course

    Raises
    ------
    ValueError
        On a missing or malformed file, naming the file and the key at fault.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as error:
        raise ValueError(f"cannot read the course file {path}: {error.strerror or error}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise ValueError(f"{path} is not valid TOML: {error}") from None
    try:
        return _course(data, list(exercises), str(path))
    except ValueError as error:
        problems = str(error).splitlines()
        if len(problems) == 1:
            raise ValueError(f"{path}: {error}") from None
        raise ValueError(f"{path}: {len(problems)} problems:\n  " + "\n  ".join(problems)) from None


def _table(data, key):
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise ValueError(f"{key}: expected a table ([{key}]), got {value!r}")
    return value


def _course(data, exercises, path=""):
    """The :class:`Course` of a course file's TOML data; every problem at once (a ValueError, one per line)."""
    problems = []

    def attempt(check, *args, default=None):
        try:
            return check(*args)
        except ValueError as error:
            problems.extend(str(error).splitlines())
            return default

    problems += [f"unknown key {k!r}; expected roster, late, exercises or extensions"
                 for k in sorted(set(data) - {"roster", "late", "exercises", "extensions"})]
    late = attempt(_table, data, "late", default={})
    problems += [f"late.{k}: unknown key; expected {', '.join(_POLICY_KEYS)}"
                 for k in sorted(set(late) - set(_POLICY_KEYS))]
    base = attempt(LatePolicy.from_table, late, "late", default=LatePolicy())
    course = Course(path=path)
    if "roster" in data:
        if not isinstance(data["roster"], str) or not data["roster"].strip():
            problems.append(f"roster: expected the roster file's path (a string), got {data['roster']!r}")
        else:
            course.roster = Path(path).parent / data["roster"] if path else Path(data["roster"])
    for name, table in attempt(_table, data, "exercises", default={}).items():
        key = f"exercises.{name}"
        if name not in exercises:
            problems.append(f"{key}: unknown exercise {name!r}; expected one of {', '.join(exercises)}")
            continue
        if not isinstance(table, dict):
            problems.append(f"{key}: expected a table ([{key}]) with a deadline, got {table!r}")
            continue
        problems += [f"{key}.{k}: unknown key; expected deadline, {', '.join(_POLICY_KEYS)}"
                     for k in sorted(set(table) - {"deadline", *_POLICY_KEYS})]
        if "deadline" not in table:
            problems.append(f"{key}: no deadline (add deadline = 2026-10-01T23:59:00+01:00, or remove the table)")
            continue
        deadline = attempt(parse_time, table["deadline"], f"{key}.deadline")
        policy = attempt(LatePolicy.from_table, table, key, base)
        if deadline is not None and policy is not None:
            course.deadlines[name], course.policies[name] = deadline, policy
    for student, table in attempt(_table, data, "extensions", default={}).items():
        key = f"extensions.{student}"
        if not isinstance(table, dict):
            problems.append(f"{key}: expected a table of exercise = new deadline or extra days, got {table!r}")
            continue
        course.extensions[student] = {}
        for name, value in table.items():
            given = attempt(_extension, name, value, f"{key}.{name}", exercises, course)
            if given is not None:
                course.extensions[student][name] = given
    if problems:
        raise ValueError("\n".join(problems))
    return course


def _extension(name, value, key, exercises, course):
    """One extension of a course file: a new deadline (aware datetime) or extra days (float), checked."""
    if name not in exercises:
        raise ValueError(f"{key}: unknown exercise {name!r}; expected one of {', '.join(exercises)}")
    if name not in course.deadlines:
        raise ValueError(f"{key}: an extension of an exercise without a deadline "
                         f"(add [exercises.{name}] with its deadline)")
    if isinstance(value, bool) or not isinstance(value, (int, float, str, datetime, date, time)):
        raise ValueError(f"{key}: expected a new deadline or a number of extra days, got {value!r}")
    if isinstance(value, (int, float)):
        if not math.isfinite(value) or value < 0:
            raise ValueError(f"{key}: extra days must be a number >= 0, got {value!r}")
        return float(value)
    return parse_time(value, key)


def find_course(root, exercises, path=None):
    """The course of ``--course FILE`` (`path`), else of ``course.toml`` at `root`, else None (no deadlines)."""
    if path is not None:
        return load_course(path, exercises)
    default = Path(root) / COURSE_FILE
    return load_course(default, exercises) if default.exists() else None


def _fmt(x):
    return f"{x:g}"


def shown_time(moment):
    """``2026-10-01 23:59 +01:00`` (seconds only when there are some)."""
    text = moment.strftime("%Y-%m-%d %H:%M" + (":%S" if moment.second else ""))
    offset = moment.strftime("%z")
    return f"{text} {offset[:3]}:{offset[3:]}" if offset else text


def _duration(delta):
    """``2 days 3 hours``, ``1 hour 5 minutes``, ``40 seconds``: the two largest units."""
    seconds = int(delta.total_seconds())
    parts = []
    for name, size in (("day", 86400), ("hour", 3600), ("minute", 60), ("second", 1)):
        count, seconds = divmod(seconds, size)
        if count:
            parts.append(f"{count} {name}{'s' if count != 1 else ''}")
    return " ".join(parts[:2]) or "0 seconds"


def decide(submitted, deadline, policy, total_max, why="", source=""):
    """The late-work decision of one record.

    Parameters
    ----------
    submitted, deadline : datetime
        Aware date-times: when the work was submitted, and the student's deadline (after extensions).
    policy : LatePolicy
    total_max : float
        The exercise's points, of which the penalty is a fraction.
    why : str
        Why the deadline is not the exercise's ("extension for alice"), "" when it is.
    source : str
        Where the submission time comes from (see :class:`SubmissionTimes`).

    Returns
    -------
    dict
        ``submitted`` and ``deadline`` (ISO 8601), ``days_late`` (started days after the deadline, 0
        when on time or within the grace period), ``fraction`` (of `total_max`), ``penalty`` (points:
        `fraction` of `total_max`; the record recomputes it when written grades change its total_max),
        ``reason`` (one sentence, in percent, so that it stays true), ``source``.

    Examples
    --------
    >>> from datetime import datetime, timedelta, timezone
    >>> due = datetime(2026, 10, 1, 23, 59, tzinfo=timezone(timedelta(hours=1)))
    >>> late = decide(due + timedelta(days=1, hours=3), due, LatePolicy(0.1, 0.5), 30)
    >>> late["days_late"], late["penalty"]
    (2, 6.0)
    >>> print(late["reason"])  # doctest: +NORMALIZE_WHITESPACE
    submitted 1 day 3 hours after the deadline 2026-10-01 23:59 +01:00: -20% of the exercise's points
    (2 days late at 10% a day, cap 50%)
    """
    submitted, deadline = parse_time(submitted, "submitted"), parse_time(deadline, "deadline")
    shown = submitted.astimezone(deadline.tzinfo)
    where = f"the deadline {shown_time(deadline)}" + (f" ({why})" if why else "")
    late = shown - deadline
    days, fraction = 0, 0.0
    if late <= timedelta(0):
        reason = f"submitted {shown_time(shown)}, before {where}: no penalty"
    elif late <= timedelta(minutes=policy.grace_minutes):
        reason = (f"submitted {_duration(late)} after {where}, within the grace period of "
                  f"{_fmt(policy.grace_minutes)} minutes: no penalty")
    else:
        days = math.ceil(late / _DAY)
        fraction = min(policy.penalty_per_day * days, policy.cap)
        capped = policy.penalty_per_day * days > policy.cap
        reason = (f"submitted {_duration(late)} after {where}: -{_fmt(round(100 * fraction, 4))}% of the "
                  f"exercise's points ({days} day{'s' if days != 1 else ''} late "
                  f"at {_fmt(round(100 * policy.penalty_per_day, 4))}% a day, "
                  f"{'capped at' if capped else 'cap'} {_fmt(round(100 * policy.cap, 4))}%)")
    return {"submitted": shown.isoformat(), "deadline": deadline.isoformat(), "days_late": days,
            "fraction": fraction, "penalty": round(fraction * total_max, 6), "reason": reason, "source": source}


def apply_late(record, course, submitted, source="", aliases=()):
    """Set ``record.late`` from the course's deadline of its student and exercise.

    Parameters
    ----------
    record : SubmissionRecord
        Changed in place: ``late`` becomes the decision (:func:`decide`), or None when the course
        gives the exercise no deadline (or there is no course, or no submission time).
    course : Course or None
    submitted : datetime or None
    source : str
    aliases : sequence of str
        Other names of the student an extension may use.

    Returns
    -------
    SubmissionRecord
        `record`.
    """
    deadline, why = course.deadline_of(record.student, record.exercise, aliases) if course else (None, "")
    if deadline is None or submitted is None:
        record.late = None
    else:
        record.late = decide(submitted, deadline, course.policies[record.exercise], record.total_max, why, source)
    return record


def resolve_extensions(course, identity, where=""):
    """The course with its extensions keyed by the grader's names of their students.

    Raises
    ------
    ValueError
        Naming every ``[extensions.NAME]`` that is no student of `identity` (nothing is graded).
    """
    if course is None or not course.extensions:
        return course
    unknown = [name for name in course.extensions if identity.find(name) is None]
    if unknown:
        raise ValueError(f"{course.path or where}: " + "; ".join(f"[extensions.{n}]: {n!r} is no student of "
                         f"{identity.describe()}" for n in unknown) + "; correct the name (or add it to the roster's "
                         "aliases); nothing was graded")
    extensions = {}
    for name, table in course.extensions.items():
        extensions.setdefault(identity.find(name).name, {}).update(table)
    return Course(course.deadlines, course.policies, extensions, course.path, course.roster)


class LateWork:
    """The late-work decision of each record of a run: the deadline from the course, the time from `times`.

    Parameters
    ----------
    course : Course or None
        The course file's deadlines (:func:`find_course`).
    times : SubmissionTimes
    units : iterable of Unit
        The run's notebooks; a record is decided with the time of its own. A record of another notebook (one
        of the term's other current results) is decided with the time the course's record kept for it, and
        keeps its decision when no time is known.
    """

    def __init__(self, course, times, units):
        self.course, self.times = course, times
        self.units = {(unit.student, unit.exercise): unit for unit in units}

    def __call__(self, record):
        """Set ``record.late`` (see :func:`apply_late`) and return `record`."""
        unit = self.units.get((record.student, record.exercise))
        when, source = self.times.of(unit or Unit(record.student, record.exercise, Path(record.notebook or "")))
        if unit is None and when is None:
            return record
        return apply_late(record, self.course, when, source, self.times.aliases())
