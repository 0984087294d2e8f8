"""The Lennard-Jones pair force, short-ranged, on the bucket grid with a Verlet list.

``f(r) = k1 / r^m - k2 / r^n`` along the line between two particles closer
than a cutoff: repulsive at short range, attractive further out. Pairs come
from :class:`particles.neighbors.VerletList` (O(n) at fixed density), or from
all pairs as the O(n^2) reference; in a periodic box each pair interacts
through its minimum image.

References
----------
.. [1] J. E. Lennard-Jones, "On the determination of molecular fields",
   Proc. R. Soc. Lond. A 106, 463-477, 1924.
.. [2] M. P. Allen and D. J. Tildesley, *Computer Simulation of Liquids*,
   2nd ed., 2017 (cutoffs, tail corrections, the virial).
"""

import numpy as np

from .._checks import as_float_array, nonnegative_number, positive_number
from ..backends import check_backend, compiled
from ..md.periodic import check_box, minimum_image
from ..neighbors import VerletList, all_pairs
from .force import Force
from .pairs import lennard_jones_virial, pair_differences

__all__ = ["LennardJones"]


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
        potential; see :meth:`from_epsilon_sigma`). The slide's symbols; the
        object stores them as :attr:`m_exp` and :attr:`n_exp` (``lj.m`` and
        ``lj.n`` read them too), and its :meth:`add_to` calls the masses that
        every force receives ``mass``, so that an exponent is never mistaken
        for a mass.
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
        :mod:`particles.md.periodic`): each pair interacts through its minimum
        image. Every side must be at least ``2 (cutoff + skin)``. Positions
        may leave the box (they need not be wrapped). Default: open space.
    backend : {None, "auto", "numpy", "numba"}, optional
        Who runs the ``"cells"`` force pass: this NumPy code, or a compiled
        loop over the listed pairs, by blocks of particles (see
        :mod:`particles.forces.kernels`; None: the global choice, see
        :mod:`particles.backends`). ``"all"`` is always the NumPy reference.

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

    The force pass works on chunks of pairs that fit the processor's cache:
    ``1/r^2`` once, the pair virial ``r f(r) = k1 r^(1-m) - k2 r^(1-n)`` from
    its powers (:func:`particles.forces.pairs.lennard_jones_virial`, which the
    compiled pass inlines), ``f / r`` from it, one scatter per chunk (see
    ``bench/bench_lennard_jones.py``).

    References
    ----------
    .. [3] M. P. Allen and D. J. Tildesley, *Computer Simulation of Liquids*,
       2nd ed., 2017, sections 1.4.3, 2.8 (long-range corrections) and 5.3.
    """

    uses_velocity = False
    uses_time = False

    def __init__(self, k1, k2, m, n, cutoff, neighbors="cells", skin=None, cells_per_cutoff=3, box=None,
                 backend=None):
        self._backend = check_backend(backend)
        self.k1 = nonnegative_number(k1, "k1")
        self.k2 = nonnegative_number(k2, "k2")
        self.m_exp = positive_number(m, "m")  # the slide's m and n, stored under names that are not masses
        self.n_exp = positive_number(n, "n")
        if not self.m_exp > self.n_exp > 1:
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
        self._compiled_pass = None  # the compiled pass's lists and windows, made at its first use

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
            `cells_per_cutoff`, `box`, `backend`).

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
    def m(self):
        """The exponent ``m`` of the repulsive term (the slide's symbol; stored as :attr:`m_exp`)."""
        return self.m_exp

    @property
    def n(self):
        """The exponent ``n`` of the attractive term (the slide's symbol; stored as :attr:`n_exp`)."""
        return self.n_exp

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
        return self.k1 / r**self.m_exp - self.k2 / r**self.n_exp

    def _pair_virials(self, inv_r2):
        """``r f(r)`` from ``1/r^2`` (:func:`~particles.forces.pairs.lennard_jones_virial`); 0 where `inv_r2` is 0."""
        return lennard_jones_virial(inv_r2, self.k1, self.k2, (self.m_exp - 1) / 2, (self.n_exp - 1) / 2)

    def _pair_weights(self, r2):
        """``f(r) / r`` and ``r f(r)`` from squared distances ``s = r^2``, both zero beyond the cutoff."""
        inv_r2 = np.divide(1.0, r2)
        inv_r2 *= r2 < self.cutoff**2
        g = self._pair_virials(inv_r2)
        return inv_r2 * g, g

    def add_to(self, F, x, v, t, mass):
        """Add the pair forces into `F` (shape (n, d), newtons), in place; `v`, `t` and `mass` are unused."""
        if self.neighbors == "all":
            self._add_all_pairs(F, x)
            return
        perm, i, j = self._list.ranked_pairs(x)  # ranks in cell order: neighbours are near in memory
        if compiled(self._backend, len(x)):  # the same law, compiled (particles.forces.kernels)
            from .kernels import LennardJonesPass  # noqa: PLC0415  (imports numba)
            if self._compiled_pass is None:
                self._compiled_pass = LennardJonesPass()
            box = None if self.box is None else check_box(self.box, x.shape[1])
            self.last_virial = self._compiled_pass.add_to(F, x, perm, i, j, self.k1, self.k2, (self.m_exp - 1) / 2,
                                                          (self.n_exp - 1) / 2, self.cutoff, box)
            return
        n_pairs, d, n = len(i), x.shape[1], len(x)
        xs = np.empty((d, n))  # positions by rank, one row per coordinate
        for a in range(d):  # a loop over the d coordinates
            np.take(x[:, a], perm, out=xs[a])
        Fs = np.zeros((d, n))  # forces by rank
        size = max(1, min(n_pairs, max(_PAIR_CHUNK, 2 * n)))
        r = np.empty((d, size))  # x_i - x_j, then the force on i, one row per axis
        r2, inv_r2, x_j = (np.empty(size) for _ in range(3))
        inside = np.empty(size, dtype=bool)
        rc2, virial = self.cutoff**2, 0.0
        for c in range(0, n_pairs, size):  # a loop over chunks of pairs, each small enough for the cache
            ic, jc = i[c:c + size], j[c:c + size]
            k = len(ic)
            rk, r2k, ik, xk, mk = (a[..., :k] for a in (r, r2, inv_r2, x_j, inside))
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
            gk = self._pair_virials(ik)  # r f(r): the pair's virial
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
            return self.k1 / ((self.m_exp - 1) * s ** (self.m_exp - 1)) - self.k2 / ((self.n_exp - 1) * s ** (self.n_exp - 1))

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

    def potential_energy(self, x, mass=None, t=0.0, shift=True):
        """Total potential energy of positions `x`, in joules.

        Parameters
        ----------
        x : array_like, shape (n, d)
            Positions, in metres.
        mass, t
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
        if self.n_exp <= d + 1:
            raise ValueError(f"the tail integrals diverge for n <= d + 1 = {d + 1}, got n = {self.n_exp:g}")
        S, rc = (2 * np.pi, 4 * np.pi)[d - 2], self.cutoff
        terms = ((1.0, self.k1, self.m_exp), (-1.0, self.k2, self.n_exp))  # (sign, k, exponent) of each term of f
        # int_rc^inf k r^(d-e) dr = k rc^(d+1-e) / (e - d - 1), and U carries a factor 1 / (e - 1)
        p_int = sum(s * k * rc ** (d + 1 - e) / (e - d - 1) for s, k, e in terms)
        u_int = sum(s * k * rc ** (d + 1 - e) / ((e - 1) * (e - d - 1)) for s, k, e in terms)
        return float(0.5 * rho * S * u_int), float(rho**2 / (2 * d) * S * p_int)
