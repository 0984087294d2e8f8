"""Neighbour search: which pairs of particles are closer than a cutoff?

Testing all pairs costs O(N^2). When the interaction is short-ranged (the
Lennard-Jones force is negligible beyond ~2.5 sigma, boids only see nearby
boids) a *bucket grid* makes it O(N): space is cut into cubic cells of side
``cutoff / k``; a particle can only interact with particles in the cells at
most ``k`` cells away along each axis, and at fixed density each cell holds a
bounded number of particles.

Implementation (no Python loop over particles):

1. integer cell coordinates ``c = floor((x - lo) / cell)`` and one linear key
   per cell, with axis 0 varying fastest;
2. sort the particles by key; ``start[key]`` is where a cell's particles begin
   in the sorted order, so each cell is a contiguous slice;
3. cells that differ only along axis 0 are *consecutive* keys, so a whole row
   of ``2k + 1`` cells is one contiguous slice ``start[key - k] : start[key + k + 1]``.
   For each row offset of the (half) stencil, every particle's candidates form
   one slice; all slices are expanded at once with ``np.repeat``;
4. keep the candidates closer than the cutoff.

Each unordered pair is found once (a half stencil, and ``j > i`` within the
particle's own row). :class:`VerletList` adds a skin so that the pair list can
be reused over many steps.

**Periodic boxes** (``box=L``, see :mod:`particles.md.periodic`): the box is cut
into a whole number of cells per axis (each at least ``cutoff / k``), and the
grid wraps around. Along axis 0 the ``k`` cell columns next to each face are
copied, shifted by ``+-L_0``, into padding cells beyond the opposite face, so
that rows stay contiguous slices; along the other axes a row's cell index is
taken modulo the number of cells, and its particles are seen shifted by the
box length. Each candidate is tested with the image it was reached by, so a
stencil that wraps all the way round (a small box) cannot report a pair
twice: only one image of a pair lies within the cutoff when ``L >= 2 cutoff``.

References
----------
.. [1] M. P. Allen and D. J. Tildesley, *Computer Simulation of Liquids*,
   2nd ed., Oxford University Press, 2017, section 5.3 (cell lists).
.. [2] L. Verlet, "Computer experiments on classical fluids. I.", Physical
   Review 159(1), 98-103, 1967 (neighbour lists with a skin).
"""

import numpy as np

from ._checks import as_float_array, nonnegative_number, positive_number
from .md.periodic import box_option, check_box

__all__ = ["CellGrid", "cell_pairs", "all_pairs", "VerletList"]

# Room for floating-point rounding when comparing cell coordinates: cells are
# made this much larger than cutoff / k so that two particles closer than the
# cutoff can never land more than k cells apart.
_CELL_INFLATION = 1.0 + 1e-9


class CellGrid:
    """A uniform bucket grid over a set of points, ready to list close pairs.

    Parameters
    ----------
    x : array_like, shape (n, d)
        Positions (any d >= 1; 2 or 3 in practice).
    cutoff : float
        Interaction range: :meth:`pairs` returns the pairs with distance < cutoff.
    cells_per_cutoff : int
        ``k``: cells have side ``cutoff / k``. Larger ``k`` wastes fewer
        candidates but visits more rows; 3 is fastest in our benchmark
        (``bench/bench_lennard_jones.py``).
    bounds : (array_like, array_like), optional
        ``(lo, hi)``, each shape (d,): the box covered by the grid. Particles
        outside are clamped into the edge cells, which keeps the result exact
        (clamping never moves two cells further apart) but is slower when many
        particles are outside. Default: the bounding box of `x`, or, if that
        would need more than `max_cells` cells because of a few far outliers,
        the box between the 1% and 99% quantiles. Not with `box`.
    max_cells : int, optional
        Largest number of cells (default ``max(4096, 8 n)``).
    box : array_like, shape (d,) or float, optional
        Side lengths ``L`` of a periodic box, in the unit of `x` (see
        :mod:`particles.md.periodic`); each at least ``2 cutoff``. Distances are
        then minimum-image distances, and `x` may lie anywhere (the grid
        wraps a copy into the box). Default ``None``: open space.

    Attributes
    ----------
    cell_size : float, or ndarray of shape (d,) with `box`
        Side of the cells (per axis in a periodic box, whose side is a whole
        number of cells).
    shape : tuple of int
        Cells along each axis, including ``k`` empty padding cells on each
        side (periodic: padding cells along axis 0 only, holding the copies).
    order : ndarray of int, shape (n,) (periodic: more, copies included)
        Particle indices sorted by cell.
    start : ndarray of int, shape (n_cells + 1,)
        Particles of cell ``c`` are ``order[start[c]:start[c + 1]]``.

    Raises
    ------
    ValueError
        For a bad `cutoff` or `cells_per_cutoff`, `bounds` with ``hi < lo``,
        both `bounds` and `box`, or a `box` side not positive or shorter
        than ``2 cutoff`` (the message names the argument).

    Examples
    --------
    >>> grid = CellGrid([[0.0, 0.0], [0.5, 0.0], [3.0, 0.0]], cutoff=1.0)
    >>> grid.pairs()
    (array([0]), array([1]))
    >>> CellGrid([[0.1, 0.0], [3.9, 0.0]], cutoff=1.0, box=4.0).pairs()   # 0.2 apart through the wall
    (array([1]), array([0]))
    """

    def __init__(self, x, cutoff, cells_per_cutoff=3, bounds=None, max_cells=None, box=None):
        x = as_float_array(x, "x", ndim=2)
        n, d = x.shape
        self.cutoff = positive_number(cutoff, "cutoff")
        if isinstance(cells_per_cutoff, bool) or not isinstance(cells_per_cutoff, (int, np.integer)) or cells_per_cutoff < 1:
            raise ValueError(f"cells_per_cutoff must be a positive integer, got {cells_per_cutoff!r}")
        self.k = k = int(cells_per_cutoff)
        max_cells = max(4096, 8 * n) if max_cells is None else int(max_cells)
        self.box = None
        if box is not None:
            if bounds is not None:
                raise ValueError("give bounds (an open grid) or box (a periodic one), not both")
            self._periodic(x, check_box(box, d, self.cutoff), max_cells)
            return
        self.cell_size = cell = self.cutoff / k * _CELL_INFLATION
        lo, hi = _grid_bounds(x, cell, bounds, max_cells)
        # very sparse points: fewer, larger cells (still exact, the stencil adapts)
        cell *= max(1.0, (np.prod(np.floor((hi - lo) / cell) + 1) / max_cells) ** (1.0 / d))
        self.cell_size = cell
        inner = np.floor((hi - lo) / cell).astype(np.int64) + 1
        cells = np.floor((x - lo) / cell)
        cells = np.clip(cells, 0, inner - 1).astype(np.int64) + k  # k padding cells
        self.shape = tuple(int(s) for s in inner + 2 * k)
        self.strides = np.concatenate([[1], np.cumprod(self.shape[:-1])]).astype(np.int64)
        key = cells @ self.strides
        self.order = np.argsort(key, kind="stable")
        self.sorted_key = key[self.order]
        self._index(n)
        self._x_sorted = [np.ascontiguousarray(x[self.order, a]) for a in range(d)]
        self._reach = np.full(d, k)
        self._owners = None  # every sorted particle is a real one

    def _index(self, n_sorted):
        """``start``: where each cell's particles begin in the sorted order."""
        n_cells = int(np.prod(self.shape))
        self.start = np.zeros(n_cells + 1, dtype=np.int64)
        np.cumsum(np.bincount(self.sorted_key, minlength=n_cells), out=self.start[1:])

    def _periodic(self, x, L, max_cells):
        """Set up the wrapped grid: whole cells per axis, copies along axis 0 (see the module notes)."""
        n, d = x.shape
        self.box = L
        count = np.maximum(np.floor(L / (self.cutoff / self.k * _CELL_INFLATION)), 1)
        while np.prod(count) > max_cells and count.max() > 1:  # very sparse: larger cells
            count = np.maximum(np.floor(count / 2), 1)
        count = count.astype(np.int64)
        self.cell_size = cell = L / count
        # cells a pair can span along each axis: at most k, fewer for large cells
        reach = np.minimum(np.ceil(self.cutoff / cell * _CELL_INFLATION), self.k)
        self._reach = reach = reach.astype(np.int64)
        self._count = count
        xw = x - L * np.floor(x / L)  # a wrapped copy
        cells = np.clip(np.floor(xw / cell), 0, count - 1).astype(np.int64)
        pad = int(reach[0])
        self.shape = (int(count[0]) + 2 * pad,) + tuple(int(c) for c in count[1:])
        self.strides = np.concatenate([[1], np.cumprod(self.shape[:-1])]).astype(np.int64)
        cells[:, 0] += pad
        key = cells @ self.strides
        # copies of the columns near the faces of axis 0, beyond the opposite face
        low = np.flatnonzero(cells[:, 0] < 2 * pad)
        high = np.flatnonzero(cells[:, 0] >= count[0])
        source = np.concatenate([np.arange(n), low, high])
        key = np.concatenate([key, key[low] + count[0], key[high] - count[0]])
        shift0 = np.concatenate([np.zeros(n), np.full(len(low), L[0]), np.full(len(high), -L[0])])
        sort = np.argsort(key, kind="stable")  # within a cell the real particles come first
        self.order = source[sort]
        self.sorted_key = key[sort]
        self._index(len(sort))
        self._x_sorted = [np.ascontiguousarray(xw[self.order, a]) for a in range(d)]
        self._x_sorted[0] += shift0[sort]
        self._owners = np.flatnonzero(sort < n)  # sorted positions of the real particles
        owner_cells = cells[self.order[self._owners]]
        self._owner_cells = [np.ascontiguousarray(owner_cells[:, a]) for a in range(d)]

    def _rows(self):
        """Half stencil: reach along axis 0 of the own row; offsets and reaches of the other rows."""
        d = len(self.shape)
        cell = np.broadcast_to(self.cell_size, (d,))
        k = self._reach
        if d == 1:
            return int(k[0]), np.zeros((0, 0), dtype=np.int64), np.zeros(0, dtype=np.int64)
        axes = [np.arange(-k[a], k[a] + 1) for a in range(1, d)]
        rows = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, d - 1)
        gap2 = np.sum((np.maximum(np.abs(rows) - 1, 0) * cell[1:]) ** 2, axis=1)
        # keep rows whose closest cells can hold a pair, reach kx along axis 0
        keep = gap2 < self.cutoff**2
        rows, gap2 = rows[keep], gap2[keep]
        reach = np.minimum(np.ceil(np.sqrt(self.cutoff**2 - gap2) / cell[0]), k[0]).astype(np.int64)
        # half of the rows: the last non-zero component is positive
        last = rows[:, ::-1]
        nonzero = last != 0
        first = np.argmax(nonzero, axis=1)
        sign = np.where(nonzero.any(axis=1), last[np.arange(len(rows)), first], 0)
        own = sign == 0
        half = sign > 0
        return int(reach[own][0]), rows[half], reach[half]

    def pairs(self, block=16384, ranks=False):
        """All pairs closer than the cutoff, each unordered pair once.

        Parameters
        ----------
        block : int
            Particles handled together; blocks keep the temporary arrays in
            the processor's cache (results do not depend on it).
        ranks : bool
            Return the pairs as ranks in the grid's cell order (see Returns):
            nearby particles have nearby ranks, which keeps a force pass
            over the pairs in the processor's cache.

        Returns
        -------
        i, j : ndarray of int, shape (p,)
            Particle indices (into the `x` given), ``i != j``. In a periodic
            box the distance is that of the minimum image.
        perm, i, j : ndarray of int, shapes (n,), (p,), (p,)
            With ``ranks=True``: particle ``perm[r]`` has rank ``r``, and the
            pairs are ``(perm[i], perm[j])``.
        """
        own_reach, rows, reaches = self._rows()
        found_i, found_j = [], []
        periodic = self._owners is not None
        owners = self._owners if periodic else np.arange(len(self.order))
        for b in range(0, len(owners), block):  # a loop over blocks of particles
            idx = owners[b:b + block]
            key = self.sorted_key[idx]
            local = np.arange(len(idx))
            owner_x = [xa[idx] for xa in self._x_sorted]
            # the particle's own row: later particles in its cell and the next cells
            slices = [(idx + 1, self.start[key + own_reach + 1], None)]
            for offset, reach in zip(rows, reaches):  # a loop over stencil rows
                centre, shifts = self._row(b, key, offset)
                slices.append((self.start[centre - reach], self.start[centre + reach + 1], shifts))
            for lo, hi, shifts in slices:
                i, j = _expand(local, lo, hi)
                close = self._squared_distances(owner_x, i, j, shifts) < self.cutoff**2
                found_i.append(i[close] + b)  # the owner's rank
                found_j.append(j[close])
        i = np.concatenate(found_i) if found_i else np.zeros(0, dtype=np.int64)
        j = np.concatenate(found_j) if found_j else np.zeros(0, dtype=np.int64)
        perm = self.order[owners]
        if periodic:  # a sorted position (of a particle or a copy) to the rank of its particle
            rank = np.empty(len(perm), dtype=np.int64)
            rank[perm] = np.arange(len(perm))
            j = rank[self.order].take(j)
        return (perm, i, j) if ranks else (perm[i], perm[j])

    def _row(self, b, key, offset):
        """Key of the centre cell of a stencil row for each owner, and the image shift along each axis."""
        if self.box is None:
            return key + offset @ self.strides[1:], None
        centre, shifts = key.copy(), []
        for a in range(1, len(self.shape)):  # a loop over the d - 1 axes of the row offset
            c = self._owner_cells[a][b:b + len(key)]
            s, wrapped = np.divmod(c + offset[a - 1], self._count[a])  # image shift, cell in the box
            centre += (wrapped - c) * self.strides[a]
            shifts.append(s * self.box[a] if s.any() else None)
        return centre, shifts

    def _squared_distances(self, owner_x, i, j, shifts=None):
        """|x_i - x_j|^2 for owners ``i`` (into the block's `owner_x`) and sorted indices `j`.

        In-place arithmetic keeps the temporaries few. ``shifts[a - 1]`` (per
        owner, or None) is the length the row's candidates are shifted by
        along axis ``a >= 1`` in a periodic box: ``x_i - (x_j + s L)``.
        """
        r2 = np.zeros(len(i))
        x_i, x_j = np.empty(len(i)), np.empty(len(i))
        for a, xa in enumerate(self._x_sorted):  # a loop over the d coordinates
            owner = owner_x[a]
            if a > 0 and shifts is not None and shifts[a - 1] is not None:
                owner = owner - shifts[a - 1]
            np.take(owner, i, out=x_i, mode="clip")  # "clip": unbuffered, indices are valid
            np.take(xa, j, out=x_j, mode="clip")
            x_i -= x_j
            x_i *= x_i
            r2 += x_i
        return r2


def _expand(idx, lo, hi):
    """Pairs (idx[p], q) for every q in lo[p]:hi[p], all p at once."""
    count = np.maximum(hi - lo, 0)
    total = int(count.sum())
    i = np.repeat(idx, count)
    first = np.cumsum(count) - count  # where each slice begins in the output
    j = np.arange(total) + np.repeat(lo - first, count)
    return i, j


def _grid_bounds(x, cell, bounds, max_cells):
    """The box (lo, hi) the grid covers."""
    n, d = x.shape
    if bounds is not None:
        lo = as_float_array(bounds[0], "bounds[0]", shape=(d,))
        hi = as_float_array(bounds[1], "bounds[1]", shape=(d,))
        if np.any(hi < lo):
            raise ValueError(f"bounds must be (lo, hi) with lo <= hi, got {lo} and {hi}")
        return lo, hi
    if n == 0:
        return np.zeros(d), np.zeros(d)
    lo, hi = x.min(axis=0), x.max(axis=0)
    if np.prod(np.floor((hi - lo) / cell) + 1) > max_cells:
        # a few far outliers: cover the bulk, clamp the rest into edge cells
        lo, hi = np.quantile(x, [0.01, 0.99], axis=0)
    return lo, hi


def cell_pairs(x, cutoff, cells_per_cutoff=3, bounds=None, box=None):
    """Pairs of points closer than `cutoff`, found with a bucket grid in O(n).

    Parameters
    ----------
    x : array_like, shape (n, d)
        Positions, finite (in metres, or any unit shared with `cutoff`).
    cutoff : float
        Interaction range, > 0.
    cells_per_cutoff : int
        See :class:`CellGrid`.
    bounds : (lo, hi), optional
        See :class:`CellGrid`.
    box : array_like, shape (d,) or float, optional
        Side lengths of a periodic box (minimum-image distances), each at
        least ``2 cutoff``; see :class:`CellGrid`.

    Returns
    -------
    i, j : ndarray of int, shape (p,)
        Each unordered pair with ``|x[i] - x[j]| < cutoff`` once.
    """
    return CellGrid(x, cutoff, cells_per_cutoff, bounds, box=box).pairs()


def all_pairs(x, cutoff, box=None):
    """Pairs closer than `cutoff` by testing all n (n - 1) / 2 pairs: the O(n^2) reference.

    Returns the same pairs as :func:`cell_pairs` (possibly in another order).
    Works in blocks of rows so that memory stays bounded.

    Parameters
    ----------
    x : array_like, shape (n, d)
        Positions, finite (in metres, or any unit shared with `cutoff`).
    cutoff : float
        Interaction range, > 0: pairs with distance strictly below it are listed.
    box : array_like, shape (d,) or float, optional
        Side lengths of a periodic box, each at least ``2 cutoff``: distances
        are then those of the minimum image.

    Returns
    -------
    i, j : ndarray of int, shape (p,)
        Each unordered pair with ``|x[i] - x[j]| < cutoff`` once, ``i < j``.

    Examples
    --------
    >>> all_pairs([[0.0, 0.0], [0.5, 0.0], [3.0, 0.0]], cutoff=1.0)
    (array([0]), array([1]))
    """
    x = as_float_array(x, "x", ndim=2)
    cutoff = positive_number(cutoff, "cutoff")
    L = None if box is None else check_box(box, x.shape[1], cutoff)
    n = len(x)
    block = max(1, 2_000_000 // max(n, 1))
    found_i, found_j = [], []
    for a in range(0, n, block):  # a loop over blocks of rows
        b = min(n, a + block)
        r = x[a:b, None, :] - x[None, :, :]
        if L is not None:
            r -= L * np.rint(r / L)  # the minimum image
        i, j = np.nonzero(np.sum(r**2, axis=-1) < cutoff**2)
        i = i + a
        later = j > i
        found_i.append(i[later])
        found_j.append(j[later])
    if not found_i:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    return np.concatenate(found_i), np.concatenate(found_j)


class VerletList:
    """A pair list with a skin, reused until some particle has moved too far.

    Pairs closer than ``cutoff + skin`` are listed; the list stays valid (it
    still contains every pair closer than `cutoff`) as long as no particle has
    moved more than ``skin / 2`` since it was built. The caller must still
    test the distance of each listed pair against the cutoff.

    Parameters
    ----------
    cutoff : float
        Interaction range.
    skin : float
        Extra margin, >= 0. With 0 the list is rebuilt as soon as any
        particle has moved at all (it is reused only for identical
        positions). About 10-20% of the cutoff is typical.
    cells_per_cutoff : int
        Passed to :class:`CellGrid`.
    box : array_like, shape (d,) or float, optional
        Side lengths of a periodic box, each at least ``2 (cutoff + skin)``.
        The list then also stores the image of each pair (which copy of `j`
        is the nearest), and :meth:`minimum_image` applies it to pair
        differences without rounding every step.

    Attributes
    ----------
    builds : int
        How many times the list has been built.

    Raises
    ------
    ValueError
        For a bad `cutoff` or `skin`, or a `box` side that is not positive
        or shorter than ``2 (cutoff + skin)``.

    Notes
    -----
    The list assumes that particle ``i`` stays particle ``i``. It is rebuilt
    automatically when the number of particles changes; call :meth:`reset`
    after reordering particles without changing their number.

    In a periodic box, positions need not be wrapped: a trajectory may leave
    the box, the images are found from the positions at each build. A
    particle wrapped by hand between two calls has jumped by ``L``, which
    rebuilds the list (correct, only slower): wrap for display
    (:func:`particles.md.periodic.wrap`), not during a run.
    """

    def __init__(self, cutoff, skin, cells_per_cutoff=3, box=None):
        self.cutoff = positive_number(cutoff, "cutoff")
        self.skin = nonnegative_number(skin, "skin")
        self.cells_per_cutoff = cells_per_cutoff
        self.box = box_option(box, self.cutoff + self.skin, reach="(cutoff + skin)")
        self.builds = 0
        self.reset()

    def reset(self):
        """Forget the list; the next call to :meth:`pairs` rebuilds it."""
        self._x_ref = None
        self._pairs = None
        self._ranked = None
        self._images = []

    def needs_rebuild(self, x):
        """True when the stored list may miss a pair for positions `x`."""
        if self._x_ref is None or self._x_ref.shape != np.shape(x):
            return True
        moved2 = np.max(np.sum((x - self._x_ref) ** 2, axis=1), initial=0.0)
        return bool(4.0 * moved2 > self.skin**2)

    def pairs(self, x):
        """Candidate pairs ``(i, j)`` for positions `x`.

        Every pair closer than the cutoff is included; some listed pairs may
        be farther (up to ``cutoff + skin``).

        Parameters
        ----------
        x : array_like, shape (n, d)
            Current positions, in the unit of the cutoff (metres).

        Returns
        -------
        i, j : ndarray of int, shape (p,)
            Each candidate unordered pair once (the stored list, rebuilt
            first if some particle has moved more than ``skin / 2``).

        Notes
        -----
        Positions that contain inf or NaN (a simulation blowing up, seen in
        the middle of a step) do not rebuild the list: the stored pairs are
        returned when they fit `x`, no pairs otherwise. The force is then
        non-finite or wrong, and the integrator's divergence check reports
        the blow-up (:class:`particles.SimulationDiverged`) instead of the
        grid refusing the positions.
        """
        perm, i, j = self.ranked_pairs(x)
        if self._ranked is None or perm is not self._ranked[0]:  # no stored list fits: no pairs
            return i, j
        if self._pairs is None:
            self._pairs = perm[i], perm[j]
        return self._pairs

    def ranked_pairs(self, x):
        """The candidate pairs as ranks in cell order: ``(perm, i, j)``, pairs ``(perm[i], perm[j])``.

        The same list as :meth:`pairs` (rebuilt under the same rule), in the
        form a force pass prefers: particles near each other in space have
        near ranks, so gathering their positions and scattering their forces
        stays in the processor's cache. :meth:`minimum_image` applies to
        differences taken in this order.

        Parameters
        ----------
        x : array_like, shape (n, d)
            Current positions, in metres.

        Returns
        -------
        perm : ndarray of int, shape (n,)
            Particle of each rank.
        i, j : ndarray of int, shape (p,)
            Ranks of the two particles of each candidate pair.
        """
        x = np.asarray(x, dtype=float)
        if self.needs_rebuild(x):
            if not np.isfinite(x).all():  # a blow-up: keep the stored list if it fits
                if self._ranked is not None and self._x_ref.shape == x.shape:
                    return self._ranked
                empty = np.zeros(0, dtype=np.int64)
                return np.arange(len(x)), empty, empty
            grid = CellGrid(x, self.cutoff + self.skin, self.cells_per_cutoff, box=self.box)
            self._ranked = grid.pairs(ranks=True)
            self._pairs = None
            self._x_ref = x.copy(order="K")
            self._images = self._find_images(x, *self._ranked)
            self.builds += 1
        return self._ranked

    def _find_images(self, x, perm, i, j):
        """Per axis: the listed pairs whose nearest copy of j is shifted, and ``L round((x_i - x_j) / L)``."""
        if self.box is None:
            return []
        L = check_box(self.box, x.shape[1])
        images, size = [], 65536
        x_i, x_j = np.empty(size), np.empty(size)
        for a in range(x.shape[1]):  # a loop over the d coordinates
            xa, s = x[perm, a], np.empty(len(i))  # positions by rank; shifts, in box lengths
            for c in range(0, len(i), size):  # a loop over chunks of pairs, in the cache
                k = min(size, len(i) - c)
                np.take(xa, i[c:c + k], out=x_i[:k])
                np.take(xa, j[c:c + k], out=x_j[:k])
                x_i[:k] -= x_j[:k]
                x_i[:k] *= 1.0 / L[a]
                np.rint(x_i[:k], out=s[c:c + k])
            moved = np.flatnonzero(s)
            if len(moved) > len(s) // 8:  # a small box: many pairs cross, subtract a full array
                images.append((None, s * L[a]))
            else:
                images.append((moved, s[moved] * L[a]))
        return images

    def minimum_image(self, r, start=0, stop=None):
        """Map pair differences of the current list to the minimum image, in place.

        Parameters
        ----------
        r : ndarray, shape (d, p)
            ``x_i - x_j`` for the pairs of the current list, in the order of
            :meth:`pairs` (and of :meth:`ranked_pairs`), in metres, in the
            layout of :func:`particles.forces.pair_differences`; or, with
            `start` and `stop`, for the pairs ``start:stop`` of it.
        start, stop : int, optional
            The slice of the pair list that `r` holds (default: all of it).

        Returns
        -------
        ndarray, shape (d, p)
            `r` itself, with the box shift of each pair subtracted (unchanged
            in open space). Only the pairs that cross the box are touched.
        """
        stop = r.shape[1] + start if stop is None else stop
        for a, (moved, shift) in enumerate(self._images):  # a loop over the d coordinates
            if moved is None:
                r[a] -= shift[start:stop]
                continue
            lo, hi = np.searchsorted(moved, [start, stop])
            if hi > lo:
                r[a, moved[lo:hi] - start] -= shift[lo:hi]
        return r
