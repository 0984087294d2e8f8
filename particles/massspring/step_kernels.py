"""The compiled symplectic Euler step of a mass-spring system (numba): one parallel pass per step.

Imported only by :mod:`particles.massspring.compiled_step`. The NumPy step
makes about twenty passes over arrays of all the springs or all the
particles; this one makes one, over blocks of particles in parallel. Block
``c`` owns the particles ``start[c]:start[c + 1]`` and, with no other block,
computes their new state:

1. it reads the positions and velocities of the particles its springs
   touch, ``lo[c]:hi[c]`` (its *window*), from the rows ``xw[p] = (x_p, v_p)``
   of a C-ordered state, so that a spring reads each end from one cache line
   (a state in the system's Fortran order is copied to C order once, before
   the first step: one kernel for every state, not one per memory order, to
   compile);
2. :func:`_block_springs`: its springs, those whose lower end ``a = min(i, j)``
   is its own, summing the force on ``a`` in registers and adding the force
   on the other end into its rows ``fw`` (the other ends of a cloth's springs
   are at most two rows further); then the springs of earlier blocks that end
   in it, for the force on that end only (about one spring in twenty is
   computed twice, by the two blocks it joins);
3. :func:`_block_joints`: the bending joints (:class:`~particles.forces.Bending`)
   that touch its particles, adding each joint's forces on its three particles
   into ``fw`` (a joint across two blocks is computed by both);
4. :func:`_block_update`: its own particles: the forces of the particles alone
   (air damping, wind, uniform gravity) are added there, then velocity, then
   position.

Each step inlines the laws of the NumPy forces
(:func:`particles.forces.springs.damped_spring_force`,
:func:`particles.forces.springs.joint_factor`,
:func:`particles.forces.fields.gust_factor`). Each particle's force is summed
in an order fixed by the springs and joints alone, so the result has the same
bits on any number of threads; the number of blocks depends on the particle
count only. Indices are unsigned where that spares numba's test for negative
ones in the inner loops.
"""

import math

from ..backends.compile import inline, jit, prange
from ..forces.fields import gust_factor
from ..forces.kernels import spring_pull  # also makes joint_factor callable in kernels (its lazy form)
from ..forces.springs import joint_factor

__all__ = ["symplectic_euler_steps", "clamp_pass", "GUST", "PHASE", "WAVELENGTH", "PER_MASS"]

inline(gust_factor)

# columns of a row of the winds' table (see symplectic_euler_steps), after the 2 d of s and u
GUST, PHASE, WAVELENGTH, PER_MASS = 0, 1, 2, 3


def _larger(big, value):
    """``max(big, |value|)``, and inf when `value` is NaN (the divergence guard's size)."""
    a = abs(value)
    if a <= big:
        return big
    return a if a == a else math.inf


@jit(fastmath={"contract"})
def _block_springs(c, shift, xw, fw, rb0, rowp, rptr, other_end, which, sidx, L0a, ka, kda, L0b, kb, kdb, L0c,
                   kc, kdc, G):
    """Block c's spring rows: each row's force summed in registers, the other ends' into their rows of fw."""
    dim = len(G)  # G is a tuple: a constant, so that the third coordinate's code is left out in 2D
    three = dim == 3
    for u in range(rb0[c], rb0[c + 1]):
        rr, rx = rowp[u] + shift, rowp[u]
        f0, f1, f2 = 0.0, 0.0, 0.0
        for e in range(rptr[u], rptr[u + 1]):
            ro, ox, q, s = other_end[e] + shift, other_end[e], which[e], sidx[e]
            if q == 0:
                L0, k, kd = L0a[s], ka[s], kda[s]
            elif q == 1:
                L0, k, kd = L0b[s], kb[s], kdb[s]
            else:
                L0, k, kd = L0c[s], kc[s], kdc[s]
            g0, g1, g2 = spring_pull(xw, xw, rx, ox, dim, L0, k, kd, three)
            f0 += g0
            f1 += g1
            f2 += g2
            fw[ro, 0] -= g0
            fw[ro, 1] -= g1
            if three:
                fw[ro, 2] -= g2
        fw[rr, 0] += f0
        fw[rr, 1] += f1
        if three:
            fw[rr, 2] += f2


@jit(fastmath={"contract"})
def _block_joints(c, shift, xw, fw, jb0, joints, bi, bj, bl, bkb, btheta0, G):
    """The joints touching block c: each one's forces on its three particles into their rows of fw."""
    three = len(G) == 3  # G is a tuple: a constant
    for e in range(jb0[c], jb0[c + 1]):  # e1 = x_j - x_i, e2 = x_l - x_j
        t = joints[e]
        ri, rj, rl = bi[t], bj[t], bl[t]
        a0, a1 = xw[rj, 0] - xw[ri, 0], xw[rj, 1] - xw[ri, 1]
        b0, b1 = xw[rl, 0] - xw[rj, 0], xw[rl, 1] - xw[rj, 1]
        a2 = xw[rj, 2] - xw[ri, 2] if three else 0.0
        b2 = xw[rl, 2] - xw[rj, 2] if three else 0.0
        L1 = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        L2 = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
        inv1 = 1.0 / L1 if L1 != 0.0 else 0.0
        inv2 = 1.0 / L2 if L2 != 0.0 else 0.0
        a0, a1, a2 = a0 * inv1, a1 * inv1, a2 * inv1
        b0, b1, b2 = b0 * inv2, b1 * inv2, b2 * inv2
        cos = min(max(a0 * b0 + a1 * b1 + a2 * b2, -1.0), 1.0)
        factor = joint_factor(cos, btheta0[t], bkb[t])
        s1, s2 = factor * inv1, factor * inv2
        g10, g11, g12 = (b0 - cos * a0) * s1, (b1 - cos * a1) * s1, (b2 - cos * a2) * s1
        g20, g21, g22 = (a0 - cos * b0) * s2, (a1 - cos * b1) * s2, (a2 - cos * b2) * s2
        fi, fj, fl = ri + shift, rj + shift, rl + shift
        fw[fi, 0] -= g10
        fw[fi, 1] -= g11
        fw[fj, 0] += g10 - g20
        fw[fj, 1] += g11 - g21
        fw[fl, 0] += g20
        fw[fl, 1] += g21
        if three:
            fw[fi, 2] -= g12
            fw[fj, 2] += g12 - g22
            fw[fl, 2] += g22


@jit(fastmath={"contract"})
def _block_update(c, start, shift, xw, fw, D, R, W, other, has_other, m, free, G, h, out):
    """Block c's particles: their forces completed (damping, wind, others), then v + h a, x + h v; max |entry|."""
    dim = len(G)  # G is a tuple: a constant, so that the third coordinate's code is left out in 2D
    three = dim == 3
    damped = D != 0.0 or R != 0.0
    big = 0.0
    for p in range(start[c], start[c + 1]):
        r = p + shift
        f0, f1 = fw[r, 0], fw[r, 1]
        f2 = fw[r, 2] if three else 0.0
        if has_other:
            f0 += other[p, 0]
            f1 += other[p, 1]
            if three:
                f2 += other[p, 2]
        if damped:  # -(d + rate m) v
            beta = D + R * m[p]
            f0 -= beta * xw[p, dim]
            f1 -= beta * xw[p, dim + 1]
            if three:
                f2 -= beta * xw[p, 5]
        for q in range(len(W)):  # a loop over the few winds
            scale = 1.0
            if W[q, 2 * dim + GUST] != 0.0:
                along = xw[p, 0] * W[q, dim] + xw[p, 1] * W[q, dim + 1]
                if three:
                    along += xw[p, 2] * W[q, dim + 2]
                scale = gust_factor(W[q, 2 * dim + PHASE], along, W[q, 2 * dim + GUST], W[q, 2 * dim + WAVELENGTH])
            if W[q, 2 * dim + PER_MASS] != 0.0:
                scale *= m[p]
            f0 += W[q, 0] * scale
            f1 += W[q, 1] * scale
            if three:
                f2 += W[q, 2] * scale
        a0, a1, a2 = 0.0, 0.0, 0.0
        if free[p]:
            inv_m = 1.0 / m[p]
            a0 = f0 * inv_m + G[0]
            a1 = f1 * inv_m + G[1]
            if three:
                a2 = f2 * inv_m + G[2]
        v0 = xw[p, dim] + h * a0
        v1 = xw[p, dim + 1] + h * a1
        x0 = xw[p, 0] + h * v0
        x1 = xw[p, 1] + h * v1
        out[p, 1, 0] = v0
        out[p, 1, 1] = v1
        out[p, 0, 0] = x0
        out[p, 0, 1] = x1
        big = _larger(_larger(_larger(_larger(big, x0), x1), v0), v1)
        if three:
            v2 = xw[p, 5] + h * a2
            x2 = xw[p, 2] + h * v2
            out[p, 1, 2] = v2
            out[p, 0, 2] = x2
            big = _larger(_larger(big, x2), v2)
    return big


inline(_larger, into="never")  # a branch: its own function (LLVM inlines it); numba warns on such IR inlining


@jit(parallel=True, fastmath={"contract"})  # fused multiply-adds: rounding differs from NumPy's by ~1e-16
def symplectic_euler_steps(start, lo, hi, row0, xw, fw, rb0, rowp, rptr, other_end, which, sidx,
                           L0a, ka, kda, L0b, kb, kdb, L0c, kc, kdc, jb0, joints, bi, bj, bl, bkb, btheta0,
                           D, R, W, other, has_other, m, free, G, hs, limit, out0, out1, sizes):
    """Steps for up to three spring sets and one bending set: ``v + h a``, then ``x + h v_new``.

    ``a = F / m + G`` (0 where `free` is False): ``F`` the springs' and joints' force, plus
    ``other[p]`` when `has_other` (forces computed before), minus ``(D + R m_p) v_p`` (air
    damping: ``D`` the sum of the coefficients in kg/s, ``R`` of the rates in 1/s), plus each
    wind of the step's table ``W[s]`` (rows ``s, u, gust, t / period, wavelength, per_mass``: ``s``
    times the gusts' factor, times ``m_p`` when per_mass); ``G`` the sum of the uniform gravities.
    Row p of ``xw`` (n, 2 d) is particle p's ``(x_p, v_p)`` in the first state; block c's rows of
    ``fw`` are ``row0[c]:row0[c + 1]``, for the particles ``lo[c]:hi[c]``; its spring rows are
    ``rb0[c]:rb0[c + 1]``: row u is particle ``rowp[u]`` and its entries ``rptr[u]:rptr[u + 1]``;
    its joints are ``joints[jb0[c]:jb0[c + 1]]``, joint t joining ``bi[t], bj[t], bl[t]``.

    Entry e joins its row's particle r to ``other_end[e]``, o; it is spring ``sidx[e]`` of set
    ``which[e]`` (0, 1, 2: the arrays ``L0a, ka, kda``, then ``b``, then ``c``), read where the
    set keeps it, so a stiffness changed in place is seen at the next step.

    Steps: ``len(hs)`` steps from the state ``xw``, step s of ``hs[s]`` seconds with the winds' table ``W[s]``;
    step s writes its state into `out0` (s even) or `out1` (s odd) and the next one reads it there
    (its rows in place: C order). After each step, the largest ``|entry|`` of the new state
    (positions and velocities, inf when one is NaN) is compared with `limit`: the steps stop
    after the first one whose state is larger or not finite (the divergence guard of
    :func:`particles.integrators.integrate`). `sizes` holds one float per block.

    Returns ``(taken, size)``: the steps whose state passed, and the size of the last state computed.
    """
    n, dim = out0.shape[0], len(G)  # G is a tuple: numba compiles a kernel for each length, with dim a constant
    size = 0.0
    for s in range(len(hs)):  # a loop over the steps: each one a parallel pass over the blocks
        dst = out0 if s % 2 == 0 else out1
        rows = xw  # the first step reads the state given; the others the state before, in place
        if s > 0:
            rows = (out1 if s % 2 == 0 else out0).reshape((n, 2 * dim))
        Ws, h = W[s], hs[s]
        for c in prange(len(start) - 1):
            shift = row0[c] - lo[c]  # particle p is row p + shift of this block's window of fw
            for p in range(lo[c], hi[c]):
                for a in range(dim):
                    fw[p + shift, a] = 0.0
            _block_springs(c, shift, rows, fw, rb0, rowp, rptr, other_end, which, sidx, L0a, ka, kda, L0b, kb, kdb,
                           L0c, kc, kdc, G)
            _block_joints(c, shift, rows, fw, jb0, joints, bi, bj, bl, bkb, btheta0, G)
            sizes[c] = _block_update(c, start, shift, rows, fw, D, R, Ws, other, has_other, m, free, G, h, dst)
        size = 0.0
        for c in range(len(sizes)):  # a loop over the blocks, in order
            size = _larger(size, sizes[c])
        if not size <= limit or size == math.inf:
            return s, size
    return len(hs), size


@jit()
def clamp_pass(F, x, i, j, u0, kb):
    """``F_j += g``, ``F_i -= g`` for each clamp (one thread; a hair has one): :func:`~particles.forces.springs.clamp_forces`.

    ``g = joint_factor(cos theta, 0, kb) (u0 - cos(theta) e_hat) / |e|`` with ``e = x_j - x_i``.
    """
    dim = F.shape[1]
    e = [0.0, 0.0, 0.0]
    for t in range(len(i)):
        L2 = 0.0
        for a in range(dim):
            e[a] = x[j[t], a] - x[i[t], a]
            L2 += e[a] * e[a]
        L = math.sqrt(L2)
        cos = 0.0
        for a in range(dim):
            if L != 0.0:
                e[a] /= L
            cos += e[a] * u0[t, a]
        cos = min(max(cos, -1.0), 1.0)
        s = joint_factor(cos, 0.0, kb[t]) / L if L > 0.0 else 0.0
        for a in range(dim):
            g = (u0[t, a] - cos * e[a]) * s
            F[j[t], a] += g
            F[i[t], a] -= g
