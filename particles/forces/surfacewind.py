"""Wind on a surface (Provot 1995): a push along each triangle's normal, from the air's velocity relative to it.

:class:`~particles.forces.Wind` is a field: every particle gets the same push
whatever the shape it belongs to, like gravity turned sideways. A sheet in
such a field swings as a whole and stays flat; it cannot billow, because
billowing is the air pressing on the *surface*: harder where the surface faces
the wind, not at all where the air runs along it. Provot's wind model [1]_
acts on the surface, along its normal ``n``, with the wind velocity ``u``
relative to the surface's own velocity ``v``::

    F = C [n . (u - v)] n

This module applies it per triangle of a mesh: for a triangle of area ``A``,
unit normal ``n`` and mean vertex velocity ``v``, the force ``C A [n . (u - v)] n``
is shared equally by its three vertices. With the area in the formula, ``C``
is a coefficient per unit area, in kg/(m^2 s) (a pressure per unit of normal
speed), so that a refined mesh of the same sheet feels the same total force.
The law is linear in the relative speed (a viscous drag, as in Provot's
paper), and it damps the sheet's motion along its normal too: a sheet moving
with the wind feels nothing.

References
----------
.. [1] X. Provot, "Deformation constraints in a mass-spring model to describe
   rigid cloth behavior", Graphics Interface 1995, section 2 (the viscous
   fluid force ``C_v [n . (u - v)] n`` on the cloth's surface).
"""

import numpy as np

from .._checks import as_float_array, index_array, indices_fit, nonnegative_number
from .force import Force

__all__ = ["SurfaceWind"]


class SurfaceWind(Force):
    """Provot's wind on the triangles of a surface: ``C A [n . (u - v)] n`` per triangle, a third to each vertex.

    Parameters
    ----------
    faces : array_like of int, shape (m, 3)
        Triangles ``(i, j, k)`` of the surface, as particle indices (e.g.
        ``particles.collisions.TriangleMesh.grid(nx, ny).faces`` for a cloth of
        :func:`particles.massspring.cloth`). Their orientation does not matter:
        ``(n . w) n`` is the same for ``n`` and ``-n``.
    velocity : array_like, shape (3,), or callable
        The wind's velocity ``u`` in m/s, or a function ``velocity(t)``
        returning it (gusts).
    coefficient : float
        ``C``, in kg/(m^2 s), >= 0: the normal force per unit area and per
        m/s of normal relative speed.

    Notes
    -----
    For a triangle with edges ``e1 = x_j - x_i`` and ``e2 = x_k - x_i``, the
    vector ``N = e1 x e2`` has length ``2 A`` and the direction of ``n``, so
    ``A [n . w] n = (N . w) N / (2 |N|)`` with ``w = u - v``: one cross product
    per triangle, no division by a vanishing area (a degenerate triangle feels
    nothing). The force is external (it does not conserve momentum) and has
    no potential; it depends on the velocities, and on the time only when
    ``velocity`` is a function. Positions must be 3D.

    Examples
    --------
    A square metre of sheet, two triangles in the plane z = 0, in a wind of
    2 m/s along its normal: ``C A |u|`` = 1.5 x 1 x 2 = 3 N, along z.

    >>> import numpy as np
    >>> x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
    >>> wind = SurfaceWind([[0, 1, 3], [0, 3, 2]], velocity=[0.0, 0.0, 2.0], coefficient=1.5)
    >>> wind(x).sum(axis=0).tolist()
    [0.0, 0.0, 3.0]
    >>> wind(x, v=np.tile([0.0, 0.0, 2.0], (4, 1))).sum(axis=0).tolist()   # moving with the wind
    [0.0, 0.0, 0.0]
    """

    uses_velocity = True

    @property
    def uses_time(self):
        """A wind given as a function of time makes the force depend on it; a constant one does not."""
        return callable(self.velocity)

    def __init__(self, faces, velocity, coefficient):
        self.faces = index_array(faces, "faces", 3)
        if callable(velocity):
            self.velocity = velocity
        else:
            self.velocity = as_float_array(velocity, "velocity", shape=(3,))
        self.coefficient = nonnegative_number(coefficient, "coefficient", "kg/(m^2 s)")

    def _wind(self, t):
        if callable(self.velocity):
            return as_float_array(self.velocity(t), "velocity(t)", shape=(3,))
        return self.velocity

    def add_to(self, F, x, v, t, m):
        if x.shape[1] != 3:
            raise ValueError(f"SurfaceWind needs positions in 3 dimensions (triangles have normals), got {x.shape[1]}")
        if len(self.faces) == 0:
            return
        indices_fit(int(self.faces.max()), len(x), "faces")
        u = self._wind(t)
        i, j, k = self.faces.T
        xt, vt = np.ascontiguousarray(x.T), np.ascontiguousarray(v.T)
        e1, e2 = xt[:, j] - xt[:, i], xt[:, k] - xt[:, i]            # (3, m) edges of every triangle
        N = np.cross(e1, e2, axis=0)                                 # |N| = 2 A, along n
        w = u[:, None] - (vt[:, i] + vt[:, j] + vt[:, k]) / 3.0     # air relative to each triangle
        size = np.sqrt(np.einsum("am,am->m", N, N))
        scale = np.divide(self.coefficient * np.einsum("am,am->m", N, w), 2.0 * size,
                          out=np.zeros_like(size), where=size > 0)   # C A (n . w) / |N| ...
        share = np.repeat(scale / 3.0, 3)                            # ... a third to each vertex
        corners = self.faces.ravel()
        for a in range(3):  # a loop over the coordinates: scatter N_a times the share
            F[:, a] += np.bincount(corners, np.repeat(N[a], 3) * share, minlength=len(x))
