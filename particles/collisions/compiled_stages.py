"""The cloth collision pipeline's compiled stages (numba): broad phase, proximity, the continuous test.

:class:`particles.collisions.ClothCollisions` and its
:class:`~particles.collisions.candidate_cache.CandidateCache` call these (through
:func:`particles.backends.compiled`) when their backend resolves to
numba. Each returns what the NumPy stage it replaces returns:

* :func:`cloth_candidates`: the candidate pairs of
  :func:`particles.collisions.candidates.candidates_in_boxes` (the same
  sorted sets: a bucket grid walked box by box, :mod:`particles.collisions.broad_kernels`);
  :meth:`~particles.collisions.candidate_cache.CandidateCache.pairs` searches each call's own boxes with it,
  which gives the rows its cache would (the cache only ever holds more pairs than the boxes select); a
  masked search walks small grids of the masked elements alone
  (:func:`particles.collisions.broad_kernels.subset_pairs`), and a search within the boxes of an
  earlier one filters that search's pairs (:func:`particles.collisions.broad_kernels.kept_pairs`) and
  searches again only around the vertices that left them;
* :func:`cloth_closest`, :func:`cloth_first_contacts`: the closest points
  of :mod:`particles.collisions.proximity` and the continuous test of
  :mod:`particles.collisions.ccd`, pair by pair (:mod:`particles.collisions.contact_kernels`);
* :func:`cloth_body_vertices`, :func:`cloth_low_edge_samples`: the bodies' vertex pass and the test of
  their edge samples, for primitives at rest (:mod:`particles.collisions.body_kernels`);
* :func:`cloth_impulses`: the Jacobi iterations of the proximity impulses, with the bodies' vertex pass
  after each when the bodies are primitives at rest (:mod:`particles.collisions.impulse_kernels`).

Each kernel inlines the formulas of the NumPy stage it replaces (the
contacts' impulses of :mod:`particles.collisions.response`, the boxes'
overlap of :mod:`particles.collisions.triangle_crossing`). The pipeline loads
this module through :func:`particles.collisions.candidates.compiled_stages`
and passes its constants; importing it imports numba.
"""

import numpy as np

from ..backends.compile import pick
from .body_kernels import body_vertices, low_edge_samples
from .broad_kernels import box_candidates, corner_bounds, key_rows, kept_pairs, subset_pairs
from .collider_kernels import surface_rows
from .contact_kernels import closest_pairs, first_contact_pairs, proximity_rows
from .impulse_kernels import BLOCKS, proximity_impulses

__all__ = ["cloth_candidates", "cloth_candidate_rows", "cloth_closest", "cloth_proximity", "cloth_first_contacts",
           "cloth_impulses", "cloth_body_vertices", "cloth_low_edge_samples", "surface_rows"]

_EMPTY_MASK = np.zeros(0, dtype=np.bool_)

# a box query walks the cells its box covers and tests their boxes: the work of about this many items of pick's
# threshold (a spring's force); 1k vertices or edges already pay for the threads (a 32^2 sheet: 2 ms a search)
QUERY_WEIGHT = 16

# the Jacobi iterations sum each vertex's terms in slices of at least this many active contacts (at most
# impulse_kernels.BLOCKS, each on one thread): below twice as many, in one slice, in np.bincount's order
JACOBI_PART_MIN = 4096

# an unmasked search may take its pairs from the memo of an earlier one when at most one vertex in this many
# left that search's boxes (the pairs of those vertices are searched again: a masked search)
LEFT_MAX = 64


def _corners(v_lo, v_hi, idx):
    lo, hi = np.empty((len(idx), 3)), np.empty((len(idx), 3))
    corner_bounds(v_lo, v_hi, idx, lo, hi)
    return lo, hi


def _keys(mesh, lo, hi, pad, vertices, memo=None, ordered=True):
    """The keys ``iv m + jf`` and ``ie e + je`` of :func:`cloth_candidates`' pairs (None where none), sorted when
    `ordered` (else in an order fixed by the boxes).

    Without a mask, with a `memo` (see :func:`cloth_candidate_rows`): taken from the pairs of its search when
    the boxes allow it, and kept there after a search. A masked search (a few vertices) walks grids of the
    masked elements alone and neither reads nor replaces the memo.
    """
    v_lo = np.ascontiguousarray(lo - pad)
    v_hi = np.ascontiguousarray(hi + pad)
    masked = vertices is not None
    if masked:
        return _searched(mesh, v_lo, v_hi, np.ascontiguousarray(vertices, dtype=np.bool_), ordered)
    if memo is not None and memo.get("v_lo") is not None and memo["v_lo"].shape == v_lo.shape and (
            memo["ordered"] or not ordered):
        left = np.any((v_lo < memo["v_lo"]) | (v_hi > memo["v_hi"]), axis=1)
        if int(left.sum()) * LEFT_MAX <= mesh.n:
            return _kept_keys(mesh, v_lo, v_hi, memo["keys"], left, ordered)
    keys = _searched(mesh, v_lo, v_hi, None, ordered)
    if memo is not None:
        memo.update(v_lo=v_lo, v_hi=v_hi, keys=keys, ordered=ordered)
    return keys


def _searched(mesh, v_lo, v_hi, mask, ordered):
    """The keys of the pairs whose padded vertex boxes ``v_lo, v_hi`` overlap (holding a vertex of `mask` unless
    None), searched: vertex-face and edge-edge (None for a kind the mesh lacks)."""
    wanted = (len(mesh.faces) > 0 and mesh.n > 0, len(mesh.edges) > 1)
    return tuple(_search(*_boxes(v_lo, v_hi, Q, T, same), Q, T, same, mask, ordered) if want else None
                 for (Q, T, same), want in zip(_kinds(mesh), wanted))  # the two kinds of pairs


def _kept_keys(mesh, v_lo, v_hi, keys, left, ordered):
    """:func:`_keys` from a memo's `keys`: those still overlapping, and a search around the vertices `left`.

    Every vertex outside `left` has its padded box within the one of the memo's search, so a pair of
    them that overlaps now overlapped then and is among the memo's keys; the pairs that hold a vertex of
    `left` are searched again (a masked search).
    """
    out = []
    for found, (Q, T, same) in zip(keys, _kinds(mesh)):  # the two kinds of pairs
        if found is None:
            out.append(None)
            continue
        q_lo, q_hi, t_lo, t_hi = _boxes(v_lo, v_hi, Q, T, same)
        keep = np.empty(len(found), dtype=np.bool_)
        pick(kept_pairs, len(found))(found, len(T), Q, T, q_lo, q_hi, t_lo, t_hi, left, keep)
        found = found[keep]
        if left.any():
            again = _search(q_lo, q_hi, t_lo, t_hi, Q, T, same, left, ordered)
            found = (np.insert(found, np.searchsorted(found, again), again) if ordered  # disjoint sorted lists
                     else np.concatenate([found, again]))
        out.append(found)
    return tuple(out)


def _search(q_lo, q_hi, t_lo, t_hi, Q, T, same, mask, ordered=True):
    """Keys of the overlapping pairs: the grid of :func:`box_candidates`, or, with a vertex `mask` (not None), the
    pairs that hold one of its vertices, from grids of the masked elements alone (:func:`subset_pairs`).

    With a mask: every query against the targets that hold a masked vertex, then (two sets) every other
    target against the queries that hold one; one set (edges): every edge against the masked ones, a pair
    of two masked edges found from its lower one.
    """
    if mask is None:
        return pick(box_candidates, QUERY_WEIGHT * len(Q))(q_lo, q_hi, t_lo, t_hi, Q, T, same, ordered)
    q_in, t_in = mask[Q].any(axis=1), mask[T].any(axis=1)
    every, none = np.ones(len(Q), dtype=np.bool_), np.zeros(max(len(Q), len(T)), dtype=np.bool_)
    search = pick(subset_pairs, QUERY_WEIGHT * len(Q))
    m = len(T)
    if same:
        keys = search(q_lo, q_hi, Q, every, t_in, np.flatnonzero(t_in), t_lo, t_hi, T, 2, m)
    else:
        keys = np.concatenate([search(q_lo, q_hi, Q, every, none, np.flatnonzero(t_in), t_lo, t_hi, T, 0, m),
                               search(t_lo, t_hi, T, ~t_in, none, np.flatnonzero(q_in), q_lo, q_hi, Q, 1, m)])
    if ordered:
        keys.sort()  # each pair is found once
    return keys


def _own(n):
    """Each vertex as a one-vertex element: ``[[0], [1], ..., [n - 1]]``, read-only like the mesh's faces and
    edges, so that the kernels see one type of element array (numba compiles a kernel for each)."""
    own = np.arange(n, dtype=np.int64)[:, None]
    own.setflags(write=False)
    return own


def _kinds(mesh):
    """The two kinds of pairs, each ``(Q, T, same)``: vertices against faces, then edges against edges."""
    return (_own(mesh.n), mesh.faces, False), (mesh.edges, mesh.edges, True)


def _boxes(v_lo, v_hi, Q, T, same):
    """Query and target boxes ``q_lo, q_hi, t_lo, t_hi`` of a kind of pairs from the padded vertex boxes."""
    t_lo, t_hi = _corners(v_lo, v_hi, T)
    return (t_lo, t_hi, t_lo, t_hi) if same else (v_lo, v_hi, t_lo, t_hi)


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
    vf, ee = _keys(mesh, lo, hi, pad, vertices)
    empty = np.zeros(0, dtype=np.int64)
    iv, jf = (empty, empty) if vf is None else np.divmod(vf, len(mesh.faces))
    ie, je = (empty, empty) if ee is None else np.divmod(ee, len(mesh.edges))
    return iv, jf, ie, je


def cloth_candidate_rows(mesh, lo, hi, pad, vertices=None, memo=None, ordered=True):
    """:func:`cloth_candidates` as :func:`particles.collisions.candidates.pair_rows` gives them: ``vf, ee``.

    The vertex-face rows ``(vertex, a, b, c)`` and the edge-edge rows ``(p_1, p_2, q_1, q_2)``, shape
    (k, 4) each, int64, in the order of the sorted keys; the arguments as :func:`cloth_candidates`, and

    memo : dict, optional
        Kept by the caller from call to call (:class:`~particles.collisions.candidate_cache.CandidateCache`
        keeps one): the padded vertex boxes and the pairs of the last search without a mask. For a search
        without a mask, when at most one vertex in ``LEFT_MAX`` has a padded box outside its box there,
        the pairs are taken from that search's (those whose boxes still overlap) and only the pairs holding
        a vertex that left are searched again: the continuous test's first search within the boxes of the
        step's proximity search filters its pairs instead of building a grid. A masked search neither
        reads nor replaces it (its small grids are quicker than filtering). The pairs are the same either
        way.
    ordered : bool
        False: the rows come in an order fixed by the boxes, with their key as a fifth column (shape
        (k, 5)), and the caller sorts what it keeps by it (:func:`in_key_order`): the cloth pipeline keeps
        a few thousand of hundreds of thousands of pairs, and sorting them all took half of its searches.
    """
    vf, ee = _keys(mesh, lo, hi, pad, vertices, memo, ordered)
    out = []
    for keys, (Q, T, _) in zip((vf, ee), _kinds(mesh)):  # the two kinds of pairs
        rows = np.empty((0 if keys is None else len(keys), 4 if ordered else 5), dtype=np.int64)
        if len(rows):
            pick(key_rows, len(rows))(keys, len(T), np.ascontiguousarray(Q, dtype=np.int64),
                                      np.ascontiguousarray(T, dtype=np.int64), rows)
        out.append(rows)
    return tuple(out)


def in_key_order(rows, keep):
    """The indices of the rows where `keep` holds, in the order of the rows' keys: with rows of
    :func:`cloth_candidate_rows` of four columns (sorted already), ``flatnonzero(keep)``; of five, sorted by the
    fifth (the key)."""
    kept = np.flatnonzero(keep)
    if rows.shape[1] == 5 and len(kept) > 1:
        kept = kept[np.argsort(rows[kept, 4], kind="stable")]
    return kept


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
    kept = in_key_order(rows, keep)
    return rows[kept, :4], weights[kept], normal[kept], distance[kept]


def cloth_first_contacts(x0, dx, rows, edge, eta, ftol, bisections, parallel_tol):
    """:func:`particles.collisions.ccd.first_contacts` on candidate `rows` of the mesh, pair by pair.

    Returns the rows that touch during the step, their weights (k, 4), normals (k, 3) and times (k,).
    """
    k = len(rows)
    hit = np.empty(k, dtype=np.bool_)
    time, normal, weights = np.empty(k), np.empty((k, 3)), np.empty((k, 4))
    pick(first_contact_pairs, k)(np.ascontiguousarray(x0), np.ascontiguousarray(dx), rows, edge, eta, ftol,
                                 bisections, parallel_tol, hit, time, normal, weights)
    kept = in_key_order(rows, hit)
    return rows[kept, :4], weights[kept], normal[kept], time[kept]


_NO_BODIES = (np.zeros(0, dtype=np.int64), np.zeros((0, 13)))


def cloth_impulses(vbar, x0, V, W, N, S, target, w, h, tol, friction, iterations, thickness, bodies=None,
                   relaxation=1.0, start=0):
    """Jacobi iterations of the proximity impulses on `vbar` (n, 3), in place: ``ClothCollisions._proximity``.

    Parameters
    ----------
    vbar : ndarray, shape (n, 3)
        The step's average velocities, in m/s (changed in place).
    x0 : ndarray, shape (n, 3)
        Positions at the start of the step, in metres.
    V, W, N, S, target : ndarray
        The contacts: vertices (k, 4), weights (k, 4), unit normals (k, 3), ``sum_j W_j^2 w_j`` (k,) and
        target normal velocities (k,), in m/s.
    w : ndarray, shape (n,)
        Inverse masses, in 1/kg (0 for pinned vertices).
    h : float
        Step, in seconds.
    tol : float
        A contact is active while its normal velocity is more than ``tol / h`` below its target (metres).
    friction : float
        Coulomb coefficient.
    iterations : int
        Most iterations; fewer when one finds no active contact.
    thickness : float
        Distance kept from the bodies, in metres.
    bodies : tuple (kinds, rows), optional
        Bodies at rest as :func:`particles.collisions.collider_kernels.surface_rows` gives them: after each iteration
        the free vertices of its active contacts are moved out of them.
    relaxation : float
        Over-relaxation (>= 1): from the pipeline's second iteration on, a contact's impulse is divided
        by ``max(load / relaxation, 1)`` instead of ``max(load, 1)`` (``ClothCollisions``' `relaxation`).
    start : int
        Number of iterations the pipeline already made (0: this call's first iteration averages plainly).

    Returns
    -------
    done : int
        Iterations that gave impulses.
    touched : ndarray of bool, shape (k,)
        The contacts that got an impulse.
    active : ndarray of bool, shape (k,)
        Those of the last iteration.
    """
    k, n = len(V), len(vbar)
    kinds, rows = _NO_BODIES if bodies is None else bodies
    touched, active = np.zeros(k, dtype=np.bool_), np.zeros(k, dtype=np.bool_)
    order, impulse, load = np.empty(k, dtype=np.int64), np.empty((k, 3)), np.empty(n)
    part_load, part_hit = np.empty((BLOCKS, n)), np.empty((BLOCKS, n), dtype=np.bool_)
    part_vel = np.empty((BLOCKS, n, 3))
    done = pick(proximity_impulses, max(k, n))(vbar, np.ascontiguousarray(x0), V, W, N, S, target, w, float(h),
                                                 float(tol), float(friction), float(relaxation), int(start),
                                                 int(iterations), float(thickness), kinds, rows,
                                                 int(JACOBI_PART_MIN), touched, active, order, impulse, load,
                                                 part_load, part_hit, part_vel)
    return done, touched, active


def cloth_body_vertices(x0, vbar, free, h, thickness, friction, bodies):
    """``BodyStage._bodies``' vertex pass for bodies at rest: `free` vertices moved out of their thickness.

    Parameters
    ----------
    x0, vbar : ndarray, shape (n, 3)
        Start positions (m) and the step's average velocities (m/s, changed in place).
    free : ndarray of bool, shape (n,)
        The vertices treated.
    h, thickness, friction : float
        Step (s), distance kept (m), Coulomb coefficient.
    bodies : tuple (kinds, rows)
        As :func:`particles.collisions.collider_kernels.surface_rows` gives them (one body, or several in turn).

    Returns
    -------
    int
        Vertex-body pairs closer than `thickness` at the end of the step (NumPy's count).
    """
    kinds, rows = bodies
    return int(pick(body_vertices, len(vbar))(np.ascontiguousarray(x0), vbar, np.ascontiguousarray(free), float(h),
                                              float(thickness), float(friction), kinds, rows))


def cloth_low_edge_samples(x0, vbar, h, edges, w, samples, target, body):
    """Edge samples that end closer than `target` to one body at rest and can move (``BodyStage._edges_out``).

    `edges` (e, 2), inverse masses `w` (n,), `samples` the fractions along each edge, `body` a pair
    ``(kind, row)`` of :func:`particles.collisions.collider_kernels.surface_rows`' table. Returns their count.
    """
    kind, row = body
    return int(pick(low_edge_samples, QUERY_WEIGHT * len(edges))(np.ascontiguousarray(x0), vbar, float(h), edges, w,
                                                                 np.asarray(samples, dtype=float), float(target),
                                                                 int(kind), row))
