"""particles review: self-contained pages of every student's answer per question, and the rubric to fill in."""

import base64
import csv
import io
import json
from html.parser import HTMLParser
from pathlib import Path

import pytest
from PIL import Image

from particles.cli import main
from particles.course.grading.discovery import find_submissions, released_exercise
from particles.course.results.review import answer_figures, write_review
from particles.course.results.rubric import COLUMNS, WrittenGrades

ROOT = Path(__file__).resolve().parents[3]
EXERCISE = "01_integrator_order"
HOSTILE = ('I think <script>alert("x")</script> and <img src=http://evil.example/x.png onerror=alert(1)> '
           "![pic](https://evil.example/p.png) [see](javascript:alert(1)) **order 1**, $h_s^2$.")


def _png(colour):
    stream = io.BytesIO()
    Image.new("RGB", (4, 3), colour).save(stream, format="PNG")
    return stream.getvalue()


RED, BLUE = _png("red"), _png("blue")


def _figure_cell(image, cell_id):
    return {"cell_type": "code", "id": cell_id, "metadata": {}, "execution_count": 1, "source": "plot()",
            "outputs": [{"output_type": "display_data", "metadata": {},
                         "data": {"image/png": base64.b64encode(image).decode(), "text/plain": "<Figure>"}}]}


def _submission(answers, figures=()):
    """The released exercise with `answers` ({k: text}) in its slots and figure cells above given slots."""
    notebook = json.loads((ROOT / "exercises" / f"{EXERCISE}.ipynb").read_text())
    cells = []
    for cell in notebook["cells"]:
        k = cell.get("metadata", {}).get("particles", {}).get("answer")
        if k in dict(figures):
            cells.append(_figure_cell(dict(figures)[k], f"fig-{k}"))
        if k in answers:
            cell = dict(cell, source=answers[k])
        cells.append(cell)
    notebook["cells"] = cells
    return notebook


class _Tags(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tags, self.ids = [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        self.ids += [value for name, value in attrs if name == "id"]


@pytest.fixture()
def reviewed(tmp_path):
    subs = tmp_path / "subs"
    for student, notebook in {"ada": _submission({1: HOSTILE, 2: "The norm does not matter."}, [(1, RED)]),
                              "bob": _submission({}, [(2, BLUE)]),
                              "cy": _submission({3: "Coarse steps: $\\omega h$ is not small."})}.items():
        (subs / student).mkdir(parents=True)
        (subs / student / f"{EXERCISE}.ipynb").write_text(json.dumps(notebook))
    summary = write_review([subs], tmp_path / "review", root=ROOT)
    return subs, tmp_path / "review", summary


def test_pages_are_self_contained_and_hold_no_markup_of_the_students(reviewed):
    """No script but the review folder's MathJax, no remote address, images only as data: URIs; a hostile answer
    shows as escaped text."""
    _, out, summary = reviewed
    assert [p.name for p in summary["pages"]] == ["question-1.html", "question-2.html", "question-3.html"]
    for page in [*summary["pages"], out / "index.html"]:
        text = page.read_text()
        parser = _Tags()
        parser.feed(text)
        scripts = [attrs.get("src") for tag, attrs in parser.tags if tag == "script"]
        assert scripts == ([] if page.name == "index.html" else ["../mathjax/review-config.js",
                                                                  "../mathjax/tex-svg-full.js"])
        for tag, attrs in parser.tags:
            assert set(attrs) <= {"class", "id", "href", "src", "alt", "lang", "charset", "http-equiv", "content",
                                  "name"}, (tag, attrs)
            assert not any(v and ("http:" in v or "https:" in v or "javascript:" in v or "//" in v)
                           for k, v in attrs.items() if k != "content"), (tag, attrs)
            if tag == "img":
                assert attrs["src"].startswith("data:image/png;base64,")
            if tag == "a":  # the other pages of the review, by relative paths
                assert attrs["href"].endswith(".html") and ":" not in attrs["href"] and attrs["href"][0] != "/"
        assert "default-src 'none'" in text
    first = (out / EXERCISE / "question-1.html").read_text()
    assert "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt;" in first
    assert "&lt;img src=http://evil.example/x.png onerror=alert(1)&gt;" in first
    assert "[image not shown: pic (https://evil.example/p.png)]" in first and "<strong>order 1</strong>" in first


def test_every_student_is_on_every_page_blank_answers_as_blank(reviewed):
    """Each page has every student, in order; a blank answer is marked blank; the question's text is there."""
    _, out, _ = reviewed
    for k in (1, 2, 3):
        text = (out / EXERCISE / f"question-{k}.html").read_text()
        parser = _Tags()
        parser.feed(text)
        assert [i for i in parser.ids] == ["MathJax-script", "ada", "bob", "cy"]
        assert f"Question {k} (" in text and "The master's answer" in text
    second = (out / EXERCISE / "question-2.html").read_text()
    assert 'class="answer blank" id="bob"' in second and 'class="answer" id="ada"' in second
    assert "The norm does not matter." in second and "3 students, 2 blank" in second


def test_figures_come_from_the_cells_the_answer_refers_to(reviewed):
    """The images of the code cells above an answer are on its page, decoded to the same bytes."""
    subs, out, _ = reviewed
    released = released_exercise(ROOT, EXERCISE)
    figures = answer_figures(json.loads((subs / "ada" / f"{EXERCISE}.ipynb").read_text()), released)
    assert figures[1] == [("image/png", RED)] and figures[2] == [] and figures[3] == []
    pages = {k: (out / EXERCISE / f"question-{k}.html").read_text() for k in (1, 2, 3)}
    assert base64.b64encode(RED).decode() in pages[1] and base64.b64encode(BLUE).decode() in pages[2]
    assert pages[3].count("<img") == 0


def test_a_broken_image_output_is_not_shown():
    """An output that says PNG but is not one is left out."""
    released = released_exercise(ROOT, EXERCISE)
    notebook = _submission({1: "x"}, [(1, b"GIF89a not a png")])
    assert answer_figures(notebook, released)[1] == []


def _rows(path):
    return list(csv.DictReader(open(path, newline="")))


def test_the_rubric_has_a_row_per_student_and_question_and_keeps_what_was_filled_in(reviewed):
    """rubric.csv is pre-filled (points empty); run again, it keeps the grader's points and comments."""
    subs, out, _ = reviewed
    path = out / EXERCISE / "rubric.csv"
    rows = _rows(path)
    assert list(rows[0]) == list(COLUMNS)
    assert [(r["student"], r["question"], r["max_points"], r["points"], r["comment"]) for r in rows] == [
        (s, str(k), p, "", "") for s in ("ada", "bob", "cy") for k, p in ((1, "3"), (2, "2"), (3, "2"))]
    rows[0].update(points="2", comment="Close, but see h^2")
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    again = write_review([subs], out, root=ROOT)
    assert again["kept"] == 1 and _rows(path)[0]["comment"] == "Close, but see h^2" and len(_rows(path)) == 9
    # the names are those of the grading run: the rubric merges as it stands
    units, _ = find_submissions([subs], [EXERCISE])
    written = WrittenGrades.load([out], units, ROOT)
    assert written.grades[(EXERCISE, "ada", 1)].points == 2


def test_a_file_in_the_way_of_the_rubric_is_never_overwritten(reviewed):
    """An existing rubric.csv that is not a rubric stops the review; the file is unchanged."""
    subs, out, _ = reviewed
    path = out / EXERCISE / "rubric.csv"
    path.write_text("my,own,notes\n")
    with pytest.raises(ValueError, match="exists and is not a rubric"):
        write_review([subs], out, root=ROOT)
    assert path.read_text() == "my,own,notes\n"


def test_the_review_command(reviewed, tmp_path, capsys):
    """particles review prints where the pages and rubrics are; bad input exits 2 or 1 with a reason."""
    subs, _, _ = reviewed
    assert main(["review", str(subs), "--out", str(tmp_path / "cli"), "--root", str(ROOT)]) == 0
    printed = capsys.readouterr().out
    assert "wrote 3 question pages of 3 students" in printed and f"{EXERCISE}/rubric.csv" in printed
    assert main(["review", str(subs), "--out", str(tmp_path / "x"), "--root", str(ROOT), "--exercise", "9_x"]) == 2
    assert "unknown exercise '9_x'" in capsys.readouterr().err
    assert main(["review", str(tmp_path / "nothing"), "--out", str(tmp_path / "y"), "--root", str(ROOT)]) == 1
    assert "does not exist" in capsys.readouterr().err


def test_a_notebook_the_grader_refuses_is_shown_blank_with_the_graders_reason(tmp_path):
    """Review reads notebooks with the grader's checks: a notebook that is not JSON, or one whose nbformat
    is 3, is listed with the one-line reason `particles grade` gives, and its answers are blank."""
    subs = tmp_path / "subs"
    for student, text in {"ada": json.dumps(_submission({1: "Order one."})), "bob": '{"cells": [',
                          "cy": json.dumps({"nbformat": 3, "nbformat_minor": 0, "worksheets": []})}.items():
        (subs / student).mkdir(parents=True)
        (subs / student / f"{EXERCISE}.ipynb").write_text(text)
    summary = write_review([subs], tmp_path / "review", root=ROOT)
    problems = "\n".join(summary["problems"])
    assert "bob" in problems and "not valid JSON" in problems and "shown blank" in problems
    assert "cy" in problems and "nbformat 3" in problems
    assert "ada" not in problems
    page = (tmp_path / "review" / EXERCISE / "question-1.html").read_text()
    assert "Order one." in page


def test_review_opens_an_lms_zip_and_exits_1_on_a_problem(tmp_path, capsys):
    """An LMS's zip is opened as `particles grade` opens it; a notebook not read makes the command exit 1."""
    import zipfile
    with zipfile.ZipFile(tmp_path / "download.zip", "w") as archive:
        archive.writestr(f"ada/{EXERCISE}.ipynb", json.dumps(_submission({1: "Order one."})))
        archive.writestr(f"bob/{EXERCISE}.ipynb", '{"cells": [')
    code = main(["review", str(tmp_path / "download.zip"), "--out", str(tmp_path / "r"), "--root", str(ROOT)])
    printed = capsys.readouterr()
    assert code == 1 and "unzip it first" not in printed.err and "not valid JSON" in printed.err
    assert "Order one." in (tmp_path / "r" / EXERCISE / "question-1.html").read_text()
    rows = list(csv.DictReader((tmp_path / "r" / EXERCISE / "rubric.csv").open()))
    assert {r["student"] for r in rows} == {"ada", "bob"}


def test_a_rubric_folder_is_read_per_exercise(reviewed, tmp_path):
    """A folder of rubrics of two exercises merges into a run of one: the other exercise's rows wait for theirs;
    a file named on its own still must fit the run."""
    subs, review, _ = reviewed
    other = review / "00_warmup" / "rubric.csv"
    other.parent.mkdir()
    other.write_text(",".join(COLUMNS) + "\n00_warmup,zed,1,2,1,ok\n")
    units, _ = find_submissions([subs], [EXERCISE])
    written = WrittenGrades.load([review], units, ROOT)
    assert written.covers(EXERCISE) and not written.covers("00_warmup")
    with pytest.raises(ValueError, match="unknown exercise '00_warmup'"):
        WrittenGrades.load([other], units, ROOT)


MATH_ATTACKS = {  # the students' TeX: links, classes, styles, ids, raw HTML, \require, a dollar in prose
    1: "Order one: $h\\mathbf v$ and $$\\dot{\\mathbf x} = \\mathbf v$$; it costs $5 at most.",
    2: "$\\href{javascript:alert(1)}{click}$ $\\style{background:url(http://evil.example/x)}{y}$ "
       "$\\class{pwn}{z}$ $\\cssId{pwn}{w}$ $\\require{html}$ $x</span><script>alert(2)</script>$",
}

SEEN = """(async () => {
  if (window.MathJax && MathJax.startup) { await MathJax.startup.promise; }
  return {spans: document.querySelectorAll('span.math').length,
          typeset: document.querySelectorAll('span.math mjx-container').length,
          elsewhere: document.querySelectorAll('mjx-container').length
                     - document.querySelectorAll('span.math mjx-container').length,
          scripts: Array.from(document.scripts).map(s => s.getAttribute('src')),
          links: Array.from(document.querySelectorAll('[href]')).map(a => a.getAttribute('href')),
          pwn: document.querySelectorAll('.pwn, #pwn').length,
          styled: Array.from(document.querySelectorAll('mjx-container [style]'))
                       .filter(e => /url\\(/.test(e.getAttribute('style'))).length,
          prose: document.body.innerText};
})()"""


def test_math_is_typeset_safely_offline_in_the_browser(tmp_path):
    """The equations of the question and of the answers are typeset by the review folder's MathJax, offline; the
    students' TeX makes no link, class, id, style or script, a dollar in prose stays a dollar, and nothing but the
    folder's own two scripts runs."""
    from ...browser import Browser, find_or_install_chromium
    subs = tmp_path / "subs"
    (subs / "ada").mkdir(parents=True)
    (subs / "ada" / f"{EXERCISE}.ipynb").write_text(json.dumps(_submission(MATH_ATTACKS)))
    summary = write_review([subs], tmp_path / "review", root=ROOT)
    assert summary["problems"] == [] and (tmp_path / "review" / "mathjax" / "review-config.js").exists()
    with Browser(find_or_install_chromium()) as browser:
        for k in (1, 2):
            page = tmp_path / "review" / EXERCISE / f"question-{k}.html"
            tab = browser.open(page)
            seen = tab.evaluate(SEEN)
            assert tab.outside(tmp_path / "review") == [] and tab.failed == [], (tab.outside(tmp_path), tab.failed)
            assert [e for e in tab.errors if "Content Security Policy" not in e] == [], tab.errors
            assert seen["spans"] > 0 and seen["typeset"] == seen["spans"] and seen["elsewhere"] == 0, seen
            mathjax = (tmp_path / "review" / "mathjax").as_uri()
            assert seen["scripts"][:2] == ["../mathjax/review-config.js", "../mathjax/tex-svg-full.js"]
            assert all(src.startswith(mathjax) for src in seen["scripts"][2:]), seen["scripts"]  # its safe extension
            assert not [href for href in seen["links"] if "javascript" in href or "evil" in href]
            assert seen["pwn"] == 0 and seen["styled"] == 0
            if k == 1:
                assert "it costs $5 at most" in seen["prose"] and "\\mathbf" not in seen["prose"]
            tab.close()
