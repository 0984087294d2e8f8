"""Drawing and animating particles with Matplotlib, without a window.

Particles are drawn as unshaded points on top of everything else (the
lecture's "no z-buffer, rendered last"); a velocity gives a motion-blur
segment ``(x, x + v dt)``. Animations embed in a notebook as HTML/JavaScript
(:func:`to_html`) and save to GIF with Pillow (:func:`save_gif`).
"""

from io import BytesIO

import matplotlib.pyplot as plt
import numpy as np
from matplotlib import animation
from matplotlib.collections import LineCollection
from PIL import Image

__all__ = ["draw_particles", "animate", "save_gif", "to_html"]


def _axes(d, ax=None, figsize=(5, 5)):
    if ax is not None:
        return ax.figure, ax
    fig = plt.figure(figsize=figsize)
    ax = fig.add_subplot(projection="3d" if d == 3 else None)
    return fig, ax


def draw_particles(ax, x, v=None, blur=None, color="tab:orange", size=8.0, alpha=1.0):
    """Draw particles as points, with optional motion-blur segments.

    Parameters
    ----------
    ax : matplotlib Axes (2D) or Axes3D
    x : ndarray, shape (n, d)
        Positions.
    v : ndarray, shape (n, d), optional
        Velocities; with `blur` a segment ``(x, x + v blur)`` is drawn per particle.
    blur : float, optional
        Exposure time of the motion blur, in seconds.
    color : color or ndarray, shape (n, 3) or (n, 4)
    size : float
        Marker area, in points^2.
    alpha : float or ndarray, shape (n,)

    Returns
    -------
    list of artists
    """
    x = np.asarray(x, dtype=float)
    artists = []
    if v is not None and blur is not None and len(x):
        seg = np.stack([x, x + blur * np.asarray(v, dtype=float)], axis=1)
        if x.shape[1] == 2:
            lines = LineCollection(seg, colors=color, linewidths=1.0, alpha=0.6, zorder=9)
            ax.add_collection(lines)
            artists.append(lines)
    style = dict(s=size, c=color, alpha=alpha, edgecolors="none", zorder=10)
    if x.shape[1] == 3:
        style["depthshade"] = False  # unshaded: particles only emit light
    artists.append(ax.scatter(*x.T, **style))
    return artists


def animate(frames, times=None, velocities=None, blur=None, limits=None, draw=None, interval=40,
            title=None, figsize=(5, 5), color="tab:orange", size=8.0):
    """Build an animation from recorded positions.

    Parameters
    ----------
    frames : sequence of ndarray, each shape (n_k, d)
        Positions per frame (the number of particles may change).
    times : sequence of float, optional
        Time of each frame, shown in the title.
    velocities : sequence of ndarray, each shape (n_k, d), optional
        With `blur`, draws motion-blur segments ``(x, x + v blur)`` (2D).
    blur : float, optional
        Exposure time of the motion blur, in seconds.
    limits : sequence of (lo, hi), optional
        Axis limits per dimension (default: all frames' bounding box).
    draw : callable, optional
        ``draw(ax, k)`` draws frame ``k`` itself on cleared axes (slower; for
        anything beyond points and blur).
    interval : int
        Milliseconds between frames.
    title : str, optional
    figsize : tuple
    color, size
        Point colour and area (points^2).

    Returns
    -------
    matplotlib.animation.FuncAnimation
        Call :func:`save_gif` or :func:`to_html` on it.
    """
    frames = [np.asarray(f, dtype=float) for f in frames]
    d = frames[0].shape[1]
    fig, ax = _axes(d, figsize=figsize)
    if limits is None:
        allx = np.concatenate([f for f in frames if len(f)] or [np.zeros((1, d))])
        lo, hi = allx.min(axis=0), allx.max(axis=0)
        pad = 0.05 * np.maximum(hi - lo, 1e-9)
        limits = list(zip(lo - pad, hi + pad))

    def setup():
        for axis, (lo, hi) in zip("xyz", limits):
            getattr(ax, f"set_{axis}lim")(lo, hi)
        if d == 2:
            ax.set_aspect("equal")

    def label(k):
        text = title or ""
        if times is not None:
            text = f"{text}  t = {times[k]:.2f} s".strip()
        ax.set_title(text)

    if draw is not None or d == 3:
        def update(k):
            ax.clear()
            setup()
            if draw is None:
                draw_particles(ax, frames[k], color=color, size=size)
            else:
                draw(ax, k)
            label(k)
            return []
    else:  # 2D points (and blur): update the artists in place, much faster
        setup()
        points = ax.scatter([], [], s=size, c=color, edgecolors="none", zorder=10)
        lines = LineCollection([], colors=color, linewidths=1.0, alpha=0.6, zorder=9)
        ax.add_collection(lines)

        def update(k):
            points.set_offsets(frames[k])
            if velocities is not None and blur is not None:
                lines.set_segments(np.stack([frames[k], frames[k] + blur * velocities[k]], axis=1))
            label(k)
            return [points, lines]

    anim = animation.FuncAnimation(fig, update, frames=len(frames), interval=interval, blit=False)
    plt.close(fig)
    return anim


class GifWriter(animation.AbstractMovieWriter):
    """Matplotlib movie writer producing a looping GIF with Pillow.

    Each frame is reduced to a 256-colour palette with Pillow's fast octree
    quantizer as soon as it is drawn (about ten times faster than the default
    median cut, and indistinguishable for flat-coloured plots).
    """

    @classmethod
    def isAvailable(cls):
        return True

    def setup(self, fig, outfile, dpi=None):
        super().setup(fig, outfile, dpi=dpi)
        self._images = []

    def grab_frame(self, **savefig_kwargs):
        buffer = BytesIO()
        self.fig.savefig(buffer, format="rgba", dpi=self.dpi, **savefig_kwargs)
        width, height = self.frame_size
        rgba = Image.frombuffer("RGBA", (width, height), buffer.getbuffer(), "raw", "RGBA", 0, 1)
        self._images.append(rgba.convert("RGB").quantize(256, method=Image.Quantize.FASTOCTREE))

    def finish(self):
        first, *rest = self._images
        first.save(self.outfile, save_all=True, append_images=rest, loop=0,
                   duration=round(1000 / self.fps))


def save_gif(anim, path, fps=20, dpi=72):
    """Write an animation to a looping GIF file; returns the path."""
    anim.save(str(path), writer=GifWriter(fps=fps), dpi=dpi)
    return path


def to_html(anim):
    """The animation as an HTML/JavaScript player for a notebook cell."""
    return anim.to_jshtml()
