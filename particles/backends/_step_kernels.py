"""The compiled symplectic Euler step of a mass-spring system (numba): one parallel pass per step.

Imported only by :mod:`particles.backends.compiled`. The NumPy step makes
about twenty passes over arrays of all the springs or all the particles;
this one makes one, over blocks of particles in parallel. Block ``c`` owns
the particles ``start[c]:start[c + 1]`` and, with no other block, computes
their new state:

1. it reads the positions and velocities of the particles its springs
   touch, ``lo[c]:hi[c]`` (its *window*), from the rows ``xw[p] = (x_p, v_p)``
   of a C-ordered state, so that a spring reads each end from one cache line
   (a state in the system's Fortran order is copied to C order once, before
   the first step, by :mod:`particles.backends.compiled`: one kernel for
   every state, not one per memory order, to compile);
2. it computes its springs, those whose lower end ``a = min(i, j)`` is its
   own, summing the force on ``a`` in registers and adding the force on the
   other end into its rows ``fw`` (the other ends of a cloth's springs are at
   most two rows further); then the springs of earlier blocks that end in
   it, for the force on that end only (about one spring in twenty is
   computed twice, by the two blocks it joins);
3. it computes the bending joints (:class:`~particles.springs.Bending`) that
   touch its particles, adding each joint's forces on its three particles
   into ``fw`` (a joint across two blocks is computed by both); for a joint
   straight at rest and bent by less than 29 degrees, ``theta / sin(theta)``
   comes from its series in ``1 - cos(theta)`` (no ``acos``, no ``sin``, and
   closer to the exact value than NumPy's quotient, which loses digits to
   cancellation below a few degrees: 1e-9 at 1e-4 rad);
4. it updates its own particles: the forces of the particles alone (air
   damping, wind, uniform gravity) are added there, then velocity, then
   position.

The springs are listed by lower end in compressed rows (``ptr``; ``nbr``
the other ends, ``which`` and ``sidx`` the set and the spring), the springs
entering each block in another list (``inptr``, ``ina`` their lower ends,
``ine`` their entries), the joints of each block in a third. Each
particle's force is summed in an order fixed by the springs and joints
alone, so the result has the same bits on any number of threads; the number
of blocks depends on the particle count only. Indices are unsigned where
that spares numba's test for negative ones in the inner loops.
"""

import math

from ._kernels import _jit, prange

# columns of a row of the winds' table (see symplectic_euler_steps), after the 2 d of s and u
GUST, PHASE, WAVELENGTH, PER_MASS = 0, 1, 2, 3

# theta / sin(theta) = acos(c) / sqrt(1 - c^2) = sum_n a_n (1 - c)^n, a_n = (n!)^2 2^n / (2n + 1)!, for a
# joint bent by less than 29 degrees (1 - c < 1/8: the terms left out are below 1e-20); a_{n+1} = a_n (n + 1) / (2n + 3)
SERIES_MAX = 0.125
RATIO_SERIES = (1.0, 1 / 3, 2 / 15, 2 / 35, 8 / 315, 8 / 693, 16 / 3003, 16 / 6435, 128 / 109395, 128 / 230945,
                256 / 969969, 256 / 2028117, 1024 / 16900975, 1024 / 35102025, 2048 / 145422675, 2048 / 300540195,
                32768 / 9917826435)


@_jit()
def _larger(big, value):
    """``max(big, |value|)``, and inf when `value` is NaN (the divergence guard's size)."""
    a = abs(value)
    if a <= big:
        return big
    return a if a == a else math.inf


@_jit(fastmath={"contract"})  # fused multiply-adds: rounding differs from NumPy's by ~1e-16
def _block(c, start, lo, hi, row0, xw, fw, rb0, rowp, rptr, other_end, which, sidx, L0a, ka, kda, L0b, kb,
           kdb, L0c, kc, kdc, jb0, joints, bi, bj, bl, bkb, btheta0, D, R, W, other, has_other, m, free, G, h, out):
    """Block c's part of a step (see :func:`symplectic_euler_steps`): the new states of its particles, into out.

    Returns the largest ``|entry|`` of those states, positions and velocities (inf when one is NaN).
    """
    dim = len(G)  # G is a tuple: numba compiles a kernel for each length, with dim a constant
    three = dim == 3
    damped = D != 0.0 or R != 0.0
    big = 0.0  # the largest |entry| of the block's new states
    shift = row0[c] - lo[c]  # particle p is row p + shift of this block's window of fw
    for p in range(lo[c], hi[c]):
        r = p + shift
        fw[r, 0] = 0.0
        fw[r, 1] = 0.0
        if three:
            fw[r, 2] = 0.0
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
            d0 = xw[rx, 0] - xw[ox, 0]
            d1 = xw[rx, 1] - xw[ox, 1]
            d2 = xw[rx, 2] - xw[ox, 2] if three else 0.0
            L2 = d0 * d0 + d1 * d1 + d2 * d2
            inv_L = 1.0 / math.sqrt(L2) if L2 > 0.0 else 1e300  # 1 / max(L, 1e-300), as NumPy has it
            w = k * (L0 * inv_L - 1.0)
            if kd != 0.0:  # with kd = 0 NumPy subtracts 0: the same w
                dot = (xw[rx, dim] - xw[ox, dim]) * d0 + (xw[rx, dim + 1] - xw[ox, dim + 1]) * d1
                if three:
                    dot += (xw[rx, 5] - xw[ox, 5]) * d2
                w -= kd * dot * (inv_L * inv_L)
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
    for e in range(jb0[c], jb0[c + 1]):  # the joints touching the block: e1 = x_j - x_i, e2 = x_l - x_j
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
        x = 1.0 - cos
        if x < SERIES_MAX and btheta0[t] == 0.0:  # theta / sin(theta) by its series: no acos, no sin
            ratio = RATIO_SERIES[16]
            for k in range(15, -1, -1):
                ratio = RATIO_SERIES[k] + x * ratio
        else:
            sin = math.sqrt(max(1.0 - cos * cos, 0.0))
            ratio = (math.acos(cos) - btheta0[t]) / sin if sin > 1e-8 else 1.0
        scale = bkb[t] * ratio
        s1, s2 = scale * inv1, scale * inv2
        g10, g11, g12 = (b0 - cos * a0) * s1, (b1 - cos * a1) * s1, (b2 - cos * a2) * s1
        g20, g21, g22 = (a0 - cos * b0) * s2, (a1 - cos * b1) * s2, (a2 - cos * b2) * s2
        fi, fj, fl = bi[t] + shift, bj[t] + shift, bl[t] + shift
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
    for p in range(start[c], start[c + 1]):  # the new state of the block's particles
        r, rx = p + shift, p
        f0, f1 = fw[r, 0], fw[r, 1]
        f2 = fw[r, 2] if three else 0.0
        if has_other:
            f0 += other[p, 0]
            f1 += other[p, 1]
            if three:
                f2 += other[p, 2]
        if damped:  # -(d + rate m) v
            beta = D + R * m[p]
            f0 -= beta * xw[rx, dim]
            f1 -= beta * xw[rx, dim + 1]
            if three:
                f2 -= beta * xw[rx, 5]
        for q in range(len(W)):  # a loop over the few winds
            scale = 1.0
            if W[q, 2 * dim + GUST] != 0.0:
                along = xw[rx, 0] * W[q, dim] + xw[rx, 1] * W[q, dim + 1]
                if three:
                    along += xw[rx, 2] * W[q, dim + 2]
                phase = W[q, 2 * dim + PHASE] - along / W[q, 2 * dim + WAVELENGTH]
                scale += W[q, 2 * dim + GUST] * math.sin(2.0 * math.pi * phase)
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
        v0 = xw[rx, dim] + h * a0
        v1 = xw[rx, dim + 1] + h * a1
        x0 = xw[rx, 0] + h * v0
        x1 = xw[rx, 1] + h * v1
        out[p, 1, 0] = v0
        out[p, 1, 1] = v1
        out[p, 0, 0] = x0
        out[p, 0, 1] = x1
        big = _larger(_larger(_larger(_larger(big, x0), x1), v0), v1)
        if three:
            v2 = xw[rx, 5] + h * a2
            x2 = xw[rx, 2] + h * v2
            out[p, 1, 2] = v2
            out[p, 0, 2] = x2
            big = _larger(_larger(big, x2), v2)
    return big


@_jit(parallel=True, fastmath={"contract"})
def symplectic_euler_steps(start, lo, hi, row0, xw, fw, rb0, rowp, rptr, other_end, which, sidx,
                           L0a, ka, kda, L0b, kb, kdb, L0c, kc, kdc, jb0, joints, bi, bj, bl, bkb, btheta0,
                           D, R, W, other, has_other, m, free, G, hs, limit, out0, out1, sizes):
    """Steps for up to three spring sets and one bending set: ``v + h a``, then ``x + h v_new``.

    ``a = F / m + G`` (0 where `free` is False): ``F`` the springs' and joints' force, plus
    ``other[p]`` when `has_other` (forces computed before), minus ``(D + R m_p) v_p`` (air
    damping: ``D`` the sum of the coefficients in kg/s, ``R`` of the rates in 1/s), plus each
    wind of the step's table ``W[s]`` (rows ``s, u, gust, t / period, wavelength, per_mass``: ``s (1 + gust
    sin(2 pi (t / period - (x . u) / wavelength)))``, times ``m_p`` when per_mass); ``G`` the
    sum of the uniform gravities. Row p of ``xw`` (n, 2 d) is particle p's ``(x_p, v_p)`` in the
    first state; block c's rows of ``fw`` are ``row0[c]:row0[c + 1]``, for the particles
    ``lo[c]:hi[c]``; its spring rows are ``rb0[c]:rb0[c + 1]``: row u is
    particle ``rowp[u]`` and its entries ``rptr[u]:rptr[u + 1]``; its joints are
    ``joints[jb0[c]:jb0[c + 1]]``, joint t joining ``bi[t], bj[t], bl[t]``.

    Entry e joins its row's particle r to ``other_end[e]``, o; it is spring ``sidx[e]`` of set
    ``which[e]`` (0, 1, 2: the arrays ``L0a, ka, kda``, then ``b``, then ``c``), read where the
    set keeps it, so a stiffness changed in place is seen at the next step. Its force on r is
    ``d k (L0/L - 1) - d kd ((v_r - v_o).d) / L^2`` with ``d = x_r - x_o`` (the arithmetic of
    :meth:`particles.springs.Springs.add_to`), summed in registers, and minus that on o. A
    joint's forces are those of :meth:`particles.springs.Bending.add_to`.

    Steps: ``len(hs)`` steps from the state ``xw``, step s of ``hs[s]`` seconds with the winds' table ``W[s]``;
    step s writes its state into `out0` (s even) or `out1` (s odd) and the next one reads it there
    (its rows in place: C order). After each step, the largest ``|entry|`` of the new state
    (positions and velocities, inf when one is NaN) is compared with `limit`: the steps stop
    after the first one whose state is larger or not finite (the divergence guard of
    :func:`particles.integrators.integrate`). `sizes` holds one float per block.

    Returns ``(taken, size)``: the steps whose state passed, and the size of the last state computed.
    """
    n, dim = out0.shape[0], len(G)
    size = 0.0
    for s in range(len(hs)):  # a loop over the steps: each one a parallel pass over the blocks
        dst = out0 if s % 2 == 0 else out1
        rows = xw  # the first step reads the state given; the others the state before, in place
        if s > 0:
            rows = (out1 if s % 2 == 0 else out0).reshape((n, 2 * dim))
        Ws, h = W[s], hs[s]
        for c in prange(len(start) - 1):
            sizes[c] = _block(c, start, lo, hi, row0, rows, fw, rb0, rowp, rptr, other_end, which, sidx,
                              L0a, ka, kda, L0b, kb, kdb, L0c, kc, kdc, jb0, joints, bi, bj, bl, bkb, btheta0,
                              D, R, Ws, other, has_other, m, free, G, h, dst)
        size = 0.0
        for c in range(len(sizes)):  # a loop over the blocks, in order
            size = _larger(size, sizes[c])
        if not size <= limit or size == math.inf:
            return s, size
    return len(hs), size


@_jit()
def clamp_forces(F, x, i, j, u0, kb):
    """``F_j += g``, ``F_i -= g`` for each clamp, as :meth:`particles.springs.Clamp.add_to` computes g (one thread).

    ``g = kb (theta / sin theta) (u0 - cos(theta) e_hat) / |e|`` with ``e = x_j - x_i``; ``theta /
    sin theta`` is 1 below ``sin theta = 1e-8``. A hair has one clamp: no threads.
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
        sin = math.sqrt(max(1.0 - cos * cos, 0.0))
        ratio = math.acos(cos) / sin if sin > 1e-8 else 1.0
        s = kb[t] * ratio / L if L > 0.0 else 0.0
        for a in range(dim):
            g = (u0[t, a] - cos * e[a]) * s
            F[j[t], a] += g
            F[i[t], a] -= g
