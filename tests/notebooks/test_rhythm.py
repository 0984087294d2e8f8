"""The notebook rhythm of CFDPython (STYLE.md, point 10; DESIGN.md, "Notebooks"), read from files.

For every lecture (``lectures/NN_*.ipynb``), appendix (``lectures/A1_*.ipynb``, ...) and master
(``solutions/*.ipynb``):

* **headers**: each section header opens its own markdown cell, so that the
  comment on a result and the next section are separate cells (the solution
  markers ``### BEGIN SOLUTION`` / ``### END SOLUTION`` of
  ``particles.course.release.notebooks`` look like headers but are not);
* **cell length**: a code cell has at most 12 lines;
* **line length**: a code line has at most 100 characters;
* **axis cosmetics**: labels, titles, grids and legends live in one small
  helper near the top of the notebook, not in every figure's cell (the rule is
  spelled out in ``test_axis_cosmetics_live_in_one_helper``).

The notebooks that do not follow a rule yet are listed in ``PENDING`` as
(rule, notebook) pairs; their tests are strict xfails, so a notebook that
comes to follow the rule makes its test fail until its entry is removed.
"""

import ast
import re
from pathlib import Path

import nbformat
import pytest
from IPython.core.inputtransformer2 import TransformerManager

from particles.course.release.notebooks import BEGIN, END

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = (sorted((ROOT / "lectures").glob("[0-9][0-9]_*.ipynb"))
             + sorted((ROOT / "lectures").glob("A[0-9]_*.ipynb"))
             + sorted((ROOT / "solutions").glob("*.ipynb")))
NAMES = [p.relative_to(ROOT).as_posix() for p in NOTEBOOKS]

MAX_CELL_LINES = 12     # lines of a code cell
MAX_LINE = 100          # characters of a code line
MAX_STYLED_CELLS = 3    # code cells that may style axes without the helper
HELPER_CELLS = 3        # the helper is defined in one of the first code cells

RULES = ("headers", "cell-length", "line-length", "axis-cosmetics")

# (rule, notebook) pairs known not to hold yet: strict xfails, to be removed when fixed
PENDING = {
}

HEADER = re.compile(r"^ {0,3}#{1,6}[ \t]")
FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
MARKERS = {BEGIN, END}  # lines `particles release` strips (it compares the stripped line)
AXIS_METHODS = {"set_xlabel", "set_ylabel", "set_title", "grid", "legend"}
LABELS = {"xlabel", "ylabel", "title"}  # keywords of Axes.set; pyplot's plt.xlabel, ...


def cases(rule):
    """The notebooks as parameters of `rule`'s test, the pending ones marked as strict xfails."""
    pending = pytest.mark.xfail(strict=True,
                                reason=f"listed in PENDING: does not follow the {rule} rule yet")
    return [pytest.param(path, id=name, marks=[pending] if (rule, name) in PENDING else [])
            for path, name in zip(NOTEBOOKS, NAMES)]


def cells(path, kind):
    """(index, cell) of the cells of `kind` of the notebook at `path`."""
    nb = nbformat.read(path, as_version=4)
    return [(k, cell) for k, cell in enumerate(nb.cells) if cell.cell_type == kind]


def headers_inside(source):
    """Header lines of a markdown source other than its first non-blank line.

    Fenced code and the solution markers (``MARKERS``) are skipped.
    """
    lines = source.splitlines()
    first = next((k for k, line in enumerate(lines)
                  if line.strip() and line.strip() not in MARKERS), None)
    fence, inside = None, []
    for k, line in enumerate(lines):
        opening = FENCE.match(line)
        if fence is None and opening:
            fence = opening.group(1)[0] * 3
        elif fence is not None:
            fence = None if line.strip().startswith(fence) else fence
        elif HEADER.match(line) and k != first and line.strip() not in MARKERS:
            inside.append(line.strip())
    return inside


def test_pending_names_existing_notebooks_and_rules():
    """Every PENDING entry names a rule of this module and a notebook that exists."""
    assert {rule for rule, _ in PENDING} <= set(RULES)
    assert {name for _, name in PENDING} <= set(NAMES)


def test_solution_markers_are_not_headers():
    """The solution markers of a markdown answer are skipped; a real header after them is not."""
    answer = f"**Question.** Why?\n\n{BEGIN}\nBecause.\n\n{END}\n"
    assert headers_inside(answer) == []
    assert headers_inside(answer + "\n## 2. Next section\n") == ["## 2. Next section"]
    assert headers_inside(f"Text\n    {BEGIN}\n") == []          # indented: no header anyway


@pytest.mark.parametrize("path", cases("headers"))
def test_each_header_opens_its_own_markdown_cell(path):
    """A markdown header (# to ###### and a space, outside fenced code) opens its cell."""
    bad = [(k, cell.get("id"), line) for k, cell in cells(path, "markdown")
           for line in headers_inside(cell.source)]
    assert bad == [], f"{path.name}: headers in the middle of a cell (cell, id, header): {bad}"


@pytest.mark.parametrize("path", cases("cell-length"))
def test_code_cells_have_at_most_12_lines(path):
    """A code cell has at most 12 lines (a trailing newline does not count)."""
    long = [(k, cell.get("id"), len(cell.source.splitlines())) for k, cell in cells(path, "code")
            if len(cell.source.splitlines()) > MAX_CELL_LINES]
    assert long == [], (f"{path.name}: code cells over {MAX_CELL_LINES} lines "
                        f"(cell, id, lines): {long}")


@pytest.mark.parametrize("path", cases("line-length"))
def test_code_lines_have_at_most_100_characters(path):
    """No line of a code cell is longer than 100 characters."""
    long = [(k, cell.get("id"), len(line)) for k, cell in cells(path, "code")
            for line in cell.source.splitlines() if len(line) > MAX_LINE]
    assert long == [], (f"{path.name}: code lines over {MAX_LINE} characters "
                        f"(cell, id, length): {long}")


def is_cosmetic(node):
    """Whether `node` is a call that styles axes: labels, title, grid or legend."""
    if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
        return False
    name = node.func.attr
    owner = node.func.value
    if isinstance(owner, ast.Name) and owner.id[:1].isupper():  # a class's constructor: TriangleMesh.grid(...)
        return False
    if name in AXIS_METHODS:
        return True
    if name == "set":                                   # ax.set(xlabel=..., ...)
        return any(keyword.arg in LABELS for keyword in node.keywords)
    return name in LABELS and isinstance(node.func.value, ast.Name) and node.func.value.id == "plt"


def calls(tree):
    """Names of the plain function calls `f(...)` in `tree`."""
    return {node.func.id for node in ast.walk(tree)
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)}


def styling(path):
    """The axis styling of a notebook: (helpers, cells calling them, cells styling axes otherwise).

    Helpers are the top-level functions defined in the first ``HELPER_CELLS``
    code cells whose body makes a cosmetic call. A cell *styles axes
    otherwise* when, outside the helpers' own definitions, it makes a
    cosmetic call or calls another function of the notebook that styles axes
    (directly or through further functions of the notebook).
    """
    transform = TransformerManager().transform_cell    # IPython's: magics become Python
    code = cells(path, "code")
    trees = [ast.parse(transform(cell.source)) for _, cell in code]
    functions = {}                                      # name -> (code cell, last definition)
    for position, tree in enumerate(trees):
        for node in tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                functions[node.name] = (position, node)
    styled = {name for name, (_, node) in functions.items()
              if any(map(is_cosmetic, ast.walk(node)))}
    helpers = {name for name in styled if functions[name][0] < HELPER_CELLS}
    styles, grown = styled - helpers, True
    while grown:                                        # calling a styling function styles too
        more = {name for name, (_, node) in functions.items()
                if name not in helpers | styles and calls(node) & styles}
        styles, grown = styles | more, bool(more)
    definitions = {id(functions[name][1]) for name in helpers}
    using, other = [], []
    for (k, cell), tree in zip(code, trees):
        rest = ast.Module([node for node in tree.body if id(node) not in definitions], [])
        if any(map(is_cosmetic, ast.walk(rest))) or calls(rest) & styles:
            other.append((k, cell.get("id")))
        if calls(rest) & helpers:
            using.append((k, cell.get("id")))
    return helpers, using, other


@pytest.mark.parametrize("path", cases("axis-cosmetics"))
def test_axis_cosmetics_live_in_one_helper(path):
    """At most 3 code cells style axes themselves; more styling goes through a helper near the top.

    Styling axes means calling ``.set_xlabel``, ``.set_ylabel``, ``.set_title``,
    ``.grid``, ``.legend``, ``.set`` with an ``xlabel``, ``ylabel`` or ``title``
    keyword, or ``plt.xlabel``/``plt.ylabel``/``plt.title``; a cell also styles
    axes when it calls a function of the notebook that does. A helper is a
    top-level function defined in one of the first three code cells whose
    body styles axes (e.g. ``def style(ax, ...)``); its own definition and the
    cells that call it do not count. So a notebook with at most three styled
    figures needs no helper, any other routes its cosmetics through the
    helper, and a helper that is defined is called by some cell.
    """
    helpers, using, other = styling(path)
    assert len(other) <= MAX_STYLED_CELLS, (
        f"{path.name}: {len(other)} code cells style axes without a helper defined in the first "
        f"{HELPER_CELLS} code cells (cell, id): {other}; at most {MAX_STYLED_CELLS} may")
    assert not helpers or using, f"{path.name}: the helper {sorted(helpers)} is never called"


def test_cosmetics_are_calls_on_axes_not_on_classes():
    """ax.grid(...) and plt.xlabel(...) style axes; TriangleMesh.grid(...) builds a mesh and does not."""
    styled = [is_cosmetic(ast.parse(code).body[0].value) for code in
              ("ax.grid(True)", "plt.xlabel('t')", "ax.set(title='x')", "TriangleMesh.grid(8, 8)", "np.sqrt(2)")]
    assert styled == [True, True, True, False, False]
