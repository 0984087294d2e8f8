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
conserves momentum (``sum_j w_j = 0``); :mod:`particles.clothcollisions`
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

from ._checks import as_float_array
from ._closest import PARALLEL, Closest, edge_edge_kernel, point_segment, vertex_face_kernel

__all__ = ["Closest", "point_segment", "vertex_face", "edge_edge", "PARALLEL"]


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
