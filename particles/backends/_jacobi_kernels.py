"""The proximity stage's Jacobi iterations, compiled (numba), with the bodies' vertex pass after each.

Imported only by :mod:`particles.backends.cloth`. :func:`proximity_impulses` runs the loop of
``ClothCollisions._proximity`` (:mod:`particles.collisions.pipeline`, ``method="jacobi"``) in one call:
each iteration finds the contacts below their target normal velocity, sums each free vertex's load over
those, gives each an impulse divided by the largest load at its free vertices (with Coulomb friction) and
adds the impulses to the vertices; then every free vertex of those contacts is moved out of the bodies
(``BodyStage._bodies`` without the edge samples, :func:`particles.backends._body_kernels.out_of_bodies`),
when the bodies are primitives at rest (:mod:`particles.backends._collider_kernels`' rows). Otherwise the
pipeline calls it one iteration at a time and runs the NumPy body pass in between.

Work per iteration follows the active contacts, not all of them: their vertices' entries are sorted into
a compressed-row list (a counting sort in blocks of contacts, in the order ``np.bincount`` meets them over
``V[k].ravel()``), so that each vertex sums its terms in NumPy's order, on one thread: the same bits on
any number of threads. The per-vertex sums run in parts of about equal entries (a few vertices carry
hundreds of contacts). In a 64^2 fold at its impact, 22k contacts, of which 20k are active at the first iteration and
a few hundred at the last.
"""

import math

import numpy as np

from ._body_kernels import out_of_bodies
from ._contact_kernels import combine, dot3, row3
from ._kernels import _jit, prange


SORT_BLOCKS = 8  # blocks of active contacts sorted by vertex in parallel (any number gives the same order)
PARTS = 64  # parts of about equal entries that the per-vertex sums are split into (static: any thread count)


@_jit()
def row4(W, k):
    return (W[k, 0], W[k, 1], W[k, 2], W[k, 3])


@_jit(parallel=True)
def proximity_impulses(vbar, x0, V, W, N, S, target, w, h, tol, friction, iterations, thickness, kinds, rows,
                       touched, active, order, impulse, load, ptr, entry, counts, parts):
    """Up to `iterations` Jacobi iterations of the proximity impulses on `vbar` (n, 3), in place.

    `V`, `W`, `N`, `S`, `target` are the contacts' vertices (k, 4), weights (k, 4), normals (k, 3),
    inverse effective masses (k,) and target normal velocities (k,); `w` the inverse masses (n,). After
    each iteration the free vertices of its active contacts are moved out of the bodies `kinds`, `rows`
    (none when empty). `touched` (k,) is set where a contact got an impulse, `active` (k,) holds the last
    iteration's; `order` (k,), `impulse` (k, 3), `load` (n,), `ptr` (n + 1,), `entry` (4 k,), `counts`
    (SORT_BLOCKS, n) and `parts` (PARTS + 1,) are work arrays. Returns the number of iterations that gave
    impulses (fewer than `iterations` when one found no contact below its target).
    """
    K, n = len(V), len(vbar)
    done = 0
    for _ in range(iterations):
        for k in prange(K):  # the contacts below their target
            active[k] = (target[k] - dot3(row3(N, k), combine(row4(W, k), vbar, V, k))) * h > tol
        m = 0
        for k in range(K):  # the active ones, in increasing order
            if active[k]:
                order[m] = k
                m += 1
                touched[k] = True
        if m == 0:
            break
        done += 1
        # their vertices' entries sorted by vertex, in bincount's order: a counting sort in blocks of contacts
        size = (m + SORT_BLOCKS - 1) // SORT_BLOCKS
        for b in prange(SORT_BLOCKS):  # each block's entries per vertex
            for p in range(n):
                counts[b, p] = 0
            for i in range(b * size, min(m, (b + 1) * size)):
                for j in range(4):
                    counts[b, V[order[i], j]] += 1
        total = 0
        for p in range(n):  # each vertex's entries start at ptr[p]: block 0's first, then block 1's, ...
            ptr[p] = total
            for b in range(SORT_BLOCKS):
                c = counts[b, p]
                counts[b, p] = total
                total += c
        ptr[n] = total
        for b in prange(SORT_BLOCKS):  # within a block in increasing contact: the whole in increasing contact
            for i in range(b * size, min(m, (b + 1) * size)):
                for j in range(4):
                    v = V[order[i], j]
                    entry[counts[b, v]] = 4 * i + j
                    counts[b, v] += 1
        for q in range(PARTS + 1):  # vertices in parts of about equal entries (the sums below are per vertex)
            parts[q] = np.searchsorted(ptr, total * q // PARTS)
        parts[PARTS] = n
        for q in prange(PARTS):  # each free vertex's load: sum of |w_j| over its active contacts
            for p in range(parts[q], parts[q + 1]):
                s = 0.0
                if w[p] > 0:
                    for e in range(ptr[p], ptr[p + 1]):
                        s += abs(W[order[entry[e] // 4], entry[e] % 4])
                load[p] = s
        for i in prange(m):  # each active contact's impulse, divided by the largest load at its free vertices
            k = order[i]
            c = 0.0
            for j in range(4):
                if w[V[k, j]] > 0 and abs(W[k, j]) > 0:
                    c = max(c, load[V[k, j]])
            c = max(c, 1.0)
            r0, r1, r2 = combine(row4(W, k), vbar, V, k)
            vN = dot3(row3(N, k), (r0, r1, r2))
            I = (target[k] - vN) / S[k] / c
            impulse[i, 0], impulse[i, 1], impulse[i, 2] = I * N[k, 0], I * N[k, 1], I * N[k, 2]
            if friction > 0:
                t0, t1, t2 = r0 - vN * N[k, 0], r1 - vN * N[k, 1], r2 - vN * N[k, 2]
                speed = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
                J = min(friction * I, speed / S[k] / c)
                f = J / speed if speed > 0 else 0.0
                impulse[i, 0] -= f * t0
                impulse[i, 1] -= f * t1
                impulse[i, 2] -= f * t2
        for q in prange(PARTS):  # vbar_j += w_j I n / m_j per vertex, then the vertex out of the bodies
            for p in range(parts[q], parts[q + 1]):
                if ptr[p + 1] == ptr[p]:
                    continue
                s0 = s1 = s2 = 0.0
                for e in range(ptr[p], ptr[p + 1]):
                    i, j = entry[e] // 4, entry[e] % 4
                    scale = W[order[i], j] * w[p]
                    s0 += scale * impulse[i, 0]
                    s1 += scale * impulse[i, 1]
                    s2 += scale * impulse[i, 2]
                vbar[p, 0] += s0
                vbar[p, 1] += s1
                vbar[p, 2] += s2
                if w[p] > 0:
                    out_of_bodies(p, x0, vbar, h, thickness, friction, kinds, rows)
    return done
