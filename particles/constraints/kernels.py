"""Provot's projection, compiled (numba): every pass of a step's projection in one call, in place.

:class:`particles.constraints.ProvotConstraint` uses :class:`CompiledProjection` when its backend
resolves to numba; importing this module imports numba. The loop inlines the formula of the NumPy passes
(:func:`particles.constraints.provot.provot_excess`) and does their arithmetic in their order: each pass
measures every spring's strain (the largest, over springs with a free end, decides whether to stop), then
shortens the springs longer than ``(1 + s) L0``. Jacobi: all at once, each particle moving by the mean of
its springs' corrections, summed per particle through the incidence list in increasing spring order, as
``np.bincount`` sums them; Gauss-Seidel: one colour group after the other, each group's springs (no
particle twice) in parallel. At the end the velocities take the displacement over the step,
``v += (x - x_start) / h``. Every sum runs in an order set by the springs alone: the same bits on any
number of threads (the largest strain is a maximum, exact in any order).
"""

import math

import numpy as np

from ..backends.compile import inline, jit, pick, prange
from ..backends.layout import c_ordered, incidence
from .provot import ROUNDING, end_shares, provot_excess

__all__ = ["CompiledProjection", "provot_passes"]

inline(provot_excess)

STRAIN_BLOCKS = 64  # blocks of springs whose largest strains are taken in parallel (a maximum: any order)


def _length(X, a, b, dim):
    """``x_a - x_b`` (three components, the third 0 in 2D) and its length."""
    d0 = X[a, 0, 0] - X[b, 0, 0]
    d1 = X[a, 0, 1] - X[b, 0, 1]
    d2 = X[a, 0, 2] - X[b, 0, 2] if dim == 3 else 0.0
    return d0, d1, d2, math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)


def _block_strains(b, blocks, X, i, j, L0, movable, max_strain, jacobi, c, too):
    """The largest strain of block b of the springs; with `jacobi`, each of its springs' correction into c."""
    s, dim = len(i), X.shape[2]
    worst = 0.0
    for q in range(b * s // blocks, (b + 1) * s // blocks):
        d0, d1, d2, L = _length(X, i[q], j[q], dim)
        if movable[q]:
            worst = max(worst, L / L0[q] - 1.0)
        if jacobi:
            excess = provot_excess(L, L0[q], max_strain) if movable[q] else 0.0
            too[q] = excess > 0
            if excess > 0:
                c[q, 0] = excess * (d0 / L)
                c[q, 1] = excess * (d1 / L)
                c[q, 2] = excess * (d2 / L)
    return worst


def _average(p, X, c, too, wi, wj, free, ptr, col):
    """Particle p's Jacobi correction: ``x_p += (sum_j wj c - sum_i wi c) / count_p`` over its too long springs."""
    s, dim = len(too), X.shape[2]
    count = 0
    i0, i1, i2, j0, j1, j2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for e in range(ptr[p], ptr[p + 1]):
        q = col[e]
        if q < s:  # p is the spring's first end
            if too[q]:
                count += 1
                i0 += wi[q] * c[q, 0]
                i1 += wi[q] * c[q, 1]
                i2 += wi[q] * c[q, 2]
        elif too[q - s]:
            q -= s
            count += 1
            j0 += wj[q] * c[q, 0]
            j1 += wj[q] * c[q, 1]
            j2 += wj[q] * c[q, 2]
    if count and free[p]:
        scale = 1.0 / count
        X[p, 0, 0] += scale * (j0 - i0)
        X[p, 0, 1] += scale * (j1 - i1)
        if dim == 3:
            X[p, 0, 2] += scale * (j2 - i2)


def _correct(q, X, i, j, L0, wi, wj, movable, max_strain):
    """Spring q's correction, if too long: its ends moved by their shares of the excess (Gauss-Seidel)."""
    if not movable[q]:
        return
    dim = X.shape[2]
    d0, d1, d2, L = _length(X, i[q], j[q], dim)
    excess = provot_excess(L, L0[q], max_strain)
    if excess > 0:
        c0, c1, c2 = excess * (d0 / L), excess * (d1 / L), excess * (d2 / L)
        X[i[q], 0, 0] -= wi[q] * c0
        X[i[q], 0, 1] -= wi[q] * c1
        X[j[q], 0, 0] += wj[q] * c0
        X[j[q], 0, 1] += wj[q] * c1
        if dim == 3:
            X[i[q], 0, 2] -= wi[q] * c2
            X[j[q], 0, 2] += wj[q] * c2


for _helper in (_length, _block_strains, _average, _correct):  # compiled into provot_passes
    inline(_helper)


@jit(parallel=True)
def provot_passes(X, i, j, L0, wi, wj, movable, free, max_strain, stop, iterations, h, jacobi, order, bounds, ptr,
                  col, x0, c, too, bworst):
    """The passes of one projection of X (n, 2, d), in place; returns ``(largest strain, passes)``.

    Passes until the largest strain of a movable spring is at most `stop` or after `iterations`
    passes: Jacobi with averaging (`jacobi`, through the incidence list ``ptr, col``) or Gauss-Seidel
    over the colour groups (``order[bounds[g]:bounds[g + 1]]``, each group's springs in parallel);
    then ``v += (x - x0) / h``.
    """
    n, _, dim = X.shape
    blocks = len(bworst)
    worst, passes = 0.0, 0
    for k in range(iterations + 1):  # a loop over the passes of the projection
        passes = k
        for b in prange(blocks):
            bworst[b] = _block_strains(b, blocks, X, i, j, L0, movable, max_strain, jacobi, c, too)
        worst = 0.0
        for b in range(blocks):
            worst = max(worst, bworst[b])
        if worst <= stop or k == iterations:
            break
        if k == 0:  # the positions before the first correction (no pass: nothing moves)
            for p in prange(n):
                for a in range(dim):
                    x0[p, a] = X[p, 0, a]
        if jacobi:
            for p in prange(n):
                _average(p, X, c, too, wi, wj, free, ptr, col)
        else:
            for g in range(len(bounds) - 1):  # Gauss-Seidel: one colour at a time
                for e in prange(bounds[g], bounds[g + 1]):
                    _correct(order[e], X, i, j, L0, wi, wj, movable, max_strain)
    if passes:
        for p in prange(n):
            for a in range(dim):
                X[p, 1, a] += (X[p, 0, a] - x0[p, a]) / h
    return worst, passes


class CompiledProjection:
    """:meth:`particles.constraints.ProvotConstraint.stepper`'s projection, compiled, in place on a step's end state.

    The springs' arrays (ends, rest lengths, shares, the incidence list, the colour groups) are made
    once for the constraint's springs and pins; the kernel reads C-ordered states (the compiled step's
    rows), and a Fortran-ordered state is corrected in a C-ordered copy written back, so that the kernel
    is compiled once, not once per memory order.
    """

    def __init__(self, constraint):
        self.constraint = constraint
        self.key = None

    def _arrays(self, n):
        constraint = self.constraint
        key = (n, id(constraint.indices), id(constraint.rest_length), id(constraint.free))
        if self.key == key:
            return
        i, j = (np.ascontiguousarray(constraint.indices[:, k], dtype=np.int64) for k in range(2))
        self.i, self.j = i, j
        self.wi, self.wj = end_shares(constraint.free[i], constraint.free[j])
        self.movable = (self.wi + self.wj) > 0
        self.L0 = np.ascontiguousarray(constraint.rest_length, dtype=float)
        self.free = np.ascontiguousarray(constraint.free)
        self.lists = incidence(np.concatenate([i, j]), n, 2, True)
        groups = constraint.groups or []
        self.order = np.concatenate(groups).astype(np.int64) if groups else np.zeros(0, dtype=np.int64)
        self.bounds = np.cumsum([0] + [len(g) for g in groups]).astype(np.int64)
        s = len(i)
        jacobi = constraint.groups is None
        self.buffers = (np.empty((n, 3)), np.zeros((s if jacobi else 0, 3)), np.zeros(s if jacobi else 0, np.bool_),
                        np.empty(max(1, min(STRAIN_BLOCKS, s // 1024))))
        self.key = key

    def project(self, X, h):
        """Provot's projection of the end state X (n, 2, d) in place, velocities corrected; returns (worst, passes)."""
        c = self.constraint
        self._arrays(len(X))
        stop = c.max_strain + c.tol + ROUNDING
        with c_ordered(X) as X_c:
            worst, passes = pick(provot_passes, len(self.i))(
                X_c, self.i, self.j, self.L0, self.wi, self.wj, self.movable, self.free, float(c.max_strain),
                float(stop), int(c.iterations), float(h), c.groups is None, self.order, self.bounds, *self.lists,
                *self.buffers)
        return float(worst), int(passes)
