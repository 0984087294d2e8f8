"""Cloth contacts, compiled (numba): closest points, proximity tests, the coplanarity cubic.

Imported only by :mod:`particles.collisions.compiled_stages`. Each candidate pair is one
loop iteration, with the arithmetic of the NumPy reference in its order
(:mod:`particles.collisions.proximity`: Ericson's closest points;
:mod:`particles.collisions.ccd`: the cubic, its Bernstein test, the monotone
pieces between the roots of its derivative, bisection, the closest points at
each root; :mod:`particles.collisions.pipeline`: the proximity tests). Points
are 3-tuples in registers. Pairs are independent, so the results have the same
bits on any number of threads. The Jacobi impulses are in
:mod:`particles.collisions.impulse_kernels`.
"""

import math

import numpy as np

from ..backends.compile import inline, jit, prange


def dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def sub3(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross3(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def row3(x, i):
    return (x[i, 0], x[i, 1], x[i, 2])


def unit_or(v, fallback):
    """`v` divided by its length; `fallback` where the length is zero."""
    L = math.sqrt(dot3(v, v))
    if L > 0:
        return (v[0] / L, v[1] / L, v[2] / L)
    return fallback


def normal_or(v, n, s):
    """`v` divided by its length; where it is zero, `n`'s; where that is zero too, ``any_perpendicular(s)``.

    ``unit_or(v, unit_or(n, any_perpendicular(s)))``, with the fallbacks computed only when they are used.
    """
    L = math.sqrt(dot3(v, v))
    if L > 0:
        return (v[0] / L, v[1] / L, v[2] / L)
    return unit_or(n, any_perpendicular(s))


def any_perpendicular(d):
    """A unit vector perpendicular to `d` (e_z for zero)."""
    k = 0
    if abs(d[1]) < abs(d[k]):
        k = 1
    if abs(d[2]) < abs(d[k]):
        k = 2
    axis = (1.0 if k == 0 else 0.0, 1.0 if k == 1 else 0.0, 1.0 if k == 2 else 0.0)
    return unit_or(cross3(d, axis), (0.0, 0.0, 1.0))


def clip01(s):
    return min(max(s, 0.0), 1.0)


def point_segment(p, a, b):
    """Parameter and distance of the point of segment ``a -> b`` closest to `p`."""
    d = sub3(b, a)
    dd = dot3(d, d)
    pa = sub3(p, a)
    s = clip01(dot3(pa, d) / dd if dd > 0 else 0.0)
    r = (pa[0] - s * d[0], pa[1] - s * d[1], pa[2] - s * d[2])
    return s, math.sqrt(dot3(r, r))


def vertex_face(p, a, b, c):
    """Distance, normal and weights ``(1, -a_1, -a_2, -a_3)`` of a vertex and a triangle (``vertex_face_kernel``)."""
    e1, e2 = sub3(b, a), sub3(c, a)
    nrm = cross3(e1, e2)
    area2 = dot3(nrm, nrm)
    scale2 = max(dot3(e1, e1), dot3(e2, e2))
    flat = area2 > 1e-14 * scale2 * scale2
    r = sub3(p, a)
    beta = dot3(cross3(r, e2), nrm) / area2 if flat else -1.0
    gamma = dot3(cross3(e1, r), nrm) / area2 if flat else -1.0
    alpha = 1.0 - beta - gamma
    if flat and alpha >= 0 and beta >= 0 and gamma >= 0:
        w0, w1, w2 = alpha, beta, gamma
    else:
        s_ab, d_ab = point_segment(p, a, b)
        s_bc, d_bc = point_segment(p, b, c)
        s_ca, d_ca = point_segment(p, c, a)
        if d_bc < d_ab and d_bc <= d_ca:
            w0, w1, w2 = 0.0, 1.0 - s_bc, s_bc
        elif d_ca < d_ab and d_ca < d_bc:
            w0, w1, w2 = s_ca, 0.0, 1.0 - s_ca
        else:
            w0, w1, w2 = 1.0 - s_ab, s_ab, 0.0
    q = (w0 * a[0] + w1 * b[0] + w2 * c[0], w0 * a[1] + w1 * b[1] + w2 * c[1], w0 * a[2] + w1 * b[2] + w2 * c[2])
    d = sub3(p, q)
    distance = math.sqrt(dot3(d, d))
    s = (e1[0] + e2[0], e1[1] + e2[1], e1[2] + e2[2])
    normal = normal_or(d, nrm, s)
    return distance, normal, (1.0, -w0, -w1, -w2)


def edge_edge(p1, p2, q1, q2, parallel_tol):
    """Distance, normal and weights ``(1 - s, s, u - 1, -u)`` of two segments (``edge_edge_kernel``)."""
    d1, d2, r = sub3(p2, p1), sub3(q2, q1), sub3(p1, q1)
    a, e, b = dot3(d1, d1), dot3(d2, d2), dot3(d1, d2)
    c, f = dot3(d1, r), dot3(d2, r)
    denom = a * e - b * b
    parallel = denom <= parallel_tol * a * e
    s = clip01((b * f - c * e) / denom if not parallel else 0.0)
    t1 = dot3(sub3(q1, p1), d1) / a if a > 0 else 0.0
    t2 = dot3(sub3(q2, p1), d1) / a if a > 0 else 0.0
    lo, hi = clip01(min(t1, t2)), clip01(max(t1, t2))
    if parallel:
        s = 0.5 * (lo + hi)
    u = clip01((b * s + f) / e if e > 0 else 0.0)
    if not parallel:
        s = clip01((b * u - c) / a if a > 0 else 0.0)
    dv = (p1[0] + s * d1[0] - (q1[0] + u * d2[0]), p1[1] + s * d1[1] - (q1[1] + u * d2[1]),
          p1[2] + s * d1[2] - (q1[2] + u * d2[2]))
    distance = math.sqrt(dot3(dv, dv))
    z = 1.0 if a == 0 else 0.0
    g = (d1[0] + z * d2[0], d1[1] + z * d2[1], d1[2] + z * d2[2])
    normal = normal_or(dv, cross3(d1, d2), g)
    return distance, normal, (1.0 - s, s, u - 1.0, -u)


def closest(P0, P1, P2, P3, edge, parallel_tol):
    if edge:
        return edge_edge(P0, P1, P2, P3, parallel_tol)
    return vertex_face(P0, P1, P2, P3)


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


@jit(parallel=True)
def closest_pairs(x, rows, edge, parallel_tol, distance, normal, weights):
    """Closest points of every pair `rows` (k, 4) into `distance` (k,), `normal` (k, 3), `weights` (k, 4)."""
    for k in prange(len(rows)):
        P0, P1, P2, P3 = pair_points(x, rows, k)
        dist, n, W = closest(P0, P1, P2, P3, edge, parallel_tol)
        distance[k] = dist
        for a in range(3):
            normal[k, a] = n[a]
        for j in range(4):
            weights[k, j] = W[j]


@jit(parallel=True)
def proximity_rows(x0, vbar, w, xr, rest, rows, edge, h, thickness, rest_distance, parallel_tol, keep, distance,
                   normal, weights):
    """The proximity tests of ``ClothCollisions._proximity_contacts`` per candidate pair, into `keep` and the rest."""
    for k in prange(len(rows)):
        P0, P1, P2, P3 = pair_points(x0, rows, k)
        dist, n, W = closest(P0, P1, P2, P3, edge, parallel_tol)
        distance[k] = dist
        for a in range(3):
            normal[k, a] = n[a]
        for j in range(4):
            weights[k, j] = W[j]
        vN = dot3(n, combine(W, vbar, rows, k))
        ok = dist < thickness or dist + h * vN < thickness
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


def horner(a, b, c, d, t):
    return ((a * t + b) * t + c) * t + d


def triple(u, v, w):
    return dot3(u, cross3(v, w))


def piece_root(a, b, c, d, lo, hi, tol, bisections):
    """The root of the cubic on a monotone piece ``[lo, hi]`` (nan when none), as ``ccd.unit_roots`` finds it."""
    if not hi > lo:
        return np.nan
    flo, fhi = horner(a, b, c, d, lo), horner(a, b, c, d, hi)
    zlo, zhi = abs(flo) <= tol, abs(fhi) <= tol
    if zlo:
        return lo
    if zhi:
        return hi
    if not np.sign(flo) * np.sign(fhi) < 0:
        return np.nan
    L, H = lo, hi
    up = horner(a, b, c, d, L) < 0
    for _ in range(bisections):
        mid = 0.5 * (L + H)
        if (horner(a, b, c, d, mid) < 0) == up:
            L = mid
        else:
            H = mid
    return 0.5 * (L + H)


def sort3(r0, r1, r2):
    """Three numbers ascending, nan last."""
    if r1 < r0 or (math.isnan(r0) and not math.isnan(r1)):
        r0, r1 = r1, r0
    if r2 < r1 or (math.isnan(r1) and not math.isnan(r2)):
        r1, r2 = r2, r1
    if r1 < r0 or (math.isnan(r0) and not math.isnan(r1)):
        r0, r1 = r1, r0
    return r0, r1, r2


def unit_roots(a, b, c, d, tol, bisections):
    """Roots in [0, 1] of ``a t^3 + b t^2 + c t + d``, one per monotone piece, ascending (``ccd.unit_roots``)."""
    A, B, C = 3.0 * a, 2.0 * b, c
    disc = B * B - 4.0 * A * C
    c0 = c1 = np.nan
    if A != 0 and disc >= 0:
        sq = math.sqrt(disc)
        qq = -0.5 * (B + (sq if B >= 0 else -sq))
        c0 = qq / A
        if qq != 0:
            c1 = C / qq
    if A == 0 and B != 0:
        c0 = -C / B
    c0 = c0 if c0 > 0 and c0 < 1 else np.nan
    c1 = c1 if c1 > 0 and c1 < 1 else np.nan
    if c1 < c0 or (math.isnan(c0) and not math.isnan(c1)):
        c0, c1 = c1, c0
    e2 = 1.0 if math.isnan(c1) else c1
    e1 = e2 if math.isnan(c0) else c0
    return sort3(piece_root(a, b, c, d, 0.0, e1, tol, bisections), piece_root(a, b, c, d, e1, e2, tol, bisections),
                 piece_root(a, b, c, d, e2, 1.0, tol, bisections))


def moved_point(x, dx, i, t):
    return (x[i, 0] + t * dx[i, 0], x[i, 1] + t * dx[i, 1], x[i, 2] + t * dx[i, 2])


def at_time(x, dx, rows, k, t):
    """The four points of pair `k` at the fraction `t` of the step, ``x + t dx``."""
    return (moved_point(x, dx, rows[k, 0], t), moved_point(x, dx, rows[k, 1], t), moved_point(x, dx, rows[k, 2], t),
            moved_point(x, dx, rows[k, 3], t))


@jit()
def kept_rows(keep, rows, weights, normal, distance):
    """The rows where `keep` is True of the four arrays, in order (one pass, no boolean masks)."""
    k = 0
    for i in range(len(keep)):
        k += keep[i]
    R, Wk, Nk, Dk = np.empty((k, 4), np.int64), np.empty((k, 4)), np.empty((k, 3)), np.empty(k)
    k = 0
    for i in range(len(keep)):
        if keep[i]:
            for j in range(4):
                R[k, j] = rows[i, j]
                Wk[k, j] = weights[i, j]
            for a in range(3):
                Nk[k, a] = normal[i, a]
            Dk[k] = distance[i]
            k += 1
    return R, Wk, Nk, Dk


@jit(parallel=True)
def first_contact_pairs(x0, dx, rows, edge, eta, f_tol, bisections, parallel_tol, hit, time, normal, weights):
    """``ccd.first_contacts`` per candidate pair: `hit` (k,), and where hit the time, normal and weights."""
    for k in prange(len(rows)):
        hit[k] = False
        X0, X1, X2, X3 = pair_points(x0, rows, k)
        D0, D1, D2, D3 = pair_points(dx, rows, k)
        p0, p1, p2 = sub3(X1, X0), sub3(X2, X0), sub3(X3, X0)
        q0, q1, q2 = sub3(D1, D0), sub3(D2, D0), sub3(D3, D0)
        d = triple(p0, p1, p2)
        c = triple(q0, p1, p2) + triple(p0, q1, p2) + triple(p0, p1, q2)
        b = triple(q0, q1, p2) + triple(q0, p1, q2) + triple(p0, q1, q2)
        a = triple(q0, q1, q2)
        L = 0.0
        for v in (p0, p1, p2, q0, q1, q2):
            L = max(L, abs(v[0]), abs(v[1]), abs(v[2]))
        ftol = f_tol * L ** 3.0
        b0, b1, b2, b3 = d, d + c / 3.0, d + (2.0 * c + b) / 3.0, d + c + b + a
        if (b0 > ftol and b1 > ftol and b2 > ftol and b3 > ftol) or \
                (b0 < -ftol and b1 < -ftol and b2 < -ftol and b3 < -ftol):
            continue
        if abs(b0) <= ftol and abs(b1) <= ftol and abs(b2) <= ftol and abs(b3) <= ftol:
            roots = (1.0, np.nan, np.nan)  # coplanar all step: the end only
        else:
            roots = unit_roots(a, b, c, d, ftol, bisections)
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
        u, v = (sub3(P1, P0), sub3(P3, P2)) if edge else (sub3(P2, P1), sub3(P3, P1))
        nrm = cross3(u, v)
        n = unit_or(nrm, fallback) if dot3(nrm, nrm) > 1e-12 * dot3(u, u) * dot3(v, v) else fallback
        if dot3(n, combine(W, dx, rows, k)) > 0:  # against the relative motion
            n = (-n[0], -n[1], -n[2])
        hit[k] = True
        time[k] = t
        for a_ in range(3):
            normal[k, a_] = n[a_]
        for j in range(4):
            weights[k, j] = W[j]


for _helper in (dot3, sub3, cross3, row3, unit_or, normal_or, any_perpendicular, clip01, point_segment, vertex_face, edge_edge, closest, pair_points, combine, rest_far, horner, triple, piece_root, sort3, unit_roots, moved_point, at_time,):  # compiled into the kernels that call them
    inline(_helper, into="never")
