"""Moving bodies: implicit surfaces carried by a rigid motion (a ball that moves, a roller that turns).

A body that moves is the same implicit surface ``H_0`` seen through a rigid
motion. A point ``y`` of the body at its placement (time ``t0``) is at

    x(t) = p + c(t) + R(t) (y - p)

at time ``t``: ``c(t)`` is the translation (``v (t - t0)`` for a constant
velocity ``v``, or any function), ``R(t)`` the rotation by the angle
``|omega| (t - t0)`` about the axis ``omega / |omega|`` through the pivot
``p`` (Rodrigues' formula), and the pivot moves with the translation.

1. **Shape at time t** (:meth:`MovingSurface.at`): the inverse motion takes a
   point back to the placement, ``y = p + R^T (x - p - c)``, so
   ``H(x, t) = H_0(y)``, ``grad H = R grad H_0(y)``, and the closest point is
   moved forward the same way. A rigid motion keeps distances, so a signed
   distance stays one.
2. **Velocity of the body's material at x** (:meth:`MovingSurface.velocity`):
   differentiate ``x(t)``: ``dx/dt = c'(t) + omega x (x - p - c(t))``. A
   cloth in contact is stopped relative to this velocity, not to zero: a
   turning roller drags the cloth along by friction although its surface
   does not move.

In 2D ``omega`` is a number (rad/s, counter-clockwise) and ``omega x r`` is
``omega (-r_y, r_x)``.

References
----------
.. [1] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM Transactions on Graphics
   21(3) (SIGGRAPH 2002), 594-603 (relative velocities at contacts with
   moving objects).
.. [2] R. M. Murray, Z. Li and S. S. Sastry, *A Mathematical Introduction to
   Robotic Manipulation*, CRC Press, 1994, chapter 2 (rigid motions, the
   exponential of a rotation: Rodrigues' formula, velocity ``omega x r + v``).
"""

import numpy as np

from .._checks import as_float_array, finite_real
from .surfaces import Box, Cylinder, Sphere, Surface

__all__ = ["MovingSurface", "RigidlyMoved", "rotation_matrix"]


def rotation_matrix(omega, angle_time):
    """The rotation ``R = exp(s [omega]_x)`` after time `angle_time` at angular velocity `omega`.

    Parameters
    ----------
    omega : float or ndarray, shape (3,)
        Angular velocity, rad/s: a number in 2D, a vector in 3D (its
        direction is the axis, right-hand rule).
    angle_time : float
        Elapsed time ``s``, in seconds.

    Returns
    -------
    ndarray, shape (2, 2) or (3, 3)

    Examples
    --------
    >>> rotation_matrix([0.0, 0.0, np.pi / 2], 1.0).round(12).tolist()
    [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    omega = np.asarray(omega, dtype=float)
    if omega.ndim == 0:
        a = float(omega) * angle_time
        return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    speed = np.linalg.norm(omega)
    if speed == 0:
        return np.eye(3)
    k = omega / speed
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    a = speed * angle_time
    return np.eye(3) + np.sin(a) * K + (1.0 - np.cos(a)) * (K @ K)


def _natural_pivot(surface):
    """The centre of a sphere or box, the axis point of a cylinder, else the origin."""
    if isinstance(surface, (Sphere, Box)):
        return surface.center.copy()
    if isinstance(surface, Cylinder):
        return surface.point.copy()
    return np.zeros(surface.d)


class RigidlyMoved(Surface):
    """A surface after a rigid motion: ``H(x) = H_0(p + R^T (x - p - c))``.

    Parameters
    ----------
    surface : Surface
        The body at its placement (``H_0``).
    R : ndarray, shape (d, d)
        A rotation matrix.
    pivot : ndarray, shape (d,)
        ``p``, the point the rotation turns about, in metres.
    shift : ndarray, shape (d,)
        ``c``, the translation, in metres.
    """

    def __init__(self, surface, R, pivot, shift):
        if not isinstance(surface, Surface):
            raise ValueError(f"surface must be a Surface, got {type(surface).__name__}")
        self.surface, self.d, self.lipschitz = surface, surface.d, surface.lipschitz
        self.R = as_float_array(R, "R", shape=(self.d, self.d))
        self.pivot = as_float_array(pivot, "pivot", shape=(self.d,))
        self.shift = as_float_array(shift, "shift", shape=(self.d,))

    def _back(self, x):
        """Points of the placement that the motion takes to `x`."""
        return self.pivot + (x - self.pivot - self.shift) @ self.R  # rows: R^T (x - p - c)

    def _H(self, x):
        return self.surface._H(self._back(x))

    def _gradient(self, x):
        return self.surface._gradient(self._back(x)) @ self.R.T

    def _closest(self, x):
        return self.pivot + self.shift + (self.surface._closest(self._back(x)) - self.pivot) @ self.R.T

    def __repr__(self):
        return f"RigidlyMoved({self.surface!r}, shift={self.shift.tolist()})"


class MovingSurface:
    """An implicit surface moving rigidly: translation and rotation about a pivot.

    Parameters
    ----------
    surface : Surface
        The body at time `t0`.
    velocity : array_like, shape (d,), optional
        Constant translation velocity ``v``, m/s: ``c(t) = v (t - t0)``.
    path : callable, optional
        Instead of `velocity`: ``path(t)`` returns the translation ``c(t)``
        (m, shape (d,)) at time ``t``, with ``c(t0) = 0`` for the body to
        start at its placement.
    path_velocity : callable, optional
        ``c'(t)`` (m/s) for a `path`; without it, a central difference of the
        path with a step of ``1e-6 (1 + |t|)`` s.
    omega : float or array_like, shape (3,), optional
        Angular velocity, rad/s, about an axis through the pivot (a number in
        2D). Default: no rotation.
    pivot : array_like, shape (d,), optional
        A point of the rotation axis at time `t0`, in metres; default the
        centre of a :class:`~particles.collisions.surfaces.Sphere` or
        :class:`~particles.collisions.surfaces.Box`, the axis point of a
        :class:`~particles.collisions.surfaces.Cylinder`, else the origin.
    t0 : float
        Time of the placement, in seconds.

    Attributes
    ----------
    d : int
        Dimension of space.

    Examples
    --------
    A ball rising at 2 m/s, and a roller of radius 0.5 m turning at 2 rad/s about its axis:

    >>> ball = MovingSurface(Sphere([0.0, 0.0, 0.0], 1.0), velocity=[0.0, 0.0, 2.0])
    >>> ball.at(0.5).H([0.0, 0.0, 3.0]).round(12).tolist()
    1.0
    >>> roller = MovingSurface(Cylinder([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.5), omega=[2.0, 0.0, 0.0])
    >>> roller.velocity([[5.0, 0.0, 0.5]], t=1.0).tolist()   # its top moves towards -y
    [[0.0, -1.0, 0.0]]
    """

    def __init__(self, surface, velocity=None, path=None, path_velocity=None, omega=None, pivot=None, t0=0.0):
        if not isinstance(surface, Surface):
            raise ValueError(f"surface must be a Surface, got {type(surface).__name__}")
        self.surface, self.d = surface, surface.d
        self.t0 = finite_real(t0, "t0", "seconds")
        if velocity is not None and path is not None:
            raise ValueError("give velocity (a constant translation) or path (a function of t), not both")
        if path is not None and not callable(path):
            raise ValueError(f"path must be a function of t returning a translation, got {type(path).__name__}")
        if path_velocity is not None and (path is None or not callable(path_velocity)):
            raise ValueError("path_velocity must be a function of t, given together with path")
        self.v = np.zeros(self.d) if velocity is None else as_float_array(velocity, "velocity", shape=(self.d,))
        self.path, self.path_velocity = path, path_velocity
        if omega is None:
            omega = 0.0 if self.d == 2 else np.zeros(3)
        if self.d == 2:
            self.omega = finite_real(omega, "omega", "rad/s")
        else:
            self.omega = as_float_array(omega, "omega", shape=(3,))
        self.pivot = _natural_pivot(surface) if pivot is None else as_float_array(pivot, "pivot", shape=(self.d,))

    def displacement(self, t):
        """The translation ``c(t)`` at time `t`, in metres, shape (d,)."""
        t = finite_real(t, "t", "seconds")
        if self.path is None:
            return self.v * (t - self.t0)
        return as_float_array(self.path(t), "path(t)", shape=(self.d,))

    def translation_velocity(self, t):
        """``c'(t)``, in m/s, shape (d,)."""
        t = finite_real(t, "t", "seconds")
        if self.path is None:
            return self.v.copy()
        if self.path_velocity is not None:
            return as_float_array(self.path_velocity(t), "path_velocity(t)", shape=(self.d,))
        dt = 1e-6 * (1.0 + abs(t))
        return (self.displacement(t + dt) - self.displacement(t - dt)) / (2 * dt)

    def rotation(self, t):
        """The rotation ``R(t)`` since `t0`, shape (d, d)."""
        return rotation_matrix(self.omega, finite_real(t, "t", "seconds") - self.t0)

    def at(self, t):
        """The body at time `t`: a :class:`~particles.collisions.surfaces.Surface` with the same ``H`` API.

        Parameters
        ----------
        t : float
            Time, in seconds.

        Returns
        -------
        Surface
            The surface itself when the body has not moved, else a
            :class:`RigidlyMoved` copy.
        """
        c, R = self.displacement(t), self.rotation(t)
        if not np.any(c) and np.array_equal(R, np.eye(self.d)):
            return self.surface
        return RigidlyMoved(self.surface, R, self.pivot, c)

    def velocity(self, x, t):
        """Velocity of the body's material point at each `x`: ``c'(t) + omega x (x - p - c(t))``.

        Parameters
        ----------
        x : array_like, shape (n, d) or (d,)
            Points, in metres (on or near the body).
        t : float
            Time, in seconds.

        Returns
        -------
        ndarray, shape (n, d) or (d,)
            In m/s.
        """
        x = as_float_array(x, "x", ndim=(1, 2))
        if x.shape[-1] != self.d:
            raise ValueError(f"x must have shape (n, {self.d}) for this {self.d}D body, got shape {x.shape}")
        r = x - self.pivot - self.displacement(t)
        if self.d == 2:
            spin = self.omega * np.stack([-r[..., 1], r[..., 0]], axis=-1)
        else:
            spin = np.cross(self.omega, r)
        return self.translation_velocity(t) + spin

    def __repr__(self):
        return f"MovingSurface({self.surface!r}, velocity={self.v.tolist()}, omega={np.asarray(self.omega).tolist()})"
