"""Kernels of the closest points of vertex-triangle and edge-edge pairs (private to the package).

The checked, documented functions are :func:`particles.proximity.vertex_face`
and :func:`particles.proximity.edge_edge`; these kernels skip the checks,
for the collision stages that call them on every step.
"""

from dataclasses import dataclass

import numpy as np

__all__ = ["PARALLEL", "Closest", "dot", "unit_or", "point_segment", "vertex_face_kernel", "edge_edge_kernel"]

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
    """:func:`particles.proximity.vertex_face` without the checks."""
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
    """:func:`particles.proximity.edge_edge` without the checks."""
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
