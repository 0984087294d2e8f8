"""Colours of particles: colour ramps by age, tints, palettes, without Matplotlib.

Effects colour their particles by age (:class:`ColorRamp`), emitters tint
them (a colour, a random hue or the parent's), and the demos give each ball
or boid its own colour. All of it is arithmetic on RGB triples, so the
physics modules (:mod:`particles.effects`, :mod:`particles.effects.emitters`) never
load Matplotlib: a :class:`particles.effects.ParticleEffect` can be built and
run where Matplotlib is not installed. :func:`to_rgb` reads the colours a
student writes (hex strings, grey levels, RGB tuples and the basic names)
itself, and asks Matplotlib, imported only then, about the other names
(``"tab:blue"``, ``"xkcd:sky blue"``). The values are Matplotlib's, to the
last bit (``tests/library/effects/test_colours.py``).
"""

import numpy as np

from .._checks import as_float_array, positive_number

__all__ = ["to_rgb", "hsv_to_rgb", "palette", "ColorRamp", "TAB10"]

BASIC = {
    "white": (1.0, 1.0, 1.0), "w": (1.0, 1.0, 1.0),
    "black": (0.0, 0.0, 0.0), "k": (0.0, 0.0, 0.0),
    "red": (1.0, 0.0, 0.0), "r": (1.0, 0.0, 0.0),
    "green": (0.0, 128 / 255, 0.0), "g": (0.0, 0.5, 0.0),
    "blue": (0.0, 0.0, 1.0), "b": (0.0, 0.0, 1.0),
    "yellow": (1.0, 1.0, 0.0), "y": (0.75, 0.75, 0.0),
    "cyan": (0.0, 1.0, 1.0), "c": (0.0, 0.75, 0.75),
    "magenta": (1.0, 0.0, 1.0), "m": (0.75, 0.0, 0.75),
    "orange": (1.0, 165 / 255, 0.0),
    "gray": (128 / 255, 128 / 255, 128 / 255), "grey": (128 / 255, 128 / 255, 128 / 255),
}
"""The colour names read without Matplotlib, with Matplotlib's values (CSS names, one-letter codes)."""

TAB10 = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
         "#17becf")
"""Matplotlib's default colour cycle ("tab10"), as hex strings."""


def to_rgb(color):
    """An RGB triple in [0, 1] from a colour as Matplotlib writes it.

    Parameters
    ----------
    color : str or sequence of float
        A hex string (``"#5aa9e6"``, ``"#fff"``, with or without alpha), a grey
        level (``"0.25"``), a basic name (:data:`BASIC`), an RGB or RGBA
        sequence in [0, 1], or any other Matplotlib colour name (then
        Matplotlib is imported to read it).

    Returns
    -------
    tuple of float
        ``(r, g, b)``, each in [0, 1] (alpha is dropped).

    Raises
    ------
    ValueError
        When `color` is not a colour (or is a name only Matplotlib knows, and
        Matplotlib is not installed).

    Examples
    --------
    >>> to_rgb("#ff8000"), to_rgb("0.5"), to_rgb("white")
    ((1.0, 0.5019607843137255, 0.0), (0.5, 0.5, 0.5), (1.0, 1.0, 1.0))
    """
    if isinstance(color, str):
        key = color.strip().lower()
        if key in BASIC:
            return BASIC[key]
        if key.startswith("#") and len(key) in (4, 5, 7, 9):
            digits = key[1:] if len(key) > 5 else "".join(2 * c for c in key[1:])
            try:
                return tuple(int(digits[k:k + 2], 16) / 255 for k in (0, 2, 4))
            except ValueError:
                raise ValueError(f"invalid hex colour {color!r}") from None
        try:
            grey = float(key)
        except ValueError:
            return _named(color)
        if not 0.0 <= grey <= 1.0:
            raise ValueError(f"a grey level must lie in [0, 1], got {color!r}")
        return (grey, grey, grey)
    try:
        rgb = np.asarray(color, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"invalid colour {color!r}") from None
    if rgb.shape not in ((3,), (4,)) or np.any((rgb < 0) | (rgb > 1)) or not np.all(np.isfinite(rgb)):
        raise ValueError(f"an RGB(A) colour needs 3 or 4 numbers in [0, 1], got {color!r}")
    return tuple(float(c) for c in rgb[:3])


def _named(color):
    """A colour name beyond :data:`BASIC`, read by Matplotlib (imported here, when one is used)."""
    try:
        from matplotlib.colors import to_rgb as matplotlib_to_rgb
    except ImportError:
        raise ValueError(f"the colour {color!r} is not one this module reads itself (hex strings, grey levels, "
                         f"RGB tuples, {', '.join(sorted(BASIC))}); other names need Matplotlib") from None
    return matplotlib_to_rgb(color)


def hsv_to_rgb(hsv):
    """RGB colours from hue, saturation and value, all in [0, 1] (Matplotlib's ``hsv_to_rgb``).

    Parameters
    ----------
    hsv : array_like, shape (n, 3)

    Returns
    -------
    ndarray, shape (n, 3)

    Examples
    --------
    >>> hsv_to_rgb([[0.0, 1.0, 1.0], [1 / 3, 1.0, 1.0]]).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    hsv = as_float_array(hsv, "hsv", shape=(None, 3))
    h, s, v = hsv[:, 0], hsv[:, 1], hsv[:, 2]
    i = (h * 6.0).astype(int)
    f = h * 6.0 - i
    p, q, t = v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f))
    sector = i % 6
    choices = [(v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q)]  # by sector of the hue
    rgb = np.empty_like(hsv)
    for c in range(3):  # a loop over the colour channels
        rgb[:, c] = np.select([sector == k for k in range(6)], [choice[c] for choice in choices])
        rgb[s == 0, c] = v[s == 0]
    return rgb


def palette(n):
    """`n` distinct colours from Matplotlib's default cycle (:data:`TAB10`, repeated), shape (n, 3)."""
    colours = np.array([to_rgb(c) for c in TAB10])
    return colours[np.arange(n) % len(colours)]


class ColorRamp:
    """Colour and transparency as functions of age, by linear interpolation between stops.

    Parameters
    ----------
    colors : sequence of colors
        Colours (names, hex strings, grey levels, RGB tuples; see
        :func:`to_rgb`) spread evenly over the relative age
        ``a = age / lifetime`` from 0 to 1.
    alphas : sequence of float
        Opacities in [0, 1], spread evenly over ``a`` the same way
        (default: from opaque to fully transparent, old particles fade).
    duration : float, optional
        Measure age in units of `duration` seconds instead of each
        particle's lifetime (for particles that live forever).

    Examples
    --------
    >>> ramp = ColorRamp(["white", "red"], alphas=[1.0, 0.0])
    >>> ramp(np.array([0.0, 0.5, 1.0])).tolist()
    [[1.0, 1.0, 1.0, 1.0], [1.0, 0.5, 0.5, 0.5], [1.0, 0.0, 0.0, 0.0]]
    """

    def __init__(self, colors=("white",), alphas=(1.0, 0.0), duration=None):
        try:
            self.colors = np.array([to_rgb(c) for c in colors])
        except (ValueError, TypeError):
            raise ValueError(f"colors must be a list of Matplotlib colours, got {colors!r}") from None
        self.alphas = as_float_array(alphas, "alphas", ndim=1)
        if len(self.colors) == 0 or len(self.alphas) == 0:
            raise ValueError("colors and alphas need at least one stop each")
        if np.any((self.alphas < 0) | (self.alphas > 1)):
            raise ValueError(f"alphas must lie in [0, 1], got {self.alphas.tolist()}")
        self.duration = None if duration is None else positive_number(duration, "duration", "seconds")

    def __call__(self, a):
        """RGBA, shape (n, 4), for relative ages `a` (shape (n,), clipped to [0, 1])."""
        a = np.clip(np.asarray(a, dtype=float), 0.0, 1.0)
        rgba = np.empty((len(a), 4))
        stops = np.linspace(0.0, 1.0, len(self.colors))
        for c in range(3):  # a loop over the colour channels
            rgba[:, c] = np.interp(a, stops, self.colors[:, c])
        rgba[:, 3] = np.interp(a, np.linspace(0.0, 1.0, len(self.alphas)), self.alphas)
        return rgba

    def relative(self, age, lifetime):
        """Relative ages in [0, 1] from ages and lifetimes in seconds (shape (n,) each)."""
        span = np.broadcast_to(lifetime if self.duration is None else self.duration, np.shape(age))
        a = np.divide(age, span, out=np.zeros(len(age)), where=np.isfinite(span) & (span > 0))
        return np.clip(a, 0.0, 1.0)

    def of(self, age, lifetime):
        """RGBA for ages and lifetimes in seconds (shape (n,) each)."""
        return self(self.relative(age, lifetime))
