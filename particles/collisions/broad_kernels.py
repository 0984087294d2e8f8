"""The broad phase of cloth collisions, compiled (numba): overlapping boxes of vertices, faces and edges.

Imported only by :mod:`particles.collisions.compiled_stages`. The NumPy broad phase
(:mod:`particles.collisions.candidates`) hashes boxes into a bucket grid with
whole-array operations and sorts; here the same grid is a compressed-row
table of the target boxes (faces, or edges) per cell, and each query box
(a vertex's, or an edge's) walks the cells it covers, one loop iteration
per query. A pair is reported from one cell only, the componentwise maximum
of the two boxes' lowest cells, as :func:`particles.collisions.triangle_crossing.box_pairs`
does (each cell's targets are kept in sublists by whether they start in it
along each axis, so that a query walks only those that can report there),
and the closed boxes are then compared exactly: the set of pairs does
not depend on the grid, and it is the NumPy one. Each query writes its own
slice of the output (sized by a bound from the cells it covers, each slice
sorted), so the pairs come out sorted by key and with the same bits on any
number of threads; no atomics. The pairs that hold a vertex of a mask (a few
vertices that moved) come from small grids of the masked elements alone
(:func:`subset_pairs`).
"""

import math

import numpy as np

from ..backends.compile import inline, jit, prange
from .triangle_crossing import intervals_overlap

inline(intervals_overlap)

# queries per block of the parallel passes (a fixed partition: the same blocks for any number of threads)
QUERY_BLOCK = 256


@jit()
def corner_bounds(v_lo, v_hi, idx, lo, hi):
    """``lo[k] = min_j v_lo[idx[k, j]]`` and ``hi[k] = max_j v_hi[idx[k, j]]``: the box around an element's corners.

    The faces' and edges' boxes of :func:`particles.collisions.candidates.candidates_in_boxes` (a gather).
    """
    for k in range(idx.shape[0]):
        for a in range(3):
            lo[k, a] = v_lo[idx[k, 0], a]
            hi[k, a] = v_hi[idx[k, 0], a]
        for j in range(1, idx.shape[1]):
            for a in range(3):
                lo[k, a] = min(lo[k, a], v_lo[idx[k, j], a])
                hi[k, a] = max(hi[k, a], v_hi[idx[k, j], a])


def grid_shape(q_lo, q_hi, t_lo, t_hi):
    """Origin, cell side and shape of a grid for query and target boxes (cell: the median target extent).

    The cell doubles while the grid would have more than ``8 (queries + targets)`` cells or the targets
    would cover more than 8 cells each on average.
    """
    origin = np.empty(3)
    top = np.empty(3)
    for a in range(3):
        origin[a] = min(q_lo[:, a].min(), t_lo[:, a].min())
        top[a] = max(q_hi[:, a].max(), t_hi[:, a].max())
    extent = np.empty(len(t_lo))
    for k in range(len(t_lo)):
        extent[k] = max(t_hi[k, 0] - t_lo[k, 0], t_hi[k, 1] - t_lo[k, 1], t_hi[k, 2] - t_lo[k, 2])
    cell = np.median(extent)
    span = max(top[0] - origin[0], top[1] - origin[1], top[2] - origin[2])
    if not cell > 0:
        cell = span / len(t_lo) ** (1.0 / 3.0) if span > 0 else 1.0
    cell = max(cell, span * 2.0 ** -40, 1e-300)
    shape = np.empty(3, dtype=np.int64)
    limit = 8.0 * (len(q_lo) + len(t_lo)) + 1024.0  # the table holds 8 sublists per cell
    while True:  # a loop over doublings of the cell
        cells = 1.0
        for a in range(3):
            shape[a] = int(math.floor((top[a] - origin[a]) / cell)) + 1
            cells *= shape[a]
        covered = 0.0
        for k in range(len(t_lo)):
            c = 1.0
            for a in range(3):
                c *= math.floor((t_hi[k, a] - origin[a]) / cell) - math.floor((t_lo[k, a] - origin[a]) / cell) + 1
            covered += c
        if cells <= limit and covered <= 8.0 * len(t_lo) + 1024.0:
            return origin, cell, shape
        cell *= 2.0


def cell_of(x, origin, cell, shape, a):
    """The grid cell of coordinate `x` along axis `a`, clamped to the grid (monotone in `x`)."""
    c = int(math.floor((x - origin[a]) / cell))
    return min(max(c, 0), shape[a] - 1)


def cell_table(t_lo, t_hi, origin, cell, shape):
    """The targets per cell, in compressed rows of 8 sublists per cell: ``ptr`` (8 cells
    + 1) and ``items``.

    Sublist ``8 c + s`` of cell ``c = (i, j, l)`` holds the targets whose lowest cell is ``i`` along the
    first axis when bit 4 of ``s`` is set (else lower), likewise ``j`` for bit 2 and ``l`` for bit 1; each
    sublist in increasing target. A pair is reported from one cell, the componentwise maximum of the two
    boxes' lowest cells: past a query's lowest cell along an axis, only targets that start there qualify,
    so the query walks only the sublists that can report (:func:`wanted`).
    """
    cells = shape[0] * shape[1] * shape[2]
    low = np.empty((len(t_lo), 3), dtype=np.int64)
    high = np.empty((len(t_lo), 3), dtype=np.int64)
    ptr = np.zeros(8 * cells + 1, dtype=np.int64)
    for k in range(len(t_lo)):
        for a in range(3):
            low[k, a] = cell_of(t_lo[k, a], origin, cell, shape, a)
            high[k, a] = cell_of(t_hi[k, a], origin, cell, shape, a)
        for i in range(low[k, 0], high[k, 0] + 1):
            for j in range(low[k, 1], high[k, 1] + 1):
                for l in range(low[k, 2], high[k, 2] + 1):
                    sub = 4 * (i == low[k, 0]) + 2 * (j == low[k, 1]) + (l == low[k, 2])
                    ptr[8 * ((i * shape[1] + j) * shape[2] + l) + sub + 1] += 1
    for c in range(8 * cells):
        ptr[c + 1] += ptr[c]
    fill = ptr[:-1].copy()
    items = np.empty(ptr[8 * cells], dtype=np.int64)
    for k in range(len(t_lo)):  # in increasing target: each sublist is sorted
        for i in range(low[k, 0], high[k, 0] + 1):
            for j in range(low[k, 1], high[k, 1] + 1):
                for l in range(low[k, 2], high[k, 2] + 1):
                    sub = 4 * (i == low[k, 0]) + 2 * (j == low[k, 1]) + (l == low[k, 2])
                    c = 8 * ((i * shape[1] + j) * shape[2] + l) + sub
                    items[fill[c]] = k
                    fill[c] += 1
    return ptr, items


def wanted(sub, i, j, l, c0, c1, c2):
    """Whether sublist `sub` of cell ``(i, j, l)`` can report pairs to a query whose lowest cell is ``(c0, c1, c2)``.

    Past the query's lowest cell along an axis, a target must start in this cell along it (the pair's
    componentwise maximum); at it, any target of the cell does (its lowest cell is at most the query's).
    """
    return (i == c0 or sub & 4) and (j == c1 or sub & 2) and (l == c2 or sub & 1)


def shares_vertex(A, ia, B, ib):
    """Whether rows ``A[ia]`` and ``B[ib]`` of two index tables have a vertex in common."""
    for p in range(A.shape[1]):
        for q in range(B.shape[1]):
            if A[ia, p] == B[ib, q]:
                return True
    return False


def holds_masked(A, ia, mask):
    """Whether row ``A[ia]`` of an index table holds a vertex of `mask`."""
    for p in range(A.shape[1]):
        if mask[A[ia, p]]:
            return True
    return False


def cell_range(q, q_lo, q_hi, origin, cell, shape):
    """The cells query `q`'s box covers: its lowest and highest cell along each axis (six scalars, no array)."""
    return (cell_of(q_lo[q, 0], origin, cell, shape, 0), cell_of(q_hi[q, 0], origin, cell, shape, 0),
            cell_of(q_lo[q, 1], origin, cell, shape, 1), cell_of(q_hi[q, 1], origin, cell, shape, 1),
            cell_of(q_lo[q, 2], origin, cell, shape, 2), cell_of(q_hi[q, 2], origin, cell, shape, 2))


def overlap(q_lo, q_hi, q, t_lo, t_hi, t):
    """Whether the closed boxes of query `q` and target `t` overlap (compared exactly, as NumPy does).

    All six comparisons are made and combined with ``&``, without branches: most boxes a query walks miss it
    along some axis, unpredictably, and with a branch per comparison the fold's largest search took twice as long.
    """
    return (intervals_overlap(q_lo[q, 0], q_hi[q, 0], t_lo[t, 0], t_hi[t, 0])
            & intervals_overlap(q_lo[q, 1], q_hi[q, 1], t_lo[t, 1], t_hi[t, 1])
            & intervals_overlap(q_lo[q, 2], q_hi[q, 2], t_lo[t, 2], t_hi[t, 2]))


def query(q, q_lo, q_hi, t_lo, t_hi, origin, cell, shape, ptr, items, Q, T, same, out, start):
    """The targets of the table ``ptr, items`` whose boxes overlap query `q`'s and share no vertex with it, into
    ``out[start:]``; their count.

    With `same` (queries and targets are one set), only targets above `q`. Each pair is met once, in the
    cell at the componentwise maximum of the two lowest cells (:func:`wanted`); written in the order met
    (sorted by the caller).
    """
    found = 0
    c00, c10, c01, c11, c02, c12 = cell_range(q, q_lo, q_hi, origin, cell, shape)
    for i in range(c00, c10 + 1):
        for j in range(c01, c11 + 1):
            for l in range(c02, c12 + 1):
                c = 8 * ((i * shape[1] + j) * shape[2] + l)
                for sub in range(8):
                    if not wanted(sub, i, j, l, c00, c01, c02):
                        continue
                    for e in range(ptr[c + sub + 1] - 1, ptr[c + sub] - 1, -1):  # the sublist from its top
                        t = items[e]
                        if same and t <= q:  # one set: only targets above the query (the rest are lower still)
                            break
                        if not overlap(q_lo, q_hi, q, t_lo, t_hi, t) or shares_vertex(Q, q, T, t):
                            continue
                        out[start + found] = t
                        found += 1
    return found


def query_bound(q, q_lo, q_hi, origin, cell, shape, ptr):
    """At most how many targets query `q` can find: the entries of the sublists it walks."""
    bound = 0
    i0, i1, j0, j1, l0, l1 = cell_range(q, q_lo, q_hi, origin, cell, shape)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            for l in range(l0, l1 + 1):
                c = 8 * ((i * shape[1] + j) * shape[2] + l)
                for sub in range(8):
                    if wanted(sub, i, j, l, i0, j0, l0):
                        bound += ptr[c + sub + 1] - ptr[c + sub]
    return bound


@jit(parallel=True)
def box_candidates(q_lo, q_hi, t_lo, t_hi, Q, T, same, ordered):
    """Keys ``q len(T) + t`` of the overlapping query-target pairs that share no vertex, sorted when `ordered`.

    Parameters: the boxes ``(lo, hi)`` of the queries and the targets (shape (k, 3)), their vertices `Q`
    and `T` (index tables), `same` (one set: pairs ``q < t``). Each query writes into its own slice of a
    buffer sized by :func:`query_bound` (one pass of tests), sorts it when `ordered`, and the slices are
    joined in query order. Unsorted, the keys come in an order fixed by the boxes alone (the grid's walk;
    the same on any number of threads): sorting the slices took half of the fold's searches, and a caller
    that keeps few of the pairs sorts those. The pairs that hold a vertex of a mask: :func:`subset_pairs`.
    """
    origin, cell, shape = grid_shape(q_lo, q_hi, t_lo, t_hi)
    ptr, items = cell_table(t_lo, t_hi, origin, cell, shape)
    nq = len(q_lo)
    bounds = np.zeros(nq + 1, dtype=np.int64)
    for q in prange(nq):
        bounds[q + 1] = query_bound(q, q_lo, q_hi, origin, cell, shape, ptr)
    for q in range(nq):
        bounds[q + 1] += bounds[q]
    found = np.zeros(nq + 1, dtype=np.int64)
    targets = np.empty(bounds[nq], dtype=np.int64)
    blocks = (nq + QUERY_BLOCK - 1) // QUERY_BLOCK
    for b in prange(blocks):  # each block of queries alone, each query into its own slice
        for q in range(b * QUERY_BLOCK, min(nq, (b + 1) * QUERY_BLOCK)):
            s = bounds[q]
            f = query(q, q_lo, q_hi, t_lo, t_hi, origin, cell, shape, ptr, items, Q, T, same, targets, s)
            if ordered:
                targets[s:s + f].sort()
            found[q + 1] = f
    for q in range(nq):
        found[q + 1] += found[q]
    keys = np.empty(found[nq], dtype=np.int64)
    m = len(t_lo)
    for b in prange(blocks):  # join the slices in query order
        for q in range(b * QUERY_BLOCK, min(nq, (b + 1) * QUERY_BLOCK)):
            s = bounds[q]
            for e in range(found[q + 1] - found[q]):
                keys[found[q] + e] = q * m + targets[s + e]
    return keys


@jit(parallel=True)
def key_rows(keys, m, Q, T, out):
    """``out[k] = (Q[q], T[t])`` for each key ``q m + t``: the vertices of each candidate pair, in one row, and the
    key itself in a last column when `out` has one.

    The rows of :func:`particles.collisions.candidates.pair_rows` (a gather).
    """
    a, b = Q.shape[1], T.shape[1]
    for k in prange(len(keys)):
        q, t = keys[k] // m, keys[k] % m
        for j in range(a):
            out[k, j] = Q[q, j]
        for j in range(b):
            out[k, a + j] = T[t, j]
        if out.shape[1] > a + b:
            out[k, a + b] = keys[k]


def subset_grid(lo, hi, idx):
    """A grid of the boxes ``lo[idx], hi[idx]`` alone: their boxes (gathered), the grid's origin, cell and shape,
    its table ``ptr, items`` (items index `idx`) and ``reach``, the box around them (shape (2, 3))."""
    s_lo = np.empty((len(idx), 3))
    s_hi = np.empty((len(idx), 3))
    reach = np.empty((2, 3))
    reach[0], reach[1] = np.inf, -np.inf
    for e in range(len(idx)):
        for a in range(3):
            s_lo[e, a] = lo[idx[e], a]
            s_hi[e, a] = hi[idx[e], a]
            reach[0, a] = min(reach[0, a], s_lo[e, a])
            reach[1, a] = max(reach[1, a], s_hi[e, a])
    origin, cell, shape = grid_shape(s_lo, s_hi, s_lo, s_hi)
    ptr, items = cell_table(s_lo, s_hi, origin, cell, shape)
    return s_lo, s_hi, origin, cell, shape, ptr, items, reach


@jit(parallel=True)
def subset_pairs(w_lo, w_hi, W, walking, own, idx, lo, hi, S, rule, m):
    """The keys of the pairs of every walker where `walking` holds with the elements `idx` of boxes ``lo, hi``
    (vertices `S`), from a grid of those elements alone (:func:`subset_grid`), unsorted: walker by walker,
    an order fixed by the boxes, the same on any number of threads.

    Each walker queries the grid as :func:`box_candidates`' queries do (:func:`query_bound`, :func:`query`;
    none when its box misses the box around the elements). A pair is an overlap of the closed boxes that
    shares no vertex; its key, by `rule`: 0, the walker a query and the element a target, ``k m + s``; 1,
    the walker a target and the element a query, ``s m + k``; 2, one set (edges against edges),
    ``min m + max``, and a walker where `own` holds (itself an element of the grid) keeps only the elements
    above it, so that a pair of two elements is met once.

    The pairs of a mask are few: :func:`particles.collisions.compiled_stages`' masked search calls this
    with the masked targets (walked by every query) and the masked queries (walked by the targets that hold
    no masked vertex). Around 14 moved vertices of the 64^2 fold's pile-up the whole grid, walked by the
    masked elements and every query near them, took 4 ms, and filtering the pairs of the step's first
    search 6 ms; these small grids take a fraction of a millisecond.
    """
    if len(idx) == 0:
        return np.zeros(0, dtype=np.int64)
    s_lo, s_hi, origin, cell, shape, ptr, items, reach = subset_grid(lo, hi, idx)
    S_in = np.empty((len(idx), S.shape[1]), dtype=np.int64)  # the elements' vertices, in the grid's numbering
    for e in range(len(idx)):
        for j in range(S.shape[1]):
            S_in[e, j] = S[idx[e], j]
    nw = len(w_lo)
    bounds = np.zeros(nw + 1, dtype=np.int64)
    for k in prange(nw):
        if walking[k] and overlap(w_lo, w_hi, k, reach[:1], reach[1:], 0):
            bounds[k + 1] = query_bound(k, w_lo, w_hi, origin, cell, shape, ptr)
    for k in range(nw):
        bounds[k + 1] += bounds[k]
    met = np.empty(bounds[nw], dtype=np.int64)
    found = np.zeros(nw + 1, dtype=np.int64)
    blocks = (nw + QUERY_BLOCK - 1) // QUERY_BLOCK
    for b in prange(blocks):  # each walker's elements (the grid's numbering) into its slice, then those it keeps
        for k in range(b * QUERY_BLOCK, min(nw, (b + 1) * QUERY_BLOCK)):
            start = bounds[k]
            if bounds[k + 1] == start:
                continue
            f = query(k, w_lo, w_hi, s_lo, s_hi, origin, cell, shape, ptr, items, W, S_in, False, met, start)
            kept = 0
            for e in range(f):
                if not own[k] or idx[met[start + e]] > k:
                    met[start + kept] = met[start + e]
                    kept += 1
            found[k + 1] = kept
    for k in range(nw):
        found[k + 1] += found[k]
    keys = np.empty(found[nw], dtype=np.int64)
    for b in prange(blocks):  # the keys, walker by walker
        for k in range(b * QUERY_BLOCK, min(nw, (b + 1) * QUERY_BLOCK)):
            for e in range(found[k + 1] - found[k]):
                s = idx[met[bounds[k] + e]]
                lower, upper = (s, k) if rule == 1 or (rule == 2 and s < k) else (k, s)
                keys[found[k] + e] = lower * m + upper
    return keys


@jit(parallel=True)
def kept_pairs(keys, m, Q, T, q_lo, q_hi, t_lo, t_hi, left, keep):
    """Which pairs of an earlier search still qualify: ``keep[k]`` for the key ``keys[k] = q m + t``.

    A pair is kept when the boxes of query `q` and target `t` overlap (the closed test of :func:`overlap`)
    and neither holds a vertex of `left` (the vertices whose boxes left those of the earlier search: their
    pairs are searched again).
    """
    for k in prange(len(keys)):
        q, t = keys[k] // m, keys[k] % m
        keep[k] = (overlap(q_lo, q_hi, q, t_lo, t_hi, t) and not holds_masked(Q, q, left)
                   and not holds_masked(T, t, left))


for _helper in (grid_shape, cell_of, cell_table, wanted, shares_vertex, holds_masked, cell_range, overlap, query,
                query_bound, subset_grid):  # compiled into the kernels that call them
    inline(_helper, into="never")
