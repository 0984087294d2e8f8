"""The forces of one particle at a time: gravity, damping, fields (each a :class:`~particles.forces.force.Force`).

The forces here act on each particle alone, as in the lecture:

* depending on mass only: :class:`Gravity` (point it up for smoke and flames);
* on the particle's own velocity: :class:`Damping`;
* on the particle's own position and the time (spatial fields):
  :class:`Wind`, :class:`Attractor`, :class:`Vortex`, :class:`Field`.

Forces between particles live in :mod:`particles.forces.nbody`,
:mod:`particles.forces.lennardjones` and :mod:`particles.forces.spring_sets`;
:mod:`particles.forces` gathers them all.

References
----------
.. [1] A. Witkin, "Particle System Dynamics", in *Physically Based Modeling:
   Principles and Practice*, SIGGRAPH 1997 course notes.
"""

import numpy as np

from .._checks import as_float_array, nonnegative_number, positive_number
from .force import Force

__all__ = ["Gravity", "Damping", "Wind", "Attractor", "Vortex", "Field", "gust_factor"]


def _vector(value, name):
    return as_float_array(value, name, ndim=1)


def _matching(vector, F, name):
    """Check a constant vector has the dimension of the force array."""
    if vector.shape != F.shape[1:]:
        raise ValueError(
            f"{name} has {vector.size} components but the particles live in "
            f"{F.shape[1]} dimensions"
        )
    return vector


def _point(value, t, name):
    """A point given as a constant (checked once, when the force was made) or as a function of time."""
    return _vector(value(t), name) if callable(value) else value


def gust_factor(phase, along, gust, wavelength):
    """The gusts' factor of the wind's strength: ``1 + gust sin(2 pi (phase - along / wavelength))``.

    Parameters
    ----------
    phase : float
        ``t / period``: the time in gust periods.
    along : float or ndarray
        ``x . u``: how far along the wind the particle is, in metres.
    gust : float
        Relative amplitude of the gusts.
    wavelength : float
        Distance between gust fronts, in metres (``inf``: the whole field gusts at once).
    """
    return 1.0 + gust * np.sin(2.0 * np.pi * (phase - along / wavelength))


class Gravity(Force):
    """Uniform gravity: ``F = m g``, the same acceleration for every particle.

    Parameters
    ----------
    g : array_like, shape (d,)
        Acceleration, in m/s^2, e.g. ``(0, -9.81)`` or ``(0, 0, -9.81)``.
        Point it up, e.g. ``(0, 0.5)``, for smoke and flames that rise.
    """

    uses_velocity = False
    uses_time = False
    _compiled_role = "gravity"  # the compiled step of particles.massspring adds g itself

    def __init__(self, g):
        self.g = _vector(g, "g")

    def add_to(self, F, x, v, t, m):
        g = _matching(self.g, F, "g")
        for a in range(len(g)):  # per coordinate, i.e. F += m[:, None] * g, but faster
            F[:, a] += g[a] * m

    def potential_energy(self, x, m, t=0.0):
        """``-sum(m g . x)``, in joules."""
        return -float(np.sum(m * (x @ self.g)))


class Damping(Force):
    """Viscous damping opposing motion: ``F = -d v``, or ``F = -rate m v``.

    Parameters
    ----------
    d : float, optional
        Damping coefficient, in kg/s, >= 0, the same for every particle. A
        little damping lets a system settle and can stabilise a solver; too
        much makes motion look as if it happened in glue (the velocity
        relaxes in ``m / d`` seconds).
    rate : float, optional
        Instead of `d`: damping per unit mass, in 1/s (``d_i = rate m_i``), so
        that every particle relaxes in ``1 / rate`` seconds whatever its
        mass. Mass-spring builders use it so that damping does not depend on
        how finely a body is discretized.
    """

    uses_time = False
    _compiled_role = "damping"  # the compiled step of particles.massspring subtracts (d + rate m) v itself

    def __init__(self, d=None, rate=None):
        if (d is None) == (rate is None):
            raise ValueError("give exactly one of d (kg/s) and rate (1/s)")
        self.d = None if d is None else nonnegative_number(d, "d", "kg/s")
        self.rate = None if rate is None else nonnegative_number(rate, "rate", "1/s")

    def add_to(self, F, x, v, t, m):
        if self.rate is None:
            F -= self.d * v
        else:
            F -= (self.rate * m)[:, None] * v


class Wind(Force):
    """Wind: a force field along a direction, with optional travelling gusts.

    ``F = s (1 + gust sin(2 pi (t / period - (x . u) / wavelength)))`` where
    ``s`` is the strength vector and ``u = s / |s|``. With ``gust = 0`` it is a
    constant field; with gusts it depends on position and time.

    Parameters
    ----------
    strength : array_like, shape (d,)
        Force on each particle in calm conditions, in newtons.
    gust : float
        Relative amplitude of the gusts, >= 0.
    period : float
        Gust period, in seconds.
    wavelength : float
        Distance between gust fronts along the wind, in metres (``inf``: the
        whole field gusts at once).
    per_mass : bool
        If True, `strength` is an acceleration (m/s^2) and each particle gets
        ``m`` times it, so the wind on a body does not depend on how many
        particles discretize it.

    Notes
    -----
    Like every spatial field, wind adds energy; some damping keeps the
    motion bounded.
    """

    uses_velocity = False
    _compiled_role = "wind"  # the compiled step of particles.massspring adds it in each particle's update

    @property
    def uses_time(self):
        """Gusts travel in time; a calm wind is constant."""
        return self.gust != 0.0

    def __init__(self, strength, gust=0.0, period=1.0, wavelength=np.inf, per_mass=False):
        self.strength = _vector(strength, "strength")
        self.per_mass = bool(per_mass)
        self.gust = nonnegative_number(gust, "gust")
        self.period = positive_number(period, "period", "seconds")
        self.wavelength = np.inf if wavelength == np.inf else positive_number(wavelength, "wavelength", "metres")

    def add_to(self, F, x, v, t, m):
        s = _matching(self.strength, F, "strength")
        if self.gust == 0.0 and not self.per_mass:
            F += s
            return
        scale = np.ones(len(x))
        if self.gust:
            norm = np.linalg.norm(s)
            along = x @ (s / norm) if norm > 0 else np.zeros(len(x))
            scale = gust_factor(t / self.period, along, self.gust, self.wavelength)
        if self.per_mass:
            scale *= m
        for a in range(len(s)):  # per coordinate: F += scale[:, None] * s
            F[:, a] += s[a] * scale


class Attractor(Force):
    """Inverse-square attraction to a point; a negative strength repels.

    ``F = s (c - x) / (|c - x|^2 + eps^2)^(3/2)``

    Parameters
    ----------
    center : array_like, shape (d,), or callable
        The point ``c``, in metres, or a function ``center(t)`` for a moving one.
    strength : float
        ``s``, in N m^2. Negative for a repulser.
    softening : float
        ``eps``, in metres, > 0: keeps the force finite at the centre.
    """

    uses_velocity = False

    @property
    def uses_time(self):
        """A centre given as a function of time moves."""
        return callable(self.center)

    def __init__(self, center, strength, softening=0.1):
        self.center = center if callable(center) else _vector(center, "center")
        self.strength = float(as_float_array(strength, "strength", ndim=0))
        self.softening = positive_number(softening, "softening", "metres")

    def add_to(self, F, x, v, t, m):
        r = _matching(_point(self.center, t, "center"), F, "center") - x
        r2 = np.einsum("ij,ij->i", r, r)
        r2 += self.softening**2
        r *= (self.strength / (r2 * np.sqrt(r2)))[:, None]
        F += r

    def potential_energy(self, x, m, t=0.0):
        """``-s / sqrt(|c - x|^2 + eps^2)`` summed, in joules."""
        r2 = np.sum((_point(self.center, t, "center") - x) ** 2, axis=1) + self.softening**2
        return -self.strength * float(np.sum(1.0 / np.sqrt(r2)))


class Vortex(Force):
    """A swirl around a point (2D) or an axis (3D).

    2D: ``F = s perp(r) / (|r|^2 + a^2)`` with ``r = x - c`` and
    ``perp(r) = (-r_y, r_x)`` (counter-clockwise for ``s > 0``).
    3D: ``F = s (u x r) / (|r_perp|^2 + a^2)`` with ``u`` the unit axis and
    ``r_perp`` the part of ``r`` perpendicular to it.

    The force is tangential and falls off as ``1 / distance`` outside the
    core radius ``a``, like the velocity of a line vortex.

    Parameters
    ----------
    center : array_like, shape (d,), or callable
        A point on the axis, in metres, or ``center(t)``.
    strength : float
        ``s``, in N m.
    axis : array_like, shape (3,), optional
        Direction of the axis (3D only, default ``(0, 0, 1)``).
    core : float
        ``a``, the core radius in metres, > 0.
    """

    uses_velocity = False

    @property
    def uses_time(self):
        """A centre given as a function of time moves."""
        return callable(self.center)

    def __init__(self, center, strength, axis=None, core=0.1):
        self.center = center if callable(center) else _vector(center, "center")
        self.strength = float(as_float_array(strength, "strength", ndim=0))
        self.axis = None if axis is None else as_float_array(axis, "axis", shape=(3,))
        if self.axis is not None and not np.any(self.axis):
            raise ValueError("axis must be a non-zero vector")
        self.core = positive_number(core, "core", "metres")

    def add_to(self, F, x, v, t, m):
        r = x - _matching(_point(self.center, t, "center"), F, "center")
        if F.shape[1] == 2:
            if self.axis is not None:
                raise ValueError("axis is only meaningful in 3D; a 2D vortex turns about its center")
            swirl = np.stack([-r[:, 1], r[:, 0]], axis=1)
            dist2 = np.sum(r * r, axis=1)
        else:
            u = np.array([0.0, 0.0, 1.0]) if self.axis is None else self.axis / np.linalg.norm(self.axis)
            swirl = np.cross(u, r)
            dist2 = np.sum(swirl * swirl, axis=1)  # |u x r| = |r_perp|
        F += (self.strength / (dist2 + self.core**2))[:, None] * swirl


class Field(Force):
    """Any spatial field given as a function: ``F = fn(x, t)``.

    Parameters
    ----------
    fn : callable
        ``fn(x, t) -> ndarray`` of shape (n, d), in newtons, with ``x`` of
        shape (n, d). Vectorize it over the particles.

    Examples
    --------
    >>> import numpy as np
    >>> spring_to_origin = Field(lambda x, t: -4.0 * x)
    >>> spring_to_origin(np.array([[1.0, 2.0]]))
    array([[-4., -8.]])
    """

    uses_velocity = False

    def __init__(self, fn):
        if not callable(fn):
            raise ValueError(f"fn must be a function fn(x, t), got {type(fn).__name__}")
        self.fn = fn

    def add_to(self, F, x, v, t, m):
        value = np.asarray(self.fn(x, t), dtype=float)
        if value.shape != F.shape:
            raise ValueError(f"fn(x, t) must return shape {F.shape}, got {value.shape}")
        F += value
