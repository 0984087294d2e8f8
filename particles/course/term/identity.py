"""Who is who: every name the course tools meet is matched to a student here, and only here.

A student has one name, the grader's (``Person.name``: their output folder and their gradebook row), and
any number of aliases: their submission names, LMS logins and e-mails, Canvas's numeric user id, SIS ids.
Names are compared by :func:`name_key` (case-folded, compatibility-normalized Unicode, with the grader's
filing of odd characters), numeric identifiers by their kind and value (Canvas user 2000 is not SIS user
2000). With a roster (:mod:`particles.course.term.roster`) the roster's students are the course: a name that
is none of theirs is unknown. Without one, the students are those the term's record knows and those a run
discovers.

``particles grade`` (submissions, extensions, times files, rubrics), ``particles review`` and ``particles
export`` all match through an :class:`Identity`.
"""

import re
import unicodedata
from dataclasses import dataclass, field

__all__ = ["ID_KINDS", "NAME_KINDS", "Person", "Identity", "IdentityError", "name_key", "filing_name"]

ID_KINDS = ("canvas_id", "sis_user_id", "idnumber")
"""Identifiers compared with their kind: numbers of different systems may coincide."""

NAME_KINDS = ("submission_name", "login", "sis_login_id", "email", "username", "alias")
"""Names compared with each other, whatever their kind (a Canvas login may be a submission folder's name)."""


class IdentityError(ValueError):
    """Two students claim one name, or a name is not a student's: the message says which and where."""


def filing_name(text):
    """The name the grader files a submission under: runs of characters other than letters, digits and
    ``. @ + -`` become ``_`` (composed Unicode, as macOS's decomposed names are not)."""
    text = unicodedata.normalize("NFC", str(text))
    return re.sub(r"[^\w.@+-]+", "_", text).strip("_") or "submission"


def name_key(text):
    """The key two names of one student compare equal by: the filing name, compatibility-normalized and
    case-folded (``"Ann Lee"``, ``"ann_lee"`` and ``"ANN_LEE"`` are one key, so are ``"Ａnn"`` and ``"ann"``)."""
    return unicodedata.normalize("NFKC", filing_name(text)).casefold()


def _alias_key(kind, value):
    value = str(value).strip()
    return (kind, value) if kind in ID_KINDS else ("name", name_key(value))


@dataclass
class Person:
    """One student.

    Attributes
    ----------
    name : str
        The grader's name of the student: their output folder and gradebook row.
    aliases : list of (kind, value)
        Other names (kinds of :data:`NAME_KINDS` and :data:`ID_KINDS`); the name itself is one too.
    display : str
        The name the LMS shows ("" when not known).
    on_roster : bool
        The roster names this student.
    """

    name: str
    aliases: list = field(default_factory=list)
    display: str = ""
    on_roster: bool = False

    def keys(self):
        """Every key this student is found by."""
        return {_alias_key("submission_name", self.name)} | {_alias_key(k, v) for k, v in self.aliases if v}


class Identity:
    """The course's students and every name each is known by.

    Parameters
    ----------
    people : iterable of Person
    closed : bool
        True when a roster defines the course: :meth:`admit` then never adds a student.

    Raises
    ------
    IdentityError
        When two students share a name or an identifier.
    """

    def __init__(self, people=(), closed=False):
        self.closed, self.people, self._keys = closed, {}, {}
        for person in people:
            self.add(person)

    def add(self, person):
        """Add a student (or more aliases of a known one, matched by its name); returns the :class:`Person`."""
        known = self.people.get(person.name)
        if known is not None:
            person = Person(known.name, [*known.aliases, *person.aliases], known.display or person.display,
                            known.on_roster or person.on_roster)
        for key in person.keys():
            owner = self._keys.get(key)
            if owner is not None and owner != person.name:
                raise IdentityError(f"{key[1]!r} ({key[0]}) names both {owner} and {person.name}")
        self.people[person.name] = person
        self._keys.update({key: person.name for key in person.keys()})
        return person

    def find(self, name=None, **ids):
        """The student a submission's names point to, or None.

        Identifiers (`ids`: ``canvas_id=...``, ``sis_user_id=...``, ``idnumber=...``; ``sid`` tries both SIS
        kinds) are tried first: they never collide between two students of one LMS; then `name`, against
        every name-like alias.
        """
        sid = ids.pop("sid", None)
        if sid:
            ids.setdefault("sis_user_id", sid)
            ids.setdefault("idnumber", sid)
        for kind, value in ids.items():
            if kind not in ID_KINDS:
                raise ValueError(f"unknown identifier kind {kind!r}; expected one of {', '.join(ID_KINDS)} or sid")
            if value and (kind, str(value).strip()) in self._keys:
                return self.people[self._keys[(kind, str(value).strip())]]
        if name and _alias_key("alias", name) in self._keys:
            return self.people[self._keys[_alias_key("alias", name)]]
        return None

    def admit(self, name, aliases=()):
        """The student of a discovered submission: a known one (by any of `aliases`, then `name`), else a new
        one named `name` (unless the course is closed by a roster: then None).

        A new student whose name another student already has (two Canvas users with one login) is named
        ``name_<first identifier>`` instead, so that two people are never one.
        """
        ids = {kind: value for kind, value in aliases if kind in ID_KINDS or kind == "sid"}
        aliases = [("sis_user_id" if kind == "sid" else kind, value) for kind, value in aliases]
        person = self.find(None, **ids) if ids else None
        if person is None and not (ids and self._taken_by_other_ids(name, ids)):
            person = self.find(name)
        if person is not None:
            return self.add(Person(person.name, self._free(aliases, person.name)))
        if self.closed:
            return None
        own = filing_name(name)
        if self.find(own) is not None or own in self.people:
            own = filing_name(f"{own}_{next(iter(ids.values()), len(self.people))}")
        return self.add(Person(own, self._free([("submission_name", name), *aliases], own)))

    def _free(self, aliases, name):
        """The aliases that name no other student than `name` (a login two Canvas users share names neither)."""
        return [(k, v) for k, v in aliases if v and self._keys.get(_alias_key(k, v), name) == name]

    def _taken_by_other_ids(self, name, ids):
        """Whether `name` belongs to a student known under another identifier of a kind in `ids`."""
        person = self.find(name)
        if person is None:
            return False
        theirs = {kind: value for kind, value in person.aliases if kind in ids}
        return any(str(theirs[kind]) != str(value) for kind, value in ids.items() if kind in theirs)

    def unknown(self, names):
        """The names of `names` (an iterable of (name, where)) that are no student's, as "where: 'name'" lines."""
        return [f"{where}: {name!r}" for name, where in names if self.find(name) is None]

    def describe(self):
        """The course in words, for messages: how many students and from where."""
        return f"the roster's {len(self.people)} students" if self.closed else \
            f"the {len(self.people)} students the course's record knows"
