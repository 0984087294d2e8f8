"""Force objects: each adds its contribution into a shared force array.

A force is a small object with one method::

    force.add_to(F, x, v, t, m)    # F += this force, F shape (n, d)

where ``x`` and ``v`` are positions and velocities (shape (n, d)), ``t`` the
time and ``m`` the masses (shape (n,)). The particle system sums all forces in
one place (:meth:`particles.ParticleSystem.total_force`). Calling a force,
``force(x, v, t, m)``, returns its contribution alone, which is handy for
testing and plotting it.

Kinds of force, as in the lecture:

* depending on mass only: :class:`Gravity` (point it up for smoke and flames);
* on the particle's own velocity: :class:`Damping`;
* on the particle's own position and the time (spatial fields):
  :class:`Wind`, :class:`Attractor`, :class:`Vortex`, :class:`Field`;
* on all other particles: :class:`NBodyGravity` (all pairs) and
  :class:`LennardJones` (short range, bucket grid).

References
----------
.. [1] A. Witkin, "Particle System Dynamics", in *Physically Based Modeling:
   Principles and Practice*, SIGGRAPH 1997 course notes.
.. [2] J. E. Lennard-Jones, "On the determination of molecular fields",
   Proc. R. Soc. Lond. A 106, 463-477, 1924.
"""

import numpy as np

from ._checks import as_float_array, finite_real, nonnegative_number, positive_number
from .neighbors import VerletList, all_pairs
from .periodic import check_box, minimum_image

__all__ = [
    "Force",
    "Gravity",
    "Damping",
    "Wind",
    "Attractor",
    "Vortex",
    "Field",
    "NBodyGravity",
    "LennardJones",
    "pair_differences",
    "scatter_pair_forces",
]


class Force:
    """Base class: subclasses implement :meth:`add_to`.

    Attributes
    ----------
    uses_velocity, uses_time : bool
        Whether the force depends on the velocities and on the time. Both
        default to True (always safe); a force that depends on positions
        only sets them False, which lets :meth:`particles.ParticleSystem.run`
        reuse the force at the end of a velocity-Verlet step as the force at
        the start of the next one instead of computing it again.
    """

    uses_velocity = True
    uses_time = True

    def add_to(self, F, x, v, t, m):
        """Add this force into `F` (shape (n, d), newtons), in place."""
        raise NotImplementedError

    def __call__(self, x, v=None, t=0.0, m=1.0):
        """This force alone, for positions `x` and velocities `v`.

        Parameters
        ----------
        x : array_like, shape (n, d)
            Positions, in metres.
        v : array_like, shape (n, d), optional
            Velocities, in m/s (default zero).
        t : float
            Time, in seconds.
        m : float or array_like, shape (n,)
            Masses, in kg, > 0.

        Returns
        -------
        ndarray, shape (n, d)
            The force on each particle, in newtons.
        """
        x = as_float_array(x, "x", ndim=2)
        v = np.zeros_like(x) if v is None else as_float_array(v, "v", shape=x.shape)
        m = as_float_array(m, "m", ndim=(0, 1))
        if m.ndim == 1 and m.shape != (len(x),):
            raise ValueError(f"m must be a number or have shape ({len(x)},), got shape {m.shape}")
        if np.any(m <= 0):
            raise ValueError("m must be positive: every mass must be > 0 kg")
        m = np.broadcast_to(m, (len(x),))
        t = finite_real(t, "t", "seconds")
        F = np.zeros_like(x)
        self.add_to(F, x, v, t, m)
        return F

    def __repr__(self):
        fields = ", ".join(f"{k}={v!r}" for k, v in vars(self).items() if not k.startswith("_"))
        return f"{type(self).__name__}({fields})"


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
            scale += self.gust * np.sin(2.0 * np.pi * (t / self.period - along / self.wavelength))
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


def pair_differences(x, i, j):
    """``x[i] - x[j]`` for each pair, as an array of shape (d, p).

    One row per axis: gathering from the contiguous columns of ``x`` is
    several times faster than fancy-indexing rows of an (n, d) array.

    Parameters
    ----------
    x : ndarray, shape (n, d)
        Positions, in metres.
    i, j : ndarray of int, shape (p,)
        The two particles of each pair, valid indices into `x` (not checked:
        this runs inside every force evaluation).

    Returns
    -------
    ndarray, shape (d, p)
        Column ``k`` is ``x[i[k]] - x[j[k]]``, in metres (the transpose of
        ``x[i] - x[j]``).

    Examples
    --------
    >>> import numpy as np
    >>> pair_differences(np.array([[0.0, 0.0], [1.0, 2.0]]), np.array([1]), np.array([0]))
    array([[1.],
           [2.]])
    """
    xt = np.ascontiguousarray(x.T)
    d = np.empty((xt.shape[0], len(i)))
    x_j = np.empty(len(i))
    for a, xa in enumerate(xt):  # a loop over the d coordinates
        np.take(xa, i, out=d[a], mode="clip")  # "clip": unbuffered, indices are valid
        np.take(xa, j, out=x_j, mode="clip")
        d[a] -= x_j
    return d


def scatter_pair_forces(F, i, j, f_ij):
    """Add ``f_ij`` to particles ``i`` and ``-f_ij`` to particles ``j``.

    Parameters
    ----------
    F : ndarray, shape (n, d)
        Force array, updated in place.
    i, j : ndarray of int, shape (p,)
        The two particles of each pair.
    f_ij : ndarray, shape (p, d)
        Force on ``i`` due to ``j``; ``j`` receives the opposite (Newton's
        third law), so the total momentum is conserved to round-off. The
        transpose of a (d, p) array is fastest (contiguous columns).

    Notes
    -----
    ``np.bincount`` sums the contributions of all pairs sharing a particle
    without a Python loop (``F[i] += f`` would drop repeated indices).
    """
    n = len(F)
    for a in range(F.shape[1]):  # a loop over the d coordinates
        F[:, a] += np.bincount(i, f_ij[:, a], minlength=n) - np.bincount(j, f_ij[:, a], minlength=n)


class NBodyGravity(Force):
    """Mutual gravitation of all pairs: ``|F_ij| = G m_i m_j / r^2``.

    ``F_i = sum_j G m_i m_j (x_j - x_i) / (|x_j - x_i|^2 + eps^2)^(3/2)``

    Parameters
    ----------
    G : float
        Gravitational constant in the model's units (``6.674e-11`` m^3/(kg s^2)
        in SI; 1 in most demos).
    softening : float
        ``eps``, in metres, >= 0. Plummer softening: removes the singularity
        when two particles pass close; 0 gives the exact inverse-square law.

    Notes
    -----
    O(n^2) time, computed in blocks of rows so memory stays O(n). Pairs are
    antisymmetric term by term, so the total force is zero to round-off.

    Open space only: gravity reaches every copy of a periodic box, so the
    minimum image (one copy per pair, as for :class:`LennardJones`) would
    be wrong, and a periodic sum needs Ewald or particle-mesh methods.
    """

    uses_velocity = False
    uses_time = False

    def __init__(self, G=1.0, softening=0.0):
        self.G = positive_number(G, "G")
        self.softening = nonnegative_number(softening, "softening", "metres")

    def add_to(self, F, x, v, t, m):
        n = len(x)
        xt = np.ascontiguousarray(x.T)  # (d, n): one row per coordinate
        block = max(1, 1_000_000 // max(n, 1))
        for a in range(0, n, block):  # a loop over blocks of rows
            b = min(n, a + block)
            r = xt[:, None, :] - xt[:, a:b, None]  # (d, block, n): x_j - x_i
            r2 = np.einsum("kij,kij->ij", r, r) + self.softening**2
            r2[np.arange(b - a), np.arange(a, b)] = np.inf  # no self-force
            w = self.G * m[a:b, None] * m[None, :] / (r2 * np.sqrt(r2))
            F[a:b] += np.einsum("ij,kij->ik", w, r)

    def potential_energy(self, x, m, t=0.0):
        """``-sum_{i<j} G m_i m_j / sqrt(r^2 + eps^2)``, in joules."""
        i, j = np.triu_indices(len(x), k=1)
        r2 = np.sum((x[i] - x[j]) ** 2, axis=1) + self.softening**2
        return -self.G * float(np.sum(m[i] * m[j] / np.sqrt(r2)))


def _power(base, p, out=None):
    """``base ** p``; small integer powers by in-place multiplication (much faster).

    With `out` (an array of the shape of `base`) the result is written there.
    """
    if float(p).is_integer() and 1 <= p <= 16:
        if out is None:
            result = base.copy()
        else:
            result = out
            result[...] = base
        for _ in range(int(p) - 1):  # a loop over the exponent, not the particles
            result *= base
        return result
    return np.power(base, p, out=out)


# Pairs handled together by the Lennard-Jones force pass: all temporaries of
# a chunk stay in the processor's cache (and at least 2 n, so that the
# per-chunk scatter into n-long arrays stays a small part of the work).
_PAIR_CHUNK = 65536


class LennardJones(Force):
    """Pairwise Lennard-Jones interaction, short-ranged: ``f(r) = k1 / r^m - k2 / r^n``.

    The force on particle i due to j is ``f(r) (x_i - x_j) / r`` with
    ``r = |x_i - x_j|``: repulsive (positive ``f``) at short range, attractive
    further out, and zero beyond `cutoff`.

    Parameters
    ----------
    k1, k2 : float
        Strengths of the repulsive and attractive terms, >= 0.
    m, n : float
        Their exponents, ``m > n > 1`` (13 and 7 for the classic 12-6
        potential; see :meth:`from_epsilon_sigma`).
    cutoff : float
        Range, in metres: pairs farther apart do not interact.
    neighbors : {"cells", "all"}
        ``"cells"``: bucket grid with a Verlet skin, O(n) at fixed density;
        ``"all"``: every pair, the O(n^2) reference. Both give the same forces.
    skin : float, optional
        Verlet-list skin for ``"cells"``, in metres (default 10% of the
        cutoff). The pair list is rebuilt only when some particle has moved
        more than half the skin; 0 rebuilds at every evaluation.
    cells_per_cutoff : int
        Grid resolution for ``"cells"`` (see :class:`particles.neighbors.CellGrid`).
    box : array_like, shape (d,) or float, optional
        Side lengths ``L`` of a periodic box, in metres (see
        :mod:`particles.periodic`): each pair interacts through its minimum
        image. Every side must be at least ``2 (cutoff + skin)``. Positions
        may leave the box (they need not be wrapped). Default: open space.

    Attributes
    ----------
    last_virial : float
        ``W = sum_{i<j} r_ij . f_ij`` of the latest force evaluation, in
        joules (N m); the pressure is ``(2 K + W) / (d V)``.

    Notes
    -----
    The force is truncated at the cutoff (with a small jump there). The
    potential energy is shifted by default so that it is continuous, which
    makes energy checks meaningful; ``shift=False`` gives the truncated
    potential whose long-range part :meth:`tail_corrections` restores [3]_.

    The force pass works on chunks of pairs that fit the processor's cache,
    with in-place arithmetic: ``1/r^2`` once, the pair virial
    ``r f(r) = k1 r^(1-m) - k2 r^(1-n)`` from its powers, ``f / r`` from it,
    one scatter per chunk (see ``bench/bench_lennard_jones.py``).

    References
    ----------
    .. [3] M. P. Allen and D. J. Tildesley, *Computer Simulation of Liquids*,
       2nd ed., 2017, sections 1.4.3, 2.8 (long-range corrections) and 5.3.
    """

    uses_velocity = False
    uses_time = False

    def __init__(self, k1, k2, m, n, cutoff, neighbors="cells", skin=None, cells_per_cutoff=3, box=None):
        self.k1 = nonnegative_number(k1, "k1")
        self.k2 = nonnegative_number(k2, "k2")
        self.m = positive_number(m, "m")
        self.n = positive_number(n, "n")
        if not self.m > self.n > 1:
            raise ValueError(f"exponents must satisfy m > n > 1, got m={m!r}, n={n!r}")
        self.cutoff = positive_number(cutoff, "cutoff", "metres")
        if neighbors not in ("cells", "all"):
            raise ValueError(f"neighbors must be 'cells' or 'all', got {neighbors!r}")
        self.neighbors = neighbors
        skin = 0.1 * self.cutoff if skin is None else skin
        self._list = VerletList(self.cutoff, skin, cells_per_cutoff, box=box)
        self.box = self._list.box
        self.last_virial = 0.0
        self._last_distances = None

    @classmethod
    def from_epsilon_sigma(cls, epsilon=1.0, sigma=1.0, cutoff=None, **options):
        """The 12-6 potential ``4 eps ((sigma/r)^12 - (sigma/r)^6)``.

        Its force is ``48 eps sigma^12 / r^13 - 24 eps sigma^6 / r^7``, i.e.
        ``k1 = 48 eps sigma^12``, ``m = 13``, ``k2 = 24 eps sigma^6``, ``n = 7``.

        Parameters
        ----------
        epsilon : float
            Depth of the potential well, in joules, > 0 (``U(r_min) = -epsilon``).
        sigma : float
            Distance where the potential crosses zero, in metres, > 0; the
            force vanishes at ``r_min = 2^(1/6) sigma ~ 1.12 sigma``.
        cutoff : float, optional
            Range, in metres (default ``2.5 sigma``).
        **options
            Other arguments of :class:`LennardJones` (`neighbors`, `skin`,
            `cells_per_cutoff`, `box`).

        Returns
        -------
        LennardJones

        Examples
        --------
        >>> lj = LennardJones.from_epsilon_sigma(epsilon=1.0, sigma=1.0)
        >>> float(abs(lj.magnitude(2 ** (1 / 6)))) < 1e-12     # no force at the minimum
        True
        """
        epsilon = positive_number(epsilon, "epsilon")
        sigma = positive_number(sigma, "sigma")
        cutoff = 2.5 * sigma if cutoff is None else cutoff
        return cls(48 * epsilon * sigma**12, 24 * epsilon * sigma**6, 13, 7, cutoff, **options)

    @property
    def skin(self):
        """Verlet-list skin, in metres."""
        return self._list.skin

    @property
    def neighbor_list(self):
        """The :class:`~particles.neighbors.VerletList` of the ``"cells"`` mode (``builds`` counts rebuilds)."""
        return self._list

    def reset(self):
        """Forget the cached pair list (particles were added, removed or reordered)."""
        self._list.reset()
        self._last_distances = None

    def magnitude(self, r):
        """``f(r) = k1 / r^m - k2 / r^n`` for distances `r` (no cutoff applied).

        Parameters
        ----------
        r : float or array_like, any shape
            Distances between two particles, in metres, > 0.

        Returns
        -------
        ndarray, shape of `r`
            Signed magnitude of the force, in newtons: positive repels,
            negative attracts.
        """
        r = np.asarray(r, dtype=float)
        return self.k1 / r**self.m - self.k2 / r**self.n

    def _pair_virials(self, inv_r2, out, tmp):
        """``r f(r) = k1 s^-p - k2 s^-q`` from ``1/s = 1/r^2``, with ``p = (m-1)/2``, ``q = (n-1)/2``.

        Written ``s^-q (k1 s^-(p-q) - k2)`` it takes a handful of in-place
        multiplications (12-6: ``u^3 (k1 u^3 - k2)`` with ``u = 1/r^2``).
        Zero where `inv_r2` is zero (pairs beyond the cutoff).
        """
        p, q = (self.m - 1) / 2, (self.n - 1) / 2
        s_q = _power(inv_r2, q, out=tmp)
        g = np.multiply(s_q if p - q == q else _power(inv_r2, p - q, out=out), self.k1, out=out)
        g -= self.k2
        g *= s_q
        return g

    def _pair_weights(self, r2):
        """``f(r) / r`` and ``r f(r)`` from squared distances ``s = r^2``, both zero beyond the cutoff."""
        inv_r2 = np.divide(1.0, r2)
        inv_r2 *= r2 < self.cutoff**2
        g = self._pair_virials(inv_r2, np.empty_like(inv_r2), np.empty_like(inv_r2))
        return inv_r2 * g, g

    def add_to(self, F, x, v, t, m):
        if self.neighbors == "all":
            self._add_all_pairs(F, x)
            return
        perm, i, j = self._list.ranked_pairs(x)  # ranks in cell order: neighbours are near in memory
        n_pairs, d, n = len(i), x.shape[1], len(x)
        xs = np.empty((d, n))  # positions by rank, one row per coordinate
        for a in range(d):  # a loop over the d coordinates
            np.take(x[:, a], perm, out=xs[a])
        Fs = np.zeros((d, n))  # forces by rank
        size = max(1, min(n_pairs, max(_PAIR_CHUNK, 2 * n)))
        r = np.empty((d, size))  # x_i - x_j, then the force on i, one row per axis
        r2, inv_r2, g, tmp, x_j = (np.empty(size) for _ in range(5))
        inside = np.empty(size, dtype=bool)
        rc2, virial = self.cutoff**2, 0.0
        for c in range(0, n_pairs, size):  # a loop over chunks of pairs, each small enough for the cache
            ic, jc = i[c:c + size], j[c:c + size]
            k = len(ic)
            rk, r2k, ik, gk, tk, xk, mk = (a[..., :k] for a in (r, r2, inv_r2, g, tmp, x_j, inside))
            lo, hi = min(ic.min(), jc.min()), max(ic.max(), jc.max()) + 1  # the ranks the chunk touches
            if hi - lo < n:
                ic, jc = ic - lo, jc - lo
            else:
                lo, hi = 0, n
            for a in range(d):  # a loop over the d coordinates: gather, subtract
                np.take(xs[a, lo:hi], ic, out=rk[a], mode="clip")  # "clip": unbuffered, indices are valid
                np.take(xs[a, lo:hi], jc, out=xk, mode="clip")
                rk[a] -= xk
            self._list.minimum_image(rk, c, c + k)
            np.einsum("ap,ap->p", rk, rk, out=r2k)
            np.less(r2k, rc2, out=mk)
            np.divide(1.0, r2k, out=ik)
            ik *= mk  # 1/r^2, zero beyond the cutoff
            gk = self._pair_virials(ik, gk, tk)  # r f(r): the pair's virial
            virial += float(gk.sum())
            ik *= gk  # f(r) / r
            for a in range(d):  # a loop over the d coordinates: f_ij = (x_i - x_j) f / r, scattered
                rk[a] *= ik
                Fs[a, lo:hi] += np.bincount(ic, rk[a], minlength=hi - lo)
                Fs[a, lo:hi] -= np.bincount(jc, rk[a], minlength=hi - lo)
        for a in range(d):  # a loop over the d coordinates: back from ranks to particles
            F[perm, a] += Fs[a]
        self.last_virial = virial

    def _add_all_pairs(self, F, x):
        """The O(n^2) reference: every particle against every other."""
        n = len(x)
        xt = np.ascontiguousarray(x.T)  # (d, n): one row per coordinate
        L = None if self.box is None else check_box(self.box, x.shape[1])
        block = max(1, 1_000_000 // max(n, 1))
        virial = 0.0
        for a in range(0, n, block):  # a loop over blocks of rows
            b = min(n, a + block)
            d = xt[:, a:b, None] - xt[:, None, :]  # (d, block, n): x_i - x_j
            if L is not None:
                d -= (L * np.rint(d.T / L)).T  # the minimum image
            r2 = np.einsum("kij,kij->ij", d, d)
            r2[np.arange(b - a), np.arange(a, b)] = np.inf  # no self-force
            w, g = self._pair_weights(r2)
            virial += 0.5 * float(np.sum(g))  # each pair seen twice
            F[a:b] += np.einsum("ij,kij->ik", w, d)
        self.last_virial = virial

    def pair_potential(self, r, shift=True):
        """Potential ``U(r) - U(cutoff)`` for ``r < cutoff``, 0 beyond, in joules.

        ``U(r) = k1 / ((m - 1) r^(m-1)) - k2 / ((n - 1) r^(n-1))`` so that
        ``f = -dU/dr``.

        Parameters
        ----------
        r : float or array_like, any shape
            Distances between two particles, in metres, > 0.
        shift : bool
            True (default): shifted to be continuous (zero) at the cutoff.
            False: the truncated ``U(r)`` itself (``U(r_c)`` just inside the
            cutoff, 0 beyond), the potential of the NIST reference tables.

        Returns
        -------
        ndarray, shape of `r`
            Pair potential energy, in joules.
        """
        r = np.asarray(r, dtype=float)

        def U(s):
            return self.k1 / ((self.m - 1) * s ** (self.m - 1)) - self.k2 / ((self.n - 1) * s ** (self.n - 1))

        return np.where(r < self.cutoff, U(r) - (U(self.cutoff) if shift else 0.0), 0.0)

    def _distances(self, x):
        """Distances of the pairs closer than the cutoff (minimum image in a box), shape (p,).

        The last result is kept: the energy and the virial of the same
        positions cost one pair search.
        """
        x = as_float_array(x, "x", ndim=2)
        last = self._last_distances
        if last is not None and last[0].shape == x.shape and np.array_equal(last[0], x):
            return last[1]
        if self.neighbors == "all":
            i, j = all_pairs(x, self.cutoff, box=self.box)
            r = pair_differences(x, i, j)
            if self.box is not None:
                r = minimum_image(r, self.box, axis=0)
        else:
            i, j = self._list.pairs(x)
            r = self._list.minimum_image(pair_differences(x, i, j))
        r2 = np.einsum("ap,ap->p", r, r)
        distances = np.sqrt(r2[r2 < self.cutoff**2])
        self._last_distances = (x.copy(), distances)
        return distances

    def potential_energy(self, x, m=None, t=0.0, shift=True):
        """Total potential energy of positions `x`, in joules.

        Parameters
        ----------
        x : array_like, shape (n, d)
            Positions, in metres.
        m, t
            Unused (the signature of every force's potential energy).
        shift : bool
            Shifted potential (default) or the truncated one (``shift=False``,
            see :meth:`pair_potential`).

        Returns
        -------
        float
            ``sum_{i<j, r_ij < cutoff} U(r_ij)``, in joules (minimum images
            in a periodic box).
        """
        return float(np.sum(self.pair_potential(self._distances(x), shift=shift)))

    def virial(self, x):
        """``W = sum_{i<j} r_ij . f_ij = sum r f(r)`` over the pairs within the cutoff, in joules.

        The pressure of a periodic system of volume ``V`` in ``d`` dimensions
        with kinetic energy ``K`` is ``p = (2 K + W) / (d V)`` [3]_ (add
        :meth:`tail_corrections` for the part beyond the cutoff).

        Parameters
        ----------
        x : array_like, shape (n, d)
            Positions, in metres.

        Returns
        -------
        float
            The virial, in joules: positive when the pairs repel on balance.
        """
        r = self._distances(x)
        return float(np.sum(r * self.magnitude(r)))

    def tail_corrections(self, density, d=3):
        """Energy per particle and pressure of the interactions beyond the cutoff, for ``g(r) = 1`` there.

        Assuming a uniform fluid beyond the cutoff (the pair distribution
        ``g(r) = 1``), the truncated potential misses [3]_

        ``u_tail = (rho / 2) int_rc^inf U(r) S_d r^(d-1) dr`` per particle and
        ``p_tail = (rho^2 / (2 d)) int_rc^inf r f(r) S_d r^(d-1) dr``,

        with ``S_3 = 4 pi``, ``S_2 = 2 pi``. For the 12-6 potential in 3D:
        ``u_tail = (8/3) pi rho eps sigma^3 ((1/3)(sigma/rc)^9 - (sigma/rc)^3)`` and
        ``p_tail = (16/3) pi rho^2 eps sigma^3 ((2/3)(sigma/rc)^9 - (sigma/rc)^3)``.
        They belong to the *truncated* potential (``shift=False``).

        Parameters
        ----------
        density : float
            Number density ``rho = N / V``, in particles per m^d, > 0.
        d : {2, 3}
            Dimension of space.

        Returns
        -------
        u_tail : float
            Energy per particle, in joules (negative: the missing attraction).
        p_tail : float
            Pressure, in pascals (N/m^2 in 3D, N/m in 2D).

        Raises
        ------
        ValueError
            For a density that is not positive, ``d`` not 2 or 3, or
            exponents for which the integrals diverge (``n <= d + 1``).

        Examples
        --------
        >>> lj = LennardJones.from_epsilon_sigma(cutoff=3.0)
        >>> [round(c, 3) for c in lj.tail_corrections(0.86)]     # NIST's state point
        [-0.267, -0.459]
        """
        rho = positive_number(density, "density", "particles per m^d")
        if d not in (2, 3):
            raise ValueError(f"d must be 2 or 3, got {d!r}")
        if self.n <= d + 1:
            raise ValueError(f"the tail integrals diverge for n <= d + 1 = {d + 1}, got n = {self.n:g}")
        S, rc = (2 * np.pi, 4 * np.pi)[d - 2], self.cutoff
        terms = ((1.0, self.k1, self.m), (-1.0, self.k2, self.n))  # (sign, k, exponent) of each term of f
        # int_rc^inf k r^(d-e) dr = k rc^(d+1-e) / (e - d - 1), and U carries a factor 1 / (e - 1)
        p_int = sum(s * k * rc ** (d + 1 - e) / (e - d - 1) for s, k, e in terms)
        u_int = sum(s * k * rc ** (d + 1 - e) / ((e - 1) * (e - d - 1)) for s, k, e in terms)
        return float(0.5 * rho * S * u_int), float(rho**2 / (2 * d) * S * p_int)
