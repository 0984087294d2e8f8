"""The roster: every line checked by file and line, the students' aliases, Canvas's own gradebook export."""

import pytest

from particles.course.term.roster import RosterError, read_roster


def roster_file(tmp_path, text, name="roster.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


BAD_ROSTERS = [
    ("", "is empty: expected a header line"),
    ("\n\n", "is empty: expected a header line"),
    ("submission_name,email\n", "has a header but no student"),
    ("name,email\nAnn,a@x\n", "line 1: no column 'submission_name'"),
    ("submission_name,email\nAnn,a@x\nann,b@x\n",
     "line 3: the name 'ann' is the grader's 'ann', as the name on line 2"),
    ("submission_name,email\nAnn Lee,a@x\nann_lee,b@x\n", "line 3: the name 'ann_lee'"),
    ("submission_name,canvas_id\na,1\nb,1\n", "line 3: canvas_id '1' is also on line 2"),
    ("submission_name,email\na,A@x.org\nb,a@X.org\n", "line 3: email 'a@X.org' is also on line 2"),
    ("submission_name,SIS User ID\na,S1\nb,S1\n", "line 3: sis_user_id 'S1' is also on line 2"),
    ("submission_name,canvas_id\na,12x\n", "line 2: canvas_id '12x' is not Canvas's numeric user ID"),
    ("submission_name,email\na,=cmd|' /C calc'!A0\n", "line 2: email \"=cmd|' /C calc'!A0\" starts with '='"),
    ("submission_name,email\n,a@x\n", "line 2: the name column is empty"),
    ("submission_name,email\na,a@x,extra\n", "line 2: 3 cells; expected at most 2"),
    ("submission_name,email,Email address\na,a@x,b@x\n", "line 1: columns 2 and 3 are both email"),
]


@pytest.mark.parametrize("text, message", BAD_ROSTERS)
def test_bad_roster_is_refused_naming_file_and_line(tmp_path, text, message):
    """A bad roster is refused with its file, the line and what was expected."""
    path = roster_file(tmp_path, text)
    with pytest.raises(RosterError) as error:
        read_roster(path)
    assert str(path) in str(error.value) and message in str(error.value)


def test_name_column_that_is_an_identifier(tmp_path):
    """--name-column may be an identifier column (it is both), but not beside another column of that identifier."""
    roster = read_roster(roster_file(tmp_path, "Email,canvas_id\nann@uni.org,1\n"), name_column="email")
    assert roster.students[0].email == roster.students[0].submission_name == "ann@uni.org"
    with pytest.raises(RosterError, match="line 1: columns 3 and 1 are both email"):
        read_roster(roster_file(tmp_path, "email,canvas_id,Email address\na@x,1,b@x\n"), name_column="email")




def test_canvas_gradebook_export_with_a_manual_posting_line_is_a_roster_and_its_aliases_match(tmp_path):
    """Canvas's export of a course with a manually posted assignment has a 'Manual Posting' line (empty name cells)
    before 'Points Possible': it is skipped like that line; the students are found by login, id and aliases."""
    text = ("Student,ID,SIS User ID,SIS Login ID,Section,aliases,Quiz 1 (55)\n"
            ",,,,,,Manual Posting\n"
            "    Points Possible,,,,,,10\n"
            "\"Lee, Ann\",101,S-1,alee,A,ann.lee@uni.edu; annie,9\n"
            "\"Ito, Carl\",102,S-2,cito,A,,7\n")
    roster = read_roster(roster_file(tmp_path, text), name_column="SIS Login ID")
    assert [(s.submission_name, s.canvas_id, s.aliases) for s in roster.students] == [
        ("alee", "101", ("ann.lee@uni.edu", "annie")), ("cito", "102", ())]
    course = roster.identity()
    assert course.closed and course.find("Annie").name == "alee" and course.find(canvas_id="102").name == "cito"
    assert course.find("ANN.LEE@UNI.EDU").name == "alee" and course.find("someone") is None


def test_an_alias_that_is_another_students_name_is_refused_naming_the_line(tmp_path):
    """Two roster lines that share a name through an alias are refused: one name, one student."""
    text = "submission_name,email,aliases\nann,ann@uni.edu,\nbob,bob@uni.edu,ann@uni.edu\n"
    with pytest.raises(RosterError, match=r"line 3: 'ann@uni.edu' \(name\) names both ann and bob"):
        read_roster(roster_file(tmp_path, text))
