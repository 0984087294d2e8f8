"""Closest points of vertex-triangle and edge-edge pairs: the geometry of cloth contact.

A cloth that is a triangle mesh touches itself in two ways (Bridson, Fedkiw
and Anderson [1]_): a vertex comes close to a triangle, or an edge comes close
to another edge. Both are answered by the closest points of the two pieces:

1. **Vertex-triangle.** The point ``q = a_1 a + a_2 b + a_3 c`` of the
   triangle ``(a, b, c)`` closest to ``p`` has barycentric weights
   ``a_i >= 0``, ``sum a_i = 1``. If the orthogonal projection of ``p`` onto
   the triangle's plane lies inside the triangle, it is ``q``; otherwise
   ``q`` lies on one of the three edges, and the closest of the three
   point-segment answers is taken. A triangle of (nearly) zero area has no
   plane: only its edges are used, so the answer stays defined.
2. **Edge-edge.** The closest points ``(1 - s) p_1 + s p_2`` and
   ``(1 - u) q_1 + u q_2`` of two segments minimize a quadratic in
   ``(s, u)`` over the unit square [2]_: the unconstrained minimum, clamped,
   then the other parameter recomputed and clamped again. For parallel
   segments (the 2x2 system singular, ``|d_1 x d_2|^2 <= 1e-12 |d_1|^2 |d_2|^2``)
   the minimum is a whole interval; the middle of the overlap is taken, so
   that a contact impulse on two parallel edges is shared evenly.
3. **Normal.** The unit vector from the second piece's point to the first's,
   ``n = (p - q) / |p - q|``. Where the two touch (distance 0) the
   triangle's normal, or ``d_1 x d_2`` for edges, or any direction
   perpendicular to a pair of collinear edges.

A contact is then written in one form for both kinds: four vertices and
four weights ``w`` with ``sum w = 0`` (``(1, -a_1, -a_2, -a_3)`` and
``(1 - s, s, -(1 - u), -u)``), so that the separation is
``sum_j w_j x_j = p - q`` and an impulse ``w_j I n`` on vertex ``j``
conserves momentum (``sum_j w_j = 0``); :mod:`particles.collisions.pipeline`
uses that.

Every function is vectorized over pairs: arrays of shape (k, 3), one row per pair.

References
----------
.. [1] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM Transactions on Graphics
   21(3) (SIGGRAPH 2002), 594-603, section 6 (proximity of point-triangle and
   edge-edge pairs).
.. [2] C. Ericson, *Real-Time Collision Detection*, Morgan Kaufmann, 2005,
   sections 5.1.2 (closest point on a segment), 5.1.5 (on a triangle) and
   5.1.9 (between two segments).
"""

from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array
from .._vectors import select, vadd, vcross, vdot, vscale, vselect, vsub

__all__ = ["Closest", "point_segment", "vertex_face", "edge_edge", "PARALLEL", "segment_closest", "triangle_closest",
           "plane_weights", "nearest_edge_weights", "triangle_contact", "normal_or",
           "segments_closest", "approaching_within"]
# The kernels (dot, unit_or, vertex_face_kernel, edge_edge_kernel) skip the checks, for the collision stages
# that call them on every step.

PARALLEL = 1e-12
"""Edges count as parallel when ``|d_1 x d_2|^2 <= PARALLEL |d_1|^2 |d_2|^2`` (an angle below 1e-6 rad)."""


@dataclass(frozen=True)
class Closest:
    """Closest points of k pairs, in the four-vertex form of a contact.

    Attributes
    ----------
    distance : ndarray, shape (k,)
        ``|p - q|``, in metres.
    normal : ndarray, shape (k, 3)
        Unit vector from ``q`` (triangle, second edge) to ``p`` (vertex, first edge).
    weights : ndarray, shape (k, 4)
        ``(1, -a_1, -a_2, -a_3)`` for vertex-triangle pairs, ``(1 - s, s, -(1 - u), -u)``
        for edge-edge pairs: ``p - q = sum_j w_j x_j`` and ``sum_j w_j = 0``.
    """

    distance: np.ndarray
    normal: np.ndarray
    weights: np.ndarray


def dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def clip01(s):
    """`s` clipped to [0, 1]."""
    return np.minimum(np.maximum(s, 0.0), 1.0)


def unit_or(v, fallback):
    """The 3-tuple `v` divided by its length; `fallback` (a unit 3-tuple) where the length is zero."""
    L = np.sqrt(vdot(v, v))
    safe = select(L > 0, L, 1.0)
    return vselect(L > 0, (v[0] / safe, v[1] / safe, v[2] / safe), fallback)


def any_perpendicular(d):
    """A unit 3-tuple perpendicular to the 3-tuple `d`: ``d x e_k`` for the axis least aligned with it (e_z for 0)."""
    to_1 = np.abs(d[1]) < np.abs(d[0])
    to_2 = np.abs(d[2]) < select(to_1, np.abs(d[1]), np.abs(d[0]))
    axis = (1.0 * (~to_1 & ~to_2), 1.0 * (to_1 & ~to_2), 1.0 * to_2)
    return unit_or(vcross(d, axis), (0.0, 0.0, 1.0))


def normal_or(v, n, g):
    """The 3-tuple `v` over its length; where that is zero, `n`'s; where that is zero too, ``any_perpendicular(g)``.

    The compiled kernels compute each fallback only where it is used
    (:mod:`particles.collisions.contact_kernels`).
    """
    return unit_or(v, unit_or(n, any_perpendicular(g)))


def segment_closest(p, a, b):
    """Parameter ``s`` of the point ``(1 - s) a + s b`` of a segment closest to `p`, and the distance (3-tuples)."""
    d = vsub(b, a)
    dd = vdot(d, d)
    pa = vsub(p, a)
    s = clip01(select(dd > 0, vdot(pa, d) / select(dd > 0, dd, 1.0), 0.0))
    r = vsub(pa, vscale(s, d))
    return s, np.sqrt(vdot(r, r))


def plane_weights(p, a, b, c):
    """Barycentric weights ``(alpha, beta, gamma)`` of the projection of `p` on the plane of ``(a, b, c)``.

    3-tuples in; also whether the projection lies inside the triangle (a triangle with a plane, not a
    sliver or a point: Cramer's rule on the edges ``e1 = b - a``, ``e2 = c - a``).
    """
    e1, e2 = vsub(b, a), vsub(c, a)
    nrm = vcross(e1, e2)
    area2 = vdot(nrm, nrm)
    scale2 = np.maximum(vdot(e1, e1), vdot(e2, e2))
    flat = area2 > 1e-14 * scale2 * scale2
    r = vsub(p, a)
    safe = select(flat, area2, 1.0)
    beta = select(flat, vdot(vcross(r, e2), nrm) / safe, -1.0)
    gamma = select(flat, vdot(vcross(e1, r), nrm) / safe, -1.0)
    alpha = 1.0 - beta - gamma
    return flat & (alpha >= 0) & (beta >= 0) & (gamma >= 0), alpha, beta, gamma


def nearest_edge_weights(p, a, b, c):
    """Weights ``(w0, w1, w2)`` of the point ``w0 a + w1 b + w2 c`` of the triangle's edges nearest `p` (the first on ties)."""
    s_ab, d_ab = segment_closest(p, a, b)
    s_bc, d_bc = segment_closest(p, b, c)
    s_ca, d_ca = segment_closest(p, c, a)
    bc = (d_bc < d_ab) & (d_bc <= d_ca)
    ca = (d_ca < d_ab) & (d_ca < d_bc)
    return (select(bc, 0.0, select(ca, s_ca, 1.0 - s_ab)), select(bc, 1.0 - s_bc, select(ca, 0.0, s_ab)),
            select(bc, s_bc, select(ca, 1.0 - s_ca, 0.0)))


def triangle_contact(p, a, b, c, w0, w1, w2):
    """Distance, normal and four weights of `p` and the triangle's point ``q = w0 a + w1 b + w2 c``.

    The normal points from ``q`` to `p`, or is the triangle's normal where they touch.
    """
    e1, e2 = vsub(b, a), vsub(c, a)
    q = vadd(vadd(vscale(w0, a), vscale(w1, b)), vscale(w2, c))
    d = vsub(p, q)
    normal = normal_or(d, vcross(e1, e2), vadd(e1, e2))
    return np.sqrt(vdot(d, d)), normal, (1.0, -w0, -w1, -w2)


def triangle_closest(p, a, b, c):
    """Closest points of a vertex `p` and a triangle ``(a, b, c)`` (3-tuples): distance, normal, four weights.

    The projection on the triangle's plane when it lies inside (:func:`plane_weights`), else the
    nearest point of the three edges (:func:`nearest_edge_weights`); then :func:`triangle_contact`.
    The law of :func:`vertex_face` for one pair; the compiled stages
    (:mod:`particles.collisions.contact_kernels`) inline its three parts, and look for the nearest
    edge only when the projection is outside.
    """
    inside, alpha, beta, gamma = plane_weights(p, a, b, c)
    w0, w1, w2 = nearest_edge_weights(p, a, b, c)
    return triangle_contact(p, a, b, c, select(inside, alpha, w0), select(inside, beta, w1),
                            select(inside, gamma, w2))


def segments_closest(p1, p2, q1, q2, parallel_tol):
    """Closest points of the segments ``p1 -> p2`` and ``q1 -> q2`` (3-tuples): distance, normal, four weights.

    Ericson's clamped minimum of the quadratic in ``(s, u)``; for parallel segments the middle of the
    overlap. The law of :func:`edge_edge` for one pair, which the compiled stages inline.
    """
    d1, d2, r = vsub(p2, p1), vsub(q2, q1), vsub(p1, q1)
    a, e, b = vdot(d1, d1), vdot(d2, d2), vdot(d1, d2)
    c, f = vdot(d1, r), vdot(d2, r)
    denom = a * e - b * b  # |d1 x d2|^2 >= 0
    parallel = denom <= parallel_tol * a * e
    # general case: the unconstrained s, clamped; u from s, clamped; s again from u (Ericson 5.1.9)
    s = clip01(select(parallel, 0.0, (b * f - c * e) / select(parallel, 1.0, denom)))
    # parallel (or a point): the middle of the overlap of q's projection onto p's line, in p's parameter
    a_safe = select(a > 0, a, 1.0)
    t1 = select(a > 0, vdot(vsub(q1, p1), d1) / a_safe, 0.0)
    t2 = select(a > 0, vdot(vsub(q2, p1), d1) / a_safe, 0.0)
    s = select(parallel, 0.5 * (clip01(np.minimum(t1, t2)) + clip01(np.maximum(t1, t2))), s)
    u = clip01(select(e > 0, (b * s + f) / select(e > 0, e, 1.0), 0.0))
    s = select(parallel, s, clip01(select(a > 0, (b * u - c) / a_safe, 0.0)))
    dv = vsub(vadd(p1, vscale(s, d1)), vadd(q1, vscale(u, d2)))
    g = vadd(d1, vscale(1.0 * (a == 0), d2))
    normal = normal_or(dv, vcross(d1, d2), g)
    return np.sqrt(vdot(dv, dv)), normal, (1.0 - s, s, u - 1.0, -u)


def _rows(v):
    """The columns of points `v` (k, 3) as a 3-tuple of contiguous arrays."""
    t = np.ascontiguousarray(np.asarray(v, dtype=float).T)
    return t[0], t[1], t[2]


def _closest(distance, normal, weights, k):
    """A :class:`Closest` from a law's tuples (numbers broadcast to the k pairs)."""
    def full(v):
        return np.broadcast_to(v, (k,))

    return Closest(np.array(full(distance)), np.stack([full(v) for v in normal], axis=1),
                   np.stack([full(v) for v in weights], axis=1))


def approaching_within(distance, vN, h, thickness):
    """Whether a pair is a proximity contact: closer than `thickness`, or ending closer along its normal.

    `distance` (m) at the start of the step, `vN` its normal velocity (m/s), `h` the step (s).
    """
    return (distance < thickness) | (distance + h * vN < thickness)


def point_segment(p, a, b):
    """Closest point of the segments ``a -> b`` to the points `p`.

    Parameters
    ----------
    p, a, b : ndarray, shape (k, d)
        Points and segment ends, in metres.

    Returns
    -------
    s : ndarray, shape (k,)
        Parameter in [0, 1] of the closest point ``(1 - s) a + s b`` (0 for a
        segment of zero length).
    distance : ndarray, shape (k,)
        Distance from ``p`` to it, in metres.
    """
    p, a, b = (np.asarray(v, dtype=float) for v in (p, a, b))
    if p.shape[1] == 2:
        p, a, b = (np.concatenate([v, np.zeros((len(v), 1))], axis=1) for v in (p, a, b))
    s, distance = segment_closest(_rows(p), _rows(a), _rows(b))
    return np.broadcast_to(s, (len(p),)).copy(), distance


def vertex_face_kernel(p, a, b, c):
    """:func:`particles.collisions.proximity.vertex_face` without the checks (:func:`triangle_closest`)."""
    return _closest(*triangle_closest(_rows(p), _rows(a), _rows(b), _rows(c)), len(p))


def edge_edge_kernel(p1, p2, q1, q2):
    """:func:`particles.collisions.proximity.edge_edge` without the checks (:func:`segments_closest`)."""
    return _closest(*segments_closest(_rows(p1), _rows(p2), _rows(q1), _rows(q2), PARALLEL), len(p1))


def _points(values, names):
    arrays = [as_float_array(v, name, ndim=2) for v, name in zip(values, names)]
    shape = arrays[0].shape
    if shape[1] != 3:
        raise ValueError(f"{names[0]} must have shape (k, 3), got shape {shape}")
    for a, name in zip(arrays[1:], names[1:]):
        if a.shape != shape:
            raise ValueError(f"{name} must have the shape of {names[0]} {shape}, got shape {a.shape}")
    return arrays


def vertex_face(p, a, b, c):
    """Closest points of vertices `p` and triangles ``(a, b, c)``.

    Parameters
    ----------
    p : array_like, shape (k, 3)
        Vertex positions, in metres.
    a, b, c : array_like, shape (k, 3)
        Triangle corners, in metres (a degenerate triangle is allowed).

    Returns
    -------
    Closest
        ``weights = (1, -a_1, -a_2, -a_3)`` with the barycentric weights
        ``a_i >= 0`` of the closest triangle point; ``normal`` from the
        triangle to ``p`` (the triangle's normal ``(b - a) x (c - a)``,
        normalized, where ``p`` lies on it).

    Examples
    --------
    >>> r = vertex_face([[0.25, 0.25, 2.0]], [[0.0, 0, 0]], [[1.0, 0, 0]], [[0.0, 1, 0]])
    >>> r.distance.tolist(), r.normal.tolist(), r.weights.tolist()
    ([2.0], [[0.0, 0.0, 1.0]], [[1.0, -0.5, -0.25, -0.25]])
    """
    return vertex_face_kernel(*_points((p, a, b, c), ("p", "a", "b", "c")))


def edge_edge(p1, p2, q1, q2):
    """Closest points of the segments ``p1 -> p2`` and ``q1 -> q2``.

    Parameters
    ----------
    p1, p2, q1, q2 : array_like, shape (k, 3)
        Segment ends, in metres (a segment of zero length is allowed).

    Returns
    -------
    Closest
        ``weights = (1 - s, s, -(1 - u), -u)`` with the parameters ``s, u``
        in [0, 1] of the closest points; ``normal`` from the second segment to
        the first (``d_1 x d_2`` normalized, or any direction perpendicular to
        collinear segments, where they touch).

    Examples
    --------
    Two crossing edges 1 m apart, and two parallel ones (the middle of their overlap):

    >>> r = edge_edge([[-1.0, 0, 1], [0.0, 0, 1]], [[1.0, 0, 1], [2.0, 0, 1]],
    ...               [[0.0, -1, 0], [1.0, 0, 0]], [[0.0, 1, 0], [3.0, 0, 0]])
    >>> r.distance.tolist(), r.weights.tolist()
    ([1.0, 1.0], [[0.5, 0.5, -0.5, -0.5], [0.25, 0.75, -0.75, -0.25]])
    """
    return edge_edge_kernel(*_points((p1, p2, q1, q2), ("p1", "p2", "q1", "q2")))
