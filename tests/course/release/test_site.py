"""The course site: lectures executed, rendered in order, and working offline in a browser.

Pages are opened in headless Chromium with the network cut off (``tests/browser.py``): every
request is logged and must stay inside the site folder (or be a ``data:`` URL), every equation
must be typeset by the site's own MathJax, and the explorations' players must switch images
when their slider moves.
"""

import html
import re
from pathlib import Path

import nbformat
import pytest

from particles.course.release.site import MATHJAX, MATHJAX_SCRIPTS, build_site, lecture_notebooks, notebook_summary

from ...browser import Browser, find_or_install_chromium, load

ROOT = Path(__file__).resolve().parents[3]


def notebook(title, *code, prose="More text."):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_markdown_cell(f"# {title}\n\nThis lecture shows {title.lower()}. {prose}")]
    nb.cells += [nbformat.v4.new_code_cell(c) for c in code]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    return nb


ANIMATION = """import numpy as np
from IPython.display import HTML
from particles import render
frames = [np.random.default_rng(0).random((5, 2)) + 0.1 * k for k in range(4)]
HTML(render.to_html(render.animate(frames)))"""

EXPLORATION = """from particles.explore import Exploration, bouncing_ball
from particles.explore.figures import plot_bounces
Exploration(run=bouncing_ball, draw=plot_bounces, parameter=("eps", [0.5, 0.8, 1.0]), value=0.8)"""

EQUATIONS = ("The energy $E = \\tfrac12 m |\\mathbf v|^2$ is kept, and\n\n"
             "$$m\\ddot{\\mathbf x} = \\mathbf F(\\mathbf x), \\qquad \\dot E = 0 .$$")

# run in the page after its load event: wait for MathJax, then report what the reader sees
TYPESET = """(async () => {
  if (window.MathJax && MathJax.startup) { await MathJax.startup.promise; }
  const prose = Array.from(document.querySelectorAll('.jp-MarkdownOutput, li, p'))
                     .map(e => e.innerText).join('\\n');
  return {prose: prose, typeset: document.querySelectorAll('mjx-container').length,
          errors: document.querySelectorAll('[data-mml-node="merror"]').length,
          mathjax: !!(window.MathJax && MathJax.version), version: window.MathJax && MathJax.version,
          recorded: document.documentElement.getAttribute('data-js-errors'),
          animations: Array.from(document.querySelectorAll('img[id^="_anim_img"]'))
                           .map(img => img.src.startsWith('data:image/png;base64')),
          explorations: document.querySelectorAll('.particles-exploration').length};
})()"""

# move every exploration's slider to every position; report which image shows and its source
SLIDE = """(() => Array.from(document.querySelectorAll('.particles-exploration')).map(root => {
  const input = root.querySelector('input.explore-slider');
  const frames = Array.from(root.querySelectorAll('img.explore-frame'));
  return frames.map((_, k) => {
    input.value = String(k);
    input.dispatchEvent(new Event('input'));
    const shown = frames.filter(img => getComputedStyle(img).display !== 'none');
    return {k: k, shown: shown.map(img => Number(img.dataset.index)),
            label: root.querySelector('output').textContent,
            src: shown.length ? shown[0].src.length + shown[0].src.slice(-120, -30) : null};
  });
}))()"""

RAW_MATH = re.compile(r"\$[^$\n]+\$|\\\(|\\\[")


@pytest.fixture(scope="module")
def small_site(tmp_path_factory):
    root = tmp_path_factory.mktemp("course")
    (root / "lectures").mkdir()
    (root / "exercises").mkdir()
    nbformat.write(notebook("Second topic", "x = 2\nprint(x)", EXPLORATION), root / "lectures" / "02_second.ipynb")
    link = nbformat.v4.new_markdown_cell("Now try [the exercise](../exercises/01_first.ipynb).")
    first = notebook("First topic", ANIMATION)
    first.cells += [nbformat.v4.new_markdown_cell(EQUATIONS), link]
    nbformat.write(first, root / "lectures" / "01_first.ipynb")
    nbformat.write(notebook("Exercise"), root / "exercises" / "01_first.ipynb")
    (root / "lectures" / "notes.ipynb").write_text("{}")  # not a numbered lecture: ignored
    pages = build_site(root / "site", root / "lectures", log=lambda *a: None)
    return root, pages


@pytest.fixture(scope="module")
def browser():
    with Browser(find_or_install_chromium()) as b:
        yield b


def visit(browser, page, site):
    """Open `page` offline; returns what TYPESET reports, the tab, and the checks every page passes."""
    tab = browser.open(page)
    seen = tab.evaluate(TYPESET)
    assert seen["recorded"] is None and tab.errors == [], (page.name, seen["recorded"], tab.errors)
    assert tab.outside(site) == [], (page.name, tab.outside(site))  # nothing left the site folder
    assert tab.failed == [], (page.name, tab.failed)  # and every file it asked for was there
    assert seen["mathjax"] and seen["errors"] == 0, page.name
    assert not RAW_MATH.findall(seen["prose"]), (page.name, RAW_MATH.findall(seen["prose"])[:5])
    return seen, tab


def check_players(tab, page, count=None):
    """Each exploration's slider shows exactly the image of its position, a different one each time."""
    players = tab.evaluate(SLIDE)
    if count is not None:
        assert len(players) == count, page.name
    for player in players:
        assert [p["shown"] for p in player] == [[p["k"]] for p in player], page.name
        assert len({p["src"] for p in player}) == len(player) and len({p["label"] for p in player}) == len(player)
    return players


def test_pages_in_lecture_order_with_navigation(small_site):
    """The index and the pages follow the lectures' numbers, and each page links the next one and the index."""
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


def test_pages_load_only_the_sites_own_files(small_site):
    """Scripts come from the site folder: its MathJax copy (with its license), no CDN, no require.js;
    the exploration is embedded as its static player (the build runs the kernel in static mode)."""
    root, pages = small_site
    assert (root / "site" / MATHJAX).is_file() and (root / "site" / "mathjax" / "LICENSE").is_file()
    for page in pages:
        text = page.read_text()
        sources = re.findall(r'<script[^>]*\bsrc="([^"]*)"', text)
        assert sources == [MATHJAX], (page.name, sources)
        for cdn in ("cdnjs", "unpkg", "jsdelivr", "maxcdn", "require.js", "require.min.js"):
            assert cdn not in text, (page.name, cdn)
    second = (root / "site" / "02_second.html").read_text()
    assert second.count('class="explore-frame"') == 3 and second.count('class="explore-slider"') == 1
    assert "widget-view" not in second


def test_lecture_list_and_summary(tmp_path):
    """A missing folder or one without lectures is refused by name; a lecture's title and summary come from its first cell."""
    with pytest.raises(ValueError, match="does not exist"):
        lecture_notebooks(tmp_path / "nowhere")
    assert notebook_summary(notebook("Forces")) == ("Forces", "This lecture shows forces.")
    with pytest.raises(ValueError, match="no lecture notebooks"):
        build_site(tmp_path / "out", tmp_path)


def test_pages_work_offline_in_headless_chromium(small_site, browser):
    """With the network cut off every page loads without script errors, asks only for files of the
    site, typesets every equation, runs its animation player, and its exploration's slider switches
    the images."""
    root, pages = small_site
    site = root / "site"
    for page in pages:
        seen, tab = visit(browser, page, site)
        if page.name == "01_first.html":
            assert seen["typeset"] == 2  # one inline, one display
            assert seen["animations"] == [True]
            assert any(url.endswith(MATHJAX) for url in tab.requests)
        if page.name == "02_second.html":
            players = check_players(tab, page, count=1)
            assert [p["label"] for p in players[0]] == ["eps = 0.5", "eps = 0.8", "eps = 1"]
        tab.close()


def test_the_offline_checks_can_fail(small_site, browser):
    """A page that asks for a remote script and a file outside the site, and holds undefined TeX,
    fails the checks: both requests are logged (the remote one blocked), and the TeX error is counted
    (a check that could not fail would be worthless)."""
    root, _ = small_site
    page = root / "site" / "offline-check.html"
    page.write_text(f'<html><head>{MATHJAX_SCRIPTS}<script src="https://cdn.example.org/x.js"></script>'
                    f'<script src="{(root / "elsewhere.js").as_uri()}"></script></head>'
                    "<body><p>Fine: $x^2$. Broken: $\\undefinedmacro x$.</p></body></html>")
    tab = browser.open(page)
    seen = tab.evaluate(TYPESET)
    outside = tab.outside(root / "site")
    assert "https://cdn.example.org/x.js" in outside and (root / "elsewhere.js").as_uri() in outside
    assert len(tab.failed) == 2  # blocked, and missing
    assert seen["typeset"] == 2 and seen["errors"] == 1
    tab.close()
    page.unlink()


def test_a_failing_script_is_reported(tmp_path, browser):
    """The error collector does catch errors (a test that could not fail would be worthless)."""
    chromium = find_or_install_chromium()
    bad = tmp_path / "lectures"
    bad.mkdir()
    nbformat.write(notebook("Broken", "from IPython.display import HTML\nHTML('<script>undefinedFunction()</script>')"),
                   bad / "01_broken.ipynb")
    page = build_site(tmp_path / "site", bad, log=lambda *a: None)[1]
    _, errors = load(chromium, page)
    assert errors and "undefinedFunction" in " ".join(errors)
    tab = browser.open(page)
    assert tab.evaluate("document.documentElement.getAttribute('data-js-errors')")
    assert any("undefinedFunction" in str(error) for error in tab.errors)
    tab.close()


def test_the_course_site_of_the_real_lectures_works_offline(tmp_path, executed_lecture, browser):
    """The site of the course's own lectures and appendices, offline: an index in lecture order, the
    appendices after the lectures; every page loading without script errors and only the site's files,
    every equation typeset, every lecture's animation player running, the explorations of lectures 2, 3,
    7 and 9 switching images on their sliders; linked exercises are copied."""
    paths = lecture_notebooks(ROOT / "lectures")
    executed = {path.name: executed_lecture(path) for path in paths}
    site = tmp_path / "site"
    pages = build_site(site, ROOT / "lectures", executed=executed, log=lambda *a: None)
    assert [p.name for p in pages] == ["index.html"] + [p.with_suffix(".html").name for p in paths]
    index = (site / "index.html").read_text()
    titles = [notebook_summary(executed[p.name])[0] for p in paths]
    assert [index.index(html.escape(t)) for t in titles] == sorted(index.index(html.escape(t)) for t in titles)
    assert any(p.name.startswith("A") for p in paths) and index.index("Appendices") > index.index(html.escape(titles[0]))
    explorations = {"02_forces.html": 1, "03_collisions.html": 1, "07_stiffness_provot_implicit.html": 2,
                    "09_cloth_collisions.html": 1}
    for page in pages:
        seen, tab = visit(browser, page, site)
        if page.name != "index.html":
            appendix = page.name.startswith("A")  # an appendix needs no animation of its own
            assert seen["typeset"] > 0 and (appendix or seen["animations"]) and all(seen["animations"]), page.name
            assert seen["explorations"] == explorations.get(page.name, 0), page.name
            check_players(tab, page)
            for link in re.findall(r'href="(exercises/[^"#]+)"', page.read_text()):
                assert (site / link).is_file(), (page.name, link)
        tab.close()
