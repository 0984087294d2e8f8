"""The explorations' figures: one figure per value of a parameter, and a player that switches them.

:class:`~particles.explore.exploration.Exploration` runs a simulation for each value of a parameter and
draws it with one of the ``plot_*`` functions below; :func:`figure_png` turns a figure into PNG bytes and
:func:`slider_player` shows the images with a slider in plain HTML (no kernel needed). Only drawing here;
the simulations are in :mod:`particles.explore.exploration`.
"""

from io import BytesIO

import matplotlib.pyplot as plt
import numpy as np

from .._checks import positive_number

__all__ = ["figure_png", "slider_player", "plot_damped_spring", "plot_bounces", "plot_time_step", "plot_provot_passes",
           "plot_cloth_drop"]


def figure_png(fig, dpi=72):
    """A Matplotlib figure as PNG bytes; the figure is closed (removed from pyplot).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    dpi : float
        Resolution, in dots per inch, > 0: the image is ``figsize * dpi`` pixels.

    Returns
    -------
    bytes
        The PNG file. The closed figure can still be inspected and saved.
    """
    dpi = positive_number(dpi, "dpi", "dots per inch")
    if not hasattr(fig, "savefig"):
        raise ValueError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    buffer = BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    plt.close(fig)
    return buffer.getvalue()


_PLAYER_SCRIPT = """<script>(function () {
  var root = document.getElementById("%(id)s");
  var input = root.querySelector("input.explore-slider"), output = root.querySelector("output");
  var frames = root.querySelectorAll("img.explore-frame");
  function show() {
    var k = Number(input.value);
    for (var i = 0; i < frames.length; i++) frames[i].style.display = i === k ? "" : "none";
    output.textContent = frames[k].getAttribute("data-label");
    root.setAttribute("data-shown", String(k));
  }
  input.addEventListener("input", show);
  show();
})();</script>"""


def slider_player(images, labels, name="value", initial=0, note=None):
    """Pre-rendered images switched by a slider: plain HTML and JavaScript, no kernel, no network.

    Every image is embedded (a ``data:`` URL), one ``<img class="explore-frame">`` per value,
    all but one hidden; an ``<input type="range" class="explore-slider">`` shows the image of
    its position and its label. The static counterpart of a live widget, for a course site or
    an HTML export (see :class:`particles.explore.Exploration`).

    Parameters
    ----------
    images : sequence of bytes
        PNG files, one per value (e.g. from :func:`figure_png`).
    labels : sequence of str
        What the slider shows for each image, e.g. ``"h = 0.5 ms"``.
    name : str
        The parameter's name, in front of the slider.
    initial : int
        Index of the image shown first.
    note : str, optional
        A line of text under the images.

    Returns
    -------
    str
        HTML for ``IPython.display.HTML`` or a ``.html`` file.
    """
    import base64
    import html
    import uuid

    images, labels = list(images), [str(label) for label in labels]
    if not images or len(images) != len(labels):
        raise ValueError(f"images and labels must be non-empty and of the same length, "
                         f"got {len(images)} images and {len(labels)} labels")
    if isinstance(initial, bool) or not isinstance(initial, (int, np.integer)) or not 0 <= initial < len(images):
        raise ValueError(f"initial must be an index from 0 to {len(images) - 1}, got {initial!r}")
    uid = f"explore_{uuid.uuid4().hex[:12]}"
    frames = "".join(
        f'<img class="explore-frame" data-index="{k}" data-label="{html.escape(label)}" '
        f'alt="{html.escape(label)}" style="max-width:100%{"" if k == initial else ";display:none"}" '
        f'src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'
        for k, (png, label) in enumerate(zip(images, labels)))
    footer = f'<div style="color:#666;font-size:12px">{html.escape(note)}</div>' if note else ""
    return (f'<div class="particles-exploration" id="{uid}" data-values="{len(images)}">'
            '<div style="display:flex;align-items:center;gap:8px;font:13px sans-serif">'
            f'<label for="{uid}_input">{html.escape(name)}</label>'
            f'<input type="range" class="explore-slider" id="{uid}_input" min="0" max="{len(images) - 1}" '
            f'step="1" value="{initial}" style="width:18em">'
            f'<output for="{uid}_input">{html.escape(labels[initial])}</output></div>'
            f'{frames}{footer}</div>' + _PLAYER_SCRIPT % {"id": uid})


def plot_damped_spring(data):
    """The damped spring of :func:`particles.explore.damped_spring`: x(t), its envelope, 1 cm band.

    Returns
    -------
    matplotlib.figure.Figure
    """
    t, x, rate = data["t"], data["x"], data["predicted_rate"]
    fig, ax = plt.subplots(figsize=(7.5, 3.2))
    ax.axhspan(-0.01, 0.01, color="0.85", label="within 1 cm of rest")
    ax.plot(t, x, lw=1.2, label="x(t)")
    ax.plot(t, np.exp(-rate * t), "k--", lw=0.8, label=f"envelope exp(-{rate:.3g} t)")
    ax.plot(t, -np.exp(-rate * t), "k--", lw=0.8)
    settle = data["settling_time"]
    settled = f"settles in {settle:.1f} s" if settle is not None else f"not settled in {t[-1]:.0f} s"
    ax.set(xlim=(0, t[-1]), ylim=(-1.05, 1.05), xlabel="time t (s)", ylabel="position x (m)",
           title=f"d = {data['d']:g} kg/s ({data['regime']}): decay rate {data['rate']:.3f} 1/s "
                 f"(predicted {rate:.3f}), {settled}")
    ax.title.set_fontsize(10)
    ax.legend(fontsize=8, loc="upper right")
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.15, top=0.9)  # the same for every value
    return fig


def plot_bounces(data):
    """The ball of :func:`particles.explore.bouncing_ball`: height over time, arc heights against eps^2k.

    Returns
    -------
    matplotlib.figure.Figure
    """
    e, H = data["restitution"], data["heights"]
    k = np.arange(len(H))
    fig, (ax, ax_k) = plt.subplots(1, 2, figsize=(9, 3.2), gridspec_kw={"width_ratios": [2, 1]})
    ax.plot(data["t"], data["y"], lw=1.2)
    for level in H[0] * e ** (2 * k):
        ax.axhline(level, color="k", ls=":", lw=0.6)
    ax.set(xlim=(0, data["t_max"]), ylim=(-0.03, 1.05 * H[0]), xlabel="time t (s)", ylabel="height y (m)",
           title=f"eps = {e:g}: dotted, the predicted tops H0 eps^(2k)")
    ax_k.semilogy(k, H, "o", label="measured")
    ax_k.semilogy(k, H[0] * e ** (2 * k), "k--", lw=0.8, label="H0 eps^(2k)")
    ratio = f"{np.mean(H[1:] / H[:-1]):.6f}" if len(H) > 1 else "-"
    ax_k.set(xlabel="bounce k", ylabel="height of arc k (m)", ylim=(1e-3, 2 * H[0]),
             title=f"H_k / H_(k-1) = {ratio}\neps^2 = {e * e:.6f}")
    for a in (ax, ax_k):
        a.title.set_fontsize(9)
    ax_k.legend(fontsize=8)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.15, top=0.84, wspace=0.3)  # the same for every value
    return fig


def _draw_cloth_front(ax, x, grid_shape, color="C0"):
    """A cloth's rows and columns seen from the front (x horizontal, z up)."""
    ny, nx = grid_shape
    g = np.asarray(x, dtype=float).reshape(ny, nx, -1)
    ax.plot(g[..., 0], g[..., -1], color=color, lw=0.6)
    ax.plot(g[..., 0].T, g[..., -1].T, color=color, lw=0.6)
    ax.set(xlabel="x (m)", ylabel="z (m)", aspect="equal")


def plot_time_step(data):
    """The stiff curtain of :func:`particles.explore.curtain_time_step`: its shape, and its strain over time.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, (ax, ax_s) = plt.subplots(1, 2, figsize=(9, 3.4), gridspec_kw={"width_ratios": [1, 2]})
    _draw_cloth_front(ax, data["x"], data["grid_shape"], "C3" if data["diverged"] else "C0")
    ax.set(xlim=(-0.3, 1.3), ylim=(-1.4, 0.2), title=f"t = {data['t_shown']:.3f} s")
    ax_s.semilogy(data["t"], np.maximum(data["strain"], 1e-6), lw=1)
    ax_s.axvline(data["t"][-1], color="C3" if data["diverged"] else "0.6", lw=0.8)
    verdict = (f"blew up at t = {data['t_diverged']:.3f} s" if data["diverged"]
               else f"stable for {data['t'][-1]:.2f} s")
    ax_s.set(xlabel="time t (s)", ylabel="largest spring strain", ylim=(1e-6, 1e3), xlim=(0, data["T"]),
             title=f"h = {1000 * data['h']:.3f} ms = {data['h'] / data['h_max']:.2f} h_max: {verdict}")
    for a in (ax, ax_s):
        a.title.set_fontsize(9)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.15, top=0.9, wspace=0.3)  # the same for every value
    return fig


def plot_provot_passes(data):
    """The curtain of :func:`particles.explore.provot_passes`: its last shape and its largest strain over time.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, (ax, ax_s) = plt.subplots(1, 2, figsize=(9, 3.4), gridspec_kw={"width_ratios": [1, 2]})
    _draw_cloth_front(ax, data["x"], data["grid_shape"], "C1")
    ax.set(xlim=(-0.3, 1.3), ylim=(-2.0, 0.2), title=f"most stretched, t = {data['t_shown']:.2f} s")
    ax_s.plot(data["t"], 100 * data["strain"], lw=1.2, label="largest structural strain")
    ax_s.axhline(100 * data["max_strain"], color="grey", ls=":", label="Provot's limit")
    ax_s.set(xlabel="time t (s)", ylabel="strain (%)", ylim=(0, 50), xlim=(0, data["t"][-1]),
             title=f"at most {data['passes']} pass{'es' if data['passes'] > 1 else ''} per step "
                   f"(used {data['mean_passes']:.1f} on average): "
                   f"largest strain {100 * data['strain'].max():.1f}%")
    ax_s.legend(fontsize=8)
    for a in (ax, ax_s):
        a.title.set_fontsize(9)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.15, top=0.9, wspace=0.3)  # the same for every value
    return fig


def plot_cloth_drop(data):
    """The sheet of :func:`particles.explore.cloth_drop`: snapshots in 3D, and what each stage did per step.

    Returns
    -------
    matplotlib.figure.Figure
    """
    shown, r = len(data["t_shown"]), data["radius"]
    fig = plt.figure(figsize=(12, 6.2))
    u, w = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    ball = [r * np.cos(u) * np.sin(w), r * np.sin(u) * np.sin(w), r + r * np.cos(w)]
    ny, nx = data["grid_shape"]
    for k in range(shown):  # a loop over the few snapshots
        ax = fig.add_subplot(2, shown, k + 1, projection="3d", computed_zorder=False)
        ax.plot_surface(*ball, color="0.6", lw=0)
        g = data["x"][k].reshape(ny, nx, 3)
        ax.plot_surface(g[..., 0], g[..., 1], g[..., 2], color="C0", edgecolor="C0", lw=0.1, alpha=0.85)
        ax.set(xlim=(-0.6, 0.6), ylim=(-0.6, 0.6), zlim=(0.0, data["x"][0][:, 2].max()),
               xticks=[-0.5, 0, 0.5], yticks=[-0.5, 0, 0.5], zticks=[0, 0.3, 0.6], aspect="equal")
        ax.view_init(elev=20, azim=-60)
        ax.set_title(f"t = {data['t_shown'][k]:.2f} s", fontsize=9)
    ax = fig.add_subplot(2, 1, 2)
    for label, counts in data["stages"].items():  # a loop over the four stages
        counts = np.asarray(counts, dtype=float)
        ax.semilogy(data["t"], np.where(counts > 0, counts, np.nan), ".", ms=4, label=label)
    ax.set(xlim=(0, data["T"]), ylim=(0.7, 1e4), xlabel="time t (s)", ylabel="per step",
           title=f"stretch modulus {data['stiffness']:g} N/m, h = {1000 * data['h']:.1f} ms: "
                 f"at most {int(np.max(data['crossings']))} crossing pairs of triangles in "
                 f"{len(data['t'])} steps, stretch at most {100 * np.max(data['strain']):.1f}%; "
                 f"lowest point at the end {100 * data['lowest']:.1f} cm")
    ax.title.set_fontsize(10)
    ax.legend(fontsize=8, loc="upper left")
    fig.subplots_adjust(left=0.07, right=0.96, bottom=0.09, top=0.95, hspace=0.25)  # the same for every value
    return fig
