"""The cloth collision pipeline's compiled stages (numba): broad phase, proximity, the continuous test.

:class:`particles.collisions.ClothCollisions` and its
:class:`~particles.collisions.candidates.CandidateCache` call these (through
:func:`particles.backends.kernels_for`) when their backend resolves to
numba. Each returns what the NumPy stage it replaces returns:

* :func:`cloth_candidates`: the candidate pairs of
  :func:`particles.collisions.candidates.candidates_in_boxes` (the same
  sorted sets: a bucket grid walked box by box, :mod:`particles.backends._broad_kernels`);
  :meth:`~particles.collisions.candidates.CandidateCache.pairs` searches each call's own boxes with it,
  which gives the rows its cache would (the cache only ever holds more pairs than the boxes select);
* :func:`cloth_closest`, :func:`cloth_first_contacts`: the closest points
  of :mod:`particles.collisions.proximity` and the continuous test of
  :mod:`particles.collisions.ccd`, pair by pair (:mod:`particles.backends._contact_kernels`);
* :func:`cloth_jacobi`: one Jacobi iteration of the proximity impulses.

Nothing here imports :mod:`particles.collisions` (the pipeline passes its
constants), so that no import circle closes through this module. Importing it
imports numba.
"""

import numpy as np

from ._broad_kernels import box_candidates, corner_bounds
from ._contact_kernels import closest_pairs, first_contact_pairs, jacobi_iteration, proximity_rows
from ._kernels import incidence, pick

__all__ = ["cloth_candidates", "cloth_closest", "cloth_proximity", "cloth_first_contacts",
           "cloth_incidence", "cloth_jacobi"]

_EMPTY_MASK = np.zeros(0, dtype=np.bool_)

# a box query walks the cells its box covers and tests their boxes: the work of about this many items of pick's
# threshold (a spring's force); 1k vertices or edges already pay for the threads (a 32^2 sheet: 2 ms a search)
QUERY_WEIGHT = 16


def _corners(v_lo, v_hi, idx):
    lo, hi = np.empty((len(idx), 3)), np.empty((len(idx), 3))
    corner_bounds(v_lo, v_hi, idx, lo, hi)
    return lo, hi


def cloth_candidates(mesh, lo, hi, pad, vertices=None):
    """:func:`particles.collisions.candidates.candidates_in_boxes`, compiled: ``iv, jf, ie, je`` (int64, sorted).

    Parameters
    ----------
    mesh : TriangleMesh
    lo, hi : ndarray, shape (n, 3)
        Each vertex's box, in metres (inflated by `pad` here; faces and edges get the union of theirs).
    pad : float
        In metres.
    vertices : ndarray of bool, shape (n,), optional
        Only pairs that hold one of these vertices.
    """
    F, E = mesh.faces, mesh.edges
    v_lo = np.ascontiguousarray(lo - pad)
    v_hi = np.ascontiguousarray(hi + pad)
    mask = _EMPTY_MASK if vertices is None else np.ascontiguousarray(vertices, dtype=np.bool_)
    masked = vertices is not None
    empty = np.zeros(0, dtype=np.int64)
    iv = jf = ie = je = empty
    if len(F) and mesh.n:
        f_lo, f_hi = _corners(v_lo, v_hi, F)
        own = np.arange(mesh.n, dtype=np.int64)[:, None]
        keys = pick(box_candidates, QUERY_WEIGHT * mesh.n)(v_lo, v_hi, f_lo, f_hi, own, F, False, mask, masked)
        iv, jf = np.divmod(keys, len(F))
    if len(E) > 1:
        e_lo, e_hi = _corners(v_lo, v_hi, E)
        keys = pick(box_candidates, QUERY_WEIGHT * len(E))(e_lo, e_hi, e_lo, e_hi, E, E, True, mask, masked)
        ie, je = np.divmod(keys, len(E))
    return iv, jf, ie, je


def cloth_closest(x, rows, edge, parallel_tol):
    """Closest points of the pairs `rows` (k, 4) of points `x` (n, 3): ``distance, normal, weights``.

    :func:`particles.collisions.proximity.vertex_face` (or, with `edge`, ``edge_edge``) pair by pair,
    with the NumPy code's arithmetic.
    """
    k = len(rows)
    distance, normal, weights = np.empty(k), np.empty((k, 3)), np.empty((k, 4))
    pick(closest_pairs, k)(np.ascontiguousarray(x), rows, edge, parallel_tol, distance, normal, weights)
    return distance, normal, weights


def cloth_proximity(x0, vbar, w, x_rest, rows, edge, h, thickness, rest_distance, parallel_tol):
    """The proximity contacts among candidate `rows`: ``rows, weights, normals, distances`` of those kept.

    A pair is kept when it is closer than `thickness` at `x0` or would end closer along its normal, has
    a finite effective mass, (edges) its closest points are not an edge's ends, and (with `x_rest`) it is
    at least `rest_distance` apart at rest: the tests of ``ClothCollisions._proximity_contacts``.
    """
    k = len(rows)
    keep = np.empty(k, dtype=np.bool_)
    distance, normal, weights = np.empty(k), np.empty((k, 3)), np.empty((k, 4))
    rest = x_rest is not None
    xr = np.ascontiguousarray(x_rest) if rest else np.zeros((0, 3))
    pick(proximity_rows, k)(np.ascontiguousarray(x0), np.ascontiguousarray(vbar), w, xr, rest, rows, edge,
                            float(h), thickness, rest_distance, parallel_tol, keep, distance, normal, weights)
    return rows[keep], weights[keep], normal[keep], distance[keep]


def cloth_first_contacts(x0, dx, rows, edge, eta, ftol, bisections, parallel_tol):
    """:func:`particles.collisions.ccd.first_contacts` on candidate `rows` of the mesh, pair by pair.

    Returns the rows that touch during the step, their weights (k, 4), normals (k, 3) and times (k,).
    """
    k = len(rows)
    hit = np.empty(k, dtype=np.bool_)
    time, normal, weights = np.empty(k), np.empty((k, 3)), np.empty((k, 4))
    pick(first_contact_pairs, k)(np.ascontiguousarray(x0), np.ascontiguousarray(dx), rows, edge, eta, ftol,
                                 bisections, parallel_tol, hit, time, normal, weights)
    return rows[hit], weights[hit], normal[hit], time[hit]


def cloth_incidence(V, n):
    """The contacts of each vertex, as ``np.bincount`` over ``V.ravel()`` meets them: ``ptr`` (n + 1), ``col``."""
    return incidence(np.ascontiguousarray(V).ravel(), n, 1, False)


def cloth_jacobi(vbar, V, W, N, S, target, w, ptr, col, h, tol, friction, active, impulse, load):
    """One Jacobi iteration of the proximity impulses on `vbar` (n, 3), in place; returns the active count.

    The arithmetic of ``ClothCollisions._active`` and ``_impulses`` with ``np.bincount``'s sums per vertex
    (in the order of `col`). `active` (k,) is set to the contacts that got an impulse; `impulse` (k, 3)
    and `load` (n,) are work arrays.
    """
    return pick(jacobi_iteration, max(len(V), len(vbar)))(vbar, V, W, N, S, target, w, ptr, col, float(h), tol,
                                                        friction, active, impulse, load)
