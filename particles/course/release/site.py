"""The course site: lectures executed and rendered as static HTML (``particles site``).

``build_site`` executes every lecture notebook (``lectures/NN_topic.ipynb``)
and every appendix (``lectures/A1_topic.ipynb``, ...) in a fresh Jupyter
kernel, converts it to a self-contained HTML page with nbconvert (figures
and animation players embedded), adds a navigation bar, and writes an index
in lecture order, the appendices after the lectures. The student notebooks
linked from the lectures (``../exercises/...``) are copied next to the
pages, so the folder can be published as it is.

The site works offline, from a disk or any static host: a page loads only
files of the site folder and ``data:`` URLs. Figures, animation players and
the players of the explorations (:mod:`particles.explore`) are embedded in the
pages; equations are typeset by MathJax 3 (its SVG output, so no web fonts),
copied into ``mathjax/`` from the files that the ``django-static-mathjax``
package installs (the MathJax distribution, no Python code). nbconvert's CDN
scripts are left out: require.js (nothing in the pages needs it), the widget
manager and mermaid. The lectures run with ``PARTICLES_EXPLORATIONS=static``
in the kernel's environment, so that every exploration shows its static
player instead of a live widget.

Every page starts with a tiny script that records JavaScript errors in the
``data-js-errors`` attribute of the ``<html>`` element; a headless browser
(see ``tests/course/release/test_site.py``) reads it to check that the pages run cleanly.
"""

import copy
import html
import os
import re
import shutil
import time
from importlib import resources
from pathlib import Path

import nbformat

__all__ = ["lecture_notebooks", "execute_notebook", "notebook_summary", "build_site", "mathjax_source",
           "copy_mathjax"]

MATHJAX = "mathjax/tex-svg-full.js"  # the site's copy, relative to its pages

# MathJax 3 with the delimiters of Jupyter's Markdown; an undefined macro is an error (shown in
# red, and found by the site's test), not silently printed; typesetting starts when the page is ready
MATHJAX_SCRIPTS = (
    "<script>window.MathJax = {tex: {packages: {'[-]': ['noundefined']}, "
    "inlineMath: [['$', '$'], ['\\\\(', '\\\\)']], "
    "displayMath: [['$$', '$$'], ['\\\\[', '\\\\]']], processEscapes: true, processEnvironments: true, "
    "tags: 'ams'}, svg: {fontCache: 'global'}};</script>"
    f'<script id="MathJax-script" src="{MATHJAX}"></script>'
)

# nbconvert's lab template without anything from a CDN
SITE_TEMPLATE = """{%- extends 'index.html.j2' -%}
{%- block html_head_js_requirejs -%}{%- endblock html_head_js_requirejs -%}
{%- block jupyter_widgets -%}{%- endblock jupyter_widgets -%}
{%- block html_head_js_mathjax -%}{% raw %}""" + MATHJAX_SCRIPTS + """{% endraw %}{%- endblock html_head_js_mathjax -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
"""

# nbconvert's order of outputs without the widget view: an output that also has HTML shows it
DISPLAY_PRIORITY = ["application/javascript", "text/html", "text/markdown", "image/svg+xml",
                    "text/latex", "image/png", "image/jpeg", "text/plain"]

ERROR_COLLECTOR = (
    "<script>window.__jsErrors=[];window.addEventListener('error',function(e){"
    "window.__jsErrors.push(String(e.message));"
    "document.documentElement.setAttribute('data-js-errors',window.__jsErrors.join(' | '));});</script>"
)

STYLE = """<style>
.course-nav{font:14px/1.4 system-ui,sans-serif;padding:8px 16px;background:#f4f4f6;border-bottom:1px solid #ddd;
display:flex;gap:16px;position:sticky;top:0;z-index:100}
.course-nav a{text-decoration:none;color:#2456a4}
.anim-buttons .fa{font-style:normal;display:inline-block}
.fa-minus:before{content:"\\2212"}.fa-plus:before{content:"+"}.fa-pause:before{content:"\\275A\\275A"}
.fa-play:before{content:"\\25B6\\FE0E"}.fa-flip-horizontal{transform:scaleX(-1)}
.fa-step-forward:before{content:"\\25B6\\FE0E|"}.fa-step-backward:before{content:"|\\25C0\\FE0E"}
.fa-fast-forward:before{content:"\\25B6\\FE0E\\25B6\\FE0E|"}
.fa-fast-backward:before{content:"|\\25C0\\FE0E\\25C0\\FE0E"}
</style>"""

# Matplotlib's animation player takes its button icons from Font Awesome on a CDN; the site draws
# them with the characters of STYLE instead
FONT_AWESOME = re.compile(r"<link[^>]*font-awesome[^>]*>\s*")


def lecture_notebooks(folder="lectures"):
    """Lecture notebooks ``NN_*.ipynb`` of `folder`, in lecture order, then its appendices ``A1_*.ipynb``, ....

    Parameters
    ----------
    folder : str or Path
        The lectures folder.

    Returns
    -------
    list of Path
        The lectures sorted by file name, so by lecture number, then the
        appendices by their number; other notebooks are left out.

    Raises
    ------
    ValueError
        When `folder` does not exist.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"lectures folder {str(folder)!r} does not exist")
    return sorted(folder.glob("[0-9][0-9]_*.ipynb")) + sorted(folder.glob("A[0-9]_*.ipynb"))


def execute_notebook(path, timeout=600, kernel_name="python3"):
    """Run a notebook top to bottom in a fresh kernel (working directory: its folder).

    The kernel's environment has ``PARTICLES_EXPLORATIONS=static``: explorations
    (:class:`particles.explore.Exploration`) show their static player, which a
    static page can show, rather than a live widget.

    Parameters
    ----------
    path : str or Path
        The notebook file.
    timeout : float
        Seconds allowed per cell.
    kernel_name : str
        The Jupyter kernel to start.

    Returns
    -------
    nbformat.NotebookNode
        The notebook with its outputs. The file on disk is not changed.

    Raises
    ------
    nbclient.exceptions.CellExecutionError
        When a cell fails; the message names the cell and the error.
    """
    import nbclient

    path = Path(path)
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=timeout, kernel_name=kernel_name,
                                     resources={"metadata": {"path": str(path.parent)}})
    from ...explore import STATIC

    client.execute(env={**os.environ, STATIC: "static"})
    return nb


def notebook_summary(nb):
    """Title (first heading) and first sentence of prose of a notebook, for the site's index.

    Parameters
    ----------
    nb : nbformat.NotebookNode

    Returns
    -------
    title, summary : str
        ``"Untitled"`` and ``""`` when the notebook has no heading or prose.
    """
    title, summary = None, ""
    for cell in nb.cells:
        if cell.cell_type != "markdown":
            continue
        for line in cell.source.splitlines():
            line = line.strip()
            if title is None and line.startswith("#"):
                title = line.lstrip("#").strip()
            elif title is not None and line and not line.startswith(("#", "<", "|", "!", "$")):
                summary = re.split(r"(?<=[.!?])\s", line, maxsplit=1)[0]
                return title, summary
    return title or "Untitled", summary


def _nav(pages, k):
    links = ['<a href="index.html">&#8962; All lectures</a>']
    if k > 0:
        links.append(f'<a href="{pages[k - 1][0]}">&larr; {html.escape(pages[k - 1][1])}</a>')
    if k + 1 < len(pages):
        links.append(f'<a href="{pages[k + 1][0]}">{html.escape(pages[k + 1][1])} &rarr;</a>')
    return f'<nav class="course-nav">{" ".join(links)}</nav>'


def mathjax_source():
    """The folder of MathJax 3's browser files (``es5``) that the site copies.

    Returns
    -------
    Path
        Inside the installed ``mathjax`` package (distribution ``django-static-mathjax``,
        a dependency of this package).

    Raises
    ------
    ValueError
        When the package or the file :data:`MATHJAX` in it is missing.
    """
    try:
        folder = Path(str(resources.files("mathjax"))) / "static" / "mathjax" / "es5"
    except ModuleNotFoundError:
        folder = None
    if folder is None or not (folder / Path(MATHJAX).name).is_file():
        raise ValueError("the course site needs MathJax's files from the package django-static-mathjax "
                         "(pip install django-static-mathjax), which is not installed")
    return folder


def copy_mathjax(out):
    """Copy MathJax into ``out/mathjax``: the one bundle the pages load and what it loads lazily (also the review
    pages' math, :mod:`particles.course.results.review`)."""
    source = mathjax_source()

    def others(folder, names):  # the other bundles at the top level, which no page loads
        if Path(folder) != source:
            return []
        return [name for name in names if name.endswith(".js") and name != Path(MATHJAX).name]

    target = Path(out) / "mathjax"
    shutil.copytree(source, target, ignore=others, dirs_exist_ok=True)
    shutil.copy2(source.parent / "LICENSE", target / "LICENSE")


def _page(body_html, nav):
    """Insert the error collector (first thing in <head>), the style and the navigation bar."""
    body_html = re.sub(r"<head([^>]*)>", lambda m: f"<head{m.group(1)}>{ERROR_COLLECTOR}", body_html, count=1)
    body_html = body_html.replace("</head>", STYLE + "</head>", 1)
    body_html = FONT_AWESOME.sub("", body_html)
    body_html = re.sub(r"<body([^>]*)>", lambda m: f"<body{m.group(1)}>{nav}", body_html, count=1)
    return body_html.replace('href="../exercises/', 'href="exercises/')


def build_site(out="site", lectures="lectures", executed=None, timeout=600, log=print):
    """Execute the lectures and write the static site into `out`.

    Parameters
    ----------
    out : str or Path
        Output folder (created; existing pages are overwritten).
    lectures : str or Path
        Folder of ``NN_topic.ipynb`` lecture notebooks (and ``A1_topic.ipynb``
        appendices); ``../exercises`` next to it is copied to ``out/exercises``
        when it exists.
    executed : dict, optional
        Already executed notebooks by path name, to skip running them again.
    timeout : float
        Seconds allowed per cell.

    Returns
    -------
    list of Path
        The pages written, index first; MathJax is copied to ``out/mathjax``.

    Raises
    ------
    ValueError
        When there is no lecture, or MathJax's files are missing (checked
        before anything is executed).
    """
    from jinja2 import DictLoader
    from nbconvert import HTMLExporter
    from traitlets.config import Config

    paths = lecture_notebooks(lectures)
    if not paths:
        raise ValueError(f"no lecture notebooks NN_topic.ipynb in {str(lectures)!r}")
    mathjax_source()  # before minutes of executing: fail now if MathJax is missing
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    executed = dict(executed or {})
    exporter = HTMLExporter(template_name="lab", template_file="site.html.j2",
                            extra_loaders=[DictLoader({"site.html.j2": SITE_TEMPLATE})],
                            config=Config({"NbConvertBase": {"display_data_priority": DISPLAY_PRIORITY}}))
    notebooks, pages = [], []
    for path in paths:
        start = time.perf_counter()
        nb = executed.get(path.name) or execute_notebook(path, timeout)
        log(f"executed {path.name} in {time.perf_counter() - start:.1f} s")
        title, summary = notebook_summary(nb)
        notebooks.append(nb)
        pages.append((path.with_suffix(".html").name, title, summary))
    written = [out / "index.html"]
    copy_mathjax(out)
    for k, nb in enumerate(notebooks):
        if "widgets" in nb.metadata:  # a widget's saved state: no use without a kernel
            nb = copy.deepcopy(nb)
            del nb.metadata["widgets"]
        body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": pages[k][1]}})
        target = out / pages[k][0]
        target.write_text(_page(body, _nav(pages, k)), encoding="utf-8")
        written.append(target)
    def items(chosen):
        return "\n".join(f'<li><a href="{name}">{html.escape(title)}</a><br><span>{html.escape(summary)}</span></li>'
                         for name, title, summary in chosen)

    appendices = [page for page in pages if page[0].startswith("A")]
    listed = f"<ol>{items([page for page in pages if page not in appendices])}</ol>"
    if appendices:
        listed += f"<h2>Appendices</h2><ul>{items(appendices)}</ul>"
    index = (f"<!DOCTYPE html><html><head>{ERROR_COLLECTOR}<meta charset='utf-8'>"
             f"<title>Particle systems and mass-spring models</title>{STYLE}{MATHJAX_SCRIPTS}"
             "<style>body{font:16px/1.5 system-ui,sans-serif;max-width:52em;margin:2em auto;padding:0 1em}"
             "li{margin:0.8em 0}span{color:#555}</style></head><body>"
             "<h1>Particle systems and mass-spring models</h1>"
             f"<p>Executable lecture notes, in teaching order.</p>{listed}</body></html>")
    (out / "index.html").write_text(index, encoding="utf-8")
    exercises = Path(lectures).parent / "exercises"
    if exercises.is_dir():
        shutil.copytree(exercises, out / "exercises", dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns(".ipynb_checkpoints"))
    log(f"wrote {len(written)} pages to {out}/")
    return written
