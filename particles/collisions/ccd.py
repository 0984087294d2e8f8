"""Continuous collision detection: when, within a step, a vertex hits a triangle or two edges meet.

A test at the end of a step misses a vertex that passes through a triangle
within the step. Following Provot [1]_ and Bridson, Fedkiw and Anderson [2]_,
every vertex moves on a straight line during the step,
``x(t) = x0 + t dx`` for ``t`` in [0, 1] (``dx = h vbar``, the step's average
velocity), and the test asks whether four points become coplanar while they
touch:

1. **Candidates.** The box swept by each vertex, edge and face over the step,
   inflated by a pad, is put in a bucket grid (:func:`particles.collisions.triangle_crossing.box_pairs`);
   only vertex-face and edge-edge pairs whose boxes overlap are tested.
   Pairs that share a vertex (a vertex of the face, two edges with a common
   end) touch by construction and are left out. A bucket grid rather than a
   bounding-volume hierarchy: the cloth's triangles all have about the same
   size, so a grid of that size costs O(n) to build every step, without a
   tree to refit.
2. **Coplanarity cubic.** Four points ``x_0 .. x_3`` (vertex and face, or
   the two edges) are coplanar when the volume
   ``f(t) = (x_1 - x_0) . ((x_2 - x_0) x (x_3 - x_0))`` vanishes. With
   ``p_i = x_i - x_0`` and ``q_i = dx_i - dx_0`` it is the cubic
   ``f(t) = a t^3 + b t^2 + c t + d`` with
   ``d = [p_1 p_2 p_3]``, ``c = [q_1 p_2 p_3] + [p_1 q_2 p_3] + [p_1 p_2 q_3]``,
   ``b = [q_1 q_2 p_3] + [q_1 p_2 q_3] + [p_1 q_2 q_3]``, ``a = [q_1 q_2 q_3]``
   (``[u v w] = u . (v x w)``).
3. **Roots, robustly.** A pair whose Bernstein coefficients on [0, 1] all
   have one sign (beyond a tolerance) has no root and is dropped. Otherwise
   [0, 1] is split at the roots of ``f'`` (a quadratic, in closed form),
   where ``f`` is monotone on every piece; a piece whose ends have opposite
   signs (or an end within the tolerance of zero) holds exactly one root,
   found by bisection to the last bits of ``t``. No polynomial solver and no
   loop over pairs: all pieces of all pairs bisect together.
4. **Touching.** At each root, in order, the closest points of the pair
   (:mod:`particles.collisions.proximity`) decide: a collision when they are closer than
   a tolerance ``eta``. The first such root is the time of impact; the
   normal there is the face's normal, or ``d_1 x d_2`` of the edges, oriented
   against the relative motion.

A pair that stays coplanar during the whole step (``f`` within the tolerance
of zero everywhere: a flat sheet moving in its plane) is tested at the end of
the step only; motion within a common plane is left to the proximity
repulsion of :mod:`particles.collisions.pipeline`, which keeps pairs a thickness
apart before that can happen.

References
----------
.. [1] X. Provot, "Collision and self-collision handling in cloth model
   dedicated to design garments", Graphics Interface 1997, 177-189
   (the coplanarity cubic, impact zones).
.. [2] R. Bridson, R. Fedkiw and J. Anderson, "Robust treatment of collisions,
   contact and friction for cloth animation", ACM Transactions on Graphics
   21(3) (SIGGRAPH 2002), 594-603, section 7.
"""

from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array, nonnegative_number, positive_number
from .candidates import candidate_pairs
from .mesh import TriangleMesh
from .._vectors import any_of, select, vcross, vdot, vselect, vsub
from .proximity import PARALLEL, dot, edge_edge_kernel, unit_or, vertex_face_kernel

__all__ = ["cubic_roots", "coplanarity_cubic", "Impacts", "candidates", "overlapping", "first_contact", "detect",
           "BISECTIONS", "F_TOL", "cubic_of", "bernstein", "cubic_unit_roots", "piece_root", "impact_normal"]

# Kernels without the checks, for the collision stages that call them on every step.

BISECTIONS = 60
"""Bisection steps per monotone piece (2^-60 of [0, 1]: below the spacing of doubles near 1)."""


F_TOL = 1e-12
"""Relative tolerance of the cubic: ``|f| <= F_TOL L^3`` counts as zero, ``L`` the pair's largest coordinate span."""


def triple(u, v, w):
    """The triple product ``[u v w] = u . (v x w)`` of 3-tuples."""
    return vdot(u, vcross(v, w))


def cubic_of(p1, p2, p3, q1, q2, q3):
    """``a, b, c, d`` of the coplanarity cubic ``f(t) = [p_1 + t q_1, p_2 + t q_2, p_3 + t q_3]`` (3-tuples).

    ``p_i = x_i - x_0`` and ``q_i = dx_i - dx_0``: ``d = [p_1 p_2 p_3]``,
    ``c = [q_1 p_2 p_3] + [p_1 q_2 p_3] + [p_1 p_2 q_3]``, ``b = [q_1 q_2 p_3] + [q_1 p_2 q_3] + [p_1 q_2 q_3]``,
    ``a = [q_1 q_2 q_3]``.
    """
    d = triple(p1, p2, p3)
    c = triple(q1, p2, p3) + triple(p1, q2, p3) + triple(p1, p2, q3)
    b = triple(q1, q2, p3) + triple(q1, p2, q3) + triple(p1, q2, q3)
    return triple(q1, q2, q3), b, c, d


def bernstein(a, b, c, d):
    """The cubic's Bernstein coefficients on [0, 1]: all of one sign, no root there."""
    return d, d + c / 3.0, d + (2.0 * c + b) / 3.0, d + c + b + a


def horner(a, b, c, d, t):
    """``((a t + b) t + c) t + d``."""
    return ((a * t + b) * t + c) * t + d


def piece_root(a, b, c, d, lo, hi, tol, bisections):
    """The root of the cubic on a monotone piece ``[lo, hi]``: an end within `tol` of zero, or the bisected sign
    change (nan when there is none, or the piece is empty)."""
    flo, fhi = horner(a, b, c, d, lo), horner(a, b, c, d, hi)
    zlo, zhi = np.abs(flo) <= tol, np.abs(fhi) <= tol
    used = hi > lo
    change = used & (np.sign(flo) * np.sign(fhi) < 0) & ~zlo & ~zhi
    L, H = lo, hi
    up = flo < 0  # f increases from lo to hi on this piece
    for _ in range(bisections if any_of(change) else 0):  # bisection steps (in NumPy, all pieces at once)
        mid = 0.5 * (L + H)
        below = (horner(a, b, c, d, mid) < 0) == up  # the root lies above mid
        L, H = select(below, mid, L), select(below, H, mid)
    return select(used & zlo, lo, select(used & zhi, hi, select(change, 0.5 * (L + H), np.nan)))


def sorted_nan_last(r0, r1, r2):
    """Three numbers ascending, nan last."""
    swap = (r1 < r0) | (np.isnan(r0) & ~np.isnan(r1))
    r0, r1 = select(swap, r1, r0), select(swap, r0, r1)
    swap = (r2 < r1) | (np.isnan(r1) & ~np.isnan(r2))
    r1, r2 = select(swap, r2, r1), select(swap, r1, r2)
    swap = (r1 < r0) | (np.isnan(r0) & ~np.isnan(r1))
    return select(swap, r1, r0), select(swap, r0, r1), r2


def cubic_unit_roots(a, b, c, d, tol, bisections):
    """Roots in [0, 1] of ``a t^3 + b t^2 + c t + d``, one per monotone piece, ascending (nan for none).

    [0, 1] is split at the roots of ``f'`` (a quadratic, in closed form: the stable formula), where ``f``
    is monotone on every piece; each piece gives :func:`piece_root`.
    """
    A, B, C = 3.0 * a, 2.0 * b, c
    disc = B * B - 4.0 * A * C
    quad = (A != 0) & (disc >= 0)
    sq = np.sqrt(select(quad, disc, 0.0))
    qq = -0.5 * (B + select(B >= 0, sq, -sq))
    c0 = select(quad, qq / select(A != 0, A, 1.0), np.nan)
    c1 = select(quad & (qq != 0), C / select(qq != 0, qq, 1.0), np.nan)
    c0 = select((A == 0) & (B != 0), -C / select(B != 0, B, 1.0), c0)
    c0 = select((c0 > 0) & (c0 < 1), c0, np.nan)
    c1 = select((c1 > 0) & (c1 < 1), c1, np.nan)
    swap = (c1 < c0) | (np.isnan(c0) & ~np.isnan(c1))
    c0, c1 = select(swap, c1, c0), select(swap, c0, c1)
    e2 = select(np.isnan(c1), 1.0, c1)
    e1 = select(np.isnan(c0), e2, c0)
    return sorted_nan_last(piece_root(a, b, c, d, 0.0, e1, tol, bisections),
                           piece_root(a, b, c, d, e1, e2, tol, bisections),
                           piece_root(a, b, c, d, e2, 1.0, tol, bisections))


def impact_normal(u, v, fallback):
    """The normal of an impact: ``u x v`` normalized (a face's, or two edges' ``d_1 x d_2``), else `fallback`.

    `u`, `v`, `fallback` are 3-tuples; ``u x v`` counts only when ``|u x v|^2 > 1e-12 |u|^2 |v|^2``.
    """
    nrm = vcross(u, v)
    big = vdot(nrm, nrm) > 1e-12 * vdot(u, u) * vdot(v, v)
    return vselect(big, unit_or(nrm, fallback), fallback)


def _points(x, j):
    """Point j of every pair of `x` (k, 4, 3), as a 3-tuple of contiguous arrays."""
    t = np.ascontiguousarray(x[:, j].T)
    return t[0], t[1], t[2]


def cubic_coefficients(x, dx):
    p = [vsub(_points(x, i), _points(x, 0)) for i in (1, 2, 3)]
    q = [vsub(_points(dx, i), _points(dx, 0)) for i in (1, 2, 3)]
    return np.stack(cubic_of(*p, *q), axis=1)


def unit_roots(coef, ftol):
    a, b, c, d = (coef[:, k] for k in range(4))
    return np.stack(cubic_unit_roots(a, b, c, d, ftol, BISECTIONS), axis=1)


@dataclass(frozen=True)
class Impacts:
    """Contacts of vertex-face and edge-edge pairs, in the four-vertex form of :mod:`particles.collisions.proximity`.

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


def _closest(pts, edge):
    """Closest points of the pairs of points `pts` (k, 4, 3), vertex-face or edge-edge."""
    args = (pts[:, 0], pts[:, 1], pts[:, 2], pts[:, 3])
    return edge_edge_kernel(*args) if edge else vertex_face_kernel(*args)


def _geometric_normal(pts, edge, fallback):
    """The face's normal, or ``d_1 x d_2`` of two edges (:func:`impact_normal`); `fallback` where it is not defined."""
    i, j, k = (0, 1, 2) if edge else (1, 2, 1)
    u = vsub(_points(pts, j), _points(pts, i))
    v = vsub(_points(pts, 3), _points(pts, k))
    return np.stack(impact_normal(u, v, tuple(fallback.T)), axis=1)


def first_contacts(x, dx, edge, eta):
    k = len(x)
    if not k:
        return Impacts.empty()
    coef = cubic_coefficients(x, dx)
    rel = np.concatenate([x[:, 1:] - x[:, :1], dx[:, 1:] - dx[:, :1]], axis=1)
    L = np.abs(rel).max(axis=(1, 2))
    ftol = F_TOL * L ** 3
    # Bernstein coefficients on [0, 1]: all of one sign beyond ftol -> no root
    bern = np.stack(bernstein(*coef.T), axis=1)
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


def detect_pairs(x0, dx, vf, ee, eta, fast=None):
    """:func:`particles.collisions.ccd.detect` on given candidate pairs (with `fast`, the compiled kernels)."""
    found = []
    for idx, edge in ((vf, False), (ee, True)):  # the two kinds of pairs
        if fast is not None:  # pair by pair, compiled (particles.collisions.compiled_stages)
            rows, W, N, T = fast.cloth_first_contacts(x0, dx, idx, edge, eta, F_TOL, BISECTIONS, PARALLEL)
            found.append(Impacts(rows, W, N, T, np.full(len(T), edge)))
            continue
        hits = first_contacts(x0[idx], dx[idx], edge, eta)
        found.append(Impacts(idx[hits.vertices[:, 0]], hits.weights, hits.normal, hits.time, hits.edge))
    return Impacts.concatenate(found)


def coplanarity_cubic(x, dx):
    """Coefficients ``(a, b, c, d)`` of ``f(t) = [x_1 - x_0, x_2 - x_0, x_3 - x_0](t)``.

    Parameters
    ----------
    x, dx : array_like, shape (k, 4, 3)
        Positions of the four points at ``t = 0`` and their displacements over
        the step, in metres.

    Returns
    -------
    ndarray, shape (k, 4)
        ``a, b, c, d`` (m^3) with ``f(t) = a t^3 + b t^2 + c t + d``.

    Examples
    --------
    A vertex 1 m above a triangle, falling 2 m: coplanar half-way.

    >>> x = [[[0.2, 0.2, 1.0], [0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]]]
    >>> dx = [[[0.0, 0.0, -2.0], [0.0, 0, 0], [0.0, 0, 0], [0.0, 0, 0]]]
    >>> coplanarity_cubic(x, dx).round(12).tolist()
    [[0.0, 0.0, 2.0, -1.0]]
    """
    x = as_float_array(x, "x", ndim=3)
    dx = as_float_array(dx, "dx", shape=x.shape)
    if x.shape[1:] != (4, 3):
        raise ValueError(f"x must have shape (k, 4, 3), got shape {x.shape}")
    return cubic_coefficients(x, dx)


def cubic_roots(coef, ftol=0.0):
    """Roots in [0, 1] of the cubics ``a t^3 + b t^2 + c t + d``, one row per cubic.

    Parameters
    ----------
    coef : array_like, shape (k, 4)
        ``a, b, c, d`` of each cubic (any of them may be zero).
    ftol : float or array_like, shape (k,)
        ``|f| <= ftol`` counts as zero: an end of a monotone piece within it
        is a root (a touching double root is then found too).

    Returns
    -------
    ndarray, shape (k, 3)
        The roots of each cubic in [0, 1], ascending, ``nan`` where there are
        fewer than three; one per monotone piece, so a root where two pieces
        meet may be listed twice. A cubic that is zero everywhere (within
        `ftol`) gives ``0`` (and the further pieces' ends).

    Examples
    --------
    >>> r = cubic_roots([[1.0, -1.5, 0.56, -0.06], [0.0, 0.0, 1.0, -2.0]])   # (t-.2)(t-.3)(t-1); t - 2
    >>> np.round(r, 12).tolist()
    [[0.2, 0.3, 1.0], [nan, nan, nan]]
    """
    coef = as_float_array(coef, "coef", ndim=2)
    if coef.shape[1] != 4:
        raise ValueError(f"coef must have shape (k, 4), got shape {coef.shape}")
    ftol = np.broadcast_to(as_float_array(ftol, "ftol", ndim=(0, 1)), (len(coef),))
    if np.any(ftol < 0):
        raise ValueError("ftol must be >= 0")
    return unit_roots(coef, ftol)


def candidates(mesh, x0, x1, pad=0.0, vertices=None):
    """Vertex-face and edge-edge pairs whose boxes, swept over the step and inflated by `pad`, overlap.

    Parameters
    ----------
    mesh : TriangleMesh
        The cloth's connectivity.
    x0, x1 : array_like, shape (n, 3)
        Positions at the start and the end of the step, in metres.
    pad : float
        Added on every side of every box, in metres (>= 0): pairs that may
        come closer than ``2 pad`` during the step are among the candidates.
    vertices : array_like of bool, shape (n,), optional
        Only pairs with at least one of these vertices (the ones whose motion
        changed since the last search).

    Returns
    -------
    vf : ndarray of int64, shape (p, 4)
        ``(vertex, a, b, c)``: vertices and faces that share no vertex.
    ee : ndarray of int64, shape (q, 4)
        ``(p_1, p_2, q_1, q_2)``: edge pairs that share no vertex, each once.
    """
    if not isinstance(mesh, TriangleMesh):
        raise ValueError(f"mesh must be a particles.collisions.mesh.TriangleMesh, got {type(mesh).__name__}")
    x0 = as_float_array(x0, "x0", shape=(mesh.n, 3))
    x1 = as_float_array(x1, "x1", shape=(mesh.n, 3))
    pad = nonnegative_number(pad, "pad", "metres")
    if vertices is not None:
        vertices = np.asarray(vertices)
        if vertices.shape != (mesh.n,) or vertices.dtype != bool:
            raise ValueError(f"vertices must be a boolean mask of shape ({mesh.n},), got {vertices.dtype} "
                             f"{vertices.shape}")
    return candidate_pairs(mesh, x0, x1, pad, vertices)


def first_contact(x, dx, edge, eta):
    """Time of first contact of vertex-face (or edge-edge) pairs moving linearly over a step.

    Parameters
    ----------
    x, dx : array_like, shape (k, 4, 3)
        Positions at the start of the step and displacements over it, in
        metres: ``(p, a, b, c)`` for a vertex and a face, ``(p_1, p_2, q_1, q_2)``
        for two edges.
    edge : bool
        Edge-edge pairs (else vertex-face).
    eta : float
        A root of the coplanarity cubic is a contact when the pair is closer
        than `eta` there, in metres (> 0).

    Returns
    -------
    Impacts
        One row per pair that touches during the step, with ``vertices`` the
        row numbers ``(r, r, r, r)`` of the pair in `x` (callers replace them
        with mesh vertices).

    Examples
    --------
    A vertex falling through a triangle, and one passing beside it:

    >>> x = [[[0.2, 0.2, 1.0], [0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]],
    ...      [[2.0, 2.0, 1.0], [0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]]]
    >>> dx = np.zeros((2, 4, 3)); dx[:, 0, 2] = -4.0
    >>> hits = first_contact(x, dx, edge=False, eta=1e-9)
    >>> hits.time.round(12).tolist(), hits.vertices[:, 0].tolist(), hits.normal.tolist()
    ([0.25], [0], [[0.0, 0.0, 1.0]])
    """
    x = as_float_array(x, "x", ndim=3)
    dx = as_float_array(dx, "dx", shape=x.shape)
    if x.shape[1:] != (4, 3):
        raise ValueError(f"x must have shape (k, 4, 3), got shape {x.shape}")
    return first_contacts(x, dx, bool(edge), positive_number(eta, "eta", "metres"))


def detect(mesh, x0, dx, eta, pad=None, vertices=None):
    """Every vertex-face and edge-edge contact of a mesh moving linearly by `dx` over a step.

    Parameters
    ----------
    mesh : TriangleMesh
    x0, dx : array_like, shape (n, 3)
        Positions at the start of the step and displacements, in metres.
    eta : float
        Contact tolerance, in metres (see :func:`first_contact`).
    pad : float, optional
        Box inflation (default `eta`).
    vertices : array_like of bool, shape (n,), optional
        Only pairs with one of these vertices.

    Returns
    -------
    Impacts
        With mesh vertex indices; vertex-face rows first.

    Examples
    --------
    Two triangles, one falling through the other within the step:

    >>> mesh = TriangleMesh([[0, 1, 2], [3, 4, 5]])
    >>> x0 = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.5], [1.2, 0.2, 0.5], [0.2, 1.2, 0.5]])
    >>> dx = np.zeros((6, 3)); dx[3:, 2] = -1.0
    >>> hits = detect(mesh, x0, dx, eta=1e-9)
    >>> hits.vertices.tolist(), hits.time.round(12).tolist()   # vertex 3 hits the face; edge 1-2 meets two edges
    ([[3, 0, 1, 2], [1, 2, 3, 4], [1, 2, 3, 5]], [0.5, 0.5, 0.5])
    """
    eta = positive_number(eta, "eta", "metres")
    pad = eta if pad is None else nonnegative_number(pad, "pad", "metres")
    if not isinstance(mesh, TriangleMesh):
        raise ValueError(f"mesh must be a particles.collisions.mesh.TriangleMesh, got {type(mesh).__name__}")
    x0 = np.ascontiguousarray(as_float_array(x0, "x0", shape=(mesh.n, 3)))
    dx = np.ascontiguousarray(as_float_array(dx, "dx", shape=(mesh.n, 3)))
    vf, ee = candidates(mesh, x0, x0 + dx, pad, vertices)
    return detect_pairs(x0, dx, vf, ee, eta)
