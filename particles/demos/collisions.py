"""The collision demo: balls bouncing in a box with a ramp and an obstacle."""

import numpy as np

from ..collisions.collider import Collider
from ..collisions.surfaces import Box, Plane, Sphere
from ..effects.colours import palette
from ..forces.fields import Gravity
from ..system import ParticleSystem
from .data import DemoData, circle, steps_per_frame

__all__ = ["bouncing"]


def bouncing(seconds=4.0, fps=15, seed=0):
    """Balls in a box with a ramp and a round obstacle: restitution 0.95, friction, backtracking, in 2D.

    Up to 24 balls start at random in the upper part of the 4 m x 3 m box
    (those that would start inside the obstacle or below the ramp are left out) with random
    velocities; gravity, velocity Verlet with steps of 1/90 s and
    :class:`particles.collisions.Collider` with ``method="backtrack"``.

    Parameters
    ----------
    seconds, fps, seed
        As for every demo (see :mod:`particles.demos`); defaults 4.0 s and
        15 frames/s. `seed`: seed of the initial positions and velocities.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (n, 2) (m, m/s; the
        same n balls throughout), one colour per ball (n, 4) and areas (n,);
        ``info``: the number of contacts and the fraction of the energy kept.
    """
    rng = np.random.default_rng(seed)
    n = 24
    x = np.column_stack([rng.uniform(0.3, 3.7, n), rng.uniform(1.8, 2.8, n)])
    ball, ramp = Sphere([2.2, 0.9], 0.45), Plane([0.0, 0.8], [1.0, 2.0])
    scene = Box([0.0, 0.0], [4.0, 3.0], container=True) | ball | ramp
    x = x[scene.H(x) > 0]
    system = ParticleSystem(x, v=rng.normal(0.0, 1.5, x.shape), forces=[Gravity([0.0, -9.81])])
    E0 = system.kinetic_energy() + system.potential_energy()
    collider = Collider(scene, restitution=0.95, friction=0.02, method="backtrack")
    h = 1 / 90
    every = steps_per_frame(fps, h)
    t, X, contacts = collider.run(system, seconds, h=h, method="verlet", every=every)
    E1 = system.kinetic_energy() + system.potential_energy()
    color = np.array([(*c, 1.0) for c in palette(len(x))])
    walls = np.array([[0, 0], [4, 0], [4, 3], [0, 3], [0, 0]], dtype=float)
    return DemoData("bouncing", "bouncing balls", t, list(X[:, :, 0]), velocities=list(X[:, :, 1]),
                    colors=[color] * len(t), sizes=[np.full(len(x), 60.0)] * len(t), blur=0.03, fps=1 / (every * h),
                    lines=[walls, circle(ball.center, ball.radius), np.array([[0.0, 0.8], [1.6, 0.0]])],
                    limits=[(-0.1, 4.1), (-0.1, 3.1)],
                    info={"contacts": len(contacts), "energy kept": f"{E1 / E0:.2f}"})
