"""The compiled XPBD projections (numba): the arithmetic of Distance.project and of the linear sets' project.

Imported only by :mod:`particles.backends.compiled` (one colour group or one
Jacobi pass per call) and :mod:`particles.backends.xpbdstep` (a whole substep
per call: :func:`substep`). Positions are coordinate-major, shape (d, n), as
the solvers of :mod:`particles.xpbd` hold them. Each projection does the
NumPy code's operations in the same order (no fused multiply-adds), so the
two give the same bits.
"""

import math

from ._kernels import _jit, numba, prange


def _inline(fn):
    """`fn` compiled into each kernel that calls it (numba's IR inlining), so that its flags become constants."""
    return fn if numba is None else numba.njit(inline="always")(fn)


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


@_inline
def _distance_row(P, ij, dco, lam, r, three, xpbd, damped):
    """Project distance row r on the particle rows P (x in columns 0-2, x_n in 3-5, w in 6): Distance.project's steps."""
    pa, pb = ij[r, 0], ij[r, 1]
    d0 = P[pa, 0] - P[pb, 0]
    d1 = P[pa, 1] - P[pb, 1]
    d2 = P[pa, 2] - P[pb, 2] if three else 0.0
    L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    Lg = max(L, 1e-150)
    lr = lam[r]
    if xpbd and not damped:
        dl = (dco[r, 0] - L - dco[r, 1] * lr) * dco[r, 2]
    elif xpbd:
        rel = d0 * (d0 - (P[pa, 3] - P[pb, 3])) + d1 * (d1 - (P[pa, 4] - P[pb, 4]))
        if three:
            rel += d2 * (d2 - (P[pa, 5] - P[pb, 5]))
        dl = (-(L - dco[r, 0]) - dco[r, 1] * lr - dco[r, 3] * (rel / Lg)) * dco[r, 2]
    else:
        dl = -(L - dco[r, 0]) * dco[r, 2]
    if xpbd:
        lam[r] = lr + dl
    scale = dl / Lg
    wa, wb = P[pa, 6], P[pb, 6]
    d0 *= scale
    d1 *= scale
    P[pa, 0] += wa * d0
    P[pb, 0] -= wb * d0
    P[pa, 1] += wa * d1
    P[pb, 1] -= wb * d1
    if three:
        d2 *= scale
        P[pa, 2] += wa * d2
        P[pb, 2] -= wb * d2


@_inline
def _linear_row(P, idx, c, wc, offset, lco, lam, r, dim, width, xpbd, damped):
    """Project linear row r, ``C = sum_k c_k x_{idx_k} - offset``, each coordinate on its own: _Linear.project's steps."""
    for e in range(dim):
        C = 0.0
        for k in range(width):
            C += c[r, k] * P[idx[r, k], e]
        C -= offset[r, e]
        lr = lam[e, r]
        if xpbd:
            res = -C - lco[r, 0] * lr
            if damped:
                Cn = 0.0
                for k in range(width):
                    Cn += c[r, k] * P[idx[r, k], 3 + e]
                res -= lco[r, 2] * (C + offset[r, e] - Cn)  # gamma (C(x) - C(x_n))
            dl = res * lco[r, 1]
            lam[e, r] = lr + dl
        else:
            dl = -C * lco[r, 1]
        for k in range(width):
            P[idx[r, k], e] += wc[r, k] * dl


@_jit(parallel=True)
def substep(x, v, a, given, terms, m, free, hs, iterations, xpbd, segments, P,
            ij, dco, d_lam, idx, c, wc, offset, lco, l_lam):
    """One XPBD substep of length hs in one call, in place on x and v (d, n).

    Prediction ``v += hs a``, ``x_n = x``, ``x += hs v`` (``a``: the given
    accelerations, else ``F / m`` from the force ``terms`` (q, 4), rows
    ``(0, g)`` for gravity, ``(1, d)`` for damping ``-d v``, ``(2, rate)``
    for ``-rate m v``; 0 at pinned particles) into the
    particle rows ``P`` (n, 8): ``x`` in columns 0-2, ``x_n`` in 3-5, the
    inverse mass ``w`` in 6 (kept there by the caller), so that a
    constraint reads one cache line per particle. Then the multipliers set to
    zero, ``iterations`` sweeps through the ``segments`` (rows ``(form, start,
    stop, width, damped)``, each one colour group: form 0 distance rows of
    ``ij`` and ``dco`` = (L0, alpha~, 1 / denominator, gamma), form 1 linear
    rows of ``idx``, ``c``, ``wc`` = w c, ``offset`` and ``lco`` = (alpha~,
    1 / denominator, gamma); a group's rows in parallel), ``v = (x - x_n) /
    hs`` and x written back. The distances' violation after it is measured
    on x by :func:`distance_violation`: the same loop over P at the end of
    this kernel added 0.42 ms on a 128^2 cloth, that kernel takes 0.25 ms.
    """
    dim, n = x.shape
    three = dim == 3
    for p in prange(n):  # particle after particle: its row of P written whole
        for e in range(dim):
            if given:
                acc = a[e, p]
            else:  # the forces' add_to in their order, then F / m (the NumPy solver's _accelerations)
                F = 0.0
                for q in range(terms.shape[0]):
                    if terms[q, 0] == 0.0:  # gravity g: F += g m
                        F += terms[q, 1 + e] * m[p]
                    elif terms[q, 0] == 1.0:  # damping d: F -= d v
                        F -= terms[q, 1] * v[e, p]
                    else:  # damping per unit mass: F -= (rate m) v
                        F -= (terms[q, 1] * m[p]) * v[e, p]
                acc = F / m[p] if free[p] else 0.0
            vp = v[e, p] + hs * acc
            v[e, p] = vp
            P[p, 3 + e] = x[e, p]
            P[p, e] = x[e, p] + hs * vp
    for r in prange(len(d_lam)):
        d_lam[r] = 0.0
    for r in prange(l_lam.shape[1]):
        for e in range(l_lam.shape[0]):
            l_lam[e, r] = 0.0
    for _ in range(iterations):
        for s in range(len(segments)):  # colour after colour: the Gauss-Seidel order
            form, start, stop, width, damped = segments[s, 0], segments[s, 1], segments[s, 2], segments[s, 3], \
                segments[s, 4] != 0
            if form == 0 and three and xpbd and damped:  # distance rows, each case its own loop without branches
                for r in prange(start, stop):
                    _distance_row(P, ij, dco, d_lam, r, True, True, True)
            elif form == 0 and three and xpbd:
                for r in prange(start, stop):
                    _distance_row(P, ij, dco, d_lam, r, True, True, False)
            elif form == 0:
                for r in prange(start, stop):
                    _distance_row(P, ij, dco, d_lam, r, three, xpbd, damped)
            elif three and width == 3 and xpbd and not damped:  # linear rows: isometric bending in 3D, on its own
                for r in prange(start, stop):
                    _linear_row(P, idx, c, wc, offset, lco, l_lam, r, 3, 3, True, False)
            else:
                for r in prange(start, stop):
                    _linear_row(P, idx, c, wc, offset, lco, l_lam, r, dim, width, xpbd, damped)
    for p in prange(n):
        for e in range(dim):
            x[e, p] = P[p, e]
            v[e, p] = (P[p, e] - P[p, 3 + e]) / hs


@_jit(parallel=True)
def distance_violation(x, ij, dco, out):
    """``|C| = ||x_i - x_j| - L0|`` of every distance row (ij, L0 = dco[:, 0]) into out (s,), at x (d, n)."""
    three = x.shape[0] == 3
    for r in prange(len(out)):
        a, b = ij[r, 0], ij[r, 1]
        d0 = x[0, a] - x[0, b]
        d1 = x[1, a] - x[1, b]
        d2 = x[2, a] - x[2, b] if three else 0.0
        out[r] = abs(math.sqrt(d0 * d0 + d1 * d1 + d2 * d2) - dco[r, 0])
