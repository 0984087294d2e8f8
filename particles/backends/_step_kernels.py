"""The compiled symplectic Euler step of a mass-spring system (numba): one parallel pass per step.

Imported only by :mod:`particles.backends.compiled`. The NumPy step makes
about twenty passes over arrays of all the springs or all the particles;
this one makes one, over blocks of particles in parallel. Block ``c`` owns
the particles ``start[c]:start[c + 1]`` and, with no other block, computes
their new state:

1. it copies the positions and velocities of the particles its springs
   touch, ``lo[c]:hi[c]`` (its *window*), into rows ``xw[r] = (x_p, v_p)``,
   so that a spring reads each end from one cache line (the system keeps
   ``X`` in Fortran order, each coordinate of all particles together);
2. it computes its springs, those whose lower end ``a = min(i, j)`` is its
   own, summing the force on ``a`` in registers and adding the force on the
   other end into its rows ``fw`` (the other ends of a cloth's springs are at
   most two rows further); then the springs of earlier blocks that end in
   it, for the force on that end only (about one spring in twenty is
   computed twice, by the two blocks it joins);
3. it updates its own particles: velocity, then position.

The springs are listed by lower end in compressed rows (``ptr``; ``nbr``
the other ends, ``which`` and ``sidx`` the set and the spring), the springs
entering each block in another list (``inptr``, ``ina`` their lower ends,
``ine`` their entries). Each particle's force is summed in an order fixed by
the springs alone, so the result has the same bits on any number of threads;
the number of blocks depends on the particle count only. Indices are
unsigned where that spares numba's test for negative ones in the inner
loops.
"""

import math

from ._kernels import _jit, prange


@_jit(parallel=True, fastmath={"contract"})  # fused multiply-adds: rounding differs from NumPy's by ~1e-16
def symplectic_euler_blocks(X, copy, start, lo, hi, row0, xw, fw, rb0, rowp, rptr, other_end, which, sidx,
                            L0a, ka, kda, L0b, kb, kdb, L0c, kc, kdc, other, has_other, m, free, G, h, out):
    """One step for up to three spring sets: ``v + h a``, then ``x + h v_new``, into out (n, 2, d).

    ``a = F / m + G`` (0 where `free` is False): ``F`` the springs' force, plus ``other[p]`` when
    `has_other` (the forces without a compiled form), ``G`` the sum of the uniform gravities.
    Block c's rows of ``xw`` and ``fw`` are ``row0[c]:row0[c + 1]``, for the particles
    ``lo[c]:hi[c]``; its spring rows are ``rb0[c]:rb0[c + 1]``: row u is particle ``rowp[u]``
    and its entries ``rptr[u]:rptr[u + 1]``.

    Entry e joins its row's particle r to ``other_end[e]``, o; it is spring ``sidx[e]`` of set
    ``which[e]`` (0, 1, 2: the arrays ``L0a, ka, kda``, then ``b``, then ``c``), read where the
    set keeps it, so a stiffness changed in place is seen at the next step. Its force on r is
    ``d k (L0/L - 1) - d kd ((v_r - v_o).d) / L^2`` with ``d = x_r - x_o`` (the arithmetic of
    :meth:`particles.springs.Springs.add_to`), summed in registers, and minus that on o.
    """
    dim = len(G)  # G is a tuple: numba compiles a kernel for each length, with dim a constant
    three = dim == 3
    for c in prange(len(start) - 1):
        shift = row0[c] - lo[c]  # particle p is row p + shift of this block's window of fw
        sx = shift if copy else 0  # and row p + sx of xw (the rows of X itself when they are not copied)
        for p in range(lo[c], hi[c]):
            r = p + shift
            fw[r, 0] = 0.0
            fw[r, 1] = 0.0
            if three:
                fw[r, 2] = 0.0
            if copy:
                xw[r, 0] = X[p, 0, 0]
                xw[r, 1] = X[p, 0, 1]
                xw[r, dim] = X[p, 1, 0]
                xw[r, dim + 1] = X[p, 1, 1]
                if three:
                    xw[r, 2] = X[p, 0, 2]
                    xw[r, 5] = X[p, 1, 2]
        for u in range(rb0[c], rb0[c + 1]):
            rr, rx = rowp[u] + shift, rowp[u] + sx
            f0, f1, f2 = 0.0, 0.0, 0.0
            for e in range(rptr[u], rptr[u + 1]):
                ro, ox, q, s = other_end[e] + shift, other_end[e] + sx, which[e], sidx[e]
                if q == 0:
                    L0, k, kd = L0a[s], ka[s], kda[s]
                elif q == 1:
                    L0, k, kd = L0b[s], kb[s], kdb[s]
                else:
                    L0, k, kd = L0c[s], kc[s], kdc[s]
                d0 = xw[rx, 0] - xw[ox, 0]
                d1 = xw[rx, 1] - xw[ox, 1]
                d2 = xw[rx, 2] - xw[ox, 2] if three else 0.0
                L2 = d0 * d0 + d1 * d1 + d2 * d2
                inv_L = 1.0 / math.sqrt(L2) if L2 > 0.0 else 1e300  # 1 / max(L, 1e-300), as NumPy has it
                w = k * (L0 * inv_L - 1.0)
                dot = (xw[rx, dim] - xw[ox, dim]) * d0 + (xw[rx, dim + 1] - xw[ox, dim + 1]) * d1
                if three:
                    dot += (xw[rx, 5] - xw[ox, 5]) * d2
                w -= kd * dot * (inv_L * inv_L)  # with kd = 0, minus 0: the same w
                f0 += d0 * w
                f1 += d1 * w
                f2 += d2 * w
                fw[ro, 0] -= d0 * w
                fw[ro, 1] -= d1 * w
                if three:
                    fw[ro, 2] -= d2 * w
            fw[rr, 0] += f0
            fw[rr, 1] += f1
            if three:
                fw[rr, 2] += f2
        for p in range(start[c], start[c + 1]):  # the new state of the block's particles
            r, rx = p + shift, p + sx
            f0, f1 = fw[r, 0], fw[r, 1]
            f2 = fw[r, 2] if three else 0.0
            if has_other:
                f0 += other[p, 0]
                f1 += other[p, 1]
                if three:
                    f2 += other[p, 2]
            a0, a1, a2 = 0.0, 0.0, 0.0
            if free[p]:
                inv_m = 1.0 / m[p]
                a0 = f0 * inv_m + G[0]
                a1 = f1 * inv_m + G[1]
                if three:
                    a2 = f2 * inv_m + G[2]
            v0 = xw[rx, dim] + h * a0
            v1 = xw[rx, dim + 1] + h * a1
            out[p, 1, 0] = v0
            out[p, 1, 1] = v1
            out[p, 0, 0] = xw[rx, 0] + h * v0
            out[p, 0, 1] = xw[rx, 1] + h * v1
            if three:
                v2 = xw[rx, 5] + h * a2
                out[p, 1, 2] = v2
                out[p, 0, 2] = xw[rx, 2] + h * v2
