"""The flock demo: Reynolds' boids from random headings to one flock."""

import numpy as np

from ..effects.colours import hsv_to_rgb
from ..effects.flocking import Boids, Flock, polarization
from .data import DemoData, steps_per_frame

__all__ = ["flock"]


def flock(seconds=8.0, fps=10, seed=0):
    """200 boids from random headings to one flock (Reynolds' rules), in 2D; the camera follows it.

    The rules and limits of tests/library/effects/test_flocking.py: radius 3 m, separation
    0.1, alignment 2, cohesion 0.5, steering at most 3 m/s^2, speeds within
    [0.5, 2] m/s; steps of 1/50 s. Each boid is coloured by its heading.

    Parameters
    ----------
    seconds, fps, seed
        As for every demo (see :mod:`particles.demos`); defaults 8.0 s and
        10 frames/s. `seed`: seed of the initial positions (uniform in a 10 m square) and headings.

    Returns
    -------
    DemoData
        Per frame, positions relative to the flock's centre and velocities,
        shape (200, 2) (m, m/s), colours (200, 4) by heading and areas
        (200,); ``info["polarization"]``: its first and last values.
    """
    rng = np.random.default_rng(seed)
    n = 200
    x = rng.uniform(0.0, 10.0, (n, 2))
    angle = rng.uniform(0.0, 2 * np.pi, n)
    v = np.column_stack([np.cos(angle), np.sin(angle)])
    rules = Boids(3.0, separation=0.1, alignment=2.0, cohesion=0.5, max_force=3.0)  # as in the tests
    birds = Flock(x, v, rules, min_speed=0.5, max_speed=2.0)
    h = 1 / 50
    every = steps_per_frame(fps, h)
    t, X = birds.run(seconds, h=h, every=every)
    heading = np.arctan2(X[:, :, 1, 1], X[:, :, 1, 0]) / (2 * np.pi) % 1.0
    colors = [np.column_stack([hsv_to_rgb(np.column_stack([hk, np.full(n, 0.75), np.full(n, 0.9)])),
                               np.ones(n)]) for hk in heading]
    p = [polarization(Xk[:, 1]) for Xk in X]
    centred = [Xk[:, 0] - Xk[:, 0].mean(axis=0) for Xk in X]  # a camera that follows the flock
    return DemoData("flock", "flock (camera follows)", t, centred, velocities=list(X[:, :, 1]), colors=colors,
                    sizes=[np.full(n, 12.0)] * len(t), blur=0.4, fps=1 / (every * h), limits=[(-8.0, 8.0), (-8.0, 8.0)],
                    info={"polarization": f"{p[0]:.2f} -> {p[-1]:.2f}"})
