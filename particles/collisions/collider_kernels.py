"""Collisions with an implicit surface, compiled (numba): :class:`particles.collisions.Collider` per particle.

:meth:`particles.collisions.Collider.stepper` calls :func:`collide` when its backend resolves to numba
and its surface is a primitive; the cloth pipeline's body stages read the same surface rows
(:func:`surface_rows`). Importing this module imports numba. The NumPy collider works on
arrays of all the particles that may touch the surface, round after round;
here each particle is one loop iteration that does its rounds alone, with
the arithmetic of the NumPy code in its order (:mod:`particles.collisions.surface_crossing`:
the Hermite path, the walk with sphere tracing and the Illinois steps;
:mod:`particles.collisions.collider`: resting contact, the projection), and the
response's formulas inlined (:func:`particles.collisions.response.normal_change`,
:func:`particles.collisions.response.friction_change`). Two passes: :func:`collider_candidates` marks the
particles that may enter the solid during the step or end inside it (the
cheap test of ``Collider._may_enter``), :func:`collider_resolve` treats
those, in parallel, writing each contact into the particle's slot of its
round (the last slot: the projection), so that the contacts come out in the
NumPy collider's order. Particles are independent: the same bits on any
number of threads.

The surfaces are the primitives of :mod:`particles.collisions.surfaces`, as a kind and
a row of numbers (:data:`PLANE`, :data:`SPHERE`, :data:`BOX`,
:data:`CYLINDER`; see :func:`surface_row`); the third coordinate of a 2D point is 0.
"""

import math

import numpy as np

from ..backends.compile import inline, jit, pick, prange
from ..backends.layout import c_ordered, kept_array
from .response import friction_change, normal_change
from .surfaces import Box, Cylinder, Plane, Sphere, box_height, plane_height, round_height

for _law in (normal_change, friction_change, plane_height, round_height, box_height):
    inline(_law)

PLANE, SPHERE, BOX, CYLINDER = 0, 1, 2, 3
CROSSING_TOL, INSIDE_TOL = 1e-12, 1e-9  # particles.collisions.surface_crossing's tolerances
ROUNDOFF_DEPTH = 1e-12  # particles.collisions.collider.ROUNDOFF_DEPTH
ITERATIONS = 60  # first_crossing's regula falsi iterations


def _dot(a0, a1, a2, b0, b1, b2):
    """``a . b`` in coordinate order, as ``particles._vectors.rowdot`` sums it (the NumPy collider's bits)."""
    return (a0 * b0 + a1 * b1) + a2 * b2


def _box_q(P, d, x0, x1, x2):
    """The box's ``q_a = |x_a - c_a| - half_a``, the signs of ``x_a - c_a``, and the first largest q (its axis)."""
    r0, r1, r2 = x0 - P[0], x1 - P[1], x2 - P[2]
    q0, q1 = abs(r0) - P[3], abs(r1) - P[4]
    q2 = abs(r2) - P[5] if d == 3 else -math.inf
    k = 0
    if q1 > q0:
        k = 1
    if d == 3 and q2 > (q0 if k == 0 else q1):
        k = 2
    return (q0, q1, q2), (-1.0 if r0 < 0 else 1.0, -1.0 if r1 < 0 else 1.0, -1.0 if r2 < 0 else 1.0), k


def _cylinder_offset(P, x0, x1, x2):
    """``y = x - p`` along the axis: ``y . a``, and the offset from the axis ``r = y - (y . a) a``."""
    y0, y1, y2 = x0 - P[0], x1 - P[1], x2 - P[2]
    ya = y0 * P[3] + y1 * P[4] + y2 * P[5]
    return ya, (y0 - ya * P[3], y1 - ya * P[4], y2 - ya * P[5])


def surface_H(kind, P, d, x0, x1, x2):
    """The signed distance ``H(x)`` of the surface (negative inside the solid): the surfaces' laws."""
    if kind == PLANE:  # P: n (3), -n . p
        return plane_height(x0, x1, x2 if d == 3 else 0.0, P[0], P[1], P[2] if d == 3 else 0.0, P[3])
    if kind == SPHERE:  # P: c (3), r, sign
        return round_height(x0 - P[0], x1 - P[1], x2 - P[2], P[3], P[4])
    if kind == BOX:  # P: c (3), half (3), lo (3), hi (3), sign
        q, _, k = _box_q(P, d, x0, x1, x2)
        return box_height(q[0], q[1], q[2], P[12])
    _, r = _cylinder_offset(P, x0, x1, x2)  # P: p (3), a (3), R, sign, across (3)
    return round_height(r[0], r[1], r[2], P[6], P[7])


def _directions(kind, P, x0, x1, x2):
    """Unit vector from a sphere's centre or a cylinder's axis (a fixed one on it), as the surfaces define it."""
    if kind == SPHERE:
        r0, r1, r2 = x0 - P[0], x1 - P[1], x2 - P[2]
        dist = math.sqrt(_dot(r0, r1, r2, r0, r1, r2))
        if dist == 0:
            r0, dist = 1.0, 1.0
        return r0 / dist, r1 / dist, r2 / dist
    _, r = _cylinder_offset(P, x0, x1, x2)
    dist = max(math.sqrt(_dot(r[0], r[1], r[2], r[0], r[1], r[2])), 1e-300)
    u0, u1, u2 = r[0] / dist, r[1] / dist, r[2] / dist
    ua = u0 * P[3] + u1 * P[4] + u2 * P[5]
    u0, u1, u2 = u0 - ua * P[3], u1 - ua * P[4], u2 - ua * P[5]
    size = math.sqrt(_dot(u0, u1, u2, u0, u1, u2))
    if size < 0.5:
        u0, u1, u2, size = P[8], P[9], P[10], 1.0
    return u0 / size, u1 / size, u2 / size


def surface_normal(kind, P, d, x0, x1, x2):
    """The unit outward normal ``grad H / |grad H|`` (0 where the gradient is 0)."""
    if kind == PLANE:
        g0, g1, g2 = P[0], P[1], P[2]
    elif kind == BOX:
        q, side, k = _box_q(P, d, x0, x1, x2)
        g0, g1, g2 = max(q[0], 0.0) * side[0], max(q[1], 0.0) * side[1], max(q[2], 0.0) * side[2]
        if d == 2:
            g2 = 0.0
        outside = math.sqrt(_dot(g0, g1, g2, g0, g1, g2))
        if outside > 0:
            g0, g1, g2 = g0 / outside, g1 / outside, g2 / outside
        else:  # inside: the normal of the nearest face
            g0, g1, g2 = (side[0] if k == 0 else 0.0), (side[1] if k == 1 else 0.0), (side[2] if k == 2 else 0.0)
        g0, g1, g2 = g0 * P[12], g1 * P[12], g2 * P[12]
    else:
        u = _directions(kind, P, x0, x1, x2)
        sign = P[4] if kind == SPHERE else P[7]
        g0, g1, g2 = u[0] * sign, u[1] * sign, u[2] * sign
    if d == 2:
        g2 = 0.0
    L = math.sqrt(_dot(g0, g1, g2, g0, g1, g2))
    if L == 0:
        return 0.0, 0.0, 0.0
    return g0 / L, g1 / L, g2 / L


def surface_closest(kind, P, d, x0, x1, x2):
    """The point of the surface closest to x."""
    if kind == PLANE:
        H = surface_H(kind, P, d, x0, x1, x2)
        return x0 - H * P[0], x1 - H * P[1], x2 - H * P[2] if d == 3 else 0.0
    if kind == SPHERE:
        u = _directions(kind, P, x0, x1, x2)
        return P[0] + P[3] * u[0], P[1] + P[3] * u[1], P[2] + P[3] * u[2] if d == 3 else 0.0
    if kind == BOX:
        q, side, k = _box_q(P, d, x0, x1, x2)
        p = [min(max(x0, P[6]), P[9]), min(max(x1, P[7]), P[10]), min(max(x2, P[8]), P[11]) if d == 3 else 0.0]
        if q[k] <= 0:  # inside: onto the nearest face
            p[k] = P[k] + side[k] * P[3 + k]
        return p[0], p[1], p[2]
    ya, _ = _cylinder_offset(P, x0, x1, x2)
    u = _directions(kind, P, x0, x1, x2)
    return (P[0] + ya * P[3] + P[6] * u[0], P[1] + ya * P[4] + P[6] * u[1], P[2] + ya * P[5] + P[6] * u[2])


def _path_speed(x0, v0, x1, v1, h):
    """``|c| + |h v0 - c| + |h v1 - c|``, c = x1 - x0: a bound on ``|dx/ds|`` (surface_crossing.path_speed)."""
    s0, s1, s2 = 0.0, 0.0, 0.0
    for a in range(3):
        chord = x1[a] - x0[a]
        s0 += chord * chord
        s1 += (h * v0[a] - chord) ** 2
        s2 += (h * v1[a] - chord) ** 2
    return math.sqrt(s0) + math.sqrt(s1) + math.sqrt(s2)


def _cubic(c, s):
    """``c0 + s (c1 + s (c2 + s c3))`` per coordinate (particles.collisions.surface_crossing.cubic_path)."""
    return (c[0][0] + s * (c[1][0] + s * (c[2][0] + s * c[3][0])),
            c[0][1] + s * (c[1][1] + s * (c[2][1] + s * c[3][1])),
            c[0][2] + s * (c[1][2] + s * (c[2][2] + s * c[3][2])))


def _hermite(x0, v0, x1, v1, h, s):
    """Position and velocity at fraction s of the step (particles.collisions.surface_crossing.hermite)."""
    s2, s3 = s * s, s * s * s
    b0, b1, b2, b3 = 2 * s3 - 3 * s2 + 1, (s3 - 2 * s2 + s) * h, 3 * s2 - 2 * s3, (s3 - s2) * h
    db0, db1, db3 = (6 * s2 - 6 * s) / h, 3 * s2 - 4 * s + 1, 3 * s2 - 2 * s
    x = (b0 * x0[0] + b1 * v0[0] + b2 * x1[0] + b3 * v1[0], b0 * x0[1] + b1 * v0[1] + b2 * x1[1] + b3 * v1[1],
         b0 * x0[2] + b1 * v0[2] + b2 * x1[2] + b3 * v1[2])
    v = (db0 * (x0[0] - x1[0]) + db1 * v0[0] + db3 * v1[0], db0 * (x0[1] - x1[1]) + db1 * v0[1] + db3 * v1[1],
         db0 * (x0[2] - x1[2]) + db1 * v0[2] + db3 * v1[2])
    return x, v


def _first_crossing(kind, P, d, x0, v0, x1, v1, h, samples, lipschitz):
    """First entry ``(s, s_in)`` of the Hermite path into the solid (surface_crossing.first_crossing)."""
    c = ((x0[0], x0[1], x0[2]), (h * v0[0], h * v0[1], h * v0[2]),
         (3 * (x1[0] - x0[0]) - h * (2 * v0[0] + v1[0]), 3 * (x1[1] - x0[1]) - h * (2 * v0[1] + v1[1]),
          3 * (x1[2] - x0[2]) - h * (2 * v0[2] + v1[2])),
         (-2 * (x1[0] - x0[0]) + h * (v0[0] + v1[0]), -2 * (x1[1] - x0[1]) + h * (v0[1] + v1[1]),
          -2 * (x1[2] - x0[2]) + h * (v0[2] + v1[2])))
    speed = _path_speed(x0, v0, x1, v1, h)
    y = _cubic(c, 0.0)
    lo, H_lo = 0.0, surface_H(kind, P, d, y[0], y[1], y[2])
    if H_lo < 0:
        return 0.0, 0.0
    hi, H_hi, found = 1.0, 0.0, False
    for _ in range(samples):  # the walk along the path
        if found or not lo < 1.0:
            break
        ahead = 1.0 / samples
        if lipschitz > 0:
            reach = H_lo / (lipschitz * speed) if speed > 0 else math.inf
            ahead = max(ahead, reach)
        sk = min(lo + ahead, 1.0)
        y = _cubic(c, sk)
        Hk = surface_H(kind, P, d, y[0], y[1], y[2])
        if Hk < 0:
            found, hi, H_hi = True, sk, Hk
        else:
            lo, H_lo = sk, Hk
    if not found:
        return 1.0, 1.0
    side = 0.0  # Illinois: halve the value kept twice in a row
    for _ in range(ITERATIONS):
        if not (hi - lo > 1e-13 and (H_lo > CROSSING_TOL or H_hi < -INSIDE_TOL)):
            break
        level = 0.0 if H_lo > CROSSING_TOL else -0.1 * INSIDE_TOL
        sm = lo + (level - H_lo) * (hi - lo) / (H_hi - H_lo)
        sm = min(max(sm, lo), hi)
        y = _cubic(c, sm)
        Hm = surface_H(kind, P, d, y[0], y[1], y[2])
        if Hm < 0:
            hi, H_hi = sm, Hm
            H_lo *= 0.5 if side == -1 else 1.0
            side = -1.0
        else:
            lo, H_lo = sm, Hm
            H_hi *= 0.5 if side == 1 else 1.0
            side = 1.0
    return lo, hi


def _respond(v, n, eps, mu):
    """Velocity after the contact, and the normal and friction changes (particles.collisions.response.response)."""
    vn = _dot(v[0], v[1], v[2], n[0], n[1], n[2])
    vt = (v[0] - vn * n[0], v[1] - vn * n[1], v[2] - vn * n[2])
    k = normal_change(vn, eps)
    dvn = (k * n[0], k * n[1], k * n[2])
    dvt = (0.0, 0.0, 0.0)
    if mu > 0:
        speed_t = math.sqrt(_dot(vt[0], vt[1], vt[2], vt[0], vt[1], vt[2]))
        slow = friction_change(mu, normal_change(vn, eps), speed_t)
        scale = slow / speed_t if speed_t > 0 else 0.0
        dvt = (-scale * vt[0], -scale * vt[1], -scale * vt[2])
    return (v[0] + dvn[0] + dvt[0], v[1] + dvn[1] + dvt[1], v[2] + dvn[2] + dvt[2]), dvn, dvt


def _changed(dvn, dvt):
    """Whether a response changes the velocity."""
    return dvn[0] != 0 or dvn[1] != 0 or dvn[2] != 0 or dvt[0] != 0 or dvt[1] != 0 or dvt[2] != 0


def _record(rec, has, k, r, m, t, x, n, dvn, dvt, d):
    """Contact slot r of candidate k: time, point, normal, impulse m dv_n, friction m dv_t."""
    has[k, r] = True
    rec[k, r, 0] = t
    for a in range(d):
        rec[k, r, 1 + a] = x[a]
        rec[k, r, 1 + d + a] = n[a]
        rec[k, r, 1 + 2 * d + a] = m * dvn[a]
        rec[k, r, 1 + 3 * d + a] = m * dvt[a]


@jit(parallel=True)
def collider_candidates(kind, P, X_old, X, free, h, backtrack, lipschitz, flag):
    """Which free particles the step must treat: those that may enter the solid, or end inside it."""
    d = X.shape[2]
    for p in prange(X.shape[0]):
        x1 = (X[p, 0, 0], X[p, 0, 1], X[p, 0, 2] if d == 3 else 0.0)
        H1 = surface_H(kind, P, d, x1[0], x1[1], x1[2])
        flag[p] = free[p] and H1 < 0
        if free[p] and backtrack and not flag[p]:
            x0 = (X_old[p, 0, 0], X_old[p, 0, 1], X_old[p, 0, 2] if d == 3 else 0.0)
            H0 = surface_H(kind, P, d, x0[0], x0[1], x0[2])
            if H0 >= 0:
                if lipschitz > 0:
                    v0 = (X_old[p, 1, 0], X_old[p, 1, 1], X_old[p, 1, 2] if d == 3 else 0.0)
                    v1 = (X[p, 1, 0], X[p, 1, 1], X[p, 1, 2] if d == 3 else 0.0)
                    D = _path_speed(x0, v0, x1, v1, h)
                    flag[p] = H0 + H1 <= lipschitz * D * (1 + 1e-12) + 1e-15
                else:
                    flag[p] = True


@jit(parallel=True)
def collider_resolve(kind, P, X_old, X, todo, m, t, h, backtrack, eps, mu, bounces, samples, lipschitz, rec, has):
    """The particles `todo`: their bounces along the step's path, then the projection of those still inside.

    Candidate k's contacts go to ``rec[k, r]`` (``has[k, r]``): r = 0 .. bounces - 1 its bounces, r =
    bounces the projection (``rec`` rows: time, point, normal, impulse, friction).
    """
    d = X.shape[2]
    for k in prange(len(todo)):
        p = todo[k]
        for r in range(bounces + 1):
            has[k, r] = False
        x0 = (X_old[p, 0, 0], X_old[p, 0, 1], X_old[p, 0, 2] if d == 3 else 0.0)
        v0 = (X_old[p, 1, 0], X_old[p, 1, 1], X_old[p, 1, 2] if d == 3 else 0.0)
        x1 = (X[p, 0, 0], X[p, 0, 1], X[p, 0, 2] if d == 3 else 0.0)
        v1 = (X[p, 1, 0], X[p, 1, 1], X[p, 1, 2] if d == 3 else 0.0)
        inside = surface_H(kind, P, d, x0[0], x0[1], x0[2]) < 0
        if backtrack and not inside:
            a = ((v1[0] - v0[0]) / h, (v1[1] - v0[1]) / h, (v1[2] - v0[2]) / h)
            t0, dt = t, h
            for r in range(bounces):  # the successive bounces within the step
                s, s_in = _first_crossing(kind, P, d, x0, v0, x1, v1, dt, samples, lipschitz)
                if not s < 1.0:
                    break
                xc, vc = _hermite(x0, v0, x1, v1, dt, s)
                x_in, _ = _hermite(x0, v0, x1, v1, dt, s_in)
                n = surface_normal(kind, P, d, x_in[0], x_in[1], x_in[2])
                v_new, dvn, dvt = _respond(vc, n, eps, mu)
                rest = (1.0 - s) * dt
                a_n = a[0] * n[0] + a[1] * n[1] + a[2] * n[2]
                resting = a_n < 0 and v_new[0] * n[0] + v_new[1] * n[1] + v_new[2] * n[2] < -a_n * rest
                ah = a
                if resting:  # the surface carries the inward pull
                    ah = (ah[0] - a_n * n[0], ah[1] - a_n * n[1], ah[2] - a_n * n[2])
                    if mu:  # Coulomb friction for the rest of the step (collisions._resting_friction)
                        vv = _dot(v_new[0], v_new[1], v_new[2], n[0], n[1], n[2])
                        e0 = v_new[0] - vv * n[0] + ah[0] * rest
                        e1 = v_new[1] - vv * n[1] + ah[1] * rest
                        e2 = v_new[2] - vv * n[2] + ah[2] * rest
                        speed = math.sqrt(_dot(e0, e1, e2, e0, e1, e2))
                        removed = min(speed, mu * -a_n * rest)
                        scale = removed / (speed * rest) if speed > 0 and rest > 0 else 0.0
                        ah = (ah[0] - scale * e0, ah[1] - scale * e1, ah[2] - scale * e2)
                tc = t0 + s * dt
                real = _changed(dvn, dvt)
                if real:
                    _record(rec, has, k, r, m[p], tc, xc, n, dvn, dvt, d)
                if real or resting:  # the rest of the step: constant acceleration from the contact state
                    x0, v0 = xc, v_new
                    x1 = (xc[0] + v_new[0] * rest + 0.5 * ah[0] * rest ** 2,
                          xc[1] + v_new[1] * rest + 0.5 * ah[1] * rest ** 2,
                          xc[2] + v_new[2] * rest + 0.5 * ah[2] * rest ** 2)
                    v1 = (v_new[0] + ah[0] * rest, v_new[1] + ah[1] * rest, v_new[2] + ah[2] * rest)
                    t0, dt = tc, max(rest, 1e-300)
                if not real:
                    break
        H = surface_H(kind, P, d, x1[0], x1[1], x1[2])
        if H < 0:  # still inside: onto the surface (Collider._project)
            q = surface_closest(kind, P, d, x1[0], x1[1], x1[2])
            n = surface_normal(kind, P, d, x1[0], x1[1], x1[2])  # it points to q (collisions._push_directions)
            v_new, dvn, dvt = _respond(v1, n, eps, mu)
            x1, v1 = q, v_new
            if _changed(dvn, dvt) or H < -ROUNDOFF_DEPTH:
                _record(rec, has, k, bounces, m[p], t + h, q, n, dvn, dvt, d)
        for a in range(d):
            X[p, 0, a] = x1[a]
            X[p, 1, a] = v1[a]


def surface_row(surface):
    """The kind and the numbers of a primitive surface as the collider's kernels read them; None for others.

    Plane: ``n, -n . p``; Sphere: ``c, r, sign``; Box: ``c, half, lo, hi,
    sign``; Cylinder: ``p, a, R, sign, across`` (3 components each, the third
    0 in 2D). Unions, intersections and complements are left to NumPy.
    """
    def padded(v):
        return list(v) + [0.0] * (3 - len(v))

    kind = type(surface)
    if kind is Plane:
        return PLANE, np.array(padded(surface.n) + [-float(surface.n @ surface.point)])
    if kind is Sphere:
        return SPHERE, np.array(padded(surface.center) + [surface.radius, surface.sign])
    if kind is Box:
        return BOX, np.array(padded(surface.center) + padded(surface.half) + padded(surface.lo) + padded(surface.hi)
                             + [surface.sign])
    if kind is Cylinder:  # across: the fixed unit normal on the axis, as Cylinder makes it
        helper = np.eye(3)[np.argmin(np.abs(surface.axis))]
        across = np.cross(surface.axis, helper) / np.linalg.norm(np.cross(surface.axis, helper))
        return CYLINDER, np.array(list(surface.point) + list(surface.axis) + [surface.radius, surface.sign]
                                  + list(across))
    return None


def surface_rows(surfaces):
    """The surfaces as :func:`surface_row` gives them, in one table: ``kinds`` (b,) and ``rows`` (b, 13); or None.

    None when one of them is not a primitive. Rows are padded with zeros to the longest (a box's 13).
    """
    table = [surface_row(s) for s in surfaces]
    if any(r is None for r in table):
        return None
    rows = np.zeros((len(table), 13))
    for b, (_, P) in enumerate(table):  # a loop over the few surfaces
        rows[b, :len(P)] = P
    return np.array([kind for kind, _ in table], dtype=np.int64), rows


def collide(collider, X_old, X, t, h, m, free):
    """The collider's fix of the end state X (n, 2, d) in place, compiled; returns the contacts' columns, or None.

    None (nothing done) when the surface is not a primitive. Otherwise
    ``(index, time, point, normal, impulse, friction)`` in the order of
    :meth:`particles.collisions.Collider.collide`: the contacts of each
    bounce, then those of the projection.
    """
    row = surface_row(collider.surface)
    if row is None:
        return None
    kind, P = row
    n, _, d = X.shape
    store = collider.compiled_buffers
    flag = kept_array(store, "flag", (n,), np.bool_)
    backtrack = collider.method == "backtrack"
    lipschitz = 0.0 if collider.surface.lipschitz is None else float(collider.surface.lipschitz)
    X_old = np.ascontiguousarray(X_old)
    with c_ordered(X) as X_c:
        pick(collider_candidates, n)(kind, P, X_old, X_c, free, float(h), backtrack, lipschitz, flag)
        todo = np.flatnonzero(flag)
        slots = collider.max_bounces + 1
        rec = kept_array(store, "rec", (max(len(todo), 16), slots, 1 + 4 * d))
        has = kept_array(store, "has", rec.shape[:2], np.bool_)
        pick(collider_resolve, len(todo))(kind, P, X_old, X_c, todo, m, float(t), float(h), backtrack,
                                          collider.restitution, collider.friction, collider.max_bounces,
                                          collider.samples, lipschitz, rec, has)
    rows = [np.flatnonzero(has[:len(todo), r]) for r in range(slots)]  # a loop over the rounds
    k = np.concatenate(rows)
    r = np.concatenate([np.full(len(q), c) for c, q in enumerate(rows)])
    data = rec[k, r]
    return (todo[k], data[:, 0], *(np.ascontiguousarray(data[:, 1 + a * d:1 + (a + 1) * d]) for a in range(4)))


for _helper in (_dot, _box_q, _cylinder_offset, surface_H, _directions, surface_normal, surface_closest, _path_speed, _cubic, _hermite, _first_crossing, _respond, _changed, _record,):  # compiled into the kernels that call them
    inline(_helper, into="never")
