"""The compiled XPBD projections (numba): the arithmetic of Distance.project and of the linear sets' project.

Imported only by :mod:`particles.backends.compiled` (one colour group or one
Jacobi pass per call) and :mod:`particles.backends.xpbdstep` (a whole substep
per call: :func:`substep`). Positions are coordinate-major, shape (d, n), as
the solvers of :mod:`particles.xpbd` hold them. Each projection does the
NumPy code's operations in the same order (no fused multiply-adds), so the
two give the same bits.
"""

import math

from ._kernels import _jit, prange


@_jit(parallel=True)
def distance_group(x, x_n, lam, rows, i, j, L0, wi, wj, at, inv, gamma, xpbd, damped):
    """One colour group of distance constraints (no shared particle): project each, in place on x (d, n)."""
    three = x.shape[0] == 3
    for r in prange(len(i)):
        a, b = i[r], j[r]
        d0 = x[0, a] - x[0, b]
        d1 = x[1, a] - x[1, b]
        d2 = x[2, a] - x[2, b] if three else 0.0
        L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        Lg = max(L, 1e-150)
        lr = lam[rows[r]]
        if xpbd and not damped:
            dl = (L0[r] - L - at[r] * lr) * inv[r]
        elif xpbd:
            rel = d0 * (d0 - (x_n[0, a] - x_n[0, b])) + d1 * (d1 - (x_n[1, a] - x_n[1, b]))
            if three:
                rel += d2 * (d2 - (x_n[2, a] - x_n[2, b]))
            dl = (-(L - L0[r]) - at[r] * lr - gamma[r] * (rel / Lg)) * inv[r]
        else:
            dl = -(L - L0[r]) * inv[r]
        if xpbd:
            lam[rows[r]] = lr + dl
        scale = dl / Lg
        d0 *= scale
        d1 *= scale
        x[0, a] += wi[r] * d0
        x[0, b] -= wj[r] * d0
        x[1, a] += wi[r] * d1
        x[1, b] -= wj[r] * d1
        if three:
            d2 *= scale
            x[2, a] += wi[r] * d2
            x[2, b] -= wj[r] * d2


@_jit()
def distance_jacobi(x, x_n, lam, i, j, L0, wi, wj, at, inv, gamma, scale, xpbd, damped, si, sj):
    """All distance constraints from the same positions, corrections summed per particle (in order), then added."""
    dim = x.shape[0]
    si[:] = 0.0
    sj[:] = 0.0
    for r in range(len(i)):
        a, b = i[r], j[r]
        L2 = 0.0
        for c in range(dim):
            L2 += (x[c, a] - x[c, b]) * (x[c, a] - x[c, b])
        L = math.sqrt(L2)
        Lg = max(L, 1e-150)
        if xpbd:
            res = -(L - L0[r]) - at[r] * lam[r]
            if damped:
                rel = 0.0
                for c in range(dim):
                    dc = x[c, a] - x[c, b]
                    rel += dc * (dc - (x_n[c, a] - x_n[c, b]))
                res -= gamma[r] * (rel / Lg)
            dl = res * inv[r] * scale[r]
            lam[r] += dl
        else:
            dl = -(L - L0[r]) * inv[r] * scale[r]
        for c in range(dim):
            dc = (x[c, a] - x[c, b]) * (dl / Lg)
            si[c, a] += wi[r] * dc
            sj[c, b] += wj[r] * dc
    for c in range(dim):
        for p in range(x.shape[1]):
            x[c, p] += si[c, p] - sj[c, p]


@_jit(parallel=True)
def substep(x, v, x_n, a, given, G, m, free, hs, iterations, xpbd, segments,
            i, j, L0, wi, wj, d_at, d_inv, d_gamma, d_lam,
            idx, c, wc, offset, l_at, l_inv, l_gamma, l_lam):
    """One XPBD substep of length hs in one call, in place on x, v (d, n); x_n receives the predicted-from x.

    Prediction ``v += hs a``, ``x_n = x``, ``x += hs v`` (``a``: the given
    accelerations, else ``sum_q G_q m / m``, 0 at pinned particles), the
    multipliers set to zero, ``iterations`` sweeps through the ``segments``
    (rows ``(form, start, stop, width, damped)``: form 0 distance rows
    ``start:stop``, form 1 linear rows; each segment one colour group, its
    rows in parallel), then ``v = (x - x_n) / hs``.
    """
    dim, n = x.shape
    three = dim == 3
    for e in range(dim):  # coordinate after coordinate: each a contiguous row of (d, n)
        for p in prange(n):
            if given:
                acc = a[e, p]
            else:
                F = 0.0
                for q in range(G.shape[0]):
                    F += G[q, e] * m[p]
                acc = F / m[p] if free[p] else 0.0
            v[e, p] += hs * acc
            x_n[e, p] = x[e, p]
            x[e, p] += hs * v[e, p]
    for r in prange(len(d_lam)):
        d_lam[r] = 0.0
    for r in prange(l_lam.shape[1]):
        for e in range(l_lam.shape[0]):
            l_lam[e, r] = 0.0
    for _ in range(iterations):
        for s in range(len(segments)):  # colour after colour: the Gauss-Seidel order
            form, start, stop, width, damped = segments[s, 0], segments[s, 1], segments[s, 2], segments[s, 3], \
                segments[s, 4] != 0
            if form == 0:  # distance rows: the arithmetic of distance_group
                for r in prange(start, stop):
                    a, b = i[r], j[r]
                    d0 = x[0, a] - x[0, b]
                    d1 = x[1, a] - x[1, b]
                    d2 = x[2, a] - x[2, b] if three else 0.0
                    L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                    Lg = max(L, 1e-150)
                    lr = d_lam[r]
                    if xpbd and not damped:
                        dl = (L0[r] - L - d_at[r] * lr) * d_inv[r]
                    elif xpbd:
                        rel = d0 * (d0 - (x_n[0, a] - x_n[0, b])) + d1 * (d1 - (x_n[1, a] - x_n[1, b]))
                        if three:
                            rel += d2 * (d2 - (x_n[2, a] - x_n[2, b]))
                        dl = (-(L - L0[r]) - d_at[r] * lr - d_gamma[r] * (rel / Lg)) * d_inv[r]
                    else:
                        dl = -(L - L0[r]) * d_inv[r]
                    if xpbd:
                        d_lam[r] = lr + dl
                    scale = dl / Lg
                    d0 *= scale
                    d1 *= scale
                    x[0, a] += wi[r] * d0
                    x[0, b] -= wj[r] * d0
                    x[1, a] += wi[r] * d1
                    x[1, b] -= wj[r] * d1
                    if three:
                        d2 *= scale
                        x[2, a] += wi[r] * d2
                        x[2, b] -= wj[r] * d2
            else:  # linear rows, C = sum_k c_k x_{idx_k} - offset, each coordinate on its own
                for r in prange(start, stop):
                    for e in range(dim):
                        C = 0.0
                        for k in range(width):
                            C += c[r, k] * x[e, idx[r, k]]
                        C -= offset[r, e]
                        lr = l_lam[e, r]
                        if xpbd:
                            res = -C - l_at[r] * lr
                            if damped:
                                Cn = 0.0
                                for k in range(width):
                                    Cn += c[r, k] * x_n[e, idx[r, k]]
                                res -= l_gamma[r] * (C + offset[r, e] - Cn)  # gamma (C(x) - C(x_n))
                            dl = res * l_inv[r]
                            l_lam[e, r] = lr + dl
                        else:
                            dl = -C * l_inv[r]
                        for k in range(width):
                            x[e, idx[r, k]] += wc[r, k] * dl
    for e in range(dim):
        for p in prange(n):
            v[e, p] = (x[e, p] - x_n[e, p]) / hs


@_jit(parallel=True)
def distance_violation(x, i, j, L0, out):
    """``|C| = ||x_i - x_j| - L0|`` of every distance constraint into out (s,)."""
    three = x.shape[0] == 3
    for r in prange(len(i)):
        a, b = i[r], j[r]
        d0 = x[0, a] - x[0, b]
        d1 = x[1, a] - x[1, b]
        d2 = x[2, a] - x[2, b] if three else 0.0
        out[r] = abs(math.sqrt(d0 * d0 + d1 * d1 + d2 * d2) - L0[r])
