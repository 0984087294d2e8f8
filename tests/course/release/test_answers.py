"""Written answers: one slot per question, blank or answered as a reader would see it."""

import json
from pathlib import Path

import nbformat
import pytest

from particles.course.release.answers import (ANSWER_PROMPT, answer_slots, count_answers, model_answers,
                                              question_points, questions_of)
from particles.course.grading.discovery import released_exercise
from particles.course.release.notebooks import release_notebook

ROOT = Path(__file__).resolve().parents[3]
EXERCISES = sorted(p.stem for p in (ROOT / "solutions").glob("[0-9][0-9]_*.ipynb"))


def _master():
    cells = [
        nbformat.v4.new_markdown_cell("Intro."),
        nbformat.v4.new_markdown_cell("**Question 1.** Why?\n\n### BEGIN SOLUTION\nBecause.\n### END SOLUTION\n\n"
                                      "**Question 2.** How?\n\n### BEGIN SOLUTION\nSo.\n### END SOLUTION"),
        nbformat.v4.new_code_cell("x = 1"),
        nbformat.v4.new_markdown_cell("**Question 3.** When?\n### BEGIN SOLUTION\nNow.\n### END SOLUTION\nEnd."),
    ]
    for k, cell in enumerate(cells):
        cell["id"] = f"c{k}"
    return nbformat.v4.new_notebook(cells=cells)


def _released():
    return json.loads(json.dumps(release_notebook(_master(), "07_test")))


def test_each_solution_block_becomes_an_answer_slot_of_its_own():
    """Each solution block of a markdown cell becomes an answer slot of its own, below its question."""
    released = _released()
    sources = [c["source"] for c in released["cells"]]
    assert sources == ["Intro.", "**Question 1.** Why?", ANSWER_PROMPT, "**Question 2.** How?", ANSWER_PROMPT,
                       "x = 1", "**Question 3.** When?", ANSWER_PROMPT, "End."]
    assert [k for k, _ in answer_slots(released)] == [1, 2, 3]
    assert len({c["id"] for c in released["cells"]}) == len(released["cells"])  # ids stay unique
    assert questions_of(released) == {1: "**Question 1.** Why?", 2: "**Question 2.** How?",
                                      3: "**Question 3.** When?"}


def _answer(released, k, text, keep_metadata=True):
    notebook = json.loads(json.dumps(released))
    for cell in notebook["cells"]:
        if cell.get("metadata", {}).get("particles", {}).get("answer") == k:
            cell["source"] = text
            if not keep_metadata:
                cell["metadata"] = {}
    return notebook


@pytest.mark.parametrize("text, answered", [
    ("", False), ("   \n", False), (ANSWER_PROMPT, False), ("*Your answer here.*\n\n", False),
    ("Because the force depends on t.", True), (ANSWER_PROMPT + "\nIt doubles.", True)])
def test_a_slot_is_blank_when_it_holds_nothing_but_the_prompt(text, answered):
    """A slot holding nothing, white space or the prompt is blank; any text is an answer (by metadata or by id)."""
    released = _released()
    for keep in (True, False):  # found by metadata, or by its id when an editor dropped the metadata
        counted = count_answers(_answer(released, 2, text, keep), released)
        assert counted["asked"] == 3 and counted["answered"] == int(answered), (text, keep)
        assert counted["blank"] == ([1, 3] if answered else [1, 2, 3])


def test_an_answer_in_a_cell_of_the_students_own_below_the_prompt_counts():
    """An answer written in a cell of the student's own below the prompt answers that slot."""
    released = _released()
    notebook = json.loads(json.dumps(released))
    at = next(i for i, c in enumerate(notebook["cells"]) if c["source"] == ANSWER_PROMPT)
    notebook["cells"].insert(at + 1, {"cell_type": "markdown", "id": "mine", "metadata": {},
                                      "source": "My answer to question 1."})
    assert count_answers(notebook, released) == {"asked": 3, "answered": 1, "blank": [2, 3]}


def test_a_deleted_slot_or_an_unreadable_notebook_answers_nothing(tmp_path):
    """A deleted slot is blank; an unreadable notebook answered nothing."""
    released = _released()
    notebook = json.loads(json.dumps(released))
    notebook["cells"] = [c for c in notebook["cells"] if c["source"] != ANSWER_PROMPT]
    assert count_answers(notebook, released)["answered"] == 0
    bad = tmp_path / "bad.ipynb"
    bad.write_bytes(b"\xff not json")
    assert count_answers(bad, released) == {"asked": 3, "answered": 0, "blank": [1, 2, 3]}


def test_a_master_checked_as_a_submission_has_answered_everything():
    """A master, whose solution blocks are its answers, answered every question."""
    master = json.loads(json.dumps(_master()))
    assert count_answers(master, _released()) == {"asked": 3, "answered": 3, "blank": []}


@pytest.mark.parametrize("exercise", EXERCISES)
def test_every_stub_answers_0_of_n_and_every_master_n_of_n(exercise):
    """N is the number of questions: the ``**Question`` paragraphs of the master, one slot each."""
    released = released_exercise(ROOT, exercise)
    master = json.loads((ROOT / "solutions" / f"{exercise}.ipynb").read_text())
    questions = sum(line.lstrip().startswith("**Question") for c in master["cells"] if c["cell_type"] == "markdown"
                    for line in "".join(c["source"]).split("\n"))
    asked = len(answer_slots(released))
    assert asked == questions > 0 or (asked == 0 and questions == 0), (asked, questions)
    stub = json.loads((ROOT / "exercises" / f"{exercise}.ipynb").read_text())
    assert count_answers(stub, released) == {"asked": asked, "answered": 0, "blank": list(range(1, asked + 1))}
    assert count_answers(master, released)["answered"] == asked


@pytest.mark.parametrize("header, points", [
    ("**Question 1 (3 points).** Why?", 3.0), ("**Question 1 (1 point).** Why?", 1.0),
    ("**Question 1 (2.5 points).** Why?", 2.5), ("**Question 1.** (3 points, before you code) Why?", 1.0),
    ("**Question 1.** Why?", 1.0)])
def test_question_points_are_read_from_the_bold_header(header, points):
    """A question's points are the ``(p points)`` of its bold header; without them it is worth 1 point."""
    master = _master()
    master["cells"][3]["source"] = f"{header}\n### BEGIN SOLUTION\nNow.\n### END SOLUTION"
    released = json.loads(json.dumps(release_notebook(master, "07_test")))
    assert question_points(released) == {1: 1.0, 2: 1.0, 3: points}


@pytest.mark.parametrize("header", ["**Question 1 (three points).**", "**Question 1 (3 pts, 3 points).**",
                                    "**Question 1 (points: 3).**"])
def test_a_header_that_mentions_points_otherwise_is_an_error(header):
    """Points written in any other way are an error naming the question, never a guess."""
    master = _master()
    master["cells"][1]["source"] = f"{header} Why?\n### BEGIN SOLUTION\nNow.\n### END SOLUTION"
    released = json.loads(json.dumps(release_notebook(master, "07_test")))
    with pytest.raises(ValueError, match=r"question 1: cannot read its points .*expected"):
        question_points(released)


@pytest.mark.parametrize("exercise", EXERCISES)
def test_every_master_question_declares_its_points(exercise):
    """Every question of every master says what it is worth (2 or 3 points), and the release keeps it."""
    released = released_exercise(ROOT, exercise)
    points = question_points(released)
    assert points and set(points.values()) <= {2.0, 3.0}, points
    stub = json.loads((ROOT / "exercises" / f"{exercise}.ipynb").read_text())
    assert question_points(stub) == points
    master = json.loads((ROOT / "solutions" / f"{exercise}.ipynb").read_text())
    assert len(model_answers(master)) == len(points)
