"""What a demo returns, and the small helpers the demo modules share (scenery, frame steps)."""

from dataclasses import dataclass, field

import numpy as np

from .._checks import positive_number

__all__ = ["DemoData", "Demo", "circle", "steps_per_frame"]


@dataclass
class DemoData:
    """What a demo computed: enough to draw every frame, and nothing drawn yet.

    Attributes
    ----------
    name, title : str
    times : ndarray, shape (K,)
        Frame times, in seconds.
    positions : list of ndarray, each shape (n_k, d)
    velocities : list of ndarray, optional
        For motion blur (``x, x + v blur``).
    colors : list of ndarray, each shape (n_k, 4), optional
    sizes : list of ndarray, each shape (n_k,), optional
    springs : ndarray of int, shape (p, 2), optional
        Index pairs drawn as lines (mass-spring models).
    lines : list of ndarray, each shape (k, d)
        Static scenery (walls, ground, obstacles).
    limits : list of (lo, hi), optional
    blur : float, optional
        Motion-blur exposure, in seconds.
    background : color, optional
    axis : bool
        Whether to draw the axes (slow: ticks and labels cost more than the particles).
    view : (elevation, azimuth), optional
        3D camera, in degrees.
    fps : float
        Frames per second of the animation (real time): one frame per
        ``1 / fps`` simulated seconds.
    info : dict
        Measured figures printed by the tour (counts, polarization...).
    """

    name: str
    title: str
    times: np.ndarray
    positions: list
    velocities: list = None
    colors: list = None
    sizes: list = None
    springs: np.ndarray = None
    lines: list = field(default_factory=list)
    limits: list = None
    blur: float = None
    background: str = None
    axis: bool = False
    view: tuple = None
    fps: float = 20
    info: dict = field(default_factory=dict)

    def __len__(self):
        return len(self.times)


@dataclass
class Demo:
    """An entry of :data:`particles.demos.DEMOS`: a demo's name, what it shows, its function and its preview.

    Attributes
    ----------
    name, description : str
    function : callable
        ``function(seconds, fps, seed) -> DemoData``.
    preview : dict
        Options of the short version the tour writes (5 frames per second by default).
    """

    name: str
    description: str
    function: object
    preview: dict = field(default_factory=dict)

    def __post_init__(self):
        self.preview = {"fps": 5, **self.preview}


def circle(center, radius, k=64, axes=(0, 1), d=2):
    """A closed polyline around a circle, for scenery.

    Parameters
    ----------
    center : array_like, shape (d,)
        Centre, in metres.
    radius : float
        Radius, in metres.
    k : int
        Segments.
    axes : (int, int)
        The plane of the circle.
    d : int
        Dimension of the points.

    Returns
    -------
    ndarray, shape (k + 1, d)
        The points, the first repeated at the end.
    """
    angle = np.linspace(0.0, 2 * np.pi, k + 1)
    line = np.zeros((k + 1, d)) + np.asarray(center, dtype=float)
    line[:, axes[0]] += radius * np.cos(angle)
    line[:, axes[1]] += radius * np.sin(angle)
    return line


def steps_per_frame(fps, h):
    """Steps of length `h` seconds between frames at `fps` frames per second (at least 1).

    Parameters
    ----------
    fps : float
        Frames per simulated second, > 0.
    h : float
        Time step, in seconds.

    Returns
    -------
    int
    """
    return max(1, int(round(1.0 / (positive_number(fps, "fps", "frames per second") * h))))
