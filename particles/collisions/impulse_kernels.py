"""The proximity stage's Jacobi iterations, compiled (numba), with the bodies' vertex pass after each.

Imported only by :mod:`particles.collisions.compiled_stages`. :func:`proximity_impulses` runs the loop of
``ClothCollisions._proximity`` (:mod:`particles.collisions.pipeline`, ``method="jacobi"``) in one call:
each iteration finds the contacts below their target normal velocity, sums each free vertex's load over
those, gives each an impulse divided by the largest load at its free vertices (from the second iteration on,
by that load over `relaxation`, never by less than 1; with Coulomb friction) and
adds the impulses to the vertices; then every free vertex of those contacts is moved out of the bodies
(``BodyStage._bodies`` without the edge samples, :func:`particles.collisions.body_kernels.out_of_bodies`),
when the bodies are primitives at rest (:mod:`particles.collisions.collider_kernels`' rows). Otherwise the
pipeline calls it one iteration at a time and runs the NumPy body pass in between.

Work per iteration follows the active contacts, not all of them. Their loads and impulses are summed per
vertex in parts: the active contacts, in increasing order, are cut into at most :data:`BLOCKS` slices of
at least `part_min` contacts, each slice sums into its own per-vertex arrays (one thread each), and each
vertex adds its slices' sums in slice order. The cut depends on the number of active contacts only:
the same bits on any number of threads. With one slice (fewer than 2 `part_min` active contacts) a vertex
sums its terms in ``np.bincount``'s order; with more, in another, which moves the sums by round-off (a few
1e-16 relative). Either way the result agrees with NumPy's to round-off, not to the bit (its relative
velocities are ``np.einsum``'s). In a 64^2 fold's pile-up, 127k contacts, of which 108k are active at the first
iteration and, with plain averaging, 33k at the 50th; at 37k active contacts, summing in parts took 0.8 ms per iteration where
sorting the entries by vertex and summing them in NumPy's order took 1.6 to 2.4 ms.
"""

import math

import numpy as np

from .._vectors import vdot
from ..backends.compile import inline, jit, prange
from .body_kernels import out_of_bodies
from .contact_kernels import combine, row3
from .response import friction_change, proximity_impulse

inline(friction_change)
inline(proximity_impulse)


BLOCKS = 8  # slices of the active contacts summed apart, at most (a fixed cut: the same bits on any thread count)


def row4(W, k):
    return (W[k, 0], W[k, 1], W[k, 2], W[k, 3])


def _mark_active(b, span, K, vbar, V, W, N, target, h, tol, active):
    """Block b of the contacts: which are below their target normal velocity (into `active`), and how many."""
    f = 0
    for k in range(b * span, min(K, (b + 1) * span)):
        a = (target[k] - vdot(row3(N, k), combine(row4(W, k), vbar, V, k))) * h > tol
        active[k] = a
        f += a
    return f


def _slice_loads(b, size, m, order, V, W, w, part_load, part_hit):
    """Slice b of the active contacts: each free vertex's load ``sum |W_j|`` over them, and whether it is touched."""
    for p in range(part_load.shape[1]):
        part_load[b, p] = 0.0
        part_hit[b, p] = False
    for i in range(b * size, min(m, (b + 1) * size)):
        k = order[i]
        for j in range(4):
            v = V[k, j]
            if w[v] > 0:
                part_load[b, v] += abs(W[k, j])
                part_hit[b, v] = True


def _impulse(i, k, vbar, V, W, N, S, target, w, load, relaxed, friction, impulse):
    """Active contact k's impulse (row i of `impulse`): to its target, divided by the largest load at its free
    vertices over `relaxed` (at least 1), with Coulomb friction (``ProximityStage._impulses``)."""
    c = 0.0
    for j in range(4):
        if w[V[k, j]] > 0 and abs(W[k, j]) > 0:
            c = max(c, load[V[k, j]])
    c = max(c / relaxed, 1.0)
    r0, r1, r2 = combine(row4(W, k), vbar, V, k)
    vN = vdot(row3(N, k), (r0, r1, r2))
    I = proximity_impulse(target[k], vN, S[k], c)
    impulse[i, 0], impulse[i, 1], impulse[i, 2] = I * N[k, 0], I * N[k, 1], I * N[k, 2]
    if friction > 0:
        t0, t1, t2 = r0 - vN * N[k, 0], r1 - vN * N[k, 1], r2 - vN * N[k, 2]
        speed = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        J = friction_change(friction, I, speed / S[k] / c)
        f = J / speed if speed > 0 else 0.0
        impulse[i, 0] -= f * t0
        impulse[i, 1] -= f * t1
        impulse[i, 2] -= f * t2


def _slice_velocities(b, size, m, order, V, W, w, impulse, part_vel):
    """Slice b of the active contacts: each free vertex's velocity change ``w_j W_j impulse``, summed."""
    for p in range(part_vel.shape[1]):
        part_vel[b, p, 0] = part_vel[b, p, 1] = part_vel[b, p, 2] = 0.0
    for i in range(b * size, min(m, (b + 1) * size)):
        k = order[i]
        for j in range(4):
            v = V[k, j]
            if w[v] > 0:
                scale = W[k, j] * w[v]
                part_vel[b, v, 0] += scale * impulse[i, 0]
                part_vel[b, v, 1] += scale * impulse[i, 1]
                part_vel[b, v, 2] += scale * impulse[i, 2]


inline(row4)
for _helper in (_mark_active, _slice_loads, _impulse, _slice_velocities):  # loops and branches: functions of their own
    inline(_helper, into="never")


@jit(parallel=True)
def proximity_impulses(vbar, x0, V, W, N, S, target, w, h, tol, friction, relaxation, start, iterations, thickness,
                       kinds, rows, part_min, touched, active, order, impulse, load, part_load, part_hit, part_vel):
    """Up to `iterations` Jacobi iterations of the proximity impulses on `vbar` (n, 3), in place.

    `V`, `W`, `N`, `S`, `target` are the contacts' vertices (k, 4), weights (k, 4), normals (k, 3),
    inverse effective masses (k,) and target normal velocities (k,); `w` the inverse masses (n,). From
    the iteration numbered 1 on (counting `start` earlier ones), a contact's divisor is its largest load over
    `relaxation`, at least 1. After
    each iteration the free vertices of its active contacts are moved out of the bodies `kinds`, `rows`
    (none when empty). The per-vertex sums run in slices of at least `part_min` active contacts (at most
    :data:`BLOCKS`). `touched` (k,) is set where a contact got an impulse, `active` (k,) holds the last
    iteration's; `order` (k,), `impulse` (k, 3), `load` (n,), `part_load` (BLOCKS, n), `part_hit`
    (BLOCKS, n) and `part_vel` (BLOCKS, n, 3) are work arrays. Returns the number of iterations that gave
    impulses (fewer than `iterations` when one found no contact below its target).
    """
    K, n = len(V), len(vbar)
    span = (K + BLOCKS - 1) // BLOCKS
    found = np.zeros(BLOCKS + 1, dtype=np.int64)
    done = 0
    for it in range(iterations):
        relaxed = relaxation if start + it > 0 else 1.0  # the first iteration plain averaging, the later ones relaxed
        for b in prange(BLOCKS):  # the contacts below their target, counted in blocks of contacts
            found[b + 1] = _mark_active(b, span, K, vbar, V, W, N, target, h, tol, active)
        for b in range(BLOCKS):
            found[b + 1] += found[b]
        m = found[BLOCKS]
        if m == 0:
            break
        for b in prange(BLOCKS):  # the active ones listed in increasing order, each block from its offset
            i = found[b]
            for k in range(b * span, min(K, (b + 1) * span)):
                if active[k]:
                    order[i] = k
                    i += 1
                    touched[k] = True
        done += 1
        parts = min(BLOCKS, max(1, m // part_min))
        size = (m + parts - 1) // parts
        for b in prange(parts):  # each slice's loads: sum of |w_j| over its contacts at each free vertex
            _slice_loads(b, size, m, order, V, W, w, part_load, part_hit)
        for p in prange(n):
            s = 0.0
            for b in range(parts):
                s += part_load[b, p]
            load[p] = s
        for i in prange(m):  # each active contact's impulse, divided by the largest load at its free vertices
            _impulse(i, order[i], vbar, V, W, N, S, target, w, load, relaxed, friction, impulse)
        for b in prange(parts):  # each slice's velocity changes w_j W_j impulse at each free vertex
            _slice_velocities(b, size, m, order, V, W, w, impulse, part_vel)
        for p in prange(n):  # the slices' sums added to vbar, then the vertex out of the bodies
            hit = False
            s0 = s1 = s2 = 0.0
            for b in range(parts):
                hit = hit or part_hit[b, p]
                s0 += part_vel[b, p, 0]
                s1 += part_vel[b, p, 1]
                s2 += part_vel[b, p, 2]
            if hit:
                vbar[p, 0] += s0
                vbar[p, 1] += s1
                vbar[p, 2] += s2
                out_of_bodies(p, x0, vbar, h, thickness, friction, kinds, rows)
    return done
