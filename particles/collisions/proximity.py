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

__all__ = ["Closest", "point_segment", "vertex_face", "edge_edge", "PARALLEL"]
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


def unit_or(v, fallback):
    """Rows of `v` divided by their length; `fallback` (unit rows) where the length is zero."""
    L = np.sqrt(dot(v, v))
    ok = L > 0
    out = np.array(fallback, dtype=float)
    out[ok] = v[ok] / L[ok, None]
    return out


def _any_perpendicular(d):
    """A unit vector perpendicular to each row of `d` (e_z for zero rows)."""
    axis = np.zeros_like(d)
    axis[np.arange(len(d)), np.argmin(np.abs(d), axis=1)] = 1.0  # the axis least aligned with d
    fallback = np.zeros_like(d)
    fallback[:, 2] = 1.0
    return unit_or(np.cross(d, axis), fallback)


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
    d = b - a
    dd = dot(d, d)
    s = np.clip(np.divide(dot(p - a, d), dd, out=np.zeros(len(p)), where=dd > 0), 0.0, 1.0)
    r = p - a - s[:, None] * d
    return s, np.sqrt(dot(r, r))


def vertex_face_kernel(p, a, b, c):
    """:func:`particles.collisions.proximity.vertex_face` without the checks."""
    k = len(p)
    e1, e2 = b - a, c - a
    nrm = np.cross(e1, e2)
    area2 = dot(nrm, nrm)
    scale2 = np.maximum(dot(e1, e1), dot(e2, e2))
    flat = area2 > 1e-14 * scale2 * scale2  # a triangle with a plane (not a sliver or a point)
    # the projection onto the plane, in barycentric coordinates (Cramer's rule on the edge vectors)
    r = p - a
    beta = np.divide(dot(np.cross(r, e2), nrm), area2, out=np.full(k, -1.0), where=flat)
    gamma = np.divide(dot(np.cross(e1, r), nrm), area2, out=np.full(k, -1.0), where=flat)
    alpha = 1.0 - beta - gamma
    inside = flat & (alpha >= 0) & (beta >= 0) & (gamma >= 0)
    w = np.stack([alpha, beta, gamma], axis=1)
    # otherwise the closest of the three edges
    s_ab, d_ab = point_segment(p, a, b)
    s_bc, d_bc = point_segment(p, b, c)
    s_ca, d_ca = point_segment(p, c, a)
    dist = np.stack([d_ab, d_bc, d_ca], axis=1)
    best = np.argmin(dist, axis=1)
    edge_w = np.zeros((k, 3, 3))
    edge_w[:, 0, 0], edge_w[:, 0, 1] = 1.0 - s_ab, s_ab
    edge_w[:, 1, 1], edge_w[:, 1, 2] = 1.0 - s_bc, s_bc
    edge_w[:, 2, 2], edge_w[:, 2, 0] = 1.0 - s_ca, s_ca
    w = np.where(inside[:, None], w, edge_w[np.arange(k), best])
    q = w[:, 0, None] * a + w[:, 1, None] * b + w[:, 2, None] * c
    d = p - q
    distance = np.sqrt(dot(d, d))
    face_normal = unit_or(nrm, _any_perpendicular(e1 + e2))
    normal = unit_or(d, face_normal)
    return Closest(distance, normal, np.concatenate([np.ones((k, 1)), -w], axis=1))


def edge_edge_kernel(p1, p2, q1, q2):
    """:func:`particles.collisions.proximity.edge_edge` without the checks."""
    k = len(p1)
    d1, d2, r = p2 - p1, q2 - q1, p1 - q1
    a, e, b = dot(d1, d1), dot(d2, d2), dot(d1, d2)
    c, f = dot(d1, r), dot(d2, r)
    denom = a * e - b * b  # |d1 x d2|^2 >= 0
    parallel = denom <= PARALLEL * a * e
    # general case: the unconstrained s, clamped; u from s, clamped; s again from u (Ericson 5.1.9)
    s = np.clip(np.divide(b * f - c * e, denom, out=np.zeros(k), where=~parallel), 0.0, 1.0)
    # parallel (or a point): the middle of the overlap of q's projection onto p's line, in p's parameter
    t1 = np.divide(dot(q1 - p1, d1), a, out=np.zeros(k), where=a > 0)
    t2 = np.divide(dot(q2 - p1, d1), a, out=np.zeros(k), where=a > 0)
    lo = np.clip(np.minimum(t1, t2), 0.0, 1.0)
    hi = np.clip(np.maximum(t1, t2), 0.0, 1.0)
    s = np.where(parallel, 0.5 * (lo + hi), s)
    u = np.clip(np.divide(b * s + f, e, out=np.zeros(k), where=e > 0), 0.0, 1.0)
    s_back = np.clip(np.divide(b * u - c, a, out=np.zeros(k), where=a > 0), 0.0, 1.0)
    s = np.where(parallel, s, s_back)
    pa = p1 + s[:, None] * d1
    qb = q1 + u[:, None] * d2
    dv = pa - qb
    distance = np.sqrt(dot(dv, dv))
    normal = unit_or(dv, unit_or(np.cross(d1, d2), _any_perpendicular(d1 + (a == 0)[:, None] * d2)))
    weights = np.stack([1.0 - s, s, u - 1.0, -u], axis=1)
    return Closest(distance, normal, weights)


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
