"""Drawing and animating particles with Matplotlib, without a window.

Particles are drawn as unshaded points on top of everything else: they only
emit light and, as on the slide, do not take part in depth sorting ("rendered
last with the z-buffer disabled"). A velocity gives a motion-blur segment
``(x, x + v dt)``; springs of a mass-spring model are lines between index
pairs; colour and transparency can change per particle (by age, see
:class:`particles.effects.colours.ColorRamp`). Everything works in 2D and 3D.
Animations embed in a notebook as HTML/JavaScript (:func:`to_html`) and save
to GIF with Pillow (:func:`save_gif`).
"""

from io import BytesIO

import matplotlib.pyplot as plt
import numpy as np
from matplotlib import animation
from matplotlib.collections import LineCollection
from matplotlib.colors import to_rgba
from mpl_toolkits.mplot3d.art3d import Line3DCollection
from PIL import Image

from ._checks import positive_number

__all__ = ["draw_particles", "draw_springs", "animate", "animate_snapshots", "save_gif", "to_html", "GifWriter"]

# Layers: static scenery, then springs, then blur, then the points on top.
_Z_LINES, _Z_SPRINGS, _Z_BLUR, _Z_POINTS = 5, 8, 9, 10


def _axes(d, ax=None, figsize=(5, 5)):
    if ax is not None:
        return ax.figure, ax
    fig = plt.figure(figsize=figsize)
    ax = fig.add_subplot(projection="3d" if d == 3 else None)
    return fig, ax


def _lines(d, **style):
    """An empty line collection for d dimensions."""
    return Line3DCollection([], **style) if d == 3 else LineCollection([], **style)


def _segments(x, springs):
    """Spring segments ``(x_i, x_j)``, shape (p, 2, d)."""
    return np.stack([x[springs[:, 0]], x[springs[:, 1]]], axis=1)


def _blur_segments(x, v, blur):
    return np.stack([x, x + blur * v], axis=1)


def _check_springs(springs, n=None):
    springs = np.asarray(springs)
    if springs.size == 0:
        return np.zeros((0, 2), dtype=int)
    if springs.ndim != 2 or springs.shape[1] != 2 or not np.issubdtype(springs.dtype, np.integer):
        raise ValueError(f"springs must be an integer array of index pairs, shape (p, 2), got shape {springs.shape}")
    if n is not None and (springs.min() < 0 or springs.max() >= n):
        raise ValueError(f"springs must index particles in [0, {n}), got indices up to {springs.max()}")
    return springs


def _fade(color, factor):
    """Colours (one, or an (n, 4) array) with their alpha scaled by factor."""
    rgba = np.array(color, dtype=float) if np.ndim(color) == 2 else np.array([to_rgba(color)])
    rgba[:, 3] *= factor
    return rgba


def _set_points(points, x, d):
    """Move a scatter's points (2D or 3D) to positions x, shape (n, d)."""
    if d == 3:
        # Matplotlib has no public setter for 3D scatter positions; its own examples set _offsets3d
        points._offsets3d = tuple(np.ascontiguousarray(x[:, a]) for a in range(3))
    else:
        points.set_offsets(x)


def draw_particles(ax, x, v=None, blur=None, color="tab:orange", size=8.0, alpha=1.0):
    """Draw particles as unshaded points on top, with optional motion-blur segments.

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
        One colour, or one per particle (e.g. by age, with transparency).
    size : float or ndarray, shape (n,)
        Marker area, in points^2.
    alpha : float or ndarray, shape (n,)
        Opacity; ignored where `color` already has an alpha column.

    Returns
    -------
    list of artists
        The blur segments (if any) and the points.
    """
    x = np.asarray(x, dtype=float)
    d = x.shape[1]
    artists = []
    per_particle = np.ndim(color) == 2
    if v is not None and blur is not None and len(x):
        lines = _lines(d, colors=_fade(color, 0.6) if per_particle else color, linewidths=1.0,
                       alpha=None if per_particle else 0.6, zorder=_Z_BLUR)
        lines.set_segments(_blur_segments(x, np.asarray(v, dtype=float), blur))
        ax.add_collection(lines)
        artists.append(lines)
    style = dict(s=size, c=color, edgecolors="none", zorder=_Z_POINTS)
    if not (per_particle and np.shape(color)[1] == 4):
        style["alpha"] = alpha
    if d == 3:
        style["depthshade"] = False  # unshaded: particles only emit light
        ax.computed_zorder = False  # drawn in zorder, i.e. on top, not depth-sorted
    artists.append(ax.scatter(*x.T, **style))
    return artists


def draw_springs(ax, x, springs, color="0.35", linewidth=0.8, alpha=1.0):
    """Draw the springs of a mass-spring model as straight lines between particles.

    Parameters
    ----------
    ax : matplotlib Axes (2D) or Axes3D
    x : ndarray, shape (n, d)
        Positions.
    springs : ndarray of int, shape (p, 2)
        Index pairs ``(i, j)``, one per spring.
    color, linewidth, alpha
        Line style.

    Returns
    -------
    LineCollection or Line3DCollection
    """
    x = np.asarray(x, dtype=float)
    springs = _check_springs(springs, len(x))
    lines = _lines(x.shape[1], colors=color, linewidths=linewidth, alpha=alpha, zorder=_Z_SPRINGS)
    lines.set_segments(_segments(x, springs))
    ax.add_collection(lines)
    return lines


def _auto_limits(frames, d):
    allx = np.concatenate([f for f in frames if len(f)] or [np.zeros((1, d))])
    lo, hi = allx.min(axis=0), allx.max(axis=0)
    pad = 0.05 * np.maximum(hi - lo, 1e-9)
    return list(zip(lo - pad, hi + pad))


def _check_frames(frames):
    """The frames as float arrays, checked: at least one, each (n_k, d), all in 2D or all in 3D."""
    frames = [np.asarray(f, dtype=float) for f in frames]
    if not frames:
        raise ValueError("frames must hold at least one frame (an array of positions, shape (n, d)), got none")
    for k, f in enumerate(frames):  # a loop over frames, not particles
        if f.ndim != 2:
            raise ValueError(f"frames[{k}] must have 2 dimensions (positions, shape (n, d)), got shape {f.shape}")
    d = frames[0].shape[1]
    if d not in (2, 3) or any(f.shape[1] != d for f in frames):
        raise ValueError(f"frames must all have shape (n_k, 2) or all (n_k, 3), got {[f.shape for f in frames]}")
    return frames


def animate(frames, times=None, velocities=None, blur=None, limits=None, draw=None, interval=40,
            title=None, figsize=(5, 5), color="tab:orange", size=8.0, *, colors=None, sizes=None,
            springs=None, lines=(), background=None, axis=True, view=None):
    """Build an animation from recorded positions, in 2D or 3D.

    Parameters
    ----------
    frames : sequence of ndarray, each shape (n_k, d)
        Positions per frame (the number of particles may change).
    times : sequence of float, optional
        Time of each frame, shown in the title.
    velocities : sequence of ndarray, each shape (n_k, d), optional
        With `blur`, draws motion-blur segments ``(x, x + v blur)``.
    blur : float, optional
        Exposure time of the motion blur, in seconds.
    limits : sequence of (lo, hi), optional
        Axis limits per dimension (default: all frames' bounding box).
    draw : callable, optional
        ``draw(ax, k)`` draws frame ``k`` itself on cleared axes (slower; for
        anything beyond points, blur, springs and lines).
    interval : int
        Milliseconds between frames.
    title : str, optional
    figsize : tuple
    color, size
        Point colour and area (points^2) when `colors` and `sizes` are not given.
    colors : sequence of ndarray, each shape (n_k, 4), optional
        RGBA per particle and frame (colour and transparency by age).
    sizes : sequence of ndarray, each shape (n_k,), optional
        Marker areas per particle and frame.
    springs : ndarray of int, shape (p, 2), optional
        Index pairs drawn as lines in every frame (mass-spring models; the
        particles must keep their indices).
    lines : sequence of ndarray, each shape (k, d)
        Static polylines (walls, the ground), drawn under the particles.
    background : color, optional
        Figure and axes colour (dark for fire and fireworks).
    axis : bool
        Whether to show the axes.
    view : (float, float), optional
        3D only: elevation and azimuth of the camera, in degrees.

    Returns
    -------
    matplotlib.animation.FuncAnimation
        Call :func:`save_gif` or :func:`to_html` on it.
    """
    frames = _check_frames(frames)
    d = frames[0].shape[1]
    if springs is not None:
        springs = _check_springs(springs, len(frames[0]))
    fig, ax = _axes(d, figsize=figsize)
    if limits is None:
        limits = _auto_limits(frames, d)
    ink = "black"
    if background is not None:
        fig.set_facecolor(background)
        ax.set_facecolor(background)
        if np.dot(to_rgba(background)[:3], [0.299, 0.587, 0.114]) < 0.5:
            ink = "white"

    def setup():
        for name, (lo, hi) in zip("xyz", limits):
            getattr(ax, f"set_{name}lim")(lo, hi)
        if d == 2:
            ax.set_aspect("equal")
        else:
            ax.computed_zorder = False
            ax.set_box_aspect([hi - lo for lo, hi in limits], zoom=1.0 if axis else 1.3)  # equal scales
            if view is not None:
                ax.view_init(*view)
        if not axis:
            ax.set_axis_off()
            ax.set_position([0.0, 0.0, 1.0, 0.92])  # no room needed for ticks
        for line in lines:
            ax.plot(*np.asarray(line, dtype=float).T, color="0.5" if ink == "black" else "0.35",
                    lw=1.5 if ink == "black" else 0.8, zorder=_Z_LINES)

    # A figure text, not the axes title: placing a title costs more than drawing the frame.
    caption = fig.text(0.5, 0.97, "", ha="center", va="top", color=ink)

    def label(k):
        text = title or ""
        if times is not None:
            text = f"{text}  t = {times[k]:.2f} s".strip()
        caption.set_text(text)

    if draw is not None:
        def update(k):
            ax.clear()
            setup()
            draw(ax, k)
            label(k)
            return []
    else:  # update the artists in place: much faster than redrawing the axes
        setup()
        style = dict(s=size, c=color, edgecolors="none", zorder=_Z_POINTS)
        if d == 3:
            style["depthshade"] = False  # unshaded: particles only emit light
        points = ax.scatter(*np.zeros((d, 0)), **style)
        blurs = _lines(d, colors=color, linewidths=1.0, alpha=0.6, zorder=_Z_BLUR)
        ax.add_collection(blurs)
        spring_lines = _lines(d, colors="0.35", linewidths=0.8, zorder=_Z_SPRINGS)
        ax.add_collection(spring_lines)

        def update(k):
            x = frames[k]
            _set_points(points, x, d)
            if colors is not None:
                points.set_facecolor(colors[k])
            if sizes is not None:
                points.set_sizes(np.asarray(sizes[k], dtype=float))
            elif d == 3:
                points.set_sizes(np.full(len(x), float(size)))
            if velocities is not None and blur is not None:
                blurs.set_segments(_blur_segments(x, velocities[k], blur))
                if colors is not None:
                    blurs.set_alpha(None)
                    blurs.set_color(_fade(colors[k], 0.6))
            if springs is not None:
                spring_lines.set_segments(_segments(x, springs))
            label(k)
            return [points, blurs, spring_lines]

    anim = animation.FuncAnimation(fig, update, frames=len(frames), interval=interval, blit=False)
    plt.close(fig)
    return anim


def animate_snapshots(snapshots, blur=None, **options):
    """Animate the snapshots of a :class:`particles.effects.ParticleEffect` run.

    Colours, transparency and sizes come from the snapshots; `blur` draws
    motion blur from their velocities; other options go to :func:`animate`.

    Parameters
    ----------
    snapshots : sequence of Snapshot
        At least one, e.g. from :meth:`particles.effects.ParticleEffect.run`;
        the positions of each are shape (n_k, d), in metres.
    blur : float, optional
        Exposure time of the motion blur, in seconds (segments ``(x, x + v blur)``).
    **options
        Passed to :func:`animate` (`limits`, `figsize`, `background`, ...).

    Returns
    -------
    matplotlib.animation.FuncAnimation
        One frame per snapshot, titled with its time.
    """
    snapshots = list(snapshots)
    if not snapshots:
        raise ValueError("snapshots must hold at least one Snapshot, got none")
    return animate([s.x for s in snapshots], times=[s.t for s in snapshots],
                   velocities=[s.v for s in snapshots], blur=blur,
                   colors=[s.rgba for s in snapshots], sizes=[s.size for s in snapshots], **options)


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
    """Write an animation to a looping GIF file.

    Parameters
    ----------
    anim : matplotlib.animation.Animation
        E.g. from :func:`animate`.
    path : str or pathlib.Path
        The file to write.
    fps : float
        Frames per second of the GIF, > 0 (each frame shows ``1 / fps``
        seconds, rounded to whole milliseconds).
    dpi : float
        Resolution, in dots per inch, > 0: the image is ``figsize * dpi``
        pixels.

    Returns
    -------
    str or pathlib.Path
        `path`, as given.
    """
    fps = positive_number(fps, "fps", "frames per second")
    dpi = positive_number(dpi, "dpi", "dots per inch")
    anim.save(str(path), writer=GifWriter(fps=fps), dpi=dpi)
    return path


def to_html(anim):
    """The animation as an HTML/JavaScript player for a notebook cell.

    Parameters
    ----------
    anim : matplotlib.animation.Animation
        E.g. from :func:`animate`.

    Returns
    -------
    str
        HTML with the frames embedded as images, for
        ``IPython.display.HTML`` or a ``.html`` file.
    """
    return anim.to_jshtml()
