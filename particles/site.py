"""The course site: lectures executed and rendered as static HTML (``particles site``).

``build_site`` executes every lecture notebook (``lectures/NN_topic.ipynb``)
in a fresh Jupyter kernel, converts it to a self-contained HTML page with
nbconvert (figures and animation players embedded), adds a navigation bar,
and writes an index in lecture order. The student notebooks linked from the
lectures (``../exercises/...``) are copied next to the pages, so the folder
can be published as it is.

Every page starts with a tiny script that records JavaScript errors in the
``data-js-errors`` attribute of the ``<html>`` element; a headless browser
(see ``tests/test_site.py``) reads it to check that the pages run cleanly.
"""

import html
import re
import shutil
import time
from pathlib import Path

import nbformat

__all__ = ["lecture_notebooks", "execute_notebook", "notebook_summary", "build_site"]

ERROR_COLLECTOR = (
    "<script>window.__jsErrors=[];window.addEventListener('error',function(e){"
    "window.__jsErrors.push(String(e.message));"
    "document.documentElement.setAttribute('data-js-errors',window.__jsErrors.join(' | '));});</script>"
)

STYLE = """<style>
.course-nav{font:14px/1.4 system-ui,sans-serif;padding:8px 16px;background:#f4f4f6;border-bottom:1px solid #ddd;
display:flex;gap:16px;position:sticky;top:0;z-index:100}
.course-nav a{text-decoration:none;color:#2456a4}
</style>"""


def lecture_notebooks(folder="lectures"):
    """Lecture notebooks ``NN_*.ipynb`` of `folder`, in lecture order.

    Parameters
    ----------
    folder : str or Path
        The lectures folder.

    Returns
    -------
    list of Path
        Sorted by file name, so by lecture number; other notebooks are left out.

    Raises
    ------
    ValueError
        When `folder` does not exist.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"lectures folder {str(folder)!r} does not exist")
    return sorted(p for p in folder.glob("[0-9][0-9]_*.ipynb"))


def execute_notebook(path, timeout=600, kernel_name="python3"):
    """Run a notebook top to bottom in a fresh kernel (working directory: its folder).

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
    client.execute()
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


def _page(body_html, nav):
    """Insert the error collector (first thing in <head>), the style and the navigation bar."""
    body_html = re.sub(r"<head([^>]*)>", lambda m: f"<head{m.group(1)}>{ERROR_COLLECTOR}", body_html, count=1)
    body_html = body_html.replace("</head>", STYLE + "</head>", 1)
    body_html = re.sub(r"<body([^>]*)>", lambda m: f"<body{m.group(1)}>{nav}", body_html, count=1)
    return body_html.replace('href="../exercises/', 'href="exercises/')


def build_site(out="site", lectures="lectures", executed=None, timeout=600, log=print):
    """Execute the lectures and write the static site into `out`.

    Parameters
    ----------
    out : str or Path
        Output folder (created; existing pages are overwritten).
    lectures : str or Path
        Folder of ``NN_topic.ipynb`` lecture notebooks; ``../exercises`` next to
        it is copied to ``out/exercises`` when it exists.
    executed : dict, optional
        Already executed notebooks by path name, to skip running them again.
    timeout : float
        Seconds allowed per cell.

    Returns
    -------
    list of Path
        The pages written, index first.
    """
    from nbconvert import HTMLExporter

    paths = lecture_notebooks(lectures)
    if not paths:
        raise ValueError(f"no lecture notebooks NN_topic.ipynb in {str(lectures)!r}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    executed = dict(executed or {})
    exporter = HTMLExporter(template_name="lab")
    notebooks, pages = [], []
    for path in paths:
        start = time.perf_counter()
        nb = executed.get(path.name) or execute_notebook(path, timeout)
        log(f"executed {path.name} in {time.perf_counter() - start:.1f} s")
        title, summary = notebook_summary(nb)
        notebooks.append(nb)
        pages.append((path.with_suffix(".html").name, title, summary))
    written = [out / "index.html"]
    for k, nb in enumerate(notebooks):
        body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": pages[k][1]}})
        target = out / pages[k][0]
        target.write_text(_page(body, _nav(pages, k)), encoding="utf-8")
        written.append(target)
    items = "\n".join(
        f'<li><a href="{name}">{html.escape(title)}</a><br><span>{html.escape(summary)}</span></li>'
        for name, title, summary in pages)
    index = (f"<!DOCTYPE html><html><head>{ERROR_COLLECTOR}<meta charset='utf-8'>"
             f"<title>Particle systems and mass-spring models</title>{STYLE}"
             "<style>body{font:16px/1.5 system-ui,sans-serif;max-width:52em;margin:2em auto;padding:0 1em}"
             "li{margin:0.8em 0}span{color:#555}</style></head><body>"
             "<h1>Particle systems and mass-spring models</h1>"
             f"<p>Executable lecture notes, in teaching order.</p><ol>{items}</ol></body></html>")
    (out / "index.html").write_text(index, encoding="utf-8")
    exercises = Path(lectures).parent / "exercises"
    if exercises.is_dir():
        shutil.copytree(exercises, out / "exercises", dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns(".ipynb_checkpoints"))
    log(f"wrote {len(written)} pages to {out}/")
    return written
