"""Cloth contacts, compiled (numba): closest points, proximity tests, the coplanarity cubic.

Imported only by :mod:`particles.collisions.compiled_stages`. Each candidate pair is one
loop iteration, inlining the laws of the NumPy reference
(:mod:`particles.collisions.proximity`: Ericson's closest points, the proximity test;
:mod:`particles.collisions.ccd`: the cubic, its Bernstein test, the roots on the monotone
pieces between the roots of its derivative, the impact's normal). Points
are 3-tuples in registers. Pairs are independent, so the results have the same
bits on any number of threads. The Jacobi impulses are in
:mod:`particles.collisions.impulse_kernels`.
"""

import math

import numpy as np

from .._vectors import vdot, vsub
from ..backends.compile import inline, jit, kernel_form, prange
from .ccd import bernstein, cubic_of, cubic_unit_roots, horner, impact_normal, piece_root, sorted_nan_last, triple
from .proximity import (any_perpendicular, approaching_within, clip01, nearest_edge_weights, normal_or, plane_weights,
                        segment_closest, segments_closest, triangle_contact, unit_or)

for _law in (clip01, unit_or, any_perpendicular, segment_closest, plane_weights, nearest_edge_weights, triangle_contact,
             segments_closest, approaching_within, triple, cubic_of, bernstein, horner, sorted_nan_last, impact_normal):
    inline(_law)
for _law in (piece_root, cubic_unit_roots):  # laws with a loop: a function of their own, which LLVM inlines
    inline(_law, into="never")


@kernel_form(normal_or)
def normal_or_in_kernels(v, n, g):
    """:func:`~particles.collisions.proximity.normal_or` in a kernel: its fallbacks computed only where used."""
    if vdot(v, v) > 0:
        return unit_or(v, v)
    if vdot(n, n) > 0:
        return unit_or(n, n)
    return any_perpendicular(g)


def row3(x, i):
    return (x[i, 0], x[i, 1], x[i, 2])


def closest(P0, P1, P2, P3, edge, parallel_tol):
    """The closest points of a pair: :func:`~particles.collisions.proximity.segments_closest` or
    :func:`~particles.collisions.proximity.triangle_closest` (its parts, the edges only when needed)."""
    if edge:
        return segments_closest(P0, P1, P2, P3, parallel_tol)
    inside, alpha, beta, gamma = plane_weights(P0, P1, P2, P3)
    if inside:
        return triangle_contact(P0, P1, P2, P3, alpha, beta, gamma)
    w0, w1, w2 = nearest_edge_weights(P0, P1, P2, P3)
    return triangle_contact(P0, P1, P2, P3, w0, w1, w2)


def pair_points(x, rows, k):
    return row3(x, rows[k, 0]), row3(x, rows[k, 1]), row3(x, rows[k, 2]), row3(x, rows[k, 3])


def combine(W, x, rows, k):
    """``sum_j W_j x[rows[k, j]]``, in the order of ``np.einsum("kj,kjd->kd", ...)``."""
    out0 = out1 = out2 = 0.0
    for j in range(4):
        i = rows[k, j]
        out0 += W[j] * x[i, 0]
        out1 += W[j] * x[i, 1]
        out2 += W[j] * x[i, 2]
    return (out0, out1, out2)


def closest_row(x, rows, k, edge, parallel_tol, distance, normal, weights):
    """The closest points of pair `k`, written into row `k` of `distance`, `normal`, `weights` and returned."""
    P0, P1, P2, P3 = pair_points(x, rows, k)
    dist, n, W = closest(P0, P1, P2, P3, edge, parallel_tol)
    distance[k] = dist
    for a in range(3):
        normal[k, a] = n[a]
    for j in range(4):
        weights[k, j] = W[j]
    return dist, n, W


@jit(parallel=True)
def closest_pairs(x, rows, edge, parallel_tol, distance, normal, weights):
    """Closest points of every pair `rows` (k, 4) into `distance` (k,), `normal` (k, 3), `weights` (k, 4)."""
    for k in prange(len(rows)):
        closest_row(x, rows, k, edge, parallel_tol, distance, normal, weights)


@jit(parallel=True)
def proximity_rows(x0, vbar, w, xr, rest, rows, edge, h, thickness, rest_distance, parallel_tol, keep, distance,
                   normal, weights):
    """The proximity tests of ``ClothCollisions._proximity_contacts`` per candidate pair, into `keep` and the rest."""
    for k in prange(len(rows)):
        dist, n, W = closest_row(x0, rows, k, edge, parallel_tol, distance, normal, weights)
        vN = vdot(n, combine(W, vbar, rows, k))
        ok = approaching_within(dist, vN, h, thickness)
        eff = 0.0
        for j in range(4):
            eff += (W[j] * W[j]) * w[rows[k, j]]
        ok = ok and eff > 0
        if edge:
            s_, u_ = W[1], -W[3]
            ok = ok and s_ > 1e-9 and s_ < 1 - 1e-9 and u_ > 1e-9 and u_ < 1 - 1e-9
        if ok and rest:
            ok = rest_far(xr, rows, k, edge, rest_distance, parallel_tol)
        keep[k] = ok


def rest_far(xr, rows, k, edge, rest_distance, parallel_tol):
    """Whether pair `k` is at least `rest_distance` apart at rest (`xr`): its closest points' distance there.

    Pairs on folds of the sheet that lie far apart at rest are most of them: when the boxes around the two
    elements' rest points (the vertex, or the first edge, against the rest) are farther apart than
    `rest_distance` (by a margin of 1e-9 of it, far above the closest points' round-off), so are any two
    points of the elements, and the closest points are not computed. The same verdicts.
    """
    first = 2 if edge else 1  # rows[k, :first] one element, rows[k, first:] the other
    gap = 0.0
    for a in range(3):
        lo_a = hi_a = xr[rows[k, 0], a]
        for j in range(1, first):
            lo_a, hi_a = min(lo_a, xr[rows[k, j], a]), max(hi_a, xr[rows[k, j], a])
        lo_b = hi_b = xr[rows[k, first], a]
        for j in range(first + 1, 4):
            lo_b, hi_b = min(lo_b, xr[rows[k, j], a]), max(hi_b, xr[rows[k, j], a])
        g = max(lo_b - hi_a, lo_a - hi_b, 0.0)
        gap += g * g
    bound = rest_distance * (1.0 + 1e-9)
    if gap > bound * bound:
        return True
    R0, R1, R2, R3 = pair_points(xr, rows, k)
    return closest(R0, R1, R2, R3, edge, parallel_tol)[0] >= rest_distance


def moved_point(x, dx, i, t):
    return (x[i, 0] + t * dx[i, 0], x[i, 1] + t * dx[i, 1], x[i, 2] + t * dx[i, 2])


def at_time(x, dx, rows, k, t):
    """The four points of pair `k` at the fraction `t` of the step, ``x + t dx``."""
    return (moved_point(x, dx, rows[k, 0], t), moved_point(x, dx, rows[k, 1], t), moved_point(x, dx, rows[k, 2], t),
            moved_point(x, dx, rows[k, 3], t))


@jit(parallel=True)
def first_contact_pairs(x0, dx, rows, edge, eta, f_tol, bisections, parallel_tol, hit, time, normal, weights):
    """``ccd.first_contacts`` per candidate pair: `hit` (k,), and where hit the time, normal and weights."""
    for k in prange(len(rows)):
        hit[k] = False
        X0, X1, X2, X3 = pair_points(x0, rows, k)
        D0, D1, D2, D3 = pair_points(dx, rows, k)
        p0, p1, p2 = vsub(X1, X0), vsub(X2, X0), vsub(X3, X0)
        q0, q1, q2 = vsub(D1, D0), vsub(D2, D0), vsub(D3, D0)
        a, b, c, d = cubic_of(p0, p1, p2, q0, q1, q2)
        L = 0.0
        for v in (p0, p1, p2, q0, q1, q2):
            L = max(L, abs(v[0]), abs(v[1]), abs(v[2]))
        ftol = f_tol * L ** 3.0
        b0, b1, b2, b3 = bernstein(a, b, c, d)
        if (b0 > ftol and b1 > ftol and b2 > ftol and b3 > ftol) or \
                (b0 < -ftol and b1 < -ftol and b2 < -ftol and b3 < -ftol):
            continue
        if abs(b0) <= ftol and abs(b1) <= ftol and abs(b2) <= ftol and abs(b3) <= ftol:
            roots = (1.0, np.nan, np.nan)  # coplanar all step: the end only
        else:
            roots = cubic_unit_roots(a, b, c, d, ftol, bisections)
        t = np.inf
        for r in roots:  # earliest first
            if math.isfinite(r) and not math.isfinite(t):
                P0, P1, P2, P3 = at_time(x0, dx, rows, k, r)
                if closest(P0, P1, P2, P3, edge, parallel_tol)[0] <= eta:
                    t = r
        if not math.isfinite(t):
            continue
        P0, P1, P2, P3 = at_time(x0, dx, rows, k, t)
        _, fallback, W = closest(P0, P1, P2, P3, edge, parallel_tol)
        u, v = (vsub(P1, P0), vsub(P3, P2)) if edge else (vsub(P2, P1), vsub(P3, P1))
        n = impact_normal(u, v, fallback)
        if vdot(n, combine(W, dx, rows, k)) > 0:  # against the relative motion
            n = (-n[0], -n[1], -n[2])
        hit[k] = True
        time[k] = t
        for a_ in range(3):
            normal[k, a_] = n[a_]
        for j in range(4):
            weights[k, j] = W[j]


# helpers compiled into the kernels, each a function of its own
for _helper in (row3, closest, pair_points, closest_row, combine, rest_far, moved_point, at_time):
    inline(_helper, into="never")
