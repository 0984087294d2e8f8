"""The prefactorized solver's loops, compiled (numba): the local step, the global step's solves, the residual.

Imported only by :mod:`particles.implicit.compiled_factorization`. The arithmetic of
:class:`particles.implicit.Prefactored`'s NumPy methods, in their order where
that costs nothing: the local step scatters each spring's projection into two
sums per particle (the spring's first ends, then its second ends, each in
increasing spring order from zero, as one ``np.bincount`` per role sums them)
and so gives NumPy's bits; the triangular solves run over the Cholesky
factor ``R`` of SuperLU's symmetric factorization (``P Q P^T = R^T R``, one triangle read twice), and
the residual's norm is a plain sum, so these two agree with NumPy to
rounding (about 1e-15 relative). Arrays are coordinate-major, ``(d, n)``,
as in the NumPy code; the solves work on particle rows ``(n, d)``. One
thread: each call is a fraction of a millisecond on a 64^2 cloth.
"""

import math

from ..backends.compile import inline, jit
from ..forces.springs import damped_spring_force
from .sparse import projection_weight

inline(projection_weight)
inline(damped_spring_force)


@jit()
def local_step(xt, i, j, k, L0, free, m, y, h2, xr, Si, Sj, Fs, Jd, out):
    """Jd (d, f) = the projections ``k L0 (x_i - x_j) / |x_i - x_j|`` scattered (+i, -j) on the free particles.

    `xt` (d, n) positions; `m` (f,) and `y` (d, f): the free particles' masses and inertial positions;
    `xr`, `Si`, `Sj`, `Fs` (n, d) scratch. Returns the springs' energy ``sum k (L - L0)^2 / 2`` and sets
    ``out[0] = |g|``, g = M (x - y) / h2 - F_springs(x) on the free particles: the gradient of Phi,
    equal to ``(Q x - b) / h2 - J d`` (whose pins' terms are the springs' pull ``L x``).
    """
    dim, n = xt.shape
    for p in range(n):  # rows (n, d): each spring touches two particles' rows
        for c in range(dim):
            xr[p, c] = xt[c, p]
            Si[p, c] = 0.0
            Sj[p, c] = 0.0
            Fs[p, c] = 0.0
    energy = 0.0
    for s in range(len(i)):  # a loop over springs (compiled)
        a, b = i[s], j[s]
        d0 = xr[a, 0] - xr[b, 0]
        d1 = xr[a, 1] - xr[b, 1]
        d2 = xr[a, 2] - xr[b, 2] if dim == 3 else 0.0
        L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        w = projection_weight(L, L0[s], k[s])
        f = damped_spring_force(L, L0[s], k[s], 0.0, 0.0) / max(L, 1e-300)  # the spring's force is f (x_i - x_j)
        Si[a, 0] += d0 * w
        Si[a, 1] += d1 * w
        Sj[b, 0] += d0 * w
        Sj[b, 1] += d1 * w
        Fs[a, 0] += d0 * f
        Fs[a, 1] += d1 * f
        Fs[b, 0] -= d0 * f
        Fs[b, 1] -= d1 * f
        if dim == 3:
            Si[a, 2] += d2 * w
            Sj[b, 2] += d2 * w
            Fs[a, 2] += d2 * f
            Fs[b, 2] -= d2 * f
        energy += k[s] * (L - L0[s]) ** 2
    total = 0.0
    for c in range(dim):
        for q in range(len(free)):
            p = free[q]
            Jd[c, q] = Si[p, c] - Sj[p, c]
            g = m[q] * (xr[p, c] - y[c, q]) / h2 - Fs[p, c]
            total += g * g
    out[0] = math.sqrt(total)
    return 0.5 * energy


@jit()
def global_step(b, Jd, h2, perm, Rp, Rj, Rx, Rd, y, out):
    """out (d, f) solving ``Q out = b + h2 Jd`` with the Cholesky factor ``P Q P^T = R^T R``: ``Prefactored._global``.

    ``Rp, Rj, Rx``: R's strictly upper part in CSR (int32 indices), ``Rd`` its diagonal; `perm` the
    symmetric permutation (SuperLU's); `y` (f, 3) scratch (in 2D its third column stays zero). One
    factor, read twice: forward ``R^T w = P r`` by R's rows scattered (columns of R^T), backward
    ``R z = w`` by R's rows gathered.
    """
    dim, f = b.shape
    y[:, 2] = 0.0
    for r in range(f):  # y = P (b + h2 Jd)
        for c in range(dim):
            y[perm[r], c] = b[c, r] + h2 * Jd[c, r]
    for r in range(f):  # R^T w = y, forward: w_r final once the rows above scattered into it
        inv = 1.0 / Rd[r]
        w0, w1, w2 = y[r, 0] * inv, y[r, 1] * inv, y[r, 2] * inv
        y[r, 0], y[r, 1], y[r, 2] = w0, w1, w2
        for e in range(Rp[r], Rp[r + 1]):
            q, v = Rj[e], Rx[e]
            y[q, 0] -= v * w0
            y[q, 1] -= v * w1
            y[q, 2] -= v * w2
    for r in range(f - 1, -1, -1):  # R z = w, backward by rows
        a0, a1, a2 = y[r, 0], y[r, 1], y[r, 2]
        for e in range(Rp[r], Rp[r + 1]):
            q, v = Rj[e], Rx[e]
            a0 -= v * y[q, 0]
            a1 -= v * y[q, 1]
            a2 -= v * y[q, 2]
        inv = 1.0 / Rd[r]
        y[r, 0], y[r, 1], y[r, 2] = a0 * inv, a1 * inv, a2 * inv
    for r in range(f):  # out = P^T z
        for c in range(dim):
            out[c, r] = y[perm[r], c]


@jit()
def gradient_norm(Qp, Qj, Qx, u, b, Jd, h2):
    """``|g|``, g = (Q u - b) / h2 - Jd the gradient of Phi on the free particles (Q in CSR, (d, f) arrays).

    ``Prefactored._gradient_norm`` computed by rows, without the sparse product's temporaries.
    """
    dim, f = u.shape
    total = 0.0
    for c in range(dim):
        for r in range(f):  # a loop over the free particles (compiled)
            q = 0.0
            for e in range(Qp[r], Qp[r + 1]):
                q += Qx[e] * u[c, Qj[e]]
            g = (q - b[c, r]) / h2 - Jd[c, r]
            total += g * g
    return math.sqrt(total)
