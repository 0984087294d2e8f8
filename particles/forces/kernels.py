"""The forces' compiled loops (numba): springs, bending, Lennard-Jones and N-body gravity, one pass each.

Each loop inlines the law that the NumPy pass applies to whole arrays
(:func:`particles.forces.springs.damped_spring_force`,
:func:`particles.forces.springs.joint_factor`,
:func:`particles.forces.pairs.lennard_jones_virial`,
:func:`particles.forces.pairs.gravitational_pull`), item by item, and the
classes below each prepare its arrays (incidence lists, buffers) once and
keep them. :class:`~particles.forces.Springs`, :class:`~particles.forces.Bending`,
:class:`~particles.forces.LennardJones` and :class:`~particles.forces.NBodyGravity`
import this module when their backend resolves to numba; importing it
imports numba.

Per-particle sums go through a compressed-row incidence list
(:func:`particles.backends.layout.incidence`) or per block of particles
(Lennard-Jones), so that each particle's force is summed by one thread in a
fixed order: the same bits for any number of threads. Springs have two forms
with the same bits: a one-pass scatter on one thread, and forces per spring
in parallel then a per-particle gather, which moves more memory and is used
from :data:`SPRING_THREADS` threads on.
"""

import math

import numpy as np

from ..backends.compile import inline, jit, kernel_form, parallel, pick, prange
from ..backends.layout import incidence
from .pairs import gravitational_pull, integer_power, lennard_jones_virial
from .springs import STRAIGHT_RANGE, TINY, bent_ratio, damped_spring_force, joint_factor, straight_ratio

__all__ = ["SpringPass", "BendingPass", "LennardJonesPass", "nbody_forces", "SPRING_THREADS"]

inline(damped_spring_force)
inline(straight_ratio)
inline(bent_ratio)
inline(gravitational_pull)
inline(integer_power, into="never")
inline(lennard_jones_virial)


@kernel_form(joint_factor)
def joint_factor_in_kernels(c, theta0, kb):
    """:func:`~particles.forces.springs.joint_factor` in a kernel: a joint takes the series or the ``acos``,
    and only the one it takes is computed (the same laws)."""
    x = 1.0 - c
    if x < STRAIGHT_RANGE and theta0 == 0.0:
        return kb * straight_ratio(x)
    return kb * bent_ratio(c, theta0)


# the two-pass parallel spring pass writes and reads every spring's force once more than the one-thread
# scatter: it pays from about this many threads (on two it was slower, bench/bench_backends.py)
SPRING_THREADS = 4


def relative_speed(v, a, b, at, d0, d1, d2, three):
    """``(v_a - v_b) . d``, the velocities in the columns from `at` of rows `a` and `b` of `v`."""
    s = (v[a, at] - v[b, at]) * d0 + (v[a, at + 1] - v[b, at + 1]) * d1
    return s + (v[a, at + 2] - v[b, at + 2]) * d2 if three else s


def spring_pull(x, v, a, b, at, L0, k, kd, three):
    """Spring (a, b)'s force on a, ``f u`` (three components, the third 0 in 2D): the arithmetic of spring_forces.

    Positions are rows `a`, `b` of `x`, velocities the columns from `at` of the same rows of `v` (the
    compiled step keeps both in one array), read only for a damped spring (``kd != 0``).
    """
    d0 = x[a, 0] - x[b, 0]
    d1 = x[a, 1] - x[b, 1]
    d2 = x[a, 2] - x[b, 2] if three else 0.0
    L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    inv_L = 1.0 / max(L, TINY)
    dL = relative_speed(v, a, b, at, d0, d1, d2, three) * inv_L if kd != 0.0 else 0.0  # kd dL = 0 either way
    w = damped_spring_force(L, L0, k, kd, dL) * inv_L  # f u = w d
    return w * d0, w * d1, w * d2


inline(relative_speed)
inline(spring_pull)


@jit()
def spring_scatter(S, x, v, i, j, L0, k, kd):
    """One pass, one thread: each spring's force added to ``S_i`` and taken from ``S_j`` (S zero, (n, d)).

    Each particle's sum runs in increasing spring order from zero, as :func:`springs_in_parallel` gathers it.
    """
    three = x.shape[1] == 3
    for s in range(len(i)):
        a, b = i[s], j[s]
        f0, f1, f2 = spring_pull(x, v, a, b, 0, L0[s], k[s], kd[s], three)
        S[a, 0] += f0
        S[a, 1] += f1
        S[b, 0] -= f0
        S[b, 1] -= f1
        if three:
            S[a, 2] += f2
            S[b, 2] -= f2


@jit(parallel=True)
def springs_in_parallel(F, x, v, i, j, L0, k, kd, f, ptr, col):
    """Forces per spring into f (s, 3) in parallel, then ``F_p += (+f where p is first, -f where second)``.

    Each particle's sum runs over its springs in increasing order (``col``, by item): the bits of
    :func:`spring_scatter`.
    """
    three = x.shape[1] == 3
    s = len(i)
    for q in prange(s):
        f[q, 0], f[q, 1], f[q, 2] = spring_pull(x, v, i[q], j[q], 0, L0[q], k[q], kd[q], three)
    for p in prange(len(ptr) - 1):
        a0, a1, a2 = 0.0, 0.0, 0.0
        for e in range(ptr[p], ptr[p + 1]):
            q = col[e]
            if q < s:
                a0 += f[q, 0]
                a1 += f[q, 1]
                a2 += f[q, 2]
            else:
                a0 -= f[q - s, 0]
                a1 -= f[q - s, 1]
                a2 -= f[q - s, 2]
        F[p, 0] += a0
        F[p, 1] += a1
        if three:
            F[p, 2] += a2


class SpringPass:
    """:meth:`particles.forces.Springs.add_to`, compiled; keeps the incidence list and the forces' buffer."""

    def __init__(self):
        self.key = self.lists = self.f = None

    def add_to(self, F, x, v, i, j, L0, k, kd):
        """F += the springs' forces: one thread, or forces per spring and a gather on SPRING_THREADS or more."""
        x = np.asarray(x, dtype=np.float64)
        damped = bool(np.any(kd))
        v = np.asarray(v, dtype=np.float64) if damped else x  # v is read only for damped springs
        s = len(i)
        if not parallel(s, SPRING_THREADS):
            S = np.zeros_like(F)
            spring_scatter(S, x, v, i, j, L0, k, kd)
            F += S
            return
        key = (len(F), id(i), id(j), s)
        if self.key != key:
            self.lists = incidence(np.concatenate([i, j]), len(F), 2, True)
            self.f = np.empty((s, 3))
            self.key = key
        pick(springs_in_parallel, s)(F, x, v, i, j, L0, k, kd, self.f, *self.lists)


@jit(parallel=True)
def bending_in_parallel(F, x, i, j, l, kb, theta0, g, ptr, col):
    """Forces of every joint on i, j, l into g (3, b, d), then ``F_p += (S_0 + S_1) + S_2`` by role (bending_forces)."""
    dim = x.shape[1]
    b = len(i)
    for t in prange(b):
        L1s, L2s = 0.0, 0.0
        for c in range(dim):
            e1 = x[j[t], c] - x[i[t], c]
            e2 = x[l[t], c] - x[j[t], c]
            L1s += e1 * e1
            L2s += e2 * e2
        L1, L2 = math.sqrt(L1s), math.sqrt(L2s)
        cos = 0.0
        for c in range(dim):
            cos += ((x[j[t], c] - x[i[t], c]) / L1 if L1 != 0 else 0.0) * \
                ((x[l[t], c] - x[j[t], c]) / L2 if L2 != 0 else 0.0)
        cos = min(max(cos, -1.0), 1.0)
        factor = joint_factor(cos, theta0[t], kb[t])
        s1 = factor / L1 if L1 > 0 else 0.0
        s2 = factor / L2 if L2 > 0 else 0.0
        for c in range(dim):
            u1 = (x[j[t], c] - x[i[t], c]) / L1 if L1 != 0 else 0.0
            u2 = (x[l[t], c] - x[j[t], c]) / L2 if L2 != 0 else 0.0
            g1 = (u2 - cos * u1) * s1
            g2 = (u1 - cos * u2) * s2
            g[0, t, c] = -g1
            g[1, t, c] = g1 - g2
            g[2, t, c] = g2
    for p in prange(len(ptr) - 1):
        for c in range(dim):
            s0, s1, s2 = 0.0, 0.0, 0.0
            for e in range(ptr[p], ptr[p + 1]):
                role, t = col[e] // b, col[e] % b
                if role == 0:
                    s0 += g[0, t, c]
                elif role == 1:
                    s1 += g[1, t, c]
                else:
                    s2 += g[2, t, c]
            F[p, c] += (s0 + s1) + s2


class BendingPass:
    """:meth:`particles.forces.Bending.add_to`, compiled; keeps the incidence list by role and the buffer."""

    def __init__(self):
        self.key = self.lists = self.g = None

    def add_to(self, F, x, i, j, l, kb, theta0):
        """F += the joints' forces: computed per joint, gathered per particle and role."""
        x = np.asarray(x, dtype=np.float64)
        b = len(i)
        key = (len(F), id(i), id(j), id(l), b)
        if self.key != key:
            self.lists = incidence(np.concatenate([i, j, l]), len(F), 3, False)
            self.key = key
        if self.g is None or self.g.shape != (3, b, x.shape[1]):
            self.g = np.empty((3, b, x.shape[1]))
        pick(bending_in_parallel, b)(F, x, i, j, l, kb, theta0, self.g, *self.lists)


def rank_blocks(i, j, n, blocks):
    """The listed pairs by first rank (``ptr``, ``nbr``: the second ranks), and `blocks` blocks of ranks.

    Block ``c`` holds ranks ``start[c]:start[c + 1]``; its pairs touch the ranks ``lo[c]:hi[c]`` (its
    window: neighbours are near in rank, so a window is a little wider than its block). Pairs keep
    their list order within each rank.
    """
    order = np.argsort(i, kind="stable")
    nbr = j[order].astype(np.uint32)  # unsigned: the pair loop skips numba's test for negative indices
    ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(i, minlength=n), out=ptr[1:])
    start = np.arange(blocks + 1, dtype=np.int64) * n // blocks
    lo, hi = start[:-1].copy(), start[1:].copy()
    for c in range(blocks):  # a loop over the blocks: each one's window
        mine = nbr[ptr[start[c]]:ptr[start[c + 1]]]
        if len(mine):
            lo[c] = min(lo[c], int(mine.min()))
            hi[c] = max(hi[c], int(mine.max()) + 1)
    return ptr, nbr, start, lo, hi


@jit(parallel=True)
def lennard_jones_blocks(F, x, perm, xs, ptr, nbr, start, lo, hi, offset, k1, k2, p, q, rc2, box, periodic, sums,
                         virials, Fs):
    """The Lennard-Jones pass by blocks of ranks: positions by rank, each block's pairs into its window, then F.

    1. ``xs[r] = x[perm[r]]``;
    2. blocks in parallel: each rank's pairs, the force on the rank (+) and on its neighbour (-) of
       ``u r f(r) (x_r - x_o)`` (:func:`~particles.forces.pairs.lennard_jones_virial`, zero beyond the
       cutoff) summed into the block's window of `sums`, the virials into ``virials[c]``; in a periodic
       box the minimum image of a coordinate is taken where it differs from the difference (``|d| > L/2``);
    3. ``Fs`` (by rank) gets the windows block after block, in parallel over blocks of ranks, each
       adding for its own ranks the windows that hold them in block order; then ``F[perm] += Fs``.

    Every sum runs in a fixed order: the same bits on any threads.
    """
    dim = xs.shape[1]
    three = dim == 3
    for r in prange(len(perm)):
        for c in range(dim):
            xs[r, c] = x[perm[r], c]
    h0, h1 = 0.5 * box[0], 0.5 * box[1]
    h2 = 0.5 * box[2] if three else 0.0
    for c in prange(len(lo)):
        base = offset[c] - lo[c] * dim
        sums[offset[c]:offset[c + 1]] = 0.0
        total = 0.0
        for r in range(start[c], start[c + 1]):
            x0, x1 = xs[r, 0], xs[r, 1]
            x2 = xs[r, 2] if three else 0.0
            a0, a1, a2 = 0.0, 0.0, 0.0
            for e in range(ptr[r], ptr[r + 1]):
                o = nbr[e]
                d0 = x0 - xs[o, 0]
                d1 = x1 - xs[o, 1]
                d2 = x2 - xs[o, 2] if three else 0.0
                if periodic:
                    if abs(d0) > h0:
                        d0 -= np.rint(d0 * (1.0 / box[0])) * box[0]
                    if abs(d1) > h1:
                        d1 -= np.rint(d1 * (1.0 / box[1])) * box[1]
                    if three and abs(d2) > h2:
                        d2 -= np.rint(d2 * (1.0 / box[2])) * box[2]
                r2 = d0 * d0 + d1 * d1 + d2 * d2
                u = 1.0 / r2 if r2 < rc2 else 0.0
                virial = lennard_jones_virial(u, k1, k2, p, q)
                total += virial
                w = u * virial
                a0 += d0 * w
                a1 += d1 * w
                a2 += d2 * w
                ko = base + o * dim
                sums[ko] -= d0 * w
                sums[ko + 1] -= d1 * w
                if three:
                    sums[ko + 2] -= d2 * w
            kr = base + r * dim
            sums[kr] += a0
            sums[kr + 1] += a1
            if three:
                sums[kr + 2] += a2
        virials[c] = total
    for b in prange(len(start) - 1):
        Fs[start[b]:start[b + 1]] = 0.0
        for c in range(len(lo)):
            for r in range(max(lo[c], start[b]), min(hi[c], start[b + 1])):
                for a in range(dim):
                    Fs[r, a] += sums[offset[c] + (r - lo[c]) * dim + a]
        for r in range(start[b], start[b + 1]):
            for a in range(dim):
                F[perm[r], a] += Fs[r, a]


class LennardJonesPass:
    """:meth:`particles.forces.LennardJones.add_to` on its Verlet list, compiled; keeps the lists and windows.

    The list sorted by first rank (again only when it is rebuilt) and cut into a fixed number of blocks
    of ranks (set by the particle count, not the threads); blocks run in parallel, each summing its
    pairs' forces, both ends, into its own window of ranks; the windows are then added in block order.
    Each pair is computed once, and the result has the same bits for any number of threads.
    """

    def __init__(self):
        self.pairs = self.n = None

    def add_to(self, F, x, perm, i, j, k1, k2, p, q, cutoff, box):
        """F += the pair forces; returns the virial, summed block after block."""
        n, d = x.shape
        if self.pairs is not i or self.n != n:
            blocks = int(min(64, max(1, n // 4096)))  # blocks of about 4k ranks: windows about twice as wide
            ptr, nbr, start, lo, hi = rank_blocks(i.astype(np.int64), j.astype(np.int64), n, blocks)
            offset = np.concatenate([[0], np.cumsum((hi - lo) * d)]).astype(np.int64)
            self.pairs, self.n = i, n
            self.lists, self.windows = (ptr, nbr, start), (lo, hi, offset)
            self.sums, self.virials = np.empty(offset[-1]), np.empty(blocks)
            self.rows, self.by_rank = np.empty((n, d)), np.empty((n, d))  # kept: no page faults
        (ptr, nbr, start), (lo, hi, offset) = self.lists, self.windows
        periodic = box is not None
        L = np.asarray(box, dtype=float) if periodic else np.ones(d)
        pick(lennard_jones_blocks, len(i))(F, np.asarray(x, dtype=np.float64), perm, self.rows, ptr, nbr, start, lo,
                                           hi, offset, k1, k2, p, q, cutoff**2, L, periodic, self.sums, self.virials,
                                           self.by_rank)
        return float(sum(self.virials.tolist()))  # block after block


@jit(parallel=True)
def nbody_pulls(F, x, m, G, eps2):
    """``F_i += sum_{j != i} gravitational_pull(G, m_i, m_j, r^2, eps^2) (x_j - x_i)``, one thread per i."""
    three = x.shape[1] == 3
    for a in prange(len(x)):
        a0, a1, a2 = 0.0, 0.0, 0.0
        for b in range(len(x)):
            if b == a:
                continue
            r0 = x[b, 0] - x[a, 0]
            r1 = x[b, 1] - x[a, 1]
            r2 = x[b, 2] - x[a, 2] if three else 0.0
            w = gravitational_pull(G, m[a], m[b], r0 * r0 + r1 * r1 + r2 * r2, eps2)
            a0 += w * r0
            a1 += w * r1
            a2 += w * r2
        F[a, 0] += a0
        F[a, 1] += a1
        if three:
            F[a, 2] += a2


def nbody_forces(F, x, m, G, softening):
    """:meth:`particles.forces.NBodyGravity.add_to`, compiled: F += every pair's pull, one thread per particle."""
    m = np.ascontiguousarray(m, dtype=np.float64)
    pick(nbody_pulls, len(x) ** 2)(F, np.asarray(x, dtype=np.float64), m, G, softening**2)
