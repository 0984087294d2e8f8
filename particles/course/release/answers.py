"""Written answers: one slot per question, counted as a reader would count them.

A master writes each question as a markdown paragraph (``**Question 2.** ...``)
followed by its own solution block (``### BEGIN SOLUTION`` ... ``### END
SOLUTION``). The release (:func:`particles.course.release.notebooks.release_notebook`)
turns every such block into a markdown cell of its own, the answer *slot*,
holding the prompt ``*Your answer here.*`` and the metadata
``{"particles": {"answer": k}}`` (k = 1, 2, ... in notebook order); its cell
id is fixed by the master, so a slot is found again even when an editor drops
the metadata.

A slot is answered when the student wrote something in it other than the
prompt, or wrote in markdown cells of their own right below it (a student who
adds a cell under the prompt and leaves the prompt has answered). A slot that
holds only the prompt, white space or nothing is blank; a deleted slot is
blank too.

Points. A question declares what it is worth in its bold header:
``**Question 2 (3 points).**`` or ``**Question 1 (1 point).**`` (a whole or
decimal number >= 0, then ``point`` or ``points``, in parentheses, inside
the bold part). A question that declares nothing is worth
:data:`DEFAULT_POINTS` (1 point); a header that mentions points in any other
way is an error, never a guess. :func:`question_points` reads them, from a
master or a released notebook alike (the release keeps the question's text).
People grade these answers (``particles review`` and ``particles grade
--rubric``, :mod:`particles.course.results.rubric`); the autograder does not.
"""

import json
import re
from pathlib import Path

__all__ = ["ANSWER_PROMPT", "STUB_LINE", "cell_source", "SLOT_KEY", "DEFAULT_POINTS", "slot_of", "answer_slots", "questions_of",
           "question_points", "count_answers", "answers_of", "answer_cells", "model_answers", "is_blank",
           "solution_parts", "answers_note"]

ANSWER_PROMPT = "*Your answer here.*"
BEGIN = "### BEGIN SOLUTION"  # the markers of a master's solution blocks (particles.course.release.notebooks uses them)
END = "### END SOLUTION"
STUB_LINE = "# YOUR CODE HERE"  # the release writes it where a code solution block was; the grader reads it
SLOT_KEY = "answer"  # under the cell metadata's "particles"
_QUESTION = re.compile(r"^\s*\*\*Question\s*([0-9]+)?[^*]*\*\*", re.M)
_POINTS = re.compile(r"\(\s*([0-9]+(?:\.[0-9]+)?)\s+points?\s*\)")
DEFAULT_POINTS = 1.0
"""What a written question is worth when its header declares nothing."""


def cell_source(cell):
    """A cell's source as one string (a list of lines joined; anything else that is not text: "")."""
    source = cell.get("source", "") if isinstance(cell, dict) else ""
    if isinstance(source, list):
        return "".join(s for s in source if isinstance(s, str))
    return source if isinstance(source, str) else ""


def slot_of(cell):
    """The answer number a cell's metadata gives it, or None."""
    meta = cell.get("metadata") if isinstance(cell, dict) else None
    mark = meta.get("particles") if isinstance(meta, dict) else None
    k = mark.get(SLOT_KEY) if isinstance(mark, dict) else None
    return k if isinstance(k, int) and not isinstance(k, bool) and k > 0 else None


def is_blank(text):
    """Whether an answer's text says nothing: empty, white space, or the prompt."""
    rest = str(text).replace(ANSWER_PROMPT, "").replace("Your answer here.", "")
    return not re.sub(r"[\s*_]", "", rest)


def answer_slots(released):
    """The slots of a released notebook: ``[(k, cell id), ...]`` in order.

    Parameters
    ----------
    released : dict
        A notebook as ``json.load`` or ``nbformat.read`` gives it.
    """
    return [(slot_of(c), c.get("id")) for c in released.get("cells", []) if slot_of(c) is not None]


def questions_of(released):
    """The question each slot answers: ``{k: text}``, from the markdown above the slot.

    The text is the last paragraph above the slot that starts with
    ``**Question``, or the last markdown paragraph when none does.
    """
    out, above = {}, []
    for cell in released.get("cells", []):
        k = slot_of(cell)
        if k is not None:
            text = "\n\n".join(above)
            starts = [m.start() for m in _QUESTION.finditer(text)]
            if starts:
                text = text[starts[-1]:]
            else:
                text = text.strip().split("\n\n")[-1] if text.strip() else ""
            out[k] = text.strip()
            above = []
        elif cell.get("cell_type") == "markdown":
            above.append(cell_source(cell))
    return out


def question_points(released):
    """What each question is worth: ``{k: points}``, read from its ``**Question k (p points).**`` header.

    Parameters
    ----------
    released : dict
        A released notebook (or a master released with
        :func:`particles.course.release.notebooks.release_notebook`).

    Returns
    -------
    dict
        Slot number -> points (float); :data:`DEFAULT_POINTS` for a question
        that declares none.

    Raises
    ------
    ValueError
        When a header mentions points but not as ``(p points)`` or ``(1 point)``.

    Examples
    --------
    >>> cell = {"cell_type": "markdown", "source": "**Question 1 (3 points).** Why?"}
    >>> slot = {"cell_type": "markdown", "source": "", "metadata": {"particles": {"answer": 1}}}
    >>> question_points({"cells": [cell, slot]})
    {1: 3.0}
    """
    out = {}
    for k, text in questions_of(released).items():
        header = _QUESTION.match(text)
        if header is None:
            out[k] = DEFAULT_POINTS
            continue
        found = _POINTS.search(header.group(0))
        if found:
            out[k] = float(found.group(1))
        elif re.search(r"point", header.group(0), re.I):
            raise ValueError(f"question {k}: cannot read its points from {header.group(0)!r}; expected "
                             "e.g. '**Question 2 (3 points).**' or '**Question 1 (1 point).**'")
        else:
            out[k] = DEFAULT_POINTS
    return out


def answer_cells(submission, released):
    """Where a submission answers each slot of `released`: ``{k: [cell indices]}`` (empty for a deleted slot).

    Slots are found by metadata, else by cell id. Markdown cells the student
    added right below a slot (ids that the released notebook does not have)
    belong to that slot.
    """
    slots = answer_slots(released)
    by_id = {cid: k for k, cid in slots if cid}
    known = {c.get("id") for c in released.get("cells", []) if isinstance(c, dict)}
    where = {k: [] for k, _ in slots}
    current = None
    cells = submission.get("cells") if isinstance(submission.get("cells"), list) else []
    for index, cell in enumerate(cells):
        if not isinstance(cell, dict):
            continue
        k = slot_of(cell) or by_id.get(cell.get("id"))
        if k in where:
            current = k
            where[k].append(index)
        elif current is not None and cell.get("cell_type") == "markdown" and cell.get("id") not in known:
            where[current].append(index)  # the student's own cell under the prompt
        else:
            current = None
    return where


def answers_of(submission, released):
    """What a submission wrote in each slot of `released`: ``{k: text}`` ("" for a blank slot).

    The cells of each answer are those of :func:`answer_cells`.
    """
    cells = submission.get("cells") if isinstance(submission.get("cells"), list) else []
    texts = {k: "\n\n".join(cell_source(cells[i]) for i in where)
             for k, where in answer_cells(submission, released).items()}
    return {k: "" if is_blank(text) else text.replace(ANSWER_PROMPT, "").strip() for k, text in texts.items()}


def model_answers(master):
    """The master's answers, its solution blocks in markdown cells: ``{k: text}`` (k = 1, 2, ... in order)."""
    return dict(enumerate(_master_blocks(master), start=1))


def solution_parts(source):
    """A markdown cell's text cut at its solution blocks: ``[("text", str) or ("answer", str), ...]``.

    The release makes each block an answer slot of its own; a master checked
    as a submission answers with the blocks' texts. Empty text between blocks
    is dropped.
    """
    parts, lines, block, inside = [], [], [], False
    for line in source.split("\n"):
        if line.strip() == BEGIN:
            parts.append(("text", "\n".join(lines).strip("\n")))
            lines, block, inside = [], [], True
        elif line.strip() == END and inside:
            parts.append(("answer", "\n".join(block)))
            inside = False
        elif inside:
            block.append(line)
        else:
            lines.append(line)
    parts.append(("text", "\n".join(lines).strip("\n")))
    return [(part, text) for part, text in parts if part == "answer" or text.strip()]


def _master_blocks(notebook):
    """The solution blocks of a master's markdown cells, as texts (a master checked as a submission)."""
    return [text for cell in notebook.get("cells", []) if cell.get("cell_type") == "markdown"
            for part, text in solution_parts(cell_source(cell)) if part == "answer"]


def answers_note(written, where=""):
    """The student's line on their written answers, e.g. "Written answers: 1 of 3 filled in; not written yet: ..."."""
    blank = written.get("blank") or []
    missing = f"; not written yet: question{'s' if len(blank) > 1 else ''} {', '.join(map(str, blank))}" \
        if blank else ""
    return (f"Written answers: {written['answered']} of {written['asked']} filled in{missing}{where}; they are "
            "read and graded by your instructor, not by the autograder")


def _read(notebook):
    if isinstance(notebook, dict):
        return notebook
    data = json.loads(Path(notebook).read_text(encoding="utf-8"))
    if not isinstance(data, dict):
        raise ValueError("not a notebook")
    return data


def count_answers(submission, released):
    """How many of the released notebook's questions a submission answered.

    Parameters
    ----------
    submission, released : dict or path
        The student's notebook and the released exercise.

    Returns
    -------
    dict
        ``{"asked": N, "answered": k, "blank": [slot numbers left blank]}``;
        ``asked`` is 0 when the released notebook has no slot. An unreadable
        submission answered nothing.
    """
    released = _read(released)
    slots = [k for k, _ in answer_slots(released)]
    try:
        submission = _read(submission)
    except (OSError, UnicodeDecodeError, ValueError):
        return {"asked": len(slots), "answered": 0, "blank": slots}
    if not any(slot_of(c) or c.get("id") in {cid for _, cid in answer_slots(released)}
               for c in submission.get("cells", []) if isinstance(c, dict)):
        blocks = _master_blocks(submission)
        if blocks:  # a master: its solution blocks are its answers
            blank = [k for k, text in zip(slots, blocks + [""] * len(slots)) if is_blank(text)]
            return {"asked": len(slots), "answered": len(slots) - len(blank), "blank": blank}
    texts = answers_of(submission, released)
    blank = [k for k in slots if not texts.get(k)]
    return {"asked": len(slots), "answered": len(slots) - len(blank), "blank": blank}
