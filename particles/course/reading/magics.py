"""A notebook cell as the Python that Jupyter runs, line for line.

Jupyter does not run a cell's text as it is: IPython first turns its magics
into calls of the shell object, ``%%time`` cells into
``get_ipython().run_cell_magic('time', '', body)``, ``x = %timeit -o f()``
into ``x = get_ipython().run_line_magic('timeit', '-o f()')``, ``!pip ...``
into ``get_ipython().system('pip ...')``. :func:`to_python` applies IPython's
own transformer (:class:`IPython.core.inputtransformer2.TransformerManager`),
so that a cell parses exactly as in Jupyter, and pads the result with blank
lines where the transformer joined lines, so that a statement keeps the line
number it has in the notebook. Without IPython it blanks the lines that start
with ``%`` or ``!`` instead. :func:`magic_call` recognises the calls the
transformer made.
"""

import ast
import difflib

__all__ = ["to_python", "magic_call", "strip_magics", "transformer"]

_MANAGER = []  # [TransformerManager or None], made on first use


def transformer():
    """IPython's ``TransformerManager`` (one, reused), or None when IPython is not installed."""
    if not _MANAGER:
        try:
            from IPython.core.inputtransformer2 import TransformerManager
        except ImportError:
            _MANAGER.append(None)
        else:
            _MANAGER.append(TransformerManager())
    return _MANAGER[0]


def strip_magics(source):
    """Blank out IPython line magics and shell escapes, keeping line numbers (used without IPython)."""
    return "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in source.split("\n"))


def _aligned(original, python):
    """`python` (lines) padded with blank lines so that unchanged lines keep their number in `original`."""
    if python and python[-1] == "" and (not original or original[-1] != ""):
        python = python[:-1]  # the transformer ends every cell with a newline
    out = []
    matcher = difflib.SequenceMatcher(None, original, python, autojunk=False)
    for tag, i1, i2, j1, j2 in matcher.get_opcodes():
        block = python[j1:j2]
        if tag != "equal" and len(block) < i2 - i1:  # lines joined (a magic continued with \) or removed
            block = block + [""] * (i2 - i1 - len(block))
        out.extend(block)
    return out


def to_python(source, manager=None):
    """The Python that Jupyter runs for cell `source`, with the cell's line numbers.

    Parameters
    ----------
    source : str
        The cell's text.
    manager : TransformerManager, optional
        Default: :func:`transformer`; when IPython is missing, magics are
        blanked out (:func:`strip_magics`).

    Returns
    -------
    str
        Python source, with as many lines as `source` wherever the transformer
        allows (a ``%%`` cell magic becomes one line).

    Examples
    --------
    >>> to_python("%matplotlib inline\\nx = %timeit -o f()").splitlines()
    ["get_ipython().run_line_magic('matplotlib', 'inline')", "x = get_ipython().run_line_magic('timeit', '-o f()')"]
    """
    manager = manager or transformer()
    if manager is None:
        return strip_magics(source)
    try:
        ast.parse(source)
        return source  # plain Python: IPython's transforms (magics, !, ?, prompts) leave it as it is
    except (SyntaxError, ValueError):
        pass
    try:
        python = manager.transform_cell(source)
    except Exception:  # the transformer tokenizes: text it cannot read is left for ast.parse to report
        return strip_magics(source)
    return "\n".join(_aligned(source.split("\n"), python.split("\n")))


def _text(node):
    return node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else None


def magic_call(node):
    """``(method, name, line, body)`` when `node` is a call ``get_ipython().method(...)`` with string arguments.

    ``method`` is ``"run_cell_magic"`` (name, line, body), ``"run_line_magic"``
    (name, line, None), ``"system"`` or ``"getoutput"`` (None, command, None);
    None when `node` is something else.
    """
    if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
        return None
    owner = node.func.value
    if not (isinstance(owner, ast.Call) and isinstance(owner.func, ast.Name) and owner.func.id == "get_ipython"
            and not owner.args and not owner.keywords):
        return None
    args = [_text(a) for a in node.args]
    method = node.func.attr
    if method == "run_cell_magic" and len(args) == 3 and None not in args:
        return method, args[0], args[1], args[2]
    if method == "run_line_magic" and len(args) == 2 and None not in args:
        return method, args[0], args[1], None
    if method in ("system", "getoutput") and len(args) == 1 and args[0] is not None:
        return method, None, args[0], None
    return None
