"""The compiled XPBD projections (numba): distance constraints, the arithmetic of Distance.project.

Imported only by :mod:`particles.backends.compiled`. Positions are coordinate-major, shape (d, n),
as the solvers of :mod:`particles.xpbd` hold them.
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
