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
number of threads; no atomics.
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


def cell_table(t_lo, t_hi, origin, cell, shape, keep):
    """The targets where `keep` is True per cell, in compressed rows of 8 sublists per cell: ``ptr`` (8 cells
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
        if not keep[k]:
            continue
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
        if not keep[k]:
            continue
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
def box_candidates(q_lo, q_hi, t_lo, t_hi, Q, T, same, mask, masked, ordered):
    """Keys ``q len(T) + t`` of the overlapping query-target pairs that share no vertex, sorted when `ordered`.

    Parameters: the boxes ``(lo, hi)`` of the queries and the targets (shape (k, 3)), their vertices `Q`
    and `T` (index tables), `same` (one set: pairs ``q < t``), and a vertex `mask` used when `masked`.
    Each query writes into its own slice of a buffer sized by :func:`query_bound` (one pass of tests),
    sorts it when `ordered`, and the slices are joined in query order. Unsorted, the keys come in an order
    fixed by the boxes alone (the grid's walk; the same on any number of threads): sorting the slices took
    half of the fold's searches, and a caller that keeps few of the pairs sorts those. With `masked`, a query that holds no masked
    vertex walks a second table, of the targets that hold one, and only when its box meets the box around
    those targets (the continuous test's searches after the first, where a few vertices still move, walk a
    few boxes instead of all).
    """
    origin, cell, shape = grid_shape(q_lo, q_hi, t_lo, t_hi)
    ptr, items = cell_table(t_lo, t_hi, origin, cell, shape, np.ones(len(t_lo), dtype=np.bool_))
    nq = len(q_lo)
    q_in = np.zeros(nq, dtype=np.bool_)
    ptr_in, items_in = ptr, items  # with a mask: the table of the targets that hold a masked vertex
    reach = np.empty((2, 3))  # with a mask: the box around the masked targets' boxes
    if masked:
        t_in = np.empty(len(t_lo), dtype=np.bool_)
        reach[0], reach[1] = np.inf, -np.inf
        for t in range(len(t_lo)):
            t_in[t] = holds_masked(T, t, mask)
            if t_in[t]:
                for a in range(3):
                    reach[0, a] = min(reach[0, a], t_lo[t, a])
                    reach[1, a] = max(reach[1, a], t_hi[t, a])
        for q in range(nq):
            q_in[q] = holds_masked(Q, q, mask)
        ptr_in, items_in = cell_table(t_lo, t_hi, origin, cell, shape, t_in)
    bounds = np.zeros(nq + 1, dtype=np.int64)
    for q in prange(nq):  # a query outside the mask walks the masked targets' table only, if it reaches them
        if q_in[q] or not masked:
            bounds[q + 1] = query_bound(q, q_lo, q_hi, origin, cell, shape, ptr)
        elif overlap(q_lo, q_hi, q, reach[:1], reach[1:], 0):
            bounds[q + 1] = query_bound(q, q_lo, q_hi, origin, cell, shape, ptr_in)
    for q in range(nq):
        bounds[q + 1] += bounds[q]
    found = np.zeros(nq + 1, dtype=np.int64)
    targets = np.empty(bounds[nq], dtype=np.int64)
    blocks = (nq + QUERY_BLOCK - 1) // QUERY_BLOCK
    for b in prange(blocks):  # each block of queries alone, each query into its own slice
        for q in range(b * QUERY_BLOCK, min(nq, (b + 1) * QUERY_BLOCK)):
            s = bounds[q]
            whole = q_in[q] or not masked
            if bounds[q + 1] == s:  # nothing to walk (a query that reaches no masked target)
                continue
            f = query(q, q_lo, q_hi, t_lo, t_hi, origin, cell, shape, ptr if whole else ptr_in,
                      items if whole else items_in, Q, T, same, targets, s)
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


def _masked_row(r, q_list, t_list, q_lo, q_hi, t_lo, t_hi, Q, T, same, q_in, out, start, write):
    """Row `r` of :func:`touching_candidates`' pairs, written into ``out[start:]`` when `write`; their count.

    Row ``r < len(q_list)``: masked query ``q = q_list[r]`` against every target (``t > q`` when `same`);
    a later row: masked target ``t = t_list[r - len(q_list)]`` against every query that holds no masked
    vertex (``q < t`` when `same`), whose pairs with masked queries are their rows'. Keys ``q len(T) + t``.
    """
    m, found = len(t_lo), 0
    if r < len(q_list):
        q = q_list[r]
        for t in range(q + 1 if same else 0, m):  # one long loop over the targets, one box against many
            if overlap(q_lo, q_hi, q, t_lo, t_hi, t) and not shares_vertex(Q, q, T, t):
                if write:
                    out[start + found] = q * m + t
                found += 1
        return found
    t = t_list[r - len(q_list)]
    for q in range(t if same else len(q_lo)):
        if overlap(q_lo, q_hi, q, t_lo, t_hi, t) and not q_in[q] and not shares_vertex(Q, q, T, t):
            if write:
                out[start + found] = q * m + t
            found += 1
    return found


@jit(parallel=True)
def touching_candidates(q_lo, q_hi, t_lo, t_hi, Q, T, same, q_in, t_list):
    """:func:`box_candidates` with a mask touching few elements, without a grid: the keys ``q len(T) + t``, unsorted.

    The queries that hold a masked vertex (`q_in`) are tested against every target, and the targets that
    hold one (`t_list`, increasing) against every other query: the pairs of :func:`box_candidates`, as
    :func:`particles.collisions.candidates.candidates_touching` tests them. One row per masked element,
    each a long loop over all the others (a short loop over the masked ones per query took twice as
    long); counted, then written, in row order: the caller sorts them (NumPy's sort of these few keys
    takes microseconds, and numba's compiled into this kernel took a third of its compile time).
    """
    q_list = np.flatnonzero(q_in)
    rows = len(q_list) + len(t_list)
    found = np.zeros(rows + 1, dtype=np.int64)
    empty = np.zeros(0, dtype=np.int64)
    for r in prange(rows):
        found[r + 1] = _masked_row(r, q_list, t_list, q_lo, q_hi, t_lo, t_hi, Q, T, same, q_in, empty, 0, False)
    for r in range(rows):
        found[r + 1] += found[r]
    keys = np.empty(found[rows], dtype=np.int64)
    for r in prange(rows):
        _masked_row(r, q_list, t_list, q_lo, q_hi, t_lo, t_hi, Q, T, same, q_in, keys, found[r], True)
    return keys


@jit(parallel=True)
def kept_pairs(keys, m, Q, T, q_lo, q_hi, t_lo, t_hi, mask, masked, left, keep):
    """Which pairs of an earlier search still qualify: ``keep[k]`` for the key ``keys[k] = q m + t``.

    A pair is kept when the boxes of query `q` and target `t` overlap (the closed test of :func:`overlap`),
    neither holds a vertex of `left` (the vertices whose boxes left those of the earlier search: their
    pairs are searched again), and, when `masked`, one of them holds a vertex of `mask` (the pairs
    :func:`box_candidates` finds with that mask).
    """
    for k in prange(len(keys)):
        q, t = keys[k] // m, keys[k] % m
        keep[k] = (overlap(q_lo, q_hi, q, t_lo, t_hi, t) and not holds_masked(Q, q, left)
                   and not holds_masked(T, t, left)
                   and (not masked or holds_masked(Q, q, mask) or holds_masked(T, t, mask)))


for _helper in (grid_shape, cell_of, cell_table, wanted, shares_vertex, holds_masked, cell_range, overlap, query, query_bound, _masked_row,):  # compiled into the kernels that call them
    inline(_helper, into="never")
