"""Kernels of the continuous collision test (private to the package).

The checked, documented functions are in :mod:`particles.ccd`, which
explains the method; these kernels skip the checks, for the collision stages
that call them on every step.
"""

from dataclasses import dataclass

import numpy as np

from ._closest import dot, edge_edge_kernel, unit_or, vertex_face_kernel
from .intersections import box_pairs

__all__ = ["BISECTIONS", "F_TOL", "Impacts", "cubic_coefficients", "unit_roots", "candidate_pairs", "first_contacts",
           "overlapping", "detect_pairs", "element_boxes", "candidate_elements", "pair_rows", "boxes_overlap",
           "candidates_in_boxes", "candidates_touching"]


BISECTIONS = 60
"""Bisection steps per monotone piece (2^-60 of [0, 1]: below the spacing of doubles near 1)."""


F_TOL = 1e-12
"""Relative tolerance of the cubic: ``|f| <= F_TOL L^3`` counts as zero, ``L`` the pair's largest coordinate span."""


def _triple(u, v, w):
    return np.einsum("ij,ij->i", u, np.cross(v, w))


def cubic_coefficients(x, dx):
    p = [x[:, i] - x[:, 0] for i in (1, 2, 3)]
    q = [dx[:, i] - dx[:, 0] for i in (1, 2, 3)]
    d = _triple(p[0], p[1], p[2])
    c = _triple(q[0], p[1], p[2]) + _triple(p[0], q[1], p[2]) + _triple(p[0], p[1], q[2])
    b = _triple(q[0], q[1], p[2]) + _triple(q[0], p[1], q[2]) + _triple(p[0], q[1], q[2])
    a = _triple(q[0], q[1], q[2])
    return np.stack([a, b, c, d], axis=1)


def _horner(coef, t):
    a, b, c, d = (coef[..., k] for k in range(4))
    return ((a * t + b) * t + c) * t + d


def unit_roots(coef, ftol):
    k = len(coef)
    a, b, c = coef[:, 0], coef[:, 1], coef[:, 2]
    # critical points: 3 a t^2 + 2 b t + c = 0, in closed form (the stable quadratic formula)
    A, B, C = 3.0 * a, 2.0 * b, c
    disc = B * B - 4.0 * A * C
    crit = np.full((k, 2), np.nan)
    quad = (A != 0) & (disc >= 0)
    sq = np.sqrt(np.where(quad, disc, 0.0))
    qq = -0.5 * (B + np.where(B >= 0, sq, -sq))
    with np.errstate(divide="ignore", invalid="ignore"):
        crit[:, 0] = np.where(quad, qq / np.where(A != 0, A, 1.0), np.nan)
        crit[:, 1] = np.where(quad & (qq != 0), C / np.where(qq != 0, qq, 1.0), np.nan)
    lin = (A == 0) & (B != 0)
    crit[lin, 0] = -C[lin] / B[lin]
    crit = np.where((crit > 0) & (crit < 1), crit, np.nan)
    crit = np.sort(crit, axis=1)  # nan last
    ends = np.concatenate([np.zeros((k, 1)), crit, np.ones((k, 1))], axis=1)  # (k, 4), nan for unused cuts
    # pieces [ends_j, next non-nan end]: fill the nan cuts with the next end (empty pieces)
    ends[:, 2] = np.where(np.isnan(ends[:, 2]), 1.0, ends[:, 2])
    ends[:, 1] = np.where(np.isnan(ends[:, 1]), ends[:, 2], ends[:, 1])
    lo, hi = ends[:, :3], ends[:, 1:]
    flo, fhi = _horner(coef[:, None, :], lo), _horner(coef[:, None, :], hi)
    tol = ftol[:, None]
    zlo, zhi = np.abs(flo) <= tol, np.abs(fhi) <= tol
    used = hi > lo
    sign_change = used & (np.sign(flo) * np.sign(fhi) < 0) & ~zlo & ~zhi
    roots = np.full((k, 3), np.nan)
    roots = np.where(used & zlo, lo, roots)
    roots = np.where(used & ~zlo & zhi, hi, roots)
    r, j = np.nonzero(sign_change)
    if len(r):
        L, H = lo[r, j].copy(), hi[r, j].copy()
        cf = coef[r]
        up = _horner(cf, L) < 0  # f increases from L to H on this piece
        for _ in range(BISECTIONS):  # a loop over bisection steps (all pieces at once)
            mid = 0.5 * (L + H)
            below = (_horner(cf, mid) < 0) == up  # the root lies above mid
            L = np.where(below, mid, L)
            H = np.where(below, H, mid)
        roots[r, j] = 0.5 * (L + H)
    return np.sort(roots, axis=1)


@dataclass(frozen=True)
class Impacts:
    """Contacts of vertex-face and edge-edge pairs, in the four-vertex form of :mod:`particles.proximity`.

    Attributes
    ----------
    vertices : ndarray of int64, shape (k, 4)
        ``(p, a, b, c)`` for a vertex ``p`` and a face ``(a, b, c)``, ``(p_1, p_2, q_1, q_2)`` for two edges.
    weights : ndarray, shape (k, 4)
        ``w`` with ``sum_j w_j = 0``; ``sum_j w_j x_j`` is the separation of the pair.
    normal : ndarray, shape (k, 3)
        Unit normal, oriented so that the pair separates along it
        (``n . sum_j w_j dx_j <= 0`` for an approaching pair).
    time : ndarray, shape (k,)
        Time of impact as a fraction of the step, in [0, 1].
    edge : ndarray of bool, shape (k,)
        True for edge-edge pairs.
    """

    vertices: np.ndarray
    weights: np.ndarray
    normal: np.ndarray
    time: np.ndarray
    edge: np.ndarray

    def __len__(self):
        return len(self.time)

    @classmethod
    def empty(cls):
        """No impacts."""
        return cls(np.zeros((0, 4), dtype=np.int64), np.zeros((0, 4)), np.zeros((0, 3)), np.zeros(0),
                   np.zeros(0, dtype=bool))

    @classmethod
    def concatenate(cls, parts):
        """The impacts of several parts, one after the other."""
        parts = [p for p in parts if len(p)]
        if not parts:
            return cls.empty()
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                     ("vertices", "weights", "normal", "time", "edge")))


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
    :func:`particles.intersections.box_pairs`).
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
    """:func:`particles.ccd.candidates` without the checks."""
    return pair_rows(mesh, *candidate_elements(mesh, x0, x1, pad, vertices))


def boxes_overlap(boxes_a, boxes_b, ia, ib):
    """Whether boxes ``ia`` of one set overlap boxes ``ib`` of another (each set a pair ``(lo, hi)``)."""
    (lo_a, hi_a), (lo_b, hi_b) = boxes_a, boxes_b
    return np.all((lo_a[ia] <= hi_b[ib]) & (lo_b[ib] <= hi_a[ia]), axis=1)


def _closest(pts, edge):
    """Closest points of the pairs of points `pts` (k, 4, 3), vertex-face or edge-edge."""
    args = (pts[:, 0], pts[:, 1], pts[:, 2], pts[:, 3])
    return edge_edge_kernel(*args) if edge else vertex_face_kernel(*args)


def _geometric_normal(pts, edge, fallback):
    """The face's normal, or ``d_1 x d_2`` of two edges; `fallback` where it is not defined."""
    if edge:
        u, v = pts[:, 1] - pts[:, 0], pts[:, 3] - pts[:, 2]
    else:
        u, v = pts[:, 2] - pts[:, 1], pts[:, 3] - pts[:, 1]
    nrm = np.cross(u, v)
    big = dot(nrm, nrm) > 1e-12 * dot(u, u) * dot(v, v)
    return np.where(big[:, None], unit_or(nrm, fallback), fallback)


def first_contacts(x, dx, edge, eta):
    k = len(x)
    if not k:
        return Impacts.empty()
    coef = cubic_coefficients(x, dx)
    rel = np.concatenate([x[:, 1:] - x[:, :1], dx[:, 1:] - dx[:, :1]], axis=1)
    L = np.abs(rel).max(axis=(1, 2))
    ftol = F_TOL * L ** 3
    # Bernstein coefficients on [0, 1]: all of one sign beyond ftol -> no root
    a, b, c, d = coef.T
    bern = np.stack([d, d + c / 3.0, d + (2.0 * c + b) / 3.0, d + c + b + a], axis=1)
    maybe = ~((bern > ftol[:, None]).all(axis=1) | (bern < -ftol[:, None]).all(axis=1))
    rows = np.flatnonzero(maybe)
    roots = unit_roots(coef[rows], ftol[rows])
    flat = (np.abs(bern[rows]) <= ftol[rows, None]).all(axis=1)  # coplanar all step: test the end only
    roots[flat] = np.array([1.0, np.nan, np.nan])
    time = np.full(len(rows), np.inf)
    for j in range(3):  # a loop over the (at most three) roots, earliest first
        todo = np.flatnonzero(np.isfinite(roots[:, j]) & np.isinf(time))
        if not len(todo):
            continue
        t = roots[todo, j]
        r = rows[todo]
        pts = x[r] + t[:, None, None] * dx[r]
        near = _closest(pts, edge).distance <= eta
        time[todo[near]] = t[near]
    hit = np.isfinite(time)
    r, t = rows[hit], time[hit]
    pts = x[r] + t[:, None, None] * dx[r]
    close = _closest(pts, edge)
    n = _geometric_normal(pts, edge, close.normal)
    rel_motion = np.einsum("kj,kjd->kd", close.weights, dx[r])
    n = np.where((dot(n, rel_motion) > 0)[:, None], -n, n)  # against the relative motion
    return Impacts(np.repeat(r[:, None], 4, axis=1).astype(np.int64), close.weights, n, t,
                   np.full(len(r), edge))


def overlapping(x0, x1, pairs, edge, pad):
    """Which rows of `pairs` have overlapping boxes, swept from `x0` to `x1` and inflated by `pad`.

    Parameters
    ----------
    x0, x1 : ndarray, shape (n, 3)
        Positions at the start and the end of the step, in metres.
    pairs : ndarray of int, shape (k, 4)
        ``(vertex, a, b, c)`` or, with `edge`, ``(p_1, p_2, q_1, q_2)``.
    edge : bool
        Edge-edge pairs (the boxes of the two edges), else vertex-face.
    pad : float
        Inflation, in metres.

    Returns
    -------
    ndarray of bool, shape (k,)
    """
    split = 2 if edge else 1
    pts = np.concatenate([x0[pairs], x1[pairs]], axis=2)  # (k, 4, 6): both ends of the step
    pts = pts.reshape(len(pairs), 4, 2, 3)
    k = len(pairs)
    a, b = pts[:, :split].reshape(k, 2 * split, 3), pts[:, split:].reshape(k, 2 * (4 - split), 3)
    return np.all((a.min(axis=1) - pad <= b.max(axis=1) + pad) & (b.min(axis=1) - pad <= a.max(axis=1) + pad),
                  axis=1)


def detect_pairs(x0, dx, vf, ee, eta):
    """:func:`particles.ccd.detect` on given candidate pairs."""
    found = []
    for idx, edge in ((vf, False), (ee, True)):  # the two kinds of pairs
        hits = first_contacts(x0[idx], dx[idx], edge, eta)
        found.append(Impacts(idx[hits.vertices[:, 0]], hits.weights, hits.normal, hits.time, hits.edge))
    return Impacts.concatenate(found)



def _overlap_matrix(lo_a, hi_a, lo_b, hi_b):
    """All overlapping pairs of a few boxes A with boxes B, by testing every pair (rows of A in chunks)."""
    I, J = [], []
    step = max(1, 2_000_000 // max(len(lo_b), 1))
    for s in range(0, len(lo_a), step):  # a loop over chunks of a few rows
        la, ha = lo_a[s:s + step, None, :], hi_a[s:s + step, None, :]
        ok = np.all((la <= hi_b[None]) & (lo_b[None] <= ha), axis=2)
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
