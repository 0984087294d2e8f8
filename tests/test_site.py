"""The course site: lectures executed, rendered in order, and loading cleanly in a browser."""

import html
import re
from pathlib import Path

import nbformat
import pytest

from particles.site import build_site, lecture_notebooks, notebook_summary

from .browser import find_or_install_chromium, load

ROOT = Path(__file__).resolve().parents[1]


def notebook(title, *code):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_markdown_cell(f"# {title}\n\nThis lecture shows {title.lower()}. More text.")]
    nb.cells += [nbformat.v4.new_code_cell(c) for c in code]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    return nb


ANIMATION = """import numpy as np
from IPython.display import HTML
from particles import render
frames = [np.random.default_rng(0).random((5, 2)) + 0.1 * k for k in range(4)]
HTML(render.to_html(render.animate(frames)))"""


@pytest.fixture(scope="module")
def small_site(tmp_path_factory):
    root = tmp_path_factory.mktemp("course")
    (root / "lectures").mkdir()
    (root / "exercises").mkdir()
    nbformat.write(notebook("Second topic", "x = 2\nprint(x)"), root / "lectures" / "02_second.ipynb")
    link = nbformat.v4.new_markdown_cell("Now try [the exercise](../exercises/01_first.ipynb).")
    first = notebook("First topic", ANIMATION)
    first.cells.append(link)
    nbformat.write(first, root / "lectures" / "01_first.ipynb")
    nbformat.write(notebook("Exercise"), root / "exercises" / "01_first.ipynb")
    (root / "lectures" / "notes.ipynb").write_text("{}")  # not a numbered lecture: ignored
    pages = build_site(root / "site", root / "lectures", log=lambda *a: None)
    return root, pages


def test_pages_in_lecture_order_with_navigation(small_site):
    root, pages = small_site
    assert [p.name for p in pages] == ["index.html", "01_first.html", "02_second.html"]
    index = (root / "site" / "index.html").read_text()
    assert index.index("First topic") < index.index("Second topic")
    assert "This lecture shows first topic." in index
    first = (root / "site" / "01_first.html").read_text()
    assert 'href="02_second.html"' in first and 'href="index.html"' in first
    assert 'href="exercises/01_first.ipynb"' in first  # link rewritten, file copied
    assert (root / "site" / "exercises" / "01_first.ipynb").exists()
    assert "anim-slider" in first  # the animation player is embedded


def test_lecture_list_and_summary(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        lecture_notebooks(tmp_path / "nowhere")
    assert notebook_summary(notebook("Forces")) == ("Forces", "This lecture shows forces.")
    with pytest.raises(ValueError, match="no lecture notebooks"):
        build_site(tmp_path / "out", tmp_path)


def test_pages_load_in_headless_chromium_without_script_errors(small_site):
    """Every page loads without JavaScript errors; the animation player initializes."""
    chromium = find_or_install_chromium()
    root, pages = small_site
    for page in pages:
        dom, errors = load(chromium, page)
        assert "<body" in dom, page.name
        assert errors == [], (page.name, errors)
    dom, _ = load(chromium, root / "site" / "01_first.html")
    # the player's script ran: it set the first frame as the image source
    assert re.search(r'<img[^>]*id="_anim_img\w+"[^>]*src="data:image/png;base64', dom)


def test_a_failing_script_is_reported(tmp_path):
    """The error collector does catch errors (a test that could not fail would be worthless)."""
    chromium = find_or_install_chromium()
    bad = tmp_path / "lectures"
    bad.mkdir()
    nbformat.write(notebook("Broken", "from IPython.display import HTML\nHTML('<script>undefinedFunction()</script>')"),
                   bad / "01_broken.ipynb")
    page = build_site(tmp_path / "site", bad, log=lambda *a: None)[1]
    _, errors = load(chromium, page)
    assert errors and "undefinedFunction" in " ".join(errors)


def test_the_course_site_of_the_real_lectures_loads_cleanly(tmp_path, executed_lecture):
    """The site of the course's own lectures: an index in lecture order, every page loading without
    script errors, and every lecture's animation player running; linked exercises are copied."""
    chromium = find_or_install_chromium()
    paths = lecture_notebooks(ROOT / "lectures")
    executed = {path.name: executed_lecture(path) for path in paths}
    pages = build_site(tmp_path / "site", ROOT / "lectures", executed=executed, log=lambda *a: None)
    assert [p.name for p in pages] == ["index.html"] + [p.with_suffix(".html").name for p in paths]
    index = (tmp_path / "site" / "index.html").read_text()
    titles = [notebook_summary(executed[p.name])[0] for p in paths]
    assert [index.index(html.escape(t)) for t in titles] == sorted(index.index(html.escape(t)) for t in titles)
    for page in pages:
        dom, errors = load(chromium, page)
        assert errors == [], (page.name, errors)
        if page.name != "index.html":
            assert re.search(r'<img[^>]*id="_anim_img\w+"[^>]*src="data:image/png;base64', dom), page.name
            for link in re.findall(r'href="(exercises/[^"#]+)"', page.read_text()):
                assert (tmp_path / "site" / link).is_file(), (page.name, link)
