"""Distributions of a particle's initial state: where it is born, how fast it leaves.

Positions come from a *shape*: :class:`Point`, :class:`Disk`,
:class:`SphereSurface` (all possibly moving: their centre can be a function
of time). Velocities come from a :class:`Cone` of directions with a mean
speed and a spread. Random quantities follow Reeves: ``mean + rand * spread``
with ``rand`` uniform in [-1, 1] (:func:`vary`). Everything is sampled for
all new particles at once, uniformly per unit area: radius ``R sqrt(u)`` on
a disk, ``cos(theta)`` uniform on a sphere or a cap of it (Archimedes'
hat-box theorem).

References
----------
.. [1] W. T. Reeves, "Particle Systems - a Technique for Modeling a Class of
   Fuzzy Objects", ACM Transactions on Graphics 2(2), 91-108, 1983.
"""

import numpy as np

from .._checks import as_float_array, nonnegative_number, positive_number

__all__ = ["Point", "Disk", "SphereSurface", "Cone", "vary"]
# mean_and_spread, lifetime_range and position_at are public for particles.effects.emitters, which shares them


def vary(rng, mean, spread, n):
    """Reeves' stochastic value ``mean + rand * spread``, ``rand`` uniform in [-1, 1]; shape (n,)."""
    return mean + spread * rng.uniform(-1.0, 1.0, n) if spread else np.full(n, float(mean))


def mean_and_spread(value, name, unit):
    """Reeves' ``(mean, spread)`` from a number or a pair, checked: ``0 <= spread <= mean``.

    Parameters
    ----------
    value : float or (float, float)
        A number (spread 0) or the pair.
    name, unit : str
        For the error messages.

    Returns
    -------
    (float, float)
    """
    pair = np.atleast_1d(as_float_array(value, name, ndim=(0, 1)))
    if pair.shape not in ((1,), (2,)):
        raise ValueError(f"{name} must be a number or a pair (mean, spread), got {value!r}")
    mean = nonnegative_number(pair[0], name, unit)
    spread = nonnegative_number(pair[1], f"{name} spread", unit) if len(pair) == 2 else 0.0
    if spread > mean:
        raise ValueError(f"{name} spread must not exceed its mean (values must stay >= 0), got {value!r}")
    return mean, spread


def lifetime_range(value):
    """A lifetime as ``(mean, spread)`` in seconds, from None or inf (forever), a number or a pair.

    Parameters
    ----------
    value : None, float or (float, float)

    Returns
    -------
    (float, float)
        ``(inf, 0)`` for a particle that lives forever.
    """
    if value is None or (np.ndim(value) == 0 and value == np.inf):
        return np.inf, 0.0
    return mean_and_spread(value, "lifetime", "seconds")


def position_at(center, t, d=None):
    """A point, or a function of time ``center(t)``, evaluated at times `t`.

    Parameters
    ----------
    center : ndarray, shape (d,), or callable
        A fixed point (m) or ``center(t)`` vectorized over an array of times.
    t : ndarray, shape (n,)
        Times, in seconds.
    d : int, optional
        The dimension `center(t)` must have.

    Returns
    -------
    ndarray, shape (n, d)
        The point at each time, in metres (a read-only broadcast for a fixed point).
    """
    if not callable(center):
        return np.broadcast_to(center, (len(t), len(center)))
    p = np.asarray(center(t), dtype=float)
    if p.ndim == 1:
        p = np.broadcast_to(p, (len(t), len(p)))
    if p.shape[0] != len(t) or (d is not None and p.shape[1] != d):
        raise ValueError(f"center(t) must return shape ({len(t)}, d) for t of shape ({len(t)},), got {p.shape}")
    return p


def _point(value, name):
    if callable(value):
        return value
    p = as_float_array(value, name, ndim=1)
    if p.size not in (2, 3):
        raise ValueError(f"{name} must have 2 or 3 components, got {p.size}")
    return p


def _basis(axis):
    """Unit axes (k, 3) and two unit vectors perpendicular to them and to each other."""
    u = axis / np.linalg.norm(axis, axis=1)[:, None]
    helper = np.zeros_like(u)
    helper[np.arange(len(u)), np.argmin(np.abs(u), axis=1)] = 1.0  # the least parallel axis
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return u, e1, np.cross(u, e1)


def _rotate_2d(u, angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * u[:, 0] - s * u[:, 1], s * u[:, 0] + c * u[:, 1]], axis=1)


class Point:
    """All particles start at one point (a function of time for a moving emitter).

    Parameters
    ----------
    center : array_like, shape (d,), or callable
        The point, in metres, or ``center(t)`` returning shape (n, d) for an
        array of n times (vectorized), e.g.
        ``lambda t: np.stack([np.cos(t), np.sin(t)], axis=-1)``.
    """

    def __init__(self, center):
        self.center = _point(center, "center")
        self.d = position_at(self.center, np.zeros(1)).shape[1]

    def sample(self, rng, t):
        """Positions of particles born at times `t`: the point (where it is at each time).

        Parameters
        ----------
        rng : numpy.random.Generator
            Random numbers (unused: a point has no randomness).
        t : ndarray, shape (n,)
            Birth times, in seconds (where a moving centre is then).

        Returns
        -------
        ndarray, shape (n, d)
            Positions, in metres, all at the centre.
        """
        return np.array(position_at(self.center, t))

    def normal(self, x, t):
        """The normal used by ``axis="normal"`` of an emitter: a point has none.

        Parameters
        ----------
        x : ndarray, shape (n, d)
            Positions of the newborn particles, in metres (unused).
        t : ndarray, shape (n,)
            Their birth times, in seconds (unused).

        Returns
        -------
        None
            The velocity cone keeps its own direction.
        """
        return None


class Disk(Point):
    """Uniformly over a disk (2D: a filled circle; 3D: a flat disk across `normal`).

    Parameters
    ----------
    center : array_like, shape (d,), or callable
    radius : float
        In metres, > 0.
    normal : array_like, shape (3,), optional
        3D only: the disk's axis (default ``(0, 0, 1)``), also its normal for
        velocities along ``axis="normal"`` (in 2D that normal is ``(0, 1)``, up).
    """

    def __init__(self, center, radius, normal=None):
        super().__init__(center)
        self.radius = positive_number(radius, "radius", "metres")
        self.axis = None if normal is None else as_float_array(normal, "normal", shape=(3,))
        if self.axis is not None and not np.any(self.axis):
            raise ValueError("normal must be a non-zero vector")

    def sample(self, rng, t):
        """Positions uniform over the disk, per unit area (radius ``R sqrt(u)``, ``u`` uniform in [0, 1]).

        Parameters
        ----------
        rng : numpy.random.Generator
            Random numbers.
        t : ndarray, shape (n,)
            Birth times, in seconds (where a moving centre is then).

        Returns
        -------
        ndarray, shape (n, d)
            Positions, in metres, within `radius` of the centre at each birth time.
        """
        c = position_at(self.center, t)
        n, d = c.shape
        r = self.radius * np.sqrt(rng.random(n))  # sqrt: uniform per unit area
        phi = 2 * np.pi * rng.random(n)
        if d == 2:
            return c + np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
        _, e1, e2 = _basis(np.broadcast_to(self._axis3(), (n, 3)))
        return c + (r * np.cos(phi))[:, None] * e1 + (r * np.sin(phi))[:, None] * e2

    def _axis3(self):
        return np.array([0.0, 0.0, 1.0]) if self.axis is None else self.axis / np.linalg.norm(self.axis)

    def normal(self, x, t):
        """The disk's unit normal at every particle: its axis in 3D, ``(0, 1)`` (up) in 2D.

        Parameters
        ----------
        x : ndarray, shape (n, d)
            Positions of the newborn particles, in metres (only their number and dimension are used).
        t : ndarray, shape (n,)
            Their birth times, in seconds (unused).

        Returns
        -------
        ndarray, shape (n, d)
            Unit vectors (a read-only broadcast view).
        """
        return np.broadcast_to(self._axis3() if x.shape[1] == 3 else [0.0, 1.0], x.shape)


class SphereSurface(Point):
    """Uniformly over a sphere (a circle in 2D), or a band of it around a pole.

    Parameters
    ----------
    center : array_like, shape (d,), or callable
    radius : float
        In metres, > 0.
    polar : (float, float) or callable, optional
        Range ``(lo, hi)`` of the angle from `pole`, in radians within
        [0, pi], or a function ``polar(t)`` returning ``(lo, hi)`` for an
        array of birth times (each a number or an array like ``t``), e.g.
        ``lambda t: (0.4 * t, 0.4 * t + 0.05)``: an expanding ring, as in
        Reeves' Genesis effect. Default: the whole sphere.
    pole : array_like, shape (d,), optional
        Direction the polar angle is measured from (default: the last axis).
    """

    def __init__(self, center, radius, polar=None, pole=None):
        super().__init__(center)
        self.radius = positive_number(radius, "radius", "metres")
        self.polar = polar if polar is None or callable(polar) else self._check_polar(polar)
        self.pole = None if pole is None else as_float_array(pole, "pole", ndim=1)
        if self.pole is not None and not np.any(self.pole):
            raise ValueError("pole must be a non-zero vector")

    @staticmethod
    def _check_polar(polar):
        lo, hi = as_float_array(polar, "polar", shape=(2,))
        if not 0 <= lo <= hi <= np.pi:
            raise ValueError(f"polar must be (lo, hi) with 0 <= lo <= hi <= pi, got {polar!r}")
        return lo, hi

    def sample(self, rng, t):
        """Positions uniform per unit area over the sphere, or over its band ``lo <= theta <= hi`` from the pole.

        In 3D ``cos(theta)`` is uniform (Archimedes' hat-box theorem); in 2D
        (a circle) ``theta`` is uniform, on either side of the pole.

        Parameters
        ----------
        rng : numpy.random.Generator
            Random numbers.
        t : ndarray, shape (n,)
            Birth times, in seconds (where a moving centre is then).

        Returns
        -------
        ndarray, shape (n, d)
            Positions, in metres, at distance `radius` from the centre at each birth time.
        """
        c = position_at(self.center, t)
        n, d = c.shape
        if self.polar is None:
            lo, hi = np.zeros(n), np.full(n, np.pi)
        elif callable(self.polar):
            lo, hi = (np.clip(np.broadcast_to(np.asarray(b, dtype=float), (n,)), 0.0, np.pi)
                      for b in self.polar(t))
        else:
            lo, hi = np.full(n, self.polar[0]), np.full(n, self.polar[1])
        pole = np.eye(d)[-1] if self.pole is None else self.pole / np.linalg.norm(self.pole)
        if d == 2:
            theta = lo + (hi - lo) * rng.random(n)
            theta *= np.where(rng.random(n) < 0.5, -1.0, 1.0)
            return c + self.radius * _rotate_2d(np.broadcast_to(pole, (n, 2)), theta)
        cos_theta = np.cos(hi) + (np.cos(lo) - np.cos(hi)) * rng.random(n)  # uniform per unit area
        sin_theta = np.sqrt(np.maximum(1.0 - cos_theta**2, 0.0))
        phi = 2 * np.pi * rng.random(n)
        u, e1, e2 = _basis(np.broadcast_to(pole, (n, 3)))
        direction = (cos_theta[:, None] * u + (sin_theta * np.cos(phi))[:, None] * e1
                     + (sin_theta * np.sin(phi))[:, None] * e2)
        return c + self.radius * direction

    def normal(self, x, t):
        """The outward unit normal ``(x - c(t)) / |x - c(t)|`` at each particle.

        Parameters
        ----------
        x : ndarray, shape (n, d)
            Positions of the newborn particles, in metres, on (or off) the sphere.
        t : ndarray, shape (n,)
            Their birth times, in seconds (where a moving centre was).

        Returns
        -------
        ndarray, shape (n, d)
            Unit vectors away from the centre.
        """
        r = x - position_at(self.center, t)
        return r / np.linalg.norm(r, axis=1)[:, None]


class Cone:
    """Initial velocities: directions in a cone around an axis, speeds around a mean.

    Directions are uniform over the cone's solid angle (3D: a spherical cap
    of half-angle `angle`; 2D: angles in [-angle, angle]); speeds are
    ``speed + rand * spread`` with ``rand`` uniform in [-1, 1].
    ``angle = pi`` gives every direction (an explosion).

    Parameters
    ----------
    direction : array_like, shape (d,)
        The cone's axis (need not be unit); emitters may override it per
        particle (see ``axis`` of :class:`Emitter`).
    speed : float
        Mean speed, in m/s, >= 0.
    spread : float
        Speed spread, in m/s, ``0 <= spread <= speed``.
    angle : float
        Half-angle of the cone, in radians, in [0, pi].
    """

    def __init__(self, direction, speed, spread=0.0, angle=0.0):
        self.direction = as_float_array(direction, "direction", ndim=1)
        if not np.any(self.direction):
            raise ValueError("direction must be a non-zero vector")
        self.speed, self.spread = mean_and_spread((speed, spread), "speed", "m/s")
        self.angle = nonnegative_number(angle, "angle", "radians")
        if self.angle > np.pi:
            raise ValueError(f"angle must lie in [0, pi] radians, got {angle!r}")

    def sample(self, rng, n, axis=None):
        """Velocities, shape (n, d); `axis` (n, d) replaces the cone's direction per particle."""
        d = len(self.direction)
        axis = np.broadcast_to(self.direction, (n, d)) if axis is None else axis
        speed = vary(rng, self.speed, self.spread, n)
        if d == 2:
            u = axis / np.linalg.norm(axis, axis=1)[:, None]
            return speed[:, None] * _rotate_2d(u, self.angle * rng.uniform(-1.0, 1.0, n))
        cos_theta = 1.0 - (1.0 - np.cos(self.angle)) * rng.random(n)  # uniform over the cap
        sin_theta = np.sqrt(np.maximum(1.0 - cos_theta**2, 0.0))
        phi = 2 * np.pi * rng.random(n)
        u, e1, e2 = _basis(axis)
        direction = (cos_theta[:, None] * u + (sin_theta * np.cos(phi))[:, None] * e1
                     + (sin_theta * np.sin(phi))[:, None] * e2)
        return speed[:, None] * direction
