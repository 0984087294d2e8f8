"""Do two triangles of a mesh cross? An exact test, for all pairs of a mesh at once.

The invariant of a cloth simulation with collisions is that the surface never
passes through itself: no two triangles that share no vertex may cross.
:func:`intersections` lists the pairs that do, exactly (rounding never turns a
crossing into a non-crossing or the reverse), in three phases:

1. **Broad phase** (:func:`box_pairs`): the axis-aligned bounding boxes of the
   triangles are hashed into a uniform bucket grid whose cell is the median
   box size; two boxes are compared only when they share a cell, and each
   overlapping pair is reported once, from the cell at the componentwise
   maximum of their lowest cells. On a cloth, whose triangles have about the
   same size, each box covers a bounded number of cells and each cell holds a
   bounded number of boxes, so the cost is O(m) for m triangles. (A
   sort-and-sweep along one axis would compare a triangle with a whole strip
   of a flat sheet, O(m^1.5); a bounding-volume hierarchy is O(m log m) and
   must be refitted as the cloth moves; the grid of
   :mod:`particles.neighbors`, bucketing points rather than boxes, would need
   the largest triangle as its cutoff.)
2. **Adjacency**: pairs that share a vertex touch by construction and are
   dropped (:meth:`particles.collisions.mesh.TriangleMesh.share_vertex`).
3. **Narrow phase**, with orientations ``o(a, b, c, d) = sign det[b - a, c - a, d - a]``
   (:func:`orientation`; positive when ``d`` lies on the side of the plane
   ``abc`` that ``(b - a) x (c - a)`` points to). An edge ``pq`` of one triangle
   *crosses* the triangle ``abc`` when ``p`` and ``q`` lie strictly on opposite
   sides of its plane (``o(a, b, c, p) o(a, b, c, q) < 0``) and the line ``pq``
   passes strictly inside it: ``o(p, q, a, b)``, ``o(p, q, b, c)``,
   ``o(p, q, c, a)`` are non-zero and equal [2]_. Two triangles cross when an
   edge of either crosses the other. Only pairs in which a triangle has
   vertices strictly on both sides of the other's plane can cross, which
   discards most candidates after six orientations; the nine edge-edge
   orientations ``o(p_i, p_i+1, q_j, q_j+1)`` serve both directions (``o`` is
   unchanged when its two pairs of arguments are swapped).

**Exactness.** Each determinant is first computed in float64 with the
forward error bound of Shewchuk [1]_: the computed ``D`` has the sign of the
exact one when ``|D| > (7 + 56 eps) eps P``, where ``P`` is the same
expression with every product replaced by its absolute value (the
permanent) and ``eps = 2^-53``. The few determinants within the bound (zero
or nearly so) are evaluated again exactly, in integer arithmetic on the exact
binary values of the coordinates (each float64 is an integer times a power
of two; NumPy object arrays of Python integers). When ``P = 0`` every term has a factor that is
a difference of two equal coordinates, exactly zero, so ``D = 0`` exactly:
a flat sheet needs no rational arithmetic.

**What counts as a crossing.** Contacts on the boundary only are not
crossings: a vertex lying on the other triangle, an edge touching an edge, two
coplanar triangles overlapping (they have no side to cross to). A triangle
of zero area has no inside to be crossed, but its edges still cross other
triangles (a triangle squashed flat stays part of the surface). A transverse crossing whose intersection segment ends,
at both ends, exactly on an edge of both triangles at once is not detected
either; it needs exactly placed coordinates (it has probability zero for
computed positions).

References
----------
.. [1] J. R. Shewchuk, "Adaptive precision floating-point arithmetic and fast
   robust geometric predicates", Discrete & Computational Geometry 18(3),
   305-363, 1997 (the orientation predicate and its error bound).
.. [2] T. Möller and B. Trumbore, "Fast, minimum storage ray-triangle
   intersection", Journal of Graphics Tools 2(1), 21-28, 1997; the signed
   volume (Plücker) form of the segment-triangle test is in C. Ericson,
   *Real-Time Collision Detection*, Morgan Kaufmann, 2005, section 5.3.4.
.. [3] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of
   collisions, contact and friction for cloth animation", ACM Transactions on
   Graphics 21(3) (SIGGRAPH 2002), 594-603 (a cloth whose triangles never cross).
"""

import numpy as np

from .._checks import as_float_array
from .mesh import TriangleMesh

__all__ = ["intersections", "box_pairs", "orientation"]

_EPS = 2.0 ** -53
_ORIENT_BOUND = (7.0 + 56.0 * _EPS) * _EPS  # Shewchuk's o3derrboundA
_TINY = 2.0 ** -500  # a difference below this may underflow in a product: decide exactly


def _det(u, v, w):
    """det[u; v; w] and its permanent, rows of shape (k, 3), in float64."""
    a = v[:, 1] * w[:, 2]
    b = v[:, 2] * w[:, 1]
    c = v[:, 2] * w[:, 0]
    d = v[:, 0] * w[:, 2]
    e = v[:, 0] * w[:, 1]
    f = v[:, 1] * w[:, 0]
    D = u[:, 0] * (a - b) + u[:, 1] * (c - d) + u[:, 2] * (e - f)
    P = (np.abs(u[:, 0]) * (np.abs(a) + np.abs(b)) + np.abs(u[:, 1]) * (np.abs(c) + np.abs(d))
         + np.abs(u[:, 2]) * (np.abs(e) + np.abs(f)))
    return D, P


def _exact_signs(a, b, c, d):
    """Signs of det[b - a, c - a, d - a] in exact integer arithmetic, int8 of shape (k,).

    Every float64 is ``M 2^e`` with an integer ``|M| < 2^53``. The twelve
    coordinates of a row are scaled by the same power of two (the smallest
    exponent of the row), which turns them into Python integers without
    changing the determinant's sign; differences and products of integers
    are exact (NumPy object arrays).
    """
    P = np.stack([a, b, c, d], axis=1)  # (k, 4 points, 3)
    mantissa, exponent = np.frexp(P)
    M = (mantissa * 2.0**53).astype(np.int64)  # exact: |mantissa| < 1 has 53 bits
    e = exponent.astype(np.int64) - 53
    none = np.iinfo(np.int64).max
    lowest = np.where(M != 0, e, none).reshape(len(P), -1).min(axis=1)
    lowest = np.where(lowest == none, 0, lowest)
    shift = np.where(M != 0, e - lowest[:, None, None], 0)
    N = np.left_shift(M.astype(object), shift.astype(object))
    u, v, w = N[:, 1] - N[:, 0], N[:, 2] - N[:, 0], N[:, 3] - N[:, 0]
    D = (u[:, 0] * (v[:, 1] * w[:, 2] - v[:, 2] * w[:, 1]) + u[:, 1] * (v[:, 2] * w[:, 0] - v[:, 0] * w[:, 2])
         + u[:, 2] * (v[:, 0] * w[:, 1] - v[:, 1] * w[:, 0]))
    return ((D > 0).astype(np.int8) - (D < 0).astype(np.int8)).astype(np.int8)


def _orient(a, b, c, d):
    """Exact orientation signs of rows of float64 arrays of shape (k, 3), without checks.

    Trusted without exact arithmetic: ``|D| > bound P``, and ``P = 0`` (every
    term has a factor that is an exactly zero difference, e.g. four points of
    a flat sheet), unless a difference is so small that a product may underflow.
    """
    u, v, w = b - a, c - a, d - a
    D, P = _det(u, v, w)
    s = np.sign(D).astype(np.int8)
    diffs = np.abs(np.concatenate([u, v, w], axis=1))
    underflow = ((diffs > 0) & (diffs < _TINY)).any(axis=1)
    unsure = np.flatnonzero(((np.abs(D) <= _ORIENT_BOUND * P) & (P > 0)) | underflow)
    if len(unsure):
        s[unsure] = _exact_signs(a[unsure], b[unsure], c[unsure], d[unsure])
    return s


def orientation(a, b, c, d):
    """Exact sign of ``det[b - a, c - a, d - a]``: on which side of the plane ``abc`` is ``d``?

    Parameters
    ----------
    a, b, c, d : array_like, shape (k, 3) or (3,)
        Points, in metres (any finite float64 values).

    Returns
    -------
    ndarray of int8, shape (k,) or ()
        +1 when ``d`` lies on the side that ``(b - a) x (c - a)`` points to,
        -1 on the other side, 0 when the four points are coplanar. Exact: a
        float64 evaluation is trusted only beyond its error bound, the rest is
        recomputed in exact integer arithmetic.

    Examples
    --------
    >>> orientation([0, 0, 0], [1, 0, 0], [0, 1, 0], [[0.2, 0.2, 1e-300], [0.2, 0.2, -1.0], [3.0, 4.0, 0.0]]).tolist()
    [1, -1, 0]
    """
    pts = [as_float_array(p, name, ndim=(1, 2)) for p, name in zip((a, b, c, d), "abcd")]
    for p, name in zip(pts, "abcd"):
        if p.shape[-1] != 3:
            raise ValueError(f"{name} must have shape (k, 3) or (3,), got shape {p.shape}")
    single = all(p.ndim == 1 for p in pts)
    k = max(len(p) if p.ndim == 2 else 1 for p in pts)
    try:
        pts = [np.ascontiguousarray(np.broadcast_to(p, (k, 3))) for p in pts]
    except ValueError:
        raise ValueError(f"a, b, c, d must have the same number of rows, got shapes "
                         f"{[p.shape for p in pts]}") from None
    s = _orient(*pts)
    return s[0] if single else s


def _check_boxes(lo, hi, name):
    lo = as_float_array(lo, f"lo_{name}", ndim=2)
    hi = as_float_array(hi, f"hi_{name}", shape=lo.shape)
    if np.any(hi < lo):
        raise ValueError(f"hi_{name} must be >= lo_{name} in every coordinate (boxes given by their corners)")
    return lo, hi


def _cell_entries(c_lo, c_hi, shape):
    """One (cell key, box) entry for every grid cell each box overlaps, from the boxes' lowest and highest cells."""
    span = c_hi - c_lo + 1  # cells per axis, (k, d)
    total = np.prod(span, axis=1)
    box = np.repeat(np.arange(len(c_lo)), total)
    r = np.arange(int(total.sum())) - np.repeat(np.cumsum(total) - total, total)  # rank within the box
    strides = np.concatenate([[1], np.cumprod(shape[:-1])]).astype(np.int64)
    key = np.zeros(len(box), dtype=np.int64)
    for a in range(c_lo.shape[1]):  # a loop over the d coordinates
        r, ra = np.divmod(r, span[box, a])
        key += (c_lo[box, a] + ra) * strides[a]
    return key, box, strides


def _grid(lo, hi):
    """Cell side and shape of the bucket grid for a set of boxes, and each box's lowest and highest cells."""
    origin, top = lo.min(axis=0), hi.max(axis=0)
    extent = np.max(hi - lo, axis=1)
    cell = float(np.median(extent))
    span = float(np.max(top - origin))
    if not cell > 0:  # points: about one per cell
        cell = span / len(lo) ** (1.0 / lo.shape[1]) if span > 0 else 1.0
    cell = max(cell, span * 2.0 ** -40, np.abs(top).max() * 2.0 ** -40, 1e-300)
    while True:  # a loop over doublings of the cell (very uneven boxes, or a sparse set)
        shape = np.floor((top - origin) / cell).astype(np.int64) + 1
        c_lo = np.floor((lo - origin) / cell).astype(np.int64)  # floor is monotone: within [0, shape)
        c_hi = np.floor((hi - origin) / cell).astype(np.int64)
        covered = np.prod(c_hi - c_lo + 1, axis=1, dtype=float).sum()
        if np.prod(shape.astype(float)) < 2.0 ** 60 and covered <= 8 * len(lo) + 1024:
            return c_lo, c_hi, shape
        cell *= 2.0


def intervals_overlap(lo_a, hi_a, lo_b, hi_b):
    """Whether the closed intervals ``[lo_a, hi_a]`` and ``[lo_b, hi_b]`` overlap (touching counts).

    Two boxes overlap when their intervals overlap along every axis: the broad phase's test of one pair,
    which the NumPy searches apply to arrays of pairs and the compiled ones (:mod:`particles.collisions.broad_kernels`)
    inline, pair by pair.
    """
    return (lo_a <= hi_b) & (lo_b <= hi_a)


def box_pairs(lo_a, hi_a, lo_b=None, hi_b=None):
    """Pairs of overlapping axis-aligned boxes, found with a bucket grid (no test of all pairs).

    Parameters
    ----------
    lo_a, hi_a : array_like, shape (k, d)
        Lowest and highest corners of the boxes of set A (``hi >= lo``).
    lo_b, hi_b : array_like, shape (l, d), optional
        A second set. Without it, pairs are taken within set A.

    Returns
    -------
    ia, ib : ndarray of int64, shape (p,)
        Every pair of boxes that overlap (closed boxes: touching counts), once,
        sorted by ``(ia, ib)``: ``ia < ib`` within one set, or ``ia`` in A and
        ``ib`` in B.

    Notes
    -----
    The grid's cell is the median largest extent of the boxes (doubled while
    the boxes would cover more than about 8 cells each on average). Each
    overlapping pair shares at least one cell, and is reported from the cell
    at the componentwise maximum of the two boxes' lowest cells only. The cost
    is O(k + l + p) when the boxes have similar sizes.

    Examples
    --------
    >>> lo = [[0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [2.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
    >>> ia, ib = box_pairs(lo, [[1.0, 1.0, 1.0], [1.5, 1.5, 1.5], [3.0, 1.0, 1.0], [2.0, 2.0, 2.0]])
    >>> ia.tolist(), ib.tolist()
    ([0, 0, 1, 2], [1, 3, 3, 3])
    """
    lo_a, hi_a = _check_boxes(lo_a, hi_a, "a")
    one_set = lo_b is None and hi_b is None
    if one_set:
        lo_b, hi_b = lo_a[:0], hi_a[:0]
    elif lo_b is None or hi_b is None:
        raise ValueError("give both lo_b and hi_b, or neither")
    else:
        lo_b, hi_b = _check_boxes(lo_b, hi_b, "b")
        if lo_b.shape[1] != lo_a.shape[1]:
            raise ValueError(f"the boxes of A and B must have the same dimension, got {lo_a.shape[1]} "
                             f"and {lo_b.shape[1]}")
    lo, hi = np.concatenate([lo_a, lo_b]), np.concatenate([hi_a, hi_b])
    k = len(lo_a)
    empty = np.zeros(0, dtype=np.int64)
    if len(lo) == 0 or (not one_set and (k == 0 or len(lo_b) == 0)):
        return empty, empty.copy()
    c_lo, c_hi, shape = _grid(lo, hi)
    key, box, strides = _cell_entries(c_lo, c_hi, shape)
    tag = (box >= k).astype(np.int64)  # 0: set A, 1: set B
    k2 = 2 * key + tag
    order = np.argsort(k2, kind="stable")
    k2, key, box = k2[order], key[order], box[order]
    owners = np.flatnonzero(tag[order] == 0)  # entries of set A
    if one_set:
        first, last = owners + 1, np.searchsorted(k2, 2 * key[owners] + 1)
    else:
        first = np.searchsorted(k2, 2 * key[owners] + 1)
        last = np.searchsorted(k2, 2 * key[owners] + 2)
    n_each = np.maximum(last - first, 0)
    p = np.repeat(owners, n_each)
    q = np.arange(int(n_each.sum())) - np.repeat(np.cumsum(n_each) - n_each - first, n_each)
    i, j, cell_key = box[p], box[q], key[p]
    home = np.zeros(len(i), dtype=np.int64)
    for a in range(lo.shape[1]):  # a loop over the d coordinates (1D gathers are the fast ones)
        ca = np.ascontiguousarray(c_lo[:, a])
        home += np.maximum(ca.take(i), ca.take(j)) * strides[a]
    keep = home == cell_key  # report each pair from one cell only
    i, j = i[keep], j[keep]
    for a in range(lo.shape[1]):  # a loop over the d coordinates: closed intervals overlap on each axis
        la, ha = np.ascontiguousarray(lo[:, a]), np.ascontiguousarray(hi[:, a])
        keep = intervals_overlap(la.take(i), ha.take(i), la.take(j), ha.take(j))
        i, j = i[keep], j[keep]
    if one_set:
        i, j = np.minimum(i, j), np.maximum(i, j)
    else:
        j = j - k
    order = np.argsort(i * max(len(lo), 1) + j, kind="stable")
    return i[order].astype(np.int64), j[order].astype(np.int64)


def _faces(faces, n):
    if isinstance(faces, TriangleMesh):
        if faces.n > n:
            raise ValueError(f"the mesh has {faces.n} vertices but x has only {n} rows")
        return faces
    mesh = TriangleMesh(faces, n)
    return mesh


def _crossing(x, F, a, b):
    """Whether triangles ``F[a[k]]`` and ``F[b[k]]`` cross (exact), bool of shape (p,)."""
    P, Q = x[F[a]], x[F[b]]  # vertices of the triangles, (p, 3, 3)
    k = len(a)
    # the six sides at once: p_i against the plane of Q, q_j against the plane of P
    A, B, C = (np.concatenate([np.repeat(Q[:, v], 3, axis=0), np.repeat(P[:, v], 3, axis=0)]) for v in range(3))
    sides = _orient(A, B, C, np.concatenate([P.reshape(-1, 3), Q.reshape(-1, 3)]))
    side_p, side_q = sides[:3 * k].reshape(k, 3), sides[3 * k:].reshape(k, 3)
    straddle = ((side_p > 0).any(1) & (side_p < 0).any(1)) | ((side_q > 0).any(1) & (side_q < 0).any(1))
    keep = np.flatnonzero(straddle)
    P, Q, side_p, side_q = P[keep], Q[keep], side_p[keep], side_q[keep]
    # O[:, i, j] = o(p_i, p_i+1, q_j, q_j+1), the nine at once
    nxt = [1, 2, 0]
    i, j = np.repeat(np.arange(3), 3), np.tile(np.arange(3), 3)
    O = _orient(P[:, i].reshape(-1, 3), P[:, np.take(nxt, i)].reshape(-1, 3), Q[:, j].reshape(-1, 3),
                Q[:, np.take(nxt, j)].reshape(-1, 3)).reshape(-1, 3, 3)
    cross = np.zeros(len(keep), dtype=bool)
    for i in range(3):  # the three edges of each triangle
        j = (i + 1) % 3
        through_q = (side_p[:, i] * side_p[:, j] < 0) & (O[:, i, 0] != 0) & (O[:, i, 0] == O[:, i, 1]) \
            & (O[:, i, 1] == O[:, i, 2])
        through_p = (side_q[:, i] * side_q[:, j] < 0) & (O[:, 0, i] != 0) & (O[:, 0, i] == O[:, 1, i]) \
            & (O[:, 1, i] == O[:, 2, i])
        cross |= through_q | through_p
    out = np.zeros(len(a), dtype=bool)
    out[keep] = cross
    return out


def intersections(x, faces, block=200000):
    """The pairs of triangles that share no vertex and cross (an edge of one passes through the other).

    Parameters
    ----------
    x : array_like, shape (n, 3)
        Vertex positions, in metres.
    faces : TriangleMesh or array_like of int, shape (m, 3)
        The triangles.
    block : int
        Candidate pairs tested together (bounds the temporary arrays; the
        result does not depend on it).

    Returns
    -------
    ndarray of int64, shape (k, 2)
        Face index pairs ``(a, b)``, ``a < b``, sorted; empty when the surface
        does not pass through itself. Exact (see the module notes for what
        counts as a crossing).

    Examples
    --------
    A horizontal triangle pierced by a vertical one:

    >>> x = [[0, 0, 0], [2, 0, 0], [0, 2, 0], [0.5, 0.5, -1], [0.5, 0.5, 1], [3, 3, 0.5]]
    >>> intersections(x, [[0, 1, 2], [3, 4, 5]]).tolist()
    [[0, 1]]
    >>> intersections(x, [[0, 1, 2], [3, 5, 4]]).tolist(), intersections(x, [[0, 1, 2], [1, 4, 5]]).tolist()
    ([[0, 1]], [])
    """
    x = as_float_array(x, "x", ndim=2)
    if x.shape[1] != 3:
        raise ValueError(f"x must have shape (n, 3), got shape {x.shape}")
    mesh = _faces(faces, len(x))
    F = mesh.faces
    if len(F) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    T = x[F]  # (m, 3 vertices, 3)
    a, b = box_pairs(T.min(axis=1), T.max(axis=1))
    apart = ~mesh.share_vertex(a, b)
    a, b = a[apart], b[apart]
    hits = [np.zeros(0, dtype=bool)]
    for s in range(0, len(a), max(int(block), 1)):  # a loop over blocks of candidate pairs
        hits.append(_crossing(x, F, a[s:s + block], b[s:s + block]))
    hit = np.concatenate(hits)
    return np.stack([a[hit], b[hit]], axis=1).astype(np.int64)
