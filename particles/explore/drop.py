"""A cloth dropped on a sphere that stands on the floor, with every stage of the cloth collisions (lecture 9).

:func:`cloth_drop` is the simulation of lecture 9's exploration (data only; its figure is
:func:`particles.explore.figures.plot_cloth_drop`): a square sheet falls onto a ball resting on the
floor, wraps its cap, and the skirt that hangs around it reaches the floor and folds there. The
cloth is stepped by the prefactorized implicit solver of lecture 7 and corrected after every step by
:class:`particles.collisions.ClothCollisions` with all four stages on (bodies, proximity,
continuous detection, impact zones) with the stretch springs held within Provot's 10%
(:mod:`particles.collisions.strain_limit`), and the invariant, no two triangles crossing, is counted
after every step with the largest stretch.

Examples
--------
>>> data = cloth_drop(200.0, n=8, T=0.1)
>>> int(data["crossings"].max()), data["x"].shape
(0, (4, 64, 3))
"""

import numpy as np

from .._checks import count, positive_number
from ..collisions.pipeline import ClothCollisions
from ..collisions.surfaces import Plane, Sphere
from ..collisions.triangle_crossing import intersections
from ..implicit.prefactored import Prefactored
from ..massspring.cloth import cloth

__all__ = ["cloth_drop", "STAGES"]

STAGES = {"body_vertices": "vertices moved out of a body", "proximity": "proximity impulses",
          "ccd": "continuous collisions", "zone_vertices": "vertices in impact zones"}
"""The counts of :class:`particles.collisions.ClothCollisionResult` recorded per step, and what they count."""


def cloth_drop(stiffness, n=32, T=0.8, h=1 / 40, drop=0.1, radius=0.25, shift=0.1, friction=0.5,
               snapshots=4, max_strain=0.1):
    """A 1 m sheet of n x n particles dropped on a ball on the floor: it wraps the ball and folds on the floor.

    The sheet (:func:`particles.massspring.cloth`, ``scaling="physical"``: the same material at
    any n, air damping 0.5 1/s) lies flat `drop` metres above the top of a ball of radius
    `radius` standing on the floor ``z = 0``, its centre `shift` metres off the ball's axis along
    x, and falls from rest. The prefactorized solver (:class:`particles.implicit.Prefactored`)
    takes steps of `h`; :class:`particles.collisions.ClothCollisions` corrects each one against
    the ball, the floor and the cloth itself at a thickness of a quarter of the spacing, and keeps
    the structural springs within ``(1 + max_strain) L0``. At 32 x 32 the prefactored solver is the
    cheap part of a step (a tenth of it, warm-started: about 4 iterations a step); the collision
    stages, compiled from 64 vertices, are the rest.

    Parameters
    ----------
    stiffness : float
        The sheet's stretch modulus, in N/m (shear: a quarter of it, flexion: a tenth).
    n : int
        Particles per side (>= 3).
    T : float
        Simulated time, in seconds.
    h : float
        Time step, in seconds.
    drop : float
        Height of the sheet above the top of the ball at the start, in metres.
    radius : float
        The ball's radius, in metres.
    shift : float
        Offset of the sheet's centre from the ball's axis, along x, in metres.
    friction : float
        Coulomb friction of the cloth on the bodies and on itself.
    snapshots : int
        States kept for drawing, evenly spread over the run (the first and the last included).
    max_strain : float or None
        The strain limit of the structural springs (Provot's 0.1); None: no limit.

    Returns
    -------
    dict
        ``"t"``: the times of the steps' ends (s), shape (steps,); ``"crossings"``: crossing pairs
        of triangles after each step; ``"strain"``: the largest structural strain after each step;
        ``"stages"``: for each field of :data:`STAGES`, named by its
        label, what that stage did in each step, shape (steps,); ``"x"``: positions (m) at ``"t_shown"``, shape (snapshots, n^2, 3);
        ``"lowest"``: the lowest height of the cloth at the end (m); ``"stiffness"``, ``"h"``,
        ``"grid_shape"``, ``"faces"`` (the mesh's triangles), ``"radius"``, ``"T"``.
    """
    n, shown = count(n, "n", 3), count(snapshots, "snapshots", 2)
    r = positive_number(radius, "radius", "m")
    top = 2 * r + positive_number(drop, "drop", "m")
    c = cloth(n, n, plane="horizontal", origin=(float(shift) - 0.5, -0.5, top), pins=None, scaling="physical",
              stretch_modulus=positive_number(stiffness, "stiffness", "N/m"), damping=0.5)
    bodies = [Sphere([0.0, 0.0, r], r), Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])]
    guard = ClothCollisions.from_system(c, thickness=0.25 / (n - 1), friction=friction, bodies=bodies,
                                        max_strain=max_strain)
    h = positive_number(h, "h", "s")
    t, X = c.run(positive_number(T, "T", "s"), h, method=guard.stepper(Prefactored(c, h)))
    keep = np.unique(np.linspace(0, len(t) - 1, shown).round().astype(int))
    stages = {label: np.array([getattr(step, field) for step in guard.history]) for field, label in STAGES.items()}
    return {"t": t[1:], "crossings": np.array([len(intersections(x[:, 0], guard.mesh)) for x in X[1:]]),
            "strain": np.array([c.max_strain(x, kind="structural") for x in X[1:]]),
            "stages": stages, "x": X[keep, :, 0], "t_shown": t[keep], "lowest": float(X[-1, :, 0, 2].min()),
            "stiffness": float(stiffness), "h": h, "grid_shape": c.grid_shape, "faces": guard.mesh.faces,
            "radius": r, "T": float(T)}
