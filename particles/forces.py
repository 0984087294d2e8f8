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
from .neighbors import VerletList, cell_pairs

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
    """Base class: subclasses implement :meth:`add_to`."""

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
    """

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


def _power(base, p):
    """``base ** p``; small integer powers by in-place multiplication (much faster)."""
    if float(p).is_integer() and 1 <= p <= 16:
        result = base.copy()
        for _ in range(int(p) - 1):  # a loop over the exponent, not the particles
            result *= base
        return result
    return base**p


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

    Notes
    -----
    The force is truncated at the cutoff (with a small jump there); the
    potential energy is shifted so that it is continuous, which makes
    energy checks meaningful [3]_.

    References
    ----------
    .. [3] M. P. Allen and D. J. Tildesley, *Computer Simulation of Liquids*,
       2nd ed., 2017, sections 1.4.3 and 5.3.
    """

    def __init__(self, k1, k2, m, n, cutoff, neighbors="cells", skin=None, cells_per_cutoff=3):
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
        self._list = VerletList(self.cutoff, skin, cells_per_cutoff)

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
            `cells_per_cutoff`).

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

    def _pair_weights(self, r2):
        """``f(r) / r`` from squared distances ``s = r^2``, zero beyond the cutoff.

        ``f(r) / r = k1 / r^(m+1) - k2 / r^(n+1) = s^-q (k1 s^-(p-q) - k2)`` with
        ``p = (m+1)/2``, ``q = (n+1)/2``: written this way it takes a handful of
        in-place multiplications (for the 12-6 force: ``s^-4 (k1 s^-3 - k2)``).
        """
        inv_r2 = 1.0 / r2
        p, q = (self.m + 1) / 2, (self.n + 1) / 2
        w = _power(inv_r2, p - q)
        w *= self.k1
        w -= self.k2
        w *= _power(inv_r2, q)
        w *= r2 < self.cutoff**2
        return w

    def add_to(self, F, x, v, t, m):
        if self.neighbors == "all":
            self._add_all_pairs(F, x)
            return
        i, j = self._list.pairs(x)
        d = pair_differences(x, i, j)  # (d, p): x_i - x_j, one row per axis
        r2 = np.einsum("ap,ap->p", d, d)
        d *= self._pair_weights(r2)  # (x_i - x_j) f(r) / r
        scatter_pair_forces(F, i, j, d.T)

    def _add_all_pairs(self, F, x):
        """The O(n^2) reference: every particle against every other."""
        n = len(x)
        xt = np.ascontiguousarray(x.T)  # (d, n): one row per coordinate
        block = max(1, 1_000_000 // max(n, 1))
        for a in range(0, n, block):  # a loop over blocks of rows
            b = min(n, a + block)
            d = xt[:, a:b, None] - xt[:, None, :]  # (d, block, n): x_i - x_j
            r2 = np.einsum("kij,kij->ij", d, d)
            r2[np.arange(b - a), np.arange(a, b)] = np.inf  # no self-force
            F[a:b] += np.einsum("ij,kij->ik", self._pair_weights(r2), d)

    def pair_potential(self, r):
        """Potential ``U(r) - U(cutoff)`` for ``r < cutoff``, 0 beyond, in joules.

        ``U(r) = k1 / ((m - 1) r^(m-1)) - k2 / ((n - 1) r^(n-1))`` so that
        ``f = -dU/dr``.

        Parameters
        ----------
        r : float or array_like, any shape
            Distances between two particles, in metres, > 0.

        Returns
        -------
        ndarray, shape of `r`
            Pair potential energy, in joules, shifted to be continuous (zero)
            at the cutoff.
        """
        r = np.asarray(r, dtype=float)

        def U(s):
            return self.k1 / ((self.m - 1) * s ** (self.m - 1)) - self.k2 / ((self.n - 1) * s ** (self.n - 1))

        return np.where(r < self.cutoff, U(r) - U(self.cutoff), 0.0)

    def potential_energy(self, x, m=None, t=0.0):
        """Total shifted potential energy of positions `x`, in joules."""
        i, j = cell_pairs(x, self.cutoff)
        return float(np.sum(self.pair_potential(np.linalg.norm(x[i] - x[j], axis=1))))
