"""Figures in the feedback: feedback.html, Gradescope's HTML output and particles.check, with curves drawn."""

import base64
import io
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from PIL import Image

from particles.course.check import check
from particles.course.grading.figures import MAX_POINTS, Feedback, curve_spec, png
from particles.course.grading.driver import LibraryChanged, grade
from particles.course.results.reports import feedback_html, gradescope_results
from particles.course.results.records import SubmissionRecord, TestRecord

from ...browser import find_or_install_chromium
from ..grader import cases_01_integrator_order, cases_02_stiffness, cases_03_provot, cases_04_discretization
from ..grader.exercise_corpus import build

ROOT = Path(__file__).resolve().parents[3]

# one wrong submission per exercise where a curve is the point, each failing a test that draws one
WRONG = {"01_integrator_order": (cases_01_integrator_order, "trapezoid_uneven_weights"),
         "02_stiffness": (cases_02_stiffness, "implicit_held_to_explicit_limit"),
         "03_provot": (cases_03_provot, "compression_counted_as_strain"),
         "04_discretization": (cases_04_discretization, "naive_constants")}

_VISIBILITY = {"enum": ["hidden", "after_due_date", "after_published", "visible"]}
_FORMAT = {"enum": ["text", "html", "simple_format", "md", "ansi"]}
GRADESCOPE_SCHEMA = {  # https://gradescope-autograders.readthedocs.io/en/latest/specs/ (results.json)
    "type": "object",
    "properties": {
        "score": {"type": "number"},
        "execution_time": {"type": "number", "minimum": 0},
        "output": {"type": "string"},
        "output_format": _FORMAT,
        "test_output_format": _FORMAT,
        "test_name_format": _FORMAT,
        "visibility": _VISIBILITY,
        "stdout_visibility": _VISIBILITY,
        "extra_data": {"type": "object"},
        "tests": {"type": "array", "items": {
            "type": "object",
            "properties": {
                "score": {"type": "number"},
                "max_score": {"type": "number"},
                "status": {"enum": ["passed", "failed"]},
                "name": {"type": "string"},
                "name_format": _FORMAT,
                "number": {"type": "string"},
                "output": {"type": "string"},
                "output_format": _FORMAT,
                "tags": {"type": "array", "items": {"type": "string"}},
                "visibility": _VISIBILITY,
                "extra_data": {"type": "object"},
            },
            "additionalProperties": False,
        }},
        "leaderboard": {"type": "array"},
    },
    "anyOf": [{"required": ["score"]}, {"required": ["tests"]}],
    "additionalProperties": False,
}
DATA_PNG = re.compile(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)"')


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """One wrong submission of each of 01-04 graded into an out folder, with a combined Gradescope file."""
    base = tmp_path_factory.mktemp("feedback")
    for exercise, (cases, name) in WRONG.items():
        folder = base / "subs" / f"student{exercise[:2]}"
        folder.mkdir(parents=True)
        (folder / f"{exercise}.ipynb").write_text(json.dumps(build(exercise, cases.REJECTED[name])))
    try:
        summary = grade([base / "subs"], base / "out", root=ROOT, seed=11, jobs=2, gradescope=base / "gradescope.json")
    except LibraryChanged as error:  # someone edited the library meanwhile: these grades say nothing
        pytest.skip(f"re-run: {error}")
    return base, summary


def _images(text):
    return [Image.open(io.BytesIO(base64.b64decode(m))) for m in DATA_PNG.findall(text)]


def _chromium_console(chromium, page):
    """Open `page` headless; return its DOM and every console message (a page without scripts logs none)."""
    with tempfile.TemporaryDirectory() as profile:
        done = subprocess.run(
            [chromium, "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0", "--virtual-time-budget=3000",
             "--dump-dom", page.resolve().as_uri()], capture_output=True, text=True, timeout=120)
    console = [line for line in done.stderr.splitlines() if ":CONSOLE" in line or "Uncaught" in line]
    return done.stdout, console


def test_feedback_html_for_every_student_loads_cleanly_with_figures(graded):
    """Every student gets a self-contained feedback.html that loads without console messages and shows a curve."""
    base, summary = graded
    chromium = find_or_install_chromium()
    assert sorted(summary["students"]) == [f"student{e[:2]}" for e in WRONG]
    for student in summary["students"]:
        page = base / "out" / student / "feedback.html"
        text = page.read_text()
        assert "<script" not in text and not re.search(r'(src|href)="(https?:)?//', text)  # no scripts, no network
        assert (base / "out" / student / "feedback.md").exists()
        dom, console = _chromium_console(chromium, page)
        assert "<h1>Feedback for " in dom and console == [], (student, console)
        images = _images(dom)
        assert images and all(image.size == (416, 272) for image in images), student


def test_failed_curve_tests_show_their_figure_open(graded):
    """The figure of a failed test sits in an open <details> under its row; a passed test's is folded."""
    base, summary = graded
    for student, (result,) in summary["students"].items():
        drawn = [t for t in result["tests"] if t.get("figures")]
        assert any(not t["passed"] for t in drawn), (student, [t["test"] for t in drawn])
        text = (base / "out" / student / "feedback.html").read_text()
        assert text.count("<details open>") == sum(not t["passed"] for t in drawn)
        assert text.count("<details>") == sum(t["passed"] for t in drawn)


def test_gradescope_results_validate_and_inline_figures_as_html(graded):
    """Per-student and combined results.json validate against Gradescope's schema; tests with figures are HTML."""
    base, summary = graded
    files = [base / "out" / s / "results.json" for s in summary["students"]] + [base / "gradescope.json"]
    for path in files:
        data = json.loads(path.read_text())
        jsonschema.validate(data, GRADESCOPE_SCHEMA)
        html_tests = [t for t in data["tests"] if t["output_format"] == "html"]
        assert html_tests, path
        assert all(_images(t["output"]) and t["output"].startswith("<p>") for t in html_tests)
        assert all("<" not in t["output"] for t in data["tests"] if t["output_format"] == "text")
    combined = json.loads((base / "gradescope.json").read_text())
    assert {t["tags"][0] for t in combined["tests"] if t["output_format"] == "html"} == set(WRONG)


def test_hidden_figures_keep_the_random_parameters_out_of_their_texts(graded):
    """A hidden test's figure texts name no number: its random parameters are plotted as relative values."""
    _, summary = graded
    hidden = [f for (r,) in summary["students"].values() for t in r["tests"] if t["hidden"]
              for f in t.get("figures", [])]
    assert hidden
    for figure in hidden:
        texts = [figure["title"], figure["xlabel"], figure["ylabel"], figure["caption"]]
        texts += [re.sub(r"\(slope [^)]*\)", "", s["label"]) for s in figure["series"]]  # the student's own slope
        assert not [t for t in texts if re.search(r"\d\.\d|=", t)], texts


def test_check_result_shows_the_convergence_figure_inline():
    """particles.check on exercise 01 gives a CheckResult whose _repr_html_ embeds the error curves as PNG."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "01_integrator_order.ipynb"
        path.write_text(json.dumps(build("01_integrator_order",
                                         cases_01_integrator_order.REJECTED["trapezoid_uneven_weights"])))
        result = check("01_integrator_order", notebook=path, root=ROOT)
    shown = result._repr_html_()
    assert not result.passed and "<table>" in shown and "❌" in shown
    assert len(_images(shown)) == sum(len(t.get("figures", [])) for t in result.tests) >= 5
    assert "Global error of your trapezoid steps on the circle field" in json.dumps([t.to_dict() for t in result.tests])


def test_curve_spec_keeps_plain_bounded_json_whatever_the_student_returned():
    """Series become lists of floats (None for NaN), at most MAX_POINTS long; odd values are kept out, not fatal."""
    board = Feedback(hidden=True)
    spec = board.curve("t", "x", "y", [{"label": "yours", "y": np.r_[np.nan, np.arange(5000.0)]},
                                       {"label": "reference", "x": [1, 2], "y": [1.0, 2.0, 3.0]},
                                       {"label": "yours again", "y": "not numbers"},
                                       {"label": "a matrix", "y": np.ones((2, 2))}], loglog=True)
    yours, reference, text, matrix = spec["series"]
    assert len(yours["y"]) == len(yours["x"]) <= MAX_POINTS and yours["y"][0] is None and yours["x"][-1] == 5000
    assert reference["role"] == "reference" and reference["problem"] == "3 values for 2 points"
    assert text["y"] == [] and text["problem"] and matrix["problem"]
    assert json.loads(json.dumps(spec)) == spec and board.hidden and board.figures == [spec]
    assert png(spec)[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(TypeError, match="title"):
        curve_spec(None, "x", "y", [{"y": [1]}])
    with pytest.raises(ValueError, match="role"):
        curve_spec("t", "x", "y", [{"y": [1], "role": "mine"}])


def test_a_figure_is_drawn_once_until_the_cache_is_cleared(monkeypatch):
    """The same figure (by content) is drawn once per process; after clear_cache it is drawn again."""
    from particles.course.grading import figures

    drawn = []
    real = figures._draw
    monkeypatch.setattr(figures, "_draw", lambda spec: drawn.append(1) or real(spec))
    spec = curve_spec("cache", "x", "y", [{"label": "yours", "x": [1, 2, 3], "y": [3.0, 1.0, 2.0]}])
    figures.clear_cache()
    first = figures.data_uri(spec)
    assert figures.data_uri(spec) == first and len(drawn) == 1
    figures.clear_cache()
    assert figures.data_uri(spec) == first and len(drawn) == 2


def test_texts_are_escaped_in_html_outputs():
    """A reason holding markup (a student's exception message) is escaped in feedback.html and Gradescope's HTML."""
    spec = curve_spec("<b>title</b>", "x", "y", [{"label": "yours", "y": [1, 2]}], caption="a <i>caption</i>")
    test = TestRecord(test="test_x", name="x <img>", reason="raised ValueError: <script>alert(1)</script>",
                      figures=[spec])
    result = SubmissionRecord(student="<eve>", exercise="01_x", tests=[test], notes=["<iframe>"], seed=1)
    page = feedback_html("<eve>", [result])
    output = gradescope_results("<eve>", [result])["tests"][0]["output"]
    for text in (page, output):
        assert "<script>" not in text and "&lt;script&gt;" in text and "<i>caption" not in text
    assert "<iframe>" not in page and "<img>" not in page


def test_drawing_loads_no_code_after_the_driver_started():
    """Once the driver has imported grading, drawing a figure imports no further module."""
    script = """
import sys
import particles.course.grading.driver
from particles.course.grading import figures
before = set(sys.modules)
for loglog in (True, False):
    spec = figures.curve_spec("t", "x", "y", [{"label": "yours", "x": [1, 2, 3], "y": [1, 0.5, None]},
                                              {"label": "reference", "y": [1, 0.25, 0.1]}], loglog=loglog)
    assert figures.figure_html(spec).count("data:image/png;base64,") == 1
print(sorted(set(sys.modules) - before))
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
