"""The mass-spring demos: a hanging cloth, and a cloth draped over a sphere."""

import numpy as np

from ..collisions.collider import Collider
from ..collisions.surfaces import Plane, Sphere
from ..constraints import ProvotConstraint
from ..integrators.steppers import symplectic_euler
from ..massspring.cloth import cloth
from .data import DemoData, circle

__all__ = ["hanging_cloth", "draped_cloth"]


def _record(system, step, seconds, fps, h_max):
    """Run `system` with stepper `step` and steps of at most `h_max`, recording `fps` frames per second.

    The step is shortened so that a whole number of steps fits in a frame.
    Returns the frame times, the states and the step used.
    """
    every = int(np.ceil(1.0 / (fps * h_max)))
    h = 1.0 / (fps * every)
    t, X = system.run(system.t + seconds, h, method=step, every=every)
    return t, X, h


def hanging_cloth(seconds=4.0, fps=12, seed=0):
    """A 16 x 16 cloth pinned at its two top corners, falling and swinging in a gusty wind, in 3D.

    Physical scaling (stretch modulus 100 N/m, damping 0.2), symplectic
    Euler at half its stability limit, and Provot's constraint holding the
    springs near their rest lengths.

    Parameters
    ----------
    seconds, fps, seed
        As for every demo (see :mod:`particles.demos`); defaults 4.0 s and
        12 frames/s. The demo is deterministic: `seed` is not used.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (256, 3) (m, m/s), the
        structural springs as index pairs (p, 2) drawn as lines;
        ``info``: the largest strain over the run and the time step.
    """
    c = cloth(16, 16, plane="horizontal", pins="top corners", scaling="physical", stretch_modulus=100.0,
              damping=0.2, wind=[0.0, 2.0, 0.0])
    provot = ProvotConstraint.from_system(c)
    t, X, h = _record(c, provot.stepper(symplectic_euler), seconds, fps, 0.5 * c.max_stable_step())
    strain = max(c.max_strain(Xk) for Xk in X)
    return DemoData("cloth", "hanging cloth", t, list(X[:, :, 0]), velocities=list(X[:, :, 1]),
                    springs=c.springs["structural"].indices,
                    limits=[(-0.3, 1.3), (-0.8, 0.8), (-1.4, 0.2)], view=(15, -70), fps=fps,
                    colors=[np.tile([0.85, 0.35, 0.1, 1.0], (c.n, 1))] * len(t), sizes=[np.full(c.n, 4.0)] * len(t),
                    info={"largest strain": f"{100 * strain:.1f}%", "time step": f"{1e3 * h:.2f} ms"})


def draped_cloth(seconds=3.0, fps=12, seed=0):
    """A free 20 x 20 cloth, 1.2 m wide, falling onto a sphere and the floor, in 3D.

    The sphere (radius 0.4 m) and the floor ``z = -0.4`` m collide with
    the cloth by projection (restitution 0, friction 0.5) after each step of
    symplectic Euler with Provot's constraint, at 0.9 of the stability limit.

    Parameters
    ----------
    seconds, fps, seed
        As for every demo (see :mod:`particles.demos`); defaults 3.0 s and
        12 frames/s. The demo is deterministic: `seed` is not used.

    Returns
    -------
    DemoData
        Per frame, positions and velocities of shape (400, 3) (m, m/s), the
        structural springs as index pairs (p, 2); ``info``: the deepest
        point inside the sphere and the time step.
    """
    c = cloth(20, 20, width=1.2, height=1.2, plane="horizontal", origin=(-0.6, -0.6, 0.5), pins=None,
              scaling="physical", stretch_modulus=200.0, damping=0.5)
    ball, floor = Sphere([0.0, 0.0, 0.0], 0.4), Plane([0.0, 0.0, -0.4], [0.0, 0.0, 1.0])
    collider = Collider(ball | floor, restitution=0.0, friction=0.5, method="project")
    step = collider.stepper(ProvotConstraint.from_system(c).stepper(symplectic_euler), m=c.m, pinned=c.pinned)
    t, X, h = _record(c, step, seconds, fps, 0.9 * c.max_stable_step())
    inside = min(float(ball.H(Xk[:, 0]).min()) for Xk in X)
    lines = [circle([0, 0, z], np.sqrt(0.16 - z * z), axes=(0, 1), d=3) for z in (-0.3, -0.15, 0.0, 0.15, 0.3)]
    lines += [circle([0, 0, 0], 0.4, axes=(0, 2), d=3), circle([0, 0, 0], 0.4, axes=(1, 2), d=3)]
    return DemoData("drape", "cloth over a sphere", t, list(X[:, :, 0]), velocities=list(X[:, :, 1]),
                    springs=c.springs["structural"].indices,
                    lines=lines, limits=[(-0.8, 0.8), (-0.8, 0.8), (-0.45, 0.6)], view=(25, -60), fps=fps,
                    colors=[np.tile([0.2, 0.45, 0.8, 1.0], (c.n, 1))] * len(t), sizes=[np.full(c.n, 3.0)] * len(t),
                    info={"deepest point inside the sphere": f"{max(0.0, -inside):.1e} m", "time step": f"{1e3 * h:.2f} ms"})
