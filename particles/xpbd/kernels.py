"""The XPBD projections, compiled (numba): one colour group, one Jacobi pass, or a whole substep per call.

Each projection inlines the laws of the NumPy sets' ``project``
(:func:`particles.xpbd.distance.distance_constraint`,
:func:`particles.xpbd.distance.multiplier_step`) and does their operations in
their order (no fused multiply-adds), so the two give the same bits to
rounding. Positions are coordinate-major, shape (d, n), as the solvers of
:mod:`particles.xpbd` hold them; :func:`substep` reads them in particle rows
(:mod:`particles.xpbd.compiled_substep` lays them out).
:class:`CompiledPasses` projects one batch of a distance set at a time (the
Jacobi solver, and sets without a form for :func:`substep`). Importing this
module imports numba.
"""

import math

import numpy as np

from ..backends.compile import inline, jit, pick, prange
from .distance import distance_constraint, multiplier_step

__all__ = ["distance_group", "distance_jacobi", "substep", "distance_violation", "CompiledPasses"]

inline(distance_constraint)
inline(multiplier_step)


@jit(parallel=True)
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
        dC = 0.0
        if xpbd and damped:
            dC = d0 * (d0 - (x_n[0, a] - x_n[0, b])) + d1 * (d1 - (x_n[1, a] - x_n[1, b]))
            if three:
                dC += d2 * (d2 - (x_n[2, a] - x_n[2, b]))
            dC /= Lg
        dl = multiplier_step(distance_constraint(L, L0[r]), lr, at[r], gamma[r] if xpbd and damped else 0.0, dC,
                             inv[r])
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


@jit()
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
        dC = 0.0
        if xpbd and damped:
            for c in range(dim):
                dc = x[c, a] - x[c, b]
                dC += dc * (dc - (x_n[c, a] - x_n[c, b]))
            dC /= Lg
        dl = multiplier_step(distance_constraint(L, L0[r]), lam[r] if xpbd else 0.0, at[r],
                             gamma[r] if xpbd and damped else 0.0, dC, inv[r]) * scale[r]
        if xpbd:
            lam[r] += dl
        for c in range(dim):
            dc = (x[c, a] - x[c, b]) * (dl / Lg)
            si[c, a] += wi[r] * dc
            sj[c, b] += wj[r] * dc
    for c in range(dim):
        for p in range(x.shape[1]):
            x[c, p] += si[c, p] - sj[c, p]


def _distance_row(P, ij, dco, lam, r, three, xpbd, damped):
    """Project distance row r on the particle rows P (x in columns 0-2, x_n in 3-5, w in 6): Distance.project's steps."""
    pa, pb = ij[r, 0], ij[r, 1]
    d0 = P[pa, 0] - P[pb, 0]
    d1 = P[pa, 1] - P[pb, 1]
    d2 = P[pa, 2] - P[pb, 2] if three else 0.0
    L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    Lg = max(L, 1e-150)
    lr = lam[r]
    dC = 0.0
    if xpbd and damped:
        dC = d0 * (d0 - (P[pa, 3] - P[pb, 3])) + d1 * (d1 - (P[pa, 4] - P[pb, 4]))
        if three:
            dC += d2 * (d2 - (P[pa, 5] - P[pb, 5]))
        dC /= Lg
    dl = multiplier_step(distance_constraint(L, dco[r, 0]), lr, dco[r, 1], dco[r, 3] if xpbd and damped else 0.0, dC,
                         dco[r, 2])
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


def _linear_row(P, idx, c, wc, offset, lco, lam, r, dim, width, xpbd, damped):
    """Project linear row r, ``C = sum_k c_k x_{idx_k} - offset``, each coordinate on its own: _Linear.project's steps."""
    for e in range(dim):
        C = 0.0
        for k in range(width):
            C += c[r, k] * P[idx[r, k], e]
        C -= offset[r, e]
        lr = lam[e, r]
        dC = 0.0
        if xpbd and damped:
            Cn = 0.0
            for k in range(width):
                Cn += c[r, k] * P[idx[r, k], 3 + e]
            dC = C + offset[r, e] - Cn  # C(x) - C(x_n)
        dl = multiplier_step(C, lr if xpbd else 0.0, lco[r, 0], lco[r, 2] if xpbd and damped else 0.0, dC, lco[r, 1])
        if xpbd:
            lam[e, r] = lr + dl
        for k in range(width):
            P[idx[r, k], e] += wc[r, k] * dl


def _predict(p, x, v, a, given, terms, m, free, hs, P, dim):
    """Particle p's prediction ``v += hs a``, ``x_n = x``, ``x += hs v``, into its row of P (NumPy's _accelerations)."""
    for e in range(dim):
        if given:
            acc = a[e, p]
        else:  # the forces' add_to in their order, then F / m
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


for _helper in (_distance_row, _linear_row, _predict):  # compiled into substep, their constants reaching them
    inline(_helper)


@jit(parallel=True)
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
        _predict(p, x, v, a, given, terms, m, free, hs, P, dim)
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


@jit(parallel=True)
def distance_violation(x, ij, dco, out):
    """``|C|`` of every distance row (ij, L0 = dco[:, 0]) into out (s,), at x (d, n)."""
    three = x.shape[0] == 3
    for r in prange(len(out)):
        a, b = ij[r, 0], ij[r, 1]
        d0 = x[0, a] - x[0, b]
        d1 = x[1, a] - x[1, b]
        d2 = x[2, a] - x[2, b] if three else 0.0
        out[r] = abs(distance_constraint(math.sqrt(d0 * d0 + d1 * d1 + d2 * d2), dco[r, 0]))


class CompiledPasses:
    """The distance sets' ``project``, one batch per call, compiled; keeps each batch's arrays.

    A colour group (no particle twice) writes its corrections directly; a Jacobi batch sums them per
    particle first. What the kernels read (contiguous indices, the rows' coefficients) is laid out once
    per batch and substep length.
    """

    def __init__(self):
        self.kept = {}  # id(batch) -> (batch, key, arrays)

    def _arrays(self, b, hs, formulation):
        b.coefficients(hs, formulation)
        found = self.kept.get(id(b))
        if found is not None and found[0] is b and found[1] == (hs, formulation):
            return found[2]
        r = len(b.idx)
        rows = np.arange(r) + (b.rows.start or 0) if isinstance(b.rows, slice) else b.rows
        arrays = dict(rows=np.ascontiguousarray(rows, dtype=np.int64),
                      ij=(np.ascontiguousarray(b.idx[:, 0]), np.ascontiguousarray(b.idx[:, 1])),
                      coefficients=tuple(np.ascontiguousarray(np.broadcast_to(np.asarray(c, dtype=float), (r,)))
                                         for c in (b.at, b.inv, b.gamma)),
                      scale=None if b.scale is None else np.ascontiguousarray(b.scale, dtype=float))
        self.kept[id(b)] = (b, (hs, formulation), arrays)
        return arrays

    def project(self, b, x, x_n, lam, hs, formulation):
        """:meth:`particles.xpbd.constraint_sets.Distance.project` of batch `b`, compiled, on x (d, n) in place."""
        arrays = self._arrays(b, hs, formulation)
        i, j = arrays["ij"]
        at, inv, gamma = arrays["coefficients"]
        xpbd, damped = formulation == "xpbd", bool(b.damped and formulation == "xpbd")
        if arrays["scale"] is None:  # a colour group: no particle twice, corrections written directly
            pick(distance_group, len(i))(x, x_n, lam, arrays["rows"], i, j, b.L0, b.wi, b.wj, at, inv, gamma, xpbd,
                                         damped)
            return
        buffers = arrays.get("buffers")
        if buffers is None or buffers[0].shape != x.shape:
            buffers = arrays["buffers"] = np.empty(x.shape), np.empty(x.shape)
        distance_jacobi(x, x_n, lam, i, j, b.L0, b.wi, b.wj, at, inv, gamma, arrays["scale"], xpbd, damped, *buffers)
