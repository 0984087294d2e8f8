"""Rendering: points on top, colours by age, motion blur, springs, and animations in 2D and 3D."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from PIL import Image  # noqa: E402

from particles import render  # noqa: E402
from particles.effects import ColorRamp, ParticleEffect  # noqa: E402
from particles.effects import Cone, Emitter, Point  # noqa: E402

# Animations built only to inspect their artists are never rendered; Matplotlib warns when they are freed.
pytestmark = pytest.mark.filterwarnings("ignore:Animation was deleted without rendering")


def chain(n=6, d=2):
    """A chain of particles and its springs (i, i + 1), as a mass-spring model would give."""
    x = np.zeros((n, d))
    x[:, 0] = np.arange(n)
    x[:, 1] = -0.1 * np.arange(n) ** 2
    return x, np.column_stack([np.arange(n - 1), np.arange(1, n)])


@pytest.mark.parametrize("d", [2, 3])
def test_points_are_unshaded_and_on_top(d):
    """Points are drawn above springs and blur, and without depth shading in 3D."""
    x, springs = chain(d=d)
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d" if d == 3 else None)
    lines = render.draw_springs(ax, x, springs)
    blur, points = render.draw_particles(ax, x, v=np.ones_like(x), blur=0.1)
    assert points.get_zorder() > blur.get_zorder() > lines.get_zorder()
    if d == 3:
        assert ax.computed_zorder is False and points._depthshade is False
    plt.close(fig)


def test_springs_are_lines_between_index_pairs():
    """A chain's springs become one segment per pair, from x_i to x_j."""
    x, springs = chain()
    fig, ax = plt.subplots()
    lines = render.draw_springs(ax, x, springs)
    segments = lines.get_segments()
    assert len(segments) == len(springs)
    for (i, j), seg in zip(springs, segments):
        np.testing.assert_allclose(seg, [x[i], x[j]])
    plt.close(fig)


def test_motion_blur_segments_are_x_to_x_plus_v_dt():
    """Blur draws (x, x + v dt) for each particle."""
    x = np.array([[0.0, 0.0], [1.0, 2.0]])
    v = np.array([[1.0, 0.0], [0.0, -2.0]])
    fig, ax = plt.subplots()
    blur, _ = render.draw_particles(ax, x, v=v, blur=0.5)
    np.testing.assert_allclose(blur.get_segments(), [[[0, 0], [0.5, 0]], [[1, 2], [1, 1]]])
    plt.close(fig)


def test_colours_and_alpha_per_particle():
    """Per-particle RGBA (by age) reaches the drawn points unchanged."""
    ramp = ColorRamp(["white", "red"], alphas=[1.0, 0.0])
    rgba = ramp(np.array([0.0, 0.5, 0.9]))
    fig, ax = plt.subplots()
    (points,) = render.draw_particles(ax, np.zeros((3, 2)), color=rgba)
    np.testing.assert_allclose(points.get_facecolor(), rgba)
    plt.close(fig)


def test_animation_updates_points_colours_blur_and_springs():
    """animate draws each frame's positions, colours, sizes, blur and springs (2D artists checked)."""
    x, springs = chain()
    frames = [x + 0.1 * k for k in range(4)]
    colors = [np.tile([1.0, 0.0, 0.0, 0.25 * (k + 1)], (len(x), 1)) for k in range(4)]
    anim = render.animate(frames, times=np.arange(4) * 0.1, velocities=[np.ones_like(x)] * 4, blur=0.1,
                          colors=colors, sizes=[np.full(len(x), 5.0 + k) for k in range(4)], springs=springs,
                          lines=[x[:2]], background="black", axis=False)
    points, blurs, spring_lines = anim._func(2)
    np.testing.assert_allclose(points.get_offsets(), frames[2])
    np.testing.assert_allclose(points.get_facecolor(), colors[2])
    np.testing.assert_allclose(points.get_sizes(), 7.0)
    np.testing.assert_allclose(spring_lines.get_segments()[0], frames[2][:2])
    np.testing.assert_allclose(blurs.get_segments()[0], [frames[2][0], frames[2][0] + 0.1])


def test_3d_animation_moves_the_points(tmp_path):
    """In 3D the points follow the frames (one GIF image per frame), with springs and blur."""
    x, springs = chain(d=3)
    frames = [x + 0.1 * k for k in range(3)]
    anim = render.animate(frames, velocities=[np.ones_like(x)] * 3, blur=0.1, springs=springs, axis=False,
                          view=(20, 30), figsize=(2, 2))
    points, _, _ = anim._func(1)
    np.testing.assert_allclose(np.column_stack(points._offsets3d), frames[1])  # Matplotlib's 3D positions
    with Image.open(render.save_gif(anim, tmp_path / "chain.gif", dpi=40)) as gif:
        assert gif.n_frames == 3


def test_number_of_particles_may_change_between_frames():
    """Frames with 0, 3 and 10 particles animate and save (births and deaths)."""
    frames = [np.zeros((0, 2)), np.ones((3, 2)), np.random.default_rng(0).random((10, 2))]
    anim = render.animate(frames, limits=[(0, 1), (0, 1)])
    html = render.to_html(anim)
    assert "<script" in html and "animation" in html.lower()


def test_gif_has_one_frame_per_state(tmp_path):
    """save_gif writes a looping GIF with one image per frame."""
    effect = ParticleEffect(2, [Emitter(50.0, Point([0, 0]), Cone([0, 1], 1.0, angle=0.5), lifetime=0.5)], seed=0)
    snapshots = effect.run(1.0, h=0.05, every=2)
    anim = render.animate_snapshots(snapshots, blur=0.05, limits=[(-1, 1), (-0.2, 1.2)], figsize=(2, 2))
    path = render.save_gif(anim, tmp_path / "effect.gif", fps=10, dpi=50)
    with Image.open(path) as gif:
        assert gif.n_frames == len(snapshots) == 11
        assert gif.info["loop"] == 0


def test_springs_of_the_wrong_shape_are_rejected():
    """Springs must be integer index pairs into the particles."""
    x, springs = chain()
    fig, ax = plt.subplots()
    with pytest.raises(ValueError, match=r"springs must be an integer array of index pairs"):
        render.draw_springs(ax, x, springs.astype(float))
    with pytest.raises(ValueError, match=r"springs must index particles in \[0, 6\)"):
        render.draw_springs(ax, x, springs + 1)
    plt.close(fig)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: render.animate([]), "frames must hold at least one frame"),
        (lambda: render.animate([np.zeros((3, 2)), np.zeros(3)]), r"frames\[1\] must have 2 dimensions"),
        (lambda: render.animate_snapshots([]), "snapshots must hold at least one Snapshot"),
        (lambda: render.save_gif(object(), "never.gif", fps=0), "fps must be a positive finite number"),
        (lambda: render.save_gif(object(), "never.gif", dpi=-72), "dpi must be a positive finite number"),
    ],
)
def test_bad_input(make, match):
    """Mistakes raise ValueError naming the argument, before anything is drawn or written."""
    with pytest.raises(ValueError, match=match):
        make()
