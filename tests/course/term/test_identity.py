"""Who is who: names matched case- and Unicode-insensitively, identifiers by kind, two people never one."""

import pytest

from particles.course.term.identity import Identity, IdentityError, Person, filing_name, name_key


def test_names_match_as_the_grader_files_them():
    """Case, Unicode forms, spaces and punctuation aside, a name is one key; different names are different keys."""
    assert name_key("Bob Smith") == name_key("bob_smith") == name_key("BOB_SMITH") == "bob_smith"
    assert name_key("Ａnn") == name_key("ann") and name_key("Zoe\u0308") == name_key("Zoë")
    assert name_key("ann.lee@uni.org") == "ann.lee@uni.org" and name_key("ann") != name_key("anne")
    assert filing_name("  Ann Lee!  ") == "Ann_Lee" and filing_name("???") == "submission"


def test_a_student_is_found_by_any_alias_and_identifiers_by_their_kind():
    """Every alias finds its student; a Canvas id is not a SIS id of the same digits; sid tries both SIS kinds."""
    course = Identity([Person("alice", [("login", "alicesmith"), ("email", "alice@uni.edu"), ("canvas_id", "2000"),
                                        ("alias", "Alice Smith")]),
                       Person("bob", [("sis_user_id", "2000"), ("idnumber", "77")])], closed=True)
    for name in ("ALICESMITH", "alice@UNI.edu", "alice smith", "Alice"):
        assert course.find(name).name == "alice", name
    assert course.find(canvas_id="2000").name == "alice" and course.find(sid="2000").name == "bob"
    assert course.find(sid="77").name == "bob" and course.find("2000") is None
    assert course.find("carol") is None and course.unknown([("carol", "times.csv, line 3")]) == [
        "times.csv, line 3: 'carol'"]
    with pytest.raises(ValueError, match="unknown identifier kind 'email'"):
        course.find(email="alice@uni.edu")


def test_two_students_with_one_name_or_alias_are_refused():
    """An alias that names two students is an error naming both."""
    with pytest.raises(IdentityError, match="'asmith' .* names both alice and andy"):
        Identity([Person("alice", [("alias", "asmith")]), Person("andy", [("login", "ASmith")])])


def test_a_closed_course_admits_no_stranger_and_an_open_one_keeps_two_canvas_users_apart():
    """With a roster nobody new is admitted; without one, a second Canvas user with a known login gets a name of
    their own (login_userid), and a known user id finds its student whatever the login."""
    closed = Identity([Person("alice", [("canvas_id", "1")])], closed=True)
    assert closed.admit("smithjohn", [("canvas_id", "9")]) is None
    assert closed.admit("whatever", [("canvas_id", "1")]).name == "alice"
    open_ = Identity()
    first = open_.admit("smithjohn", [("canvas_id", "2000"), ("login", "smithjohn")])
    second = open_.admit("smithjohn", [("canvas_id", "2001"), ("login", "smithjohn")])
    assert (first.name, second.name) == ("smithjohn", "smithjohn_2001")
    assert open_.admit("SmithJohn", [("canvas_id", "2001")]).name == "smithjohn_2001"
    assert open_.admit("Alice", []).name == "Alice" and open_.admit("alice", []).name == "Alice"
    gradescope = open_.admit("bo@uni.edu", [("email", "bo@uni.edu"), ("sid", "42")])
    assert open_.find(sid="42") is gradescope or open_.find(sid="42").name == gradescope.name
