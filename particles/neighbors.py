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

References
----------
.. [1] M. P. Allen and D. J. Tildesley, *Computer Simulation of Liquids*,
   2nd ed., Oxford University Press, 2017, section 5.3 (cell lists).
.. [2] L. Verlet, "Computer experiments on classical fluids. I.", Physical
   Review 159(1), 98-103, 1967 (neighbour lists with a skin).
"""

import numpy as np

from ._checks import as_float_array, nonnegative_number, positive_number

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
        the box between the 1% and 99% quantiles.
    max_cells : int, optional
        Largest number of cells (default ``max(4096, 8 n)``).

    Attributes
    ----------
    cell_size : float
    shape : tuple of int
        Cells along each axis, including ``k`` empty padding cells on each side.
    order : ndarray of int, shape (n,)
        Particle indices sorted by cell.
    start : ndarray of int, shape (n_cells + 1,)
        Particles of cell ``c`` are ``order[start[c]:start[c + 1]]``.

    Examples
    --------
    >>> grid = CellGrid([[0.0, 0.0], [0.5, 0.0], [3.0, 0.0]], cutoff=1.0)
    >>> grid.pairs()
    (array([0]), array([1]))
    """

    def __init__(self, x, cutoff, cells_per_cutoff=3, bounds=None, max_cells=None):
        x = as_float_array(x, "x", ndim=2)
        n, d = x.shape
        self.cutoff = positive_number(cutoff, "cutoff")
        if isinstance(cells_per_cutoff, bool) or not isinstance(cells_per_cutoff, (int, np.integer)) or cells_per_cutoff < 1:
            raise ValueError(f"cells_per_cutoff must be a positive integer, got {cells_per_cutoff!r}")
        self.k = k = int(cells_per_cutoff)
        self.cell_size = cell = self.cutoff / k * _CELL_INFLATION
        max_cells = max(4096, 8 * n) if max_cells is None else int(max_cells)
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
        n_cells = int(np.prod(self.shape))
        self.start = np.zeros(n_cells + 1, dtype=np.int64)
        np.cumsum(np.bincount(self.sorted_key, minlength=n_cells), out=self.start[1:])
        self._x_sorted = [np.ascontiguousarray(x[self.order, a]) for a in range(d)]

    def _rows(self):
        """Half stencil: (row key offset, reach along axis 0) for each row."""
        d, k, cell = len(self.shape), self.k, self.cell_size
        if d == 1:
            return k, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        r = np.arange(-k, k + 1)
        rows = np.stack(np.meshgrid(*[r] * (d - 1), indexing="ij"), axis=-1).reshape(-1, d - 1)
        gap2 = np.sum((np.maximum(np.abs(rows) - 1, 0) * cell) ** 2, axis=1)
        # keep rows whose closest cells can hold a pair, reach kx along axis 0
        keep = gap2 < self.cutoff**2
        rows, gap2 = rows[keep], gap2[keep]
        reach = np.minimum(np.ceil(np.sqrt(self.cutoff**2 - gap2) / cell), k).astype(np.int64)
        # half of the rows: the last non-zero component is positive
        last = rows[:, ::-1]
        nonzero = last != 0
        first = np.argmax(nonzero, axis=1)
        sign = np.where(nonzero.any(axis=1), last[np.arange(len(rows)), first], 0)
        own = sign == 0
        half = sign > 0
        return reach[own][0], rows[half] @ self.strides[1:], reach[half]

    def pairs(self, block=16384):
        """All pairs closer than the cutoff, each unordered pair once.

        Parameters
        ----------
        block : int
            Particles handled together; blocks keep the temporary arrays in
            the processor's cache (results do not depend on it).

        Returns
        -------
        i, j : ndarray of int, shape (p,)
            Particle indices (into the `x` given), ``i != j``.
        """
        n = len(self.order)
        own_reach, row_keys, reaches = self._rows()
        found_i, found_j = [], []
        for b in range(0, n, block):  # a loop over blocks of particles
            idx = np.arange(b, min(n, b + block))
            key = self.sorted_key[b:b + block]
            # the particle's own row: later particles in its cell and the next cells
            slices = [(idx + 1, self.start[key + own_reach + 1])]
            for row_key, reach in zip(row_keys, reaches):  # a loop over stencil rows
                centre = key + row_key
                slices.append((self.start[centre - reach], self.start[centre + reach + 1]))
            for lo, hi in slices:
                i, j = _expand(idx, lo, hi)
                close = self._squared_distances(i, j) < self.cutoff**2
                found_i.append(i[close])
                found_j.append(j[close])
        if not found_i:
            empty = np.zeros(0, dtype=np.int64)
            return empty, empty
        i, j = np.concatenate(found_i), np.concatenate(found_j)
        return self.order[i], self.order[j]

    def _squared_distances(self, i, j):
        """|x_i - x_j|^2 for sorted indices, with in-place arithmetic (fewer temporaries)."""
        r2 = np.zeros(len(i))
        x_i, x_j = np.empty(len(i)), np.empty(len(i))
        for xa in self._x_sorted:  # a loop over the d coordinates
            np.take(xa, i, out=x_i, mode="clip")  # "clip": unbuffered, indices are valid
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


def cell_pairs(x, cutoff, cells_per_cutoff=3, bounds=None):
    """Pairs of points closer than `cutoff`, found with a bucket grid in O(n).

    Parameters
    ----------
    x : array_like, shape (n, d)
    cutoff : float
    cells_per_cutoff : int
    bounds : (lo, hi), optional
        See :class:`CellGrid`.

    Returns
    -------
    i, j : ndarray of int, shape (p,)
        Each unordered pair with ``|x[i] - x[j]| < cutoff`` once.
    """
    return CellGrid(x, cutoff, cells_per_cutoff, bounds).pairs()


def all_pairs(x, cutoff):
    """Pairs closer than `cutoff` by testing all n (n - 1) / 2 pairs: the O(n^2) reference.

    Returns the same pairs as :func:`cell_pairs` (possibly in another order).
    Works in blocks of rows so that memory stays bounded.

    Parameters
    ----------
    x : array_like, shape (n, d)
        Positions, finite (in metres, or any unit shared with `cutoff`).
    cutoff : float
        Interaction range, > 0: pairs with distance strictly below it are listed.

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
    rc2 = positive_number(cutoff, "cutoff") ** 2
    n = len(x)
    block = max(1, 2_000_000 // max(n, 1))
    found_i, found_j = [], []
    for a in range(0, n, block):  # a loop over blocks of rows
        b = min(n, a + block)
        r2 = np.sum((x[a:b, None, :] - x[None, :, :]) ** 2, axis=-1)
        i, j = np.nonzero(r2 < rc2)
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

    Attributes
    ----------
    builds : int
        How many times the list has been built.

    Notes
    -----
    The list assumes that particle ``i`` stays particle ``i``. It is rebuilt
    automatically when the number of particles changes; call :meth:`reset`
    after reordering particles without changing their number.
    """

    def __init__(self, cutoff, skin, cells_per_cutoff=3):
        self.cutoff = positive_number(cutoff, "cutoff")
        self.skin = nonnegative_number(skin, "skin")
        self.cells_per_cutoff = cells_per_cutoff
        self.builds = 0
        self.reset()

    def reset(self):
        """Forget the list; the next call to :meth:`pairs` rebuilds it."""
        self._x_ref = None
        self._pairs = None

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
        x = np.asarray(x, dtype=float)
        if self.needs_rebuild(x):
            if not np.isfinite(x).all():
                if self._pairs is not None and self._x_ref is not None and self._x_ref.shape == x.shape:
                    return self._pairs
                empty = np.zeros(0, dtype=np.int64)
                return empty, empty
            self._pairs = cell_pairs(x, self.cutoff + self.skin, self.cells_per_cutoff)
            self._x_ref = x.copy(order="K")
            self.builds += 1
        return self._pairs
