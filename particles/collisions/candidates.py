"""Broad phase of cloth collisions: which vertex-face and edge-edge pairs can touch within a step.

The box swept by each vertex, face and edge over a step, inflated by a pad, is put in the bucket grid of
:func:`particles.collisions.triangle_crossing.box_pairs`; only pairs whose boxes overlap go on to the
narrow phase (:mod:`particles.collisions.proximity`, :mod:`particles.collisions.ccd`). Pairs that share a
vertex touch by construction and are left out. :class:`~particles.collisions.candidate_cache.CandidateCache`
keeps the pairs from step to step, as a Verlet list keeps neighbours, for the pipeline of :mod:`particles.collisions.pipeline`
(:mod:`particles.collisions.candidate_cache`).
"""

import numpy as np

from .triangle_crossing import box_pairs, intervals_overlap

__all__ = ["element_boxes", "candidate_elements", "candidates_in_boxes", "pair_rows", "candidate_pairs",
           "boxes_overlap", "candidates_touching", "merge_keys"]


def _boxes(x0, x1, index, pad):
    """Boxes around the points `index` (shape (k, j)) at both ends of the step, inflated by `pad`."""
    lo = np.minimum(x0[index].min(axis=1), x1[index].min(axis=1))
    hi = np.maximum(x0[index].max(axis=1), x1[index].max(axis=1))
    return lo - pad, hi + pad


def element_boxes(mesh, x0, x1, pad):
    """Swept, inflated boxes of the vertices, faces and edges: ``(lo, hi)`` of each, in that order."""
    return (_boxes(x0, x1, np.arange(mesh.n)[:, None], pad), _boxes(x0, x1, mesh.faces, pad),
            _boxes(x0, x1, mesh.edges, pad))


def candidate_elements(mesh, x0, x1, pad, vertices=None):
    """Vertex-face pairs ``(iv, jf)`` and edge pairs ``(ie, je)`` (``ie < je``) with overlapping boxes.

    Pairs with a common vertex are left out; with a mask `vertices`, only
    pairs that hold one of them. Each list is sorted by its key
    ``iv m + jf`` (``ie e + je``).
    """
    lo, hi = np.minimum(x0, x1), np.maximum(x0, x1)
    return candidates_in_boxes(mesh, lo, hi, pad, vertices)


def candidates_in_boxes(mesh, lo, hi, pad, vertices=None, pairs=box_pairs):
    """:func:`candidate_elements` from the vertices' boxes ``(lo, hi)`` (faces and edges get their union).

    `pairs(lo_a, hi_a, lo_b, hi_b)` finds the overlapping boxes of the masked search (default: the grid of
    :func:`particles.collisions.triangle_crossing.box_pairs`).
    """
    F, E = mesh.faces, mesh.edges
    v_lo, v_hi = lo - pad, hi + pad
    f_lo, f_hi = v_lo[F].min(axis=1), v_hi[F].max(axis=1)
    e_lo, e_hi = v_lo[E].min(axis=1), v_hi[E].max(axis=1)
    if vertices is None:
        iv, jf = box_pairs(v_lo, v_hi, f_lo, f_hi)
        ie, je = box_pairs(e_lo, e_hi)
    else:
        sv = np.flatnonzero(vertices)
        sf = np.flatnonzero(vertices[F].any(axis=1))
        se = np.flatnonzero(vertices[E].any(axis=1))
        a, b = pairs(v_lo[sv], v_hi[sv], f_lo, f_hi)
        c, d = pairs(v_lo, v_hi, f_lo[sf], f_hi[sf])
        keys = np.unique(np.concatenate([sv[a] * len(F) + b, c * len(F) + sf[d]]))
        iv, jf = np.divmod(keys, max(len(F), 1))
        a, b = pairs(e_lo[se], e_hi[se], e_lo, e_hi)
        a = se[a]
        keys = np.unique(np.minimum(a, b) * len(E) + np.maximum(a, b))
        ie, je = np.divmod(keys, max(len(E), 1))
        keep = ie != je
        ie, je = ie[keep], je[keep]
    keep = ~(F[jf] == iv[:, None]).any(axis=1)  # the vertex is not a corner of the face
    iv, jf = iv[keep], jf[keep]
    keep = ~(E[ie][:, :, None] == E[je][:, None, :]).any(axis=(1, 2))  # no common vertex
    return iv.astype(np.int64), jf.astype(np.int64), ie[keep].astype(np.int64), je[keep].astype(np.int64)


def pair_rows(mesh, iv, jf, ie, je):
    """The four vertices of each pair: ``(vertex, a, b, c)`` and ``(p_1, p_2, q_1, q_2)``."""
    vf = np.concatenate([iv[:, None], mesh.faces[jf]], axis=1)
    ee = np.concatenate([mesh.edges[ie], mesh.edges[je]], axis=1)
    return vf.astype(np.int64), ee.astype(np.int64)


def candidate_pairs(mesh, x0, x1, pad, vertices=None):
    """:func:`particles.collisions.ccd.candidates` without the checks."""
    return pair_rows(mesh, *candidate_elements(mesh, x0, x1, pad, vertices))


def boxes_overlap(boxes_a, boxes_b, ia, ib):
    """Whether boxes ``ia`` of one set overlap boxes ``ib`` of another (each set a pair ``(lo, hi)``)."""
    (lo_a, hi_a), (lo_b, hi_b) = boxes_a, boxes_b
    return np.all(intervals_overlap(lo_a[ia], hi_a[ia], lo_b[ib], hi_b[ib]), axis=1)


def _overlap_matrix(lo_a, hi_a, lo_b, hi_b):
    """All overlapping pairs of a few boxes A with boxes B, by testing every pair (rows of A in chunks)."""
    I, J = [], []
    step = max(1, 2_000_000 // max(len(lo_b), 1))
    for s in range(0, len(lo_a), step):  # a loop over chunks of a few rows
        la, ha = lo_a[s:s + step, None, :], hi_a[s:s + step, None, :]
        ok = np.all(intervals_overlap(la, ha, lo_b[None], hi_b[None]), axis=2)
        i, j = np.nonzero(ok)
        I.append(i + s)
        J.append(j)
    if not I:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(I).astype(np.int64), np.concatenate(J).astype(np.int64)


def candidates_touching(mesh, lo, hi, pad, far):
    """:func:`candidates_in_boxes` for the pairs with a vertex in `far` only, testing them against every box.

    For a few vertices (a grid search costs the same whatever their number).
    """
    return candidates_in_boxes(mesh, lo, hi, pad, far, pairs=_overlap_matrix)


def merge_keys(keys, new):
    """The sorted union of the sorted unique `keys` and a few `new` ones (inserted, not re-sorted)."""
    new = np.unique(new)
    pos = np.searchsorted(keys, new)
    present = np.zeros(len(new), dtype=bool)
    inside = pos < len(keys)
    present[inside] = keys[pos[inside]] == new[inside]
    return np.insert(keys, pos[~present], new[~present])
