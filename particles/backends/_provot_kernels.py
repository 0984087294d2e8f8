"""Provot's deformation constraint, compiled (numba): the whole projection of a step in one call.

Imported only by :mod:`particles.backends.fixes`. The arithmetic of
:func:`particles.constraints.provot_projection`, in its order: each pass
measures every spring's strain (the largest, over springs with a free end,
decides whether to stop), then shortens the springs longer than ``(1 + s)
L0``. Jacobi (:func:`provot_jacobi`): all at once, each particle moving by
the mean of its springs' corrections, summed per particle through the
incidence list in increasing spring order, as ``np.bincount`` sums them;
Gauss-Seidel (:func:`provot_gauss_seidel`): one colour group after the
other, each group's springs (no particle twice) in parallel. At the end the
velocities take the displacement over the step, ``v += (x - x_start) / h``.
Every sum runs in an order set by the springs alone: the same bits on any
number of threads (the largest strain is a maximum, exact in any order).
"""

import math

from ._kernels import _jit, prange


@_jit(parallel=True)
def provot_start(X, x0):
    """``x0 = X[:, 0]``: the positions before the projection."""
    for p in prange(X.shape[0]):
        for a in range(X.shape[2]):
            x0[p, a] = X[p, 0, a]


@_jit(parallel=True)
def provot_end(X, x0, h):
    """``v += (x - x0) / h``: the velocity is still the displacement over the step."""
    for p in prange(X.shape[0]):
        for a in range(X.shape[2]):
            X[p, 1, a] += (X[p, 0, a] - x0[p, a]) / h


@_jit(parallel=True)
def provot_strains(X, i, j, L0, movable, limit, bworst, c, too):
    """Largest strain ``L / L0 - 1`` over the movable springs, per block of springs into bworst (0 if none).

    With `c` (s, d) given (Jacobi), also each spring's correction ``(L - limit L0) u`` where it is
    too long (``too``), ``u = (x_i - x_j) / L``.
    """
    s, dim, blocks = len(i), X.shape[2], len(bworst)
    keep = c.shape[0] == s
    for b in prange(blocks):
        worst = 0.0
        for q in range(b * s // blocks, (b + 1) * s // blocks):
            d0 = X[i[q], 0, 0] - X[j[q], 0, 0]
            d1 = X[i[q], 0, 1] - X[j[q], 0, 1]
            d2 = X[i[q], 0, 2] - X[j[q], 0, 2] if dim == 3 else 0.0
            L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            if movable[q]:
                worst = max(worst, L / L0[q] - 1.0)
            if keep:
                too[q] = movable[q] and L > limit * L0[q]
                if too[q]:
                    excess = L - limit * L0[q]
                    c[q, 0] = excess * (d0 / L)
                    c[q, 1] = excess * (d1 / L)
                    if dim == 3:
                        c[q, 2] = excess * (d2 / L)
        bworst[b] = worst


@_jit()
def largest(bworst):
    """The largest of the blocks' strains."""
    worst = 0.0
    for b in range(len(bworst)):
        worst = max(worst, bworst[b])
    return worst


@_jit(parallel=True)
def provot_average(X, c, too, wi, wj, free, ptr, col):
    """One Jacobi correction: ``x_p += (sum_j wj c - sum_i wi c) / max(count_p, 1)`` over the too long springs."""
    s, dim = len(too), X.shape[2]
    for p in prange(len(ptr) - 1):
        count = 0
        i0, i1, i2, j0, j1, j2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        for e in range(ptr[p], ptr[p + 1]):
            q = col[e]
            if q < s:  # p is the spring's first end
                if too[q]:
                    count += 1
                    i0 += wi[q] * c[q, 0]
                    i1 += wi[q] * c[q, 1]
                    if dim == 3:
                        i2 += wi[q] * c[q, 2]
            elif too[q - s]:
                q -= s
                count += 1
                j0 += wj[q] * c[q, 0]
                j1 += wj[q] * c[q, 1]
                if dim == 3:
                    j2 += wj[q] * c[q, 2]
        if count and free[p]:
            scale = 1.0 / count
            X[p, 0, 0] += scale * (j0 - i0)
            X[p, 0, 1] += scale * (j1 - i1)
            if dim == 3:
                X[p, 0, 2] += scale * (j2 - i2)


@_jit(parallel=True)
def provot_group(X, springs, i, j, L0, wi, wj, movable, limit):
    """One colour group's correction: each too long spring moves its ends (no particle is in two springs)."""
    dim = X.shape[2]
    for e in prange(len(springs)):
        q = springs[e]
        if not movable[q]:
            continue
        d0 = X[i[q], 0, 0] - X[j[q], 0, 0]
        d1 = X[i[q], 0, 1] - X[j[q], 0, 1]
        d2 = X[i[q], 0, 2] - X[j[q], 0, 2] if dim == 3 else 0.0
        L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if L > limit * L0[q]:
            excess = L - limit * L0[q]
            c0, c1, c2 = excess * (d0 / L), excess * (d1 / L), excess * (d2 / L)
            X[i[q], 0, 0] -= wi[q] * c0
            X[i[q], 0, 1] -= wi[q] * c1
            X[j[q], 0, 0] += wj[q] * c0
            X[j[q], 0, 1] += wj[q] * c1
            if dim == 3:
                X[i[q], 0, 2] -= wi[q] * c2
                X[j[q], 0, 2] += wj[q] * c2
