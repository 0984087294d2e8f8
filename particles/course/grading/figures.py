"""Figures in the feedback: the student's curve beside the reference's.

A test attaches the *data* of a figure to its record through the ``feedback``
fixture of :mod:`particles.course.grading.plugin` (a :class:`Feedback`)::

    @pytest.mark.points(1)
    def test_errors(student, feedback):
        '''convergence_errors matches the reference's global errors.'''
        h, errors = student.call("convergence_errors", ...)
        feedback.curve("Global error of your Euler steps", "step h (s)", "error at t1",
                       [{"label": "yours", "x": h, "y": errors},
                        {"label": "reference", "x": h, "y": expected}], loglog=True)
        expect_array(errors, expected, "convergence_errors(...)")

Attach before the check that may fail: a failing test is where the figure
helps most. The pytest session only records plain JSON (:func:`curve_spec`:
lists of floats, ``None`` for a value that is not finite, at most
:data:`MAX_POINTS` points per series), so a record stays small and a
student's odd return value (a string, a 2-D array, NaN) never breaks the test.
Hidden tests must keep their random parameters out of the title, the labels
and the caption (plot relative quantities, e.g. ``h / h0``, if the values
themselves would tell).

The driver draws the figures when it writes ``feedback.html`` and
Gradescope's ``results.json`` (:func:`png`, :func:`figure_html`), with
Matplotlib's Agg backend and no pyplot state; ``particles.check`` draws them
in the notebook. :func:`load` imports everything drawing needs, so that the
driver has loaded its code before the first worker starts.
"""

import base64
import hashlib
import html
import json
import math
import textwrap
import threading
from collections import OrderedDict
from io import BytesIO

import numpy as np

__all__ = ["Feedback", "curve_spec", "load", "png", "data_uri", "figure_html", "clear_cache", "MAX_POINTS",
           "MAX_SERIES", "MAX_FIGURES"]

MAX_POINTS = 300
"""Points kept per series (evenly spaced, the first and the last included)."""
MAX_SERIES = 8
"""Series per figure."""
MAX_FIGURES = 6
"""Figures per test; further ones are dropped."""
_MAX_TEXT = 160
_ROLES = ("yours", "reference")
_COLORS = ("#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000", "#999999")
_YOURS, _REFERENCE = "#d55e00", "#333333"


def _text(value, what):
    if not isinstance(value, str):
        raise TypeError(f"the {what} of a feedback figure must be a str, got {type(value).__name__}")
    value = " ".join(value.split())
    return value if len(value) <= _MAX_TEXT else value[:_MAX_TEXT - 1] + "…"


def _numbers(values):
    """`values` as a 1-D float array, or None when they are not a sequence of real numbers."""
    if values is None or isinstance(values, (str, bytes, dict)):
        return None
    try:
        array = np.asarray(values)
        if array.dtype.kind not in "biuf":
            array = array.astype(float)
        array = array.astype(float)
    except (TypeError, ValueError, OverflowError):
        return None
    if array.ndim == 0:
        array = array.reshape(1)
    return array if array.ndim == 1 else None


def _plain(array):
    """JSON numbers: 6 significant digits, None where the value is not finite."""
    return [float(f"{v:.6g}") if math.isfinite(v) else None for v in array.tolist()]


def _series(entry, k):
    if not isinstance(entry, dict) or "y" not in entry:
        raise TypeError(f"series {k} of a feedback figure must be a dict with 'label', 'y' and optionally 'x'")
    label = _text(entry.get("label", f"series {k + 1}"), "label of a series")
    role = entry.get("role") or ("reference" if label.split(" ")[0].lower() in ("reference", "theory", "expected")
                                 else "yours")
    if role not in _ROLES:
        raise ValueError(f"the role of a series must be one of {_ROLES}, got {role!r}")
    out = {"label": label, "role": role, "x": [], "y": []}
    if entry.get("group") is not None:
        out["group"] = _text(str(entry["group"]), "group of a series")
    y = _numbers(entry["y"])
    x = np.arange(len(y), dtype=float) if y is not None and entry.get("x") is None else _numbers(entry.get("x"))
    if y is None or x is None:
        out["problem"] = "not a sequence of numbers"
        return out
    n = min(len(x), len(y))
    if len(x) != len(y):
        out["problem"] = f"{len(y)} values for {len(x)} points"
    if n > MAX_POINTS:
        keep = np.unique(np.linspace(0, n - 1, MAX_POINTS).round().astype(int))
        x, y = x[keep], y[keep]
    else:
        x, y = x[:n], y[:n]
    out["x"], out["y"] = _plain(x), _plain(y)
    return out


def curve_spec(title, xlabel, ylabel, series, loglog=False, logx=False, logy=False, caption=""):
    """The JSON record of a figure of curves (see :meth:`Feedback.curve` for the parameters).

    Returns
    -------
    dict
        ``kind`` ("curve"), ``title``, ``xlabel``, ``ylabel``, ``xscale`` and
        ``yscale`` ("linear" or "log"), ``caption`` and ``series``: each
        ``label``, ``role`` ("yours" or "reference"), ``x``, ``y`` (lists of
        floats or None), optionally ``group`` (series of one group share a
        colour) and ``problem`` (why values of the series could not be kept).

    Raises
    ------
    TypeError, ValueError
        On a mistake of the test's author: a title or label that is not a
        str, a series that is not a dict with ``y``, an unknown role, no
        series or too many. A student's value that is not a sequence of
        numbers is never an error: its series is kept empty, with a problem.
    """
    if isinstance(series, dict) or not isinstance(series, (list, tuple)) or not series:
        raise TypeError("series of a feedback figure must be a non-empty list of dicts")
    if len(series) > MAX_SERIES:
        raise ValueError(f"a feedback figure holds at most {MAX_SERIES} series, got {len(series)}")
    return {
        "kind": "curve", "title": _text(title, "title"), "xlabel": _text(xlabel, "x label"),
        "ylabel": _text(ylabel, "y label"), "xscale": "log" if loglog or logx else "linear",
        "yscale": "log" if loglog or logy else "linear", "caption": _text(caption, "caption"),
        "series": [_series(entry, k) for k, entry in enumerate(series)],
    }


class Feedback:
    """The figures a test attaches to its record (the ``feedback`` fixture).

    Parameters
    ----------
    hidden : bool
        Whether the test is hidden: its figures must not show its random
        parameters in their texts.

    Attributes
    ----------
    figures : list of dict
        The records made so far (:func:`curve_spec`), at most :data:`MAX_FIGURES`.
    """

    def __init__(self, hidden=False):
        self.hidden = bool(hidden)
        self.figures = []

    def curve(self, title, xlabel, ylabel, series, loglog=False, logx=False, logy=False, caption=""):
        """Attach a figure of curves: the student's beside the reference's.

        Parameters
        ----------
        title, xlabel, ylabel : str
            Texts of the figure (one line each; no hidden parameters in them).
        series : list of dict
            Each ``{"label": "yours", "x": [...], "y": [...]}``; ``x`` may be
            left out (then 0, 1, 2, ...), ``role`` is ``"yours"`` (solid,
            with markers) or ``"reference"`` (dashed; the default when the
            label starts with "reference", "theory" or "expected"), and
            series with the same ``group`` share a colour.
        loglog, logx, logy : bool
            Logarithmic axes (values <= 0 are left out of the drawing).
        caption : str
            A sentence under the figure.

        Returns
        -------
        dict or None
            The record, or None when the test already has :data:`MAX_FIGURES`.
        """
        spec = curve_spec(title, xlabel, ylabel, series, loglog=loglog, logx=logx, logy=logy, caption=caption)
        if len(self.figures) >= MAX_FIGURES:
            return None
        self.figures.append(spec)
        return spec


# -- drawing (in the driver and in particles.check) ---------------------------------------------

_lock = threading.Lock()
_cache = OrderedDict()  # digest of a record -> base64 PNG
_CACHE_SIZE = 2048
_backend = None


def load():
    """Import Matplotlib's Agg canvas and everything a drawing uses (the classes it draws with).

    The grading driver calls it when :mod:`particles.course.results.reports` is
    imported, before its first worker starts, so that drawing a figure later
    loads no new code.
    """
    global _backend
    if _backend is None:  # the canvas is used directly: pyplot's backend (a notebook's inline one) is left alone
        import matplotlib.legend  # noqa: F401  (imported by axes on demand in some versions)
        import matplotlib.scale  # noqa: F401
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator
        from PIL import Image

        Image.preinit()  # the PNG plugin, which saving would otherwise import at the first figure
        _backend = (Figure, FigureCanvasAgg, FuncFormatter, LogLocator, NullLocator, Image)
    return _backend


def _drawable(values, log):
    array = np.array([np.nan if v is None else v for v in values], dtype=float)
    if log:
        array[array <= 0] = np.nan
    return array


def _draw(spec):
    Figure, FigureCanvasAgg, FuncFormatter, LogLocator, NullLocator, Image = load()
    figure = Figure(figsize=(5.2, 3.4), dpi=80)
    FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    groups = {}
    for s in spec.get("series", []):
        if s.get("group") is not None:
            groups.setdefault(s["group"], _COLORS[len(groups) % len(_COLORS)])
    xlog, ylog = spec.get("xscale") == "log", spec.get("yscale") == "log"
    drawn, xs, ys = 0, [], []
    for s in spec.get("series", []):
        x, y = _drawable(s.get("x", []), xlog), _drawable(s.get("y", []), ylog)
        n = min(len(x), len(y))
        x, y = x[:n], y[:n]
        xs.append(x[np.isfinite(y)])
        ys.append(y[np.isfinite(x)])
        label = str(s.get("label", "")).replace("$", r"\$")
        visible = np.isfinite(x) & np.isfinite(y)
        if not visible.any():
            label += " (nothing to draw)"
        reference = s.get("role") == "reference"
        color = groups.get(s.get("group"), _REFERENCE if reference else _YOURS)
        if reference:
            ax.plot(x, y, "--", color=color, lw=1.4, label=label, zorder=4)  # on top: visible where yours agrees
        else:
            ax.plot(x, y, "o-", color=color, lw=1.3, ms=4, label=label, zorder=3)
        drawn += int(visible.sum())
    for log, axis, scale, values in ((xlog, ax.xaxis, ax.set_xscale, xs), (ylog, ax.yaxis, ax.set_yscale, ys)):
        if log and drawn:  # plain "0.02" labels at 1, 2, 5 x 10^k: no mathtext, no crowded minor ticks
            scale("log")
            values = np.concatenate(values)
            decades = np.log10(np.nanmax(values) / np.nanmin(values)) if np.isfinite(values).any() else 0.0
            axis.set_major_locator(LogLocator(base=10.0, subs=(1.0,) if decades > 3 else (1.0, 2.0, 5.0), numticks=8))
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_locator(NullLocator())
    title = "\n".join(textwrap.wrap(str(spec.get("title", "")).replace("$", r"\$"), 62)[:2])
    ax.set_title(title, fontsize=9.5)
    ax.set_xlabel(str(spec.get("xlabel", "")).replace("$", r"\$"), fontsize=8.5)
    ax.set_ylabel(str(spec.get("ylabel", "")).replace("$", r"\$"), fontsize=8.5)
    ax.tick_params(labelsize=7.5)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7.5, loc="best", framealpha=0.85)
    figure.subplots_adjust(left=0.15, right=0.97, bottom=0.14, top=0.86 if "\n" in title else 0.91)
    figure.canvas.draw()
    # a 64-colour palette keeps the antialiased lines and makes the PNG about a third of its RGBA size
    image = Image.fromarray(np.asarray(figure.canvas.buffer_rgba())).convert("RGB").quantize(colors=64)
    buffer = BytesIO()
    image.save(buffer, format="PNG", optimize=True)
    return buffer.getvalue()


def _digest(spec):
    return hashlib.sha256(json.dumps(spec, sort_keys=True, default=str).encode()).hexdigest()


def _base64(spec):
    key = _digest(spec)
    with _lock:
        if key in _cache:
            _cache.move_to_end(key)
            return _cache[key]
        try:
            text = base64.b64encode(_draw(spec)).decode("ascii")
        except Exception:  # a record the drawing cannot read: the text of the feedback still goes out
            text = None
        _cache[key] = text
        while len(_cache) > _CACHE_SIZE:
            _cache.popitem(last=False)
        return text


def clear_cache():
    """Forget every figure drawn so far in this process (they are kept by content, at most 2048).

    For a benchmark that grades the same submissions twice: with the cache, the second run draws nothing.
    """
    with _lock:
        _cache.clear()


def png(spec):
    """The figure of a record (see :func:`curve_spec`) as PNG bytes, or None when it cannot be drawn."""
    text = _base64(spec)
    return None if text is None else base64.b64decode(text)


def data_uri(spec):
    """``data:image/png;base64,...`` of a record's figure, or None when it cannot be drawn."""
    text = _base64(spec)
    return None if text is None else f"data:image/png;base64,{text}"


def _problems(spec):
    return [f"{s['label']}: {s['problem']}" for s in spec.get("series", []) if s.get("problem")]


def figure_html(spec, css=True):
    """An HTML fragment with the figure of a record inlined as a PNG and its caption.

    Parameters
    ----------
    spec : dict
        A record made by :func:`curve_spec`.
    css : bool
        Use the classes of ``feedback.html`` (True) or plain tags only, for
        places that strip styles (Gradescope's output).
    """
    uri = data_uri(spec)
    notes = [spec.get("caption", "")] + _problems(spec)
    caption = html.escape(" ".join(n for n in notes if n))
    alt = html.escape(f"figure: {spec.get('title', '')}", quote=True)
    if uri is None:
        image = f"<p>(the figure “{html.escape(str(spec.get('title', '')))}” could not be drawn)</p>"
    else:
        image = f'<img src="{uri}" alt="{alt}" width="416" height="272">'
    if not css:
        return f"<div>{image}" + (f"<br><small>{caption}</small>" if caption else "") + "</div>"
    return (f'<figure class="feedback-figure">{image}'
            + (f"<figcaption>{caption}</figcaption>" if caption else "") + "</figure>")
